"""What :func:`savant_cli.run` and :func:`savant_cli.load` return: one finished study, read
from its run folder (docs/api.md).

Everything is read from the folder's files (``summary.json``, ``savant.h5``,
``.hydra/config.yaml``), the same ones ``savant report`` redraws from, so a loaded result
and the one a run returned are the same object. Large parts (the time history, the
linear systems, the Monte Carlo tables) are read the first time they are asked for.

The time history is an :class:`xarray.Dataset` (docs/api.md, *Why xarray*): one variable
per logged signal on the ``time`` dimension (s), a vector signal with a second dimension
named ``<signal>_axis`` whose coordinate holds its component names, and the attributes
``units`` (SI), ``description`` and ``frame`` on every variable. Tables are
:class:`pandas.DataFrame`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import h5py
import numpy as np
from omegaconf import DictConfig, OmegaConf

from savant_cli.io.hdf5 import as_str as _text
from savant_cli.io.integrity import read_h5

if TYPE_CHECKING:  # imported when used: pandas, xarray and python-control are slow to import
    import control
    import pandas
    import xarray
    from matplotlib.figure import Figure

RUN_FILE = "savant.h5"
PLOTS_DIR = "plots"
SUMMARY_FILE = "summary.json"
#: Linear-chart names :meth:`Result.plot` draws for one point (``time=`` required).
LINEAR_CHARTS = ("bode", "nichols", "nyquist", "rootlocus", "pzmap", "response")


def _frame(group: h5py.Group, index: str | None = None) -> "pandas.DataFrame":
    """The 1-D datasets of an h5 group as DataFrame columns (strings decoded), in the
    group's order; ``index`` names the column to index by."""
    import pandas as pd

    cols = {}
    for name, ds in group.items():
        if not isinstance(ds, h5py.Dataset) or ds.ndim != 1:
            continue
        cols[name] = ds.asstr()[()] if h5py.check_string_dtype(ds.dtype) else ds[()]
    df = pd.DataFrame(cols)
    return df.set_index(index) if index and index in df else df


@dataclass
class LinearPointResult:
    """One operating point of a linear study.

    Attributes
    ----------
    time_s : float
        Flight time of the point (s).
    phase : str
        Vehicle configuration at the point (``stack``, ``upper`` …).
    systems : dict of str to control.StateSpace
        Every stored system (``open_pitch``, ``open_yaw``, ``plant``, ``controller``,
        ``closed_loop`` …; :func:`savant_cli.linear.store.systems`), python-control
        objects with their state, input and output names; ``point["open_pitch"]`` is
        the same.
    margins : pandas.DataFrame
        The point's rows of the margin table (axis, kind, value in dB or deg, frequency
        in Hz, band, mode, meets_requirement).
    checks : pandas.DataFrame or None
        The point's requirement checks (docs/requirements.md), None without a set.
    passed : bool or None
        Whether the point meets its requirement set (None without one).
    judged : bool or None
        Whether it counts in the study's verdict (False in the first-stage tail-off window).
    """

    time_s: float
    phase: str
    systems: dict[str, "control.StateSpace"]
    margins: "pandas.DataFrame"
    checks: "pandas.DataFrame | None" = None
    passed: bool | None = None
    judged: bool | None = None

    def __getitem__(self, name: str) -> "control.StateSpace":
        try:
            return self.systems[name]
        except KeyError:
            raise KeyError(f"no system {name!r} at t = {self.time_s:g} s; stored: {sorted(self.systems)}") from None


class LinearPoints(dict):
    """The points of a linear study by flight time (s); ``points[55]`` finds 55.0."""

    def __missing__(self, key):
        raise KeyError(f"no linear point at t = {key} s; stored: {sorted(self)}")


@dataclass
class MonteCarloResult:
    """The tables of a Monte Carlo batch (``savant.h5`` group ``montecarlo``).

    Attributes
    ----------
    runs : pandas.DataFrame
        One row per run present, indexed by run number: ``status``, ``message``,
        ``t_final_s``, ``wall_time_s``, then every summary key of the run (SI units in
        the key names), then the event times ``<event>_s``.
    dispersions : pandas.DataFrame
        The drawn value of every dispersion per run (indexed by run; a ``winds`` choice
        as its option name). ``attrs["items"]`` holds each item's target, apply, dist,
        units and source.
    margins : pandas.DataFrame
        Every run's margins at ``study.linear_times`` (run, time_s, axis, kind, band,
        value, frequency_hz, mode, meets_requirement); empty without linear times.
    margin_spread : pandas.DataFrame
        The spread of those margins over the runs, as in ``summary.json``.
    statistics : pandas.DataFrame
        The summary statistics (min/max with their runs, percentiles, mean, std) of
        every summary key.
    """

    runs: "pandas.DataFrame"
    dispersions: "pandas.DataFrame"
    margins: "pandas.DataFrame"
    margin_spread: "pandas.DataFrame"
    statistics: "pandas.DataFrame"


@dataclass
class Result:
    """A finished study (returned by :func:`savant_cli.run`, or :func:`savant_cli.load`).

    Attributes
    ----------
    run_dir : pathlib.Path
        The run folder.
    study : str
        The study's name (``nominal``, ``linear``, ``montecarlo`` …).
    summary : dict
        ``summary.json`` (the keys carry their units; docs/outputs.md).
    config : omegaconf.DictConfig
        The composed configuration the study ran with, resolved.
    status, message : str
        The run's verdict (``complete``, ``loss_of_control``, ``limit_cycle``,
        ``slow_divergence``, ``saturated``, ``diverged`` …)
        and why it stopped; a Monte Carlo's ``status`` is ``complete`` when every run is.
    exit_code : int
        What ``savant run`` exited with, or would have: 0 when the flight flew to its end
        (a Monte Carlo: no run missing), 1 when not.
    provenance : dict
        Versions, host, git commit and time of the run.
    """

    run_dir: Path
    study: str
    summary: dict[str, Any]
    config: DictConfig
    status: str
    message: str
    exit_code: int
    provenance: dict[str, str] = field(default_factory=dict)

    def __repr__(self) -> str:
        return f"Result(study={self.study!r}, status={self.status!r}, run_dir={str(self.run_dir)!r})"

    @property
    def complete(self) -> bool:
        """True when the study's flight (or every run of a batch) flew to its end healthy."""
        return self.status == "complete"

    @property
    def h5(self) -> Path:
        """The run file, ``run_dir/savant.h5``."""
        return self.run_dir / RUN_FILE

    def _format(self) -> str:
        with read_h5(self.h5) as f:
            return _text(f.attrs.get("format", ""))

    def _groups(self) -> set[str]:
        with read_h5(self.h5) as f:
            return set(f)

    @cached_property
    def _record(self):
        from savant_cli.io.hdf5 import FORMAT, read_run

        return read_run(self.h5) if self._format() == FORMAT else None

    @property
    def events(self) -> dict[str, float]:
        """The flight's discrete events, name → mission time (s), in the order they
        happened (empty for a study without a single flight)."""
        rec = self._record
        return {} if rec is None else {name: float(t) for name, t in rec.events}

    @cached_property
    def history(self) -> "xarray.Dataset | None":
        """The flight's time history (module notes); None for a study without one."""
        rec = self._record
        if rec is None:
            return None
        return history_dataset(rec.signals, rec.status, rec.message)

    @cached_property
    def linear(self) -> LinearPoints | None:
        """The operating points of a linear study by flight time (s); None when the run
        file has no group ``linear`` (a Monte Carlo's per-run margins are in
        :attr:`montecarlo`)."""
        import pandas as pd

        from savant_cli.linear.store import point_keys, point_verdicts, read_system, system_names

        if "linear" not in self._groups():
            return None
        out = LinearPoints()
        with read_h5(self.h5) as f:
            g = f["linear"]
            margins = _frame(g["margins"])
            checks = _frame(g["requirements/checks"]) if "requirements/checks" in g else None
            verdicts = point_verdicts(g)
            for key in point_keys(g):
                pg = g[key]
                t = float(pg.attrs["time_s"])
                near = np.isclose(margins["time_s"].to_numpy(float), t, atol=5e-4) if len(margins) else []
                mine = margins[near].reset_index(drop=True) if len(margins) else margins
                pc = None
                if checks is not None:
                    pc = checks[np.isclose(checks["time_s"].to_numpy(float), t, atol=5e-4)].reset_index(drop=True)
                passed, judged = verdicts.get(t, (None, None))
                out[t] = LinearPointResult(time_s=t, phase=_text(pg.attrs.get("phase", "")),
                                           systems={n: read_system(pg, n) for n in system_names(pg)},
                                           margins=pd.DataFrame(mine), checks=pc, passed=passed, judged=judged)
        return out

    @cached_property
    def margins(self) -> "pandas.DataFrame | None":
        """The margin table of every point of a linear study (None without one)."""
        if "linear" not in self._groups():
            return None
        with read_h5(self.h5) as f:
            return _frame(f["linear/margins"])

    @cached_property
    def montecarlo(self) -> MonteCarloResult | None:
        """The tables of a Monte Carlo batch (None for another study)."""
        import pandas as pd

        if "montecarlo" not in self._groups():
            return None
        with read_h5(self.h5) as f:
            g = f["montecarlo"]
            runs = _frame(g["runs"], index="run")
            for name, ds in g["summary"].items():
                runs[name] = ds[()]
            for name, ds in g["events"].items():
                runs[name] = ds[()]
            disp = pd.DataFrame(index=runs.index)
            items = {}
            for name, ds in g["dispersions"].items():
                a = {k: _text(v) for k, v in ds.attrs.items()}
                values = ds[()]
                choices = json.loads(a["choices"]) if a.get("choices") else None
                if choices:
                    values = [choices[int(v)] if np.isfinite(v) else None for v in values]
                disp[name] = values
                items[name] = a
            disp.attrs["items"] = items
            margins = _frame(g["margins"])
        spread = pd.DataFrame(self.summary.get("margin_spread") or [])
        stats = pd.DataFrame(self.summary.get("statistics") or [])
        return MonteCarloResult(runs=runs, dispersions=disp, margins=margins, margin_spread=spread,
                                statistics=stats.set_index("variable") if "variable" in stats else stats)

    def figure_names(self) -> list[str]:
        """The names :meth:`plot` draws for this study: the ascent figures, a linear
        study's charts, and every other figure the study drew, by its file under
        ``plots/`` without ``.png`` (``time_margins/t55_pitch_delay``,
        ``histograms_01``, ``flex_sweep/nichols_pitch_frequency_t0055.0`` …)."""
        names = self._chart_names()
        return names + [n for n in self._study_figures if n not in names]

    def _chart_names(self) -> list[str]:
        """The ascent figures and a linear study's charts: drawn by name when asked for,
        without drawing the study's other figures."""
        from savant_cli.plots.ascent import figure_names

        names = figure_names(self._record) if self._record is not None else []
        if "linear" in self._groups():
            names += [*LINEAR_CHARTS, "margin_envelope"]
        return names

    @cached_property
    def _study_figures(self) -> dict[str, "Figure"]:
        """The figures of the study groups other than ``linear`` (which :meth:`plot` draws
        by chart and point), drawn once by the code ``savant report`` writes them with,
        kept instead of written (:func:`savant_cli.plots.figure.capture_figures`)."""
        from savant_cli.plots.figure import capture_figures
        from savant_cli.studies.redraw import draw_groups

        folder = self.run_dir / PLOTS_DIR
        groups = self._groups() - {"linear"}
        with capture_figures() as kept:
            draw_groups(self.h5, groups, folder)
        return {path.relative_to(folder).with_suffix("").as_posix(): fig for path, fig in kept.items()}

    def plot(self, name: str, time: float | None = None) -> "Figure":
        """Draw one figure now, from the stored data, and return it (a matplotlib
        ``Figure``; a notebook shows it).

        Parameters
        ----------
        name : str
            An ascent figure (``alpha_beta``, ``body_rates``, ``gimbal`` …, the PNG
            names of ``plots/`` without ``.png``); for a linear study one of
            ``bode``, ``nichols``, ``nyquist``, ``rootlocus``, ``pzmap``, ``response``
            (with ``time``) or ``margin_envelope``; for the other studies a figure's
            file under ``plots/`` without ``.png`` (drawn all at once, on the first call of
            :meth:`figure_names` or of :meth:`plot` for one of them, and the same figure
            returned after; an ascent or linear figure does not draw them).
            :meth:`figure_names` lists them.
        time : float, optional
            The linear point (s) of a linear chart.

        Raises
        ------
        KeyError
            An unknown name, listing the known ones; a linear chart of a point that
            has no chart data.
        """
        charts = self._chart_names()
        if name not in charts and name not in self._study_figures:
            raise KeyError(f"no figure {name!r} for this {self.study} study; known: {', '.join(self.figure_names())}")
        if name in LINEAR_CHARTS or name == "margin_envelope":
            from savant_cli.linear.store import read_linear_group
            from savant_cli.plots.linear import chart_figure, envelope_figure

            charts, rows, requirements, zones, failed = read_linear_group(self.h5)
            if name == "margin_envelope":
                return envelope_figure(rows, requirements or None, failed)
            if time is None:
                raise KeyError(f"{name} needs time= (one of {[c.time_s for c in charts]})")
            match = [c for c in charts if math.isclose(c.time_s, float(time), abs_tol=5e-4)]
            if not match:
                raise KeyError(f"no chart data at t = {time} s; points with charts: {[c.time_s for c in charts]}")
            pts = [r for r in rows if math.isclose(r.time_s, match[0].time_s, abs_tol=5e-4)]
            return chart_figure(name, match[0], pts, zones)
        if name not in charts:
            return self._study_figures[name]
        from savant_cli.plots.ascent import figure

        return figure(self._record, name)


def history_dataset(signals: dict, status: str = "", message: str = "") -> "xarray.Dataset":
    """A run's signals (:class:`savant_cli.io.record.Signal`, ``"time"`` among them) as an
    :class:`xarray.Dataset` (module notes)."""
    import xarray as xr

    t = np.asarray(signals["time"].data)
    data_vars = {}
    for name, sig in signals.items():
        if name == "time":
            continue
        attrs = {"units": sig.units, "description": sig.description, "frame": sig.frame}
        arr = np.asarray(sig.data)
        if arr.ndim == 1:
            data_vars[name] = xr.Variable(("time",), arr, attrs)
        else:
            dim = f"{name}_axis"
            data_vars[name] = (("time", dim), arr, attrs)
    coords = {"time": ("time", t, {"units": signals["time"].units, "description": signals["time"].description})}
    for name, sig in signals.items():
        if name != "time" and np.ndim(sig.data) == 2:
            cols = list(sig.columns) or [str(i) for i in range(np.shape(sig.data)[1])]
            coords[f"{name}_axis"] = cols
    return xr.Dataset(data_vars, coords=coords, attrs={"status": status, "message": message})


def _read_summary(path: Path) -> dict[str, Any]:
    """``summary.json``, or a :class:`~savant_cli.errors.DamagedFileError` naming it."""
    from savant_cli.errors import DamagedFileError
    from savant_cli.io.integrity import rebuild_hint

    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(summary, dict):
            raise ValueError(f"a JSON {type(summary).__name__}, not an object")
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise DamagedFileError(path, f"unreadable: {type(exc).__name__}: {exc}", rebuild_hint(path.parent)) from None
    return summary


def load(run_dir: str | Path, exit_code: int | None = None) -> Result:
    """The :class:`Result` of a finished run folder.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        A folder written by ``savant run`` or :func:`savant_cli.run` (it holds
        ``savant.h5``).
    exit_code : int, optional
        The code the run returned (default: what ``savant run`` returns for the files:
        0 when the flight flew to its end or no Monte Carlo run is missing).

    Raises
    ------
    FileNotFoundError
        No such folder, or no ``savant.h5`` in it.
    savant_cli.io.hdf5.RunFileError
        ``savant.h5`` is an HDF5 file but not a savant one.
    savant_cli.errors.DamagedFileError
        ``savant.h5`` (or ``summary.json``) cannot be read back (truncated, not HDF5,
        damaged inside): the message names the file, what is wrong and the command that
        writes it again. The lazily read parts (history, linear points, Monte Carlo
        tables) raise it too when their part of the file is damaged.
    """
    from savant_cli.io.hdf5 import FORMAT, STUDY_FORMAT, RunFileError

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"run folder {run_dir} does not exist")
    h5 = run_dir / RUN_FILE
    if not h5.is_file():
        raise FileNotFoundError(f"no {RUN_FILE} in {run_dir}: not a savant run folder, or the run was made "
                                f"with output.hdf5=false")
    provenance: dict[str, str] = {}
    with read_h5(h5) as f:
        fmt = _text(f.attrs.get("format", ""))
        if fmt in (FORMAT, STUDY_FORMAT):
            config_text = _text(f["config"][()])
            provenance = {k: _text(v) for k, v in f.attrs.items() if k not in ("format", "format_version", "complete",
                                                                                 "status", "message", "study")}
            status = _text(f.attrs.get("status", "complete" if fmt == STUDY_FORMAT else ""))
            message = _text(f.attrs.get("message", ""))
            code = 0 if fmt == STUDY_FORMAT or bool(f.attrs.get("complete", False)) else 1
        elif "montecarlo" in f:
            g = f["montecarlo"]
            config_text = _text(g.attrs["config_yaml"])
            provenance = {k[len("provenance_"):]: _text(v) for k, v in g.attrs.items() if k.startswith("provenance_")}
            statuses = list(g["runs/status"].asstr()[()])
            status = "complete" if statuses and all(s == "complete" for s in statuses) else "incomplete"
            message = f"{statuses.count('complete')} of {len(statuses)} runs complete"
            missing = _text(g.attrs.get("missing_runs", ""))  # run ranges, "" when none
            code = 0 if not missing else 1  # as savant run: unhealthy runs are findings, missing ones a failure
        else:
            raise RunFileError(f"{h5} is not a savant run file (format attribute {fmt!r})")
    summary_path = run_dir / SUMMARY_FILE
    summary = _read_summary(summary_path) if summary_path.is_file() else {}
    config = OmegaConf.create(config_text)
    study = str(OmegaConf.select(config, "study.name", default="") or "")
    code = exit_code if exit_code is not None else code
    return Result(run_dir=run_dir, study=study, summary=summary, config=config, status=status, message=message,
                  exit_code=code, provenance=provenance)
