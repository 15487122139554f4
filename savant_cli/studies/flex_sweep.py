"""``study=flex_sweep``: the flex parameter study behind the GVT decision (source paper
§IV, Figures 15–22).

One time run of the configured vehicle (flex on) sets the operating points. At each of
``study.times``, for each parameter (``frequency``: the bending frequencies;
``shape``: the mode-shape magnitudes, i.e. every modal slope and deflection) and each
scale factor of ``study.levels``, the retained modes (or ``study.modes``) are scaled in
the model's flex tables, the plant is linearized about the same state and the loops are
assembled and analysed as in ``study=linear``. Outputs: ``flex_sweep.csv`` (every margin
of every case with its requirement verdict), ``summary.json`` (each case's verdict and worst
offender, and the one-line ``requirements_verdict``), a console table of the worst margin
per band and case with losses of stability and the worst requirement offender, the verdict
line, ``savant.h5`` (the time
run, and group ``flex_sweep``: the margin table and the Nichols data of every chart) and
one Nichols chart per time, parameter and chart axis with the levels overlaid
(``plots/flex_sweep/``), which ``savant report`` redraws from ``savant.h5``.
"""

from __future__ import annotations

import copy
import csv
import io
import time
import warnings
from pathlib import Path

import h5py
import numpy as np
from omegaconf import DictConfig
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from savant_cli.config import FlexSweepStudyConfig, SavantConfig, linear_settings
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_text_atomic
from savant_cli.io.console import print_verdict, study_console
from savant_cli.io.record import FLOWN
from savant_cli.linear.charts import LoopResponse, loop_response
from savant_cli.linear.point_analysis import analyse
from savant_cli.linear.requirements import verdict_line
from savant_cli.linear.store import read_loop_response, write_loop_response
from savant_cli.sim.build import SimModel
from savant_cli.studies import flight as flight_mod
from savant_cli.studies.linear import check_times

COLUMNS = ("time_s", "parameter", "level", "axis", "kind", "band", "mode", "value", "frequency_hz",
           "meets_requirement", "closed_loop_stable")


def variant(model: SimModel, parameter: str, level: float, modes: list[int]) -> SimModel:
    """A copy of ``model`` with the flex frequencies or mode shapes of ``modes``
    (1-based; all retained when empty) scaled by ``level``."""
    n = model.layout.n_modes
    idx = [m - 1 for m in modes] if modes else list(range(n))
    tb = model.tables
    out = copy.copy(model)
    if parameter == "frequency":
        freq = tb.flex_freq.copy()
        freq[:, idx] *= level
        out.tables = tb._replace(flex_freq=freq)
    else:
        shape = tb.flex_shape.copy()
        shape[:, idx] *= level
        out.tables = tb._replace(flex_shape=shape)
    return out


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly, sweep, write ``flex_sweep.csv``, ``summary.json`` and the Nichols charts."""
    study: FlexSweepStudyConfig = cfg.study
    console = study_console(cfg.output.console)
    t_start = time.perf_counter()
    if not cfg.flex.enabled:
        raise ConfigError("flex", cfg.flex.name, "study=flex_sweep needs the flexible body: add flex=on")
    for i, m in enumerate(study.modes):
        if m > cfg.flex.n_modes:
            raise ConfigError(f"study.modes[{i}]", m, f"must be a retained mode, 1 to flex.n_modes = {cfg.flex.n_modes}")
    steps = flight_mod.control_steps(cfg, study.times)
    flight = flight_mod.fly(cfg, snapshot_steps=steps)
    model, result = flight.prep.model, flight.result
    rt = model.rates
    dt = rt.dt * rt.n_fcs
    events = dict(flight_mod.events_of(result))
    times = check_times(sorted({k * rt.dt for k in steps}), result.t_final, events, study, skip=False)
    lin = linear_settings(times)  # study=linear's Jacobian settings
    cases = [(t, prm, lvl) for t in times for prm in study.parameters for lvl in study.levels]
    rows, charts, stable, verdicts = [], {}, {}, {}
    bar = Progress(TextColumn("[bold]flex sweep"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   transient=True, disable=not cfg.sim.progress)
    with warnings.catch_warnings(), bar:
        warnings.simplefilter("ignore")
        task = bar.add_task("cases", total=len(cases))
        for t, prm, lvl in cases:
            snap = result.snapshots[int(round(t / rt.dt))]
            a = analyse(variant(model, prm, lvl, list(study.modes)), snap, lin, dt, cfg.requirements)
            stable[(t, prm, lvl)] = a.scalars["closed_loop_stable"]
            verdicts[(t, prm, lvl)] = a.verdict
            for axis in study.chart_axes:
                charts.setdefault((t, prm, axis), []).append(loop_response(f"{prm} × {lvl:g}", a.point.loops[axis]))
            for r in a.rows:
                rows.append({"time_s": t, "parameter": prm, "level": lvl, "axis": r.axis, "kind": r.kind,
                             "band": r.band, "mode": r.mode, "value": r.value, "frequency_hz": r.frequency_hz,
                             "meets_requirement": r.meets_requirement, "closed_loop_stable": bool(a.scalars["closed_loop_stable"])})
            bar.advance(task)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(COLUMNS), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    worst = _worst(rows, stable, verdicts)
    line = verdict_line([(f"{t:g} s, {prm} × {lvl:g}", [v]) for (t, prm, lvl), v in verdicts.items()],
                        cfg.requirements.name, "cases")
    wall = time.perf_counter() - t_start
    summary = {"study": "flex_sweep", "times_s": times, "parameters": list(study.parameters),
               "levels": list(study.levels), "modes": list(study.modes) or list(range(1, cfg.flex.n_modes + 1)),
               "requirement_set": cfg.requirements.name, "requirements_met": all(v.passed for v in verdicts.values()),
               "requirements_verdict": line,
               "cases": worst, "unstable_cases": [c for c in worst if not c["closed_loop_stable"]],
               "study_wall_time_s": wall}
    console.print(_table(worst))  # before the files: shown even if they cannot be written
    print_verdict(line, summary["requirements_met"], console)
    rec = flight_mod.record(result, flight.signals, flight.summary, raw_cfg, wall)
    flight_mod.write(out_dir, rec, cfg, json_summary=summary,
                     extra=lambda f: write_group(f, rows, charts, study.exclusion_zones))
    write_text_atomic(out_dir / "flex_sweep.csv", buf.getvalue())
    if cfg.output.plots:
        draw(charts, study.exclusion_zones, out_dir / "plots")
    console.print(f"{len(cases)} cases in {time.perf_counter() - t_start:.1f} s; outputs: {out_dir}")
    return 0 if result.status in FLOWN else 1  # flown to its end (its health is in its status)


def write_group(f: h5py.File, rows: list[dict], charts: dict[tuple[float, str, str], list[LoopResponse]],
                exclusion_zones: bool) -> None:
    """Group ``flex_sweep`` of ``savant.h5``: ``cases/<column>`` (the rows of
    ``flex_sweep.csv``) and ``nichols/<n>`` per chart (attributes ``time_s``, ``parameter``,
    ``axis``; one ``loop_<k>`` group per level, :func:`savant_cli.linear.store.write_loop_response`)."""
    g = f.create_group("flex_sweep", track_order=True)
    g.attrs["exclusion_zones"] = bool(exclusion_zones)
    cg = g.create_group("cases", track_order=True)
    for col in COLUMNS:
        vals = [r[col] for r in rows]
        cg.create_dataset(col, data=np.array(vals, dtype=h5py.string_dtype()) if col in ("parameter", "axis", "kind",
                                                                                          "band", "mode") else np.asarray(vals))
    ng = g.create_group("nichols", track_order=True)
    for n, ((t, prm, axis), loops) in enumerate(charts.items()):
        chart = ng.create_group(f"{n:03d}", track_order=True)
        chart.attrs.update({"time_s": t, "parameter": str(prm), "axis": str(axis)})  # StrEnum → str for h5py
        for k, lp in enumerate(loops):
            write_loop_response(chart.create_group(f"loop_{k:02d}"), lp)


def read_group(path: Path) -> tuple[dict[tuple[float, str, str], list[LoopResponse]], bool]:
    """The Nichols data of every chart and the ``exclusion_zones`` option of a flex sweep's
    ``savant.h5``."""
    with h5py.File(path, "r") as f:
        g = f["flex_sweep"]
        charts = {}
        for chart in g["nichols"].values():
            key = (float(chart.attrs["time_s"]), str(chart.attrs["parameter"]), str(chart.attrs["axis"]))
            charts[key] = [read_loop_response(chart[k]) for k in chart]
        return charts, bool(g.attrs["exclusion_zones"])


def draw(charts: dict[tuple[float, str, str], list[LoopResponse]], exclusion_zones: bool, folder: Path) -> list[Path]:
    """One Nichols chart per (time, parameter, axis), the levels overlaid, into
    ``folder/flex_sweep``."""
    from savant_cli.plots.linear import plot_nichols_overlay

    return [plot_nichols_overlay(t, loops, folder / "flex_sweep" / f"nichols_{axis}_{prm}_t{t:06.1f}.png",
                                 title=f"{axis} loop, flex {prm} scaled", exclusion_zones=exclusion_zones)
            for (t, prm, axis), loops in charts.items()]


def _worst(rows: list[dict], stable: dict, verdicts: dict) -> list[dict]:
    """Per case: stability, the smallest |margin| per band and kind, the requirement
    verdict, the violations and the worst offender."""
    out = []
    for (t, prm, lvl), ok in stable.items():
        v = verdicts[(t, prm, lvl)]
        case = {"time_s": t, "parameter": prm, "level": lvl, "closed_loop_stable": bool(ok),
                "meets_requirements": v.passed, "violations": len(v.failed),
                "worst": v.worst.text() if v.worst is not None else ""}
        for r in rows:
            if (r["time_s"], r["parameter"], r["level"]) != (t, prm, lvl):
                continue
            key = f"{r['band']}_{r['kind']}"
            if key not in case or abs(r["value"]) < abs(case[key]):
                case[key] = r["value"]
        out.append(case)
    return out


def _table(cases: list[dict]) -> Table:
    tb = Table(title="flex sweep: smallest |margin| per band (gain dB, phase deg); the worst requirement offender")
    cols = ("rigid/aero_gain", "rigid/aero_phase", "flex_gain", "flex_phase")
    for c in ("t (s)", "parameter", "level", "stable", *cols, "violations", "worst offender"):
        tb.add_column(c, justify="left" if c == "worst offender" else "right")
    for c in cases:
        tb.add_row(f"{c['time_s']:.1f}", c["parameter"], f"{c['level']:g}",
                   "yes" if c["closed_loop_stable"] else "[red]NO[/red]",
                   *[f"{c[k]:.2f}" if k in c else "–" for k in cols],
                   f"[red]{c['violations']}[/red]" if c["violations"] else "0",
                   c["worst"] if c["meets_requirements"] else f"[red]{c['worst']}[/red]")
    return tb
