"""``study=mode_retention``: how many bending modes the analysis must keep (the source
paper's methodology, §IV).

Starting from the rigid vehicle, modes are added lowest first, ``study.step`` at a time,
up to ``study.max_modes`` (0: as many as the modal data and the plant rate allow; a mode
must stay below ``sim.plant_rate_hz / 8``). Each count flies the nominal ascent (flex
on) and is linearized at ``study.times``. Against the previous count:

* the closed-loop response: at each time, the linear closed loop's response to a unit
  attitude-command step of each axis over ``study.response_duration_s`` (attitude and
  gimbal angle of that axis); per response, max |y_n − y_(n−1)| relative to the peak of
  |y_(n−1)| (the nonlinear flight itself is not compared: its on/off roll jets make two
  flights differ by switching times that say nothing about the modes);
* the margins: per time, axis and kind, the critical (smallest |margin|) crossing over
  every band and the critical rigid/aero crossing, in dB or deg.

The recommended count is the smallest n from which every further step changes the
response by at most ``study.response_tolerance`` and the margins by at most
``study.margin_tolerance_dB`` / ``_deg``. Outputs: ``mode_retention.csv``,
``summary.json`` (the recommendation and its evidence), ``savant.h5`` (group
``mode_retention``: every count's step responses and critical margins, from which
``savant report`` redraws the plots), a console table and the plots
``plots/mode_retention_<time>_<output>.png`` (step response per count) and
``plots/mode_retention_margins.png`` (critical margins vs count).
"""

from __future__ import annotations

import copy
import csv
import dataclasses
import io
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import control as ct
import h5py
import numpy as np
from omegaconf import DictConfig, OmegaConf
from rich.table import Table

from savant_cli.config import ModeRetentionStudyConfig, SavantConfig, check_physics, linear_settings, shipped_option
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_json_atomic, write_text_atomic
from savant_cli.io.console import study_console
from savant_cli.io.hdf5 import write_study_file
from savant_cli.io.provenance import collect_provenance
from savant_cli.linear.point_analysis import analyse
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.studies import flight as flight_mod


@dataclass
class CountResult:
    """One retained-mode count: its response histories and critical margins."""

    n_modes: int
    time_s: np.ndarray  # of the step responses, s
    histories: dict[str, np.ndarray]  # "t<time>_<output>" → step response
    margins: dict[tuple[float, str, str, str], float] = field(default_factory=dict)  # (t, axis, kind, which)
    stable: dict[float, bool] = field(default_factory=dict)


def _config(cfg: SavantConfig, n: int) -> SavantConfig:
    """``cfg`` with ``n`` retained modes (``flex=off`` for none; the other flex keys of
    ``cfg``'s own ``flex=on`` section are kept)."""
    c = copy.deepcopy(cfg)
    on = c.flex if c.flex.enabled else shipped_option("flex", "on")
    c.flex = dataclasses.replace(on, n_modes=n) if n > 0 else shipped_option("flex", "off")
    check_physics(c)
    return c


def _fly(cfg: SavantConfig, n: int, study: ModeRetentionStudyConfig) -> CountResult:
    model = prepare(_config(cfg, n)).model
    rt = model.rates
    dt = rt.dt * rt.n_fcs
    steps = flight_mod.control_steps(cfg, study.times)
    res = simulate(model, progress=False, snapshot_steps=steps)
    t_resp = np.arange(0.0, study.response_duration_s + 0.5 * dt, dt)
    out = CountResult(n, t_resp, {})
    lin = linear_settings(study.times)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k in steps:
            snap = res.snapshots.get(k)
            if snap is None:
                continue
            a = analyse(model, snap, lin, dt)
            pt, rows, extra = a.point, a.rows, a.scalars
            t = round(float(snap.t), 6)
            out.stable[t] = bool(extra["closed_loop_stable"])
            closed = pt.closed
            for axis in ("pitch", "yaw"):
                i_in = closed.input_labels.index(f"{axis}_command")
                for what in ("attitude", "gimbal"):
                    i_out = closed.output_labels.index(f"{axis}_{what}")
                    y = ct.step_response(closed[i_out, i_in], T=t_resp).outputs
                    out.histories[f"t{t:g}_{axis}_{what}"] = np.asarray(y, dtype=float).ravel()
            for r in rows:
                for which in ("all", "rigid/aero"):
                    if which != "all" and r.band != which:
                        continue
                    key = (t, r.axis, r.kind, which)
                    if key not in out.margins or abs(r.value) < abs(out.margins[key]):
                        out.margins[key] = r.value
    return out


def _response_change(a: CountResult, b: CountResult) -> dict[str, float]:
    """Per step response: max |b − a| / max |a| (the same time grid); inf for a
    response one of them lacks or that diverges."""
    out = {}
    for name in set(a.histories) | set(b.histories):
        if name not in a.histories or name not in b.histories:
            out[name] = float("inf")
            continue
        ya, yb = a.histories[name], b.histories[name]
        peak = float(np.max(np.abs(ya))) or 1.0
        out[name] = float(np.max(np.abs(yb - ya))) / peak
    return out


def _margin_change(a: CountResult, b: CountResult) -> tuple[float, float]:
    """Largest change of a critical gain (dB) and phase (deg) margin; inf when a crossing
    appears or disappears."""
    dg = dp = 0.0
    for key in set(a.margins) | set(b.margins):
        d = abs(b.margins[key] - a.margins[key]) if key in a.margins and key in b.margins else float("inf")
        if key[2] == "gain":
            dg = max(dg, d)
        else:
            dp = max(dp, d)
    return dg, dp


def recommend(rows: list[dict], counts: list[int]) -> tuple[int, bool]:
    """The smallest count from which every further step is within the tolerances, and
    whether the sweep converged at all (else the largest count flown)."""
    for i in range(len(rows)):
        if all(r["converged"] for r in rows[i:]):
            return rows[i]["from_modes"], True
    return counts[-1], False


def _max_modes(cfg: SavantConfig, study: ModeRetentionStudyConfig) -> int:
    """The largest count the modal data and the plant rate allow (or ``max_modes``)."""
    n = 0
    limit = study.max_modes or 64
    while n < limit:
        try:
            prepare(_config(cfg, n + 1))
        except ConfigError as exc:
            if n == 0:
                raise
            if study.max_modes:
                raise ConfigError("study.max_modes", study.max_modes, f"cannot be retained: {exc}") from None
            break
        n += 1
    return n


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Sweep the retained-mode count and recommend one."""
    study: ModeRetentionStudyConfig = cfg.study
    console = study_console(cfg.output.console)
    t0 = time.perf_counter()
    n_max = _max_modes(cfg, study)
    counts = list(range(0, n_max + 1, study.step))
    if counts[-1] != n_max:
        counts.append(n_max)
    results = []
    for n in counts:
        results.append(_fly(cfg, n, study))
        console.print(f"{n} modes: flown and linearized ({time.perf_counter() - t0:.1f} s)")
    rows = []
    for prev, cur in zip(results, results[1:]):
        resp = _response_change(prev, cur)
        dg, dp = _margin_change(prev, cur)
        ok = (max(resp.values(), default=0.0) <= study.response_tolerance and dg <= study.margin_tolerance_dB
              and dp <= study.margin_tolerance_deg)
        rows.append({"from_modes": prev.n_modes, "to_modes": cur.n_modes, "max_response_change": max(resp.values()),
                     "margin_change_dB": dg, "margin_change_deg": dp, "converged": ok,
                     "all_stable": all(cur.stable.values()),
                     **{f"response_change_{k}": v for k, v in resp.items()}})
    recommended, converged = recommend(rows, counts)
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    note = ("the changes settle within the tolerances" if converged else
            f"the changes had not settled at {counts[-1]} modes, the most the modal data and sim.plant_rate_hz "
            "allow: raise sim.plant_rate_hz (or supply more modes) and run again")
    console.print(_table(rows, study))  # before the files: shown even if they cannot be written
    console.print(f"recommended: [bold]{recommended} modes[/] ({note})")
    write_text_atomic(out_dir / "mode_retention.csv", buf.getvalue())
    margins = {str(r.n_modes): {f"t{k[0]:g}_{k[1]}_{k[2]}_{k[3]}": v for k, v in r.margins.items()} for r in results}
    write_json_atomic(out_dir / "summary.json", {
        "study": "mode_retention", "counts": counts, "recommended_n_modes": recommended, "converged": converged,
        "note": note, "steps": rows, "critical_margins": margins,
        "tolerances": {"response": study.response_tolerance, "gain_dB": study.margin_tolerance_dB,
                       "phase_deg": study.margin_tolerance_deg},
        "study_wall_time_s": time.perf_counter() - t0})
    if cfg.output.hdf5:
        write_study_file(out_dir / "savant.h5", "mode_retention", OmegaConf.to_yaml(raw_cfg, resolve=True),
                         collect_provenance(wall_time_s=time.perf_counter() - t0),
                         lambda f: write_group(f, results, recommended, converged))
    if cfg.output.plots:
        draw(results, out_dir / "plots")
    console.print(f"outputs: {out_dir}")
    return 0


def _table(rows: list[dict], study: ModeRetentionStudyConfig) -> Table:
    tb = Table(title=f"mode retention (tolerances: response {study.response_tolerance:g} of peak, "
                     f"{study.margin_tolerance_dB:g} dB, {study.margin_tolerance_deg:g} deg)")
    for c in ("modes", "response change", "gain margin change (dB)", "phase margin change (deg)", "stable",
              "within"):
        tb.add_column(c, justify="right")
    for r in rows:
        tb.add_row(f"{r['from_modes']} → {r['to_modes']}", f"{r['max_response_change']:.3g}",
                   f"{r['margin_change_dB']:.3g}", f"{r['margin_change_deg']:.3g}",
                   "yes" if r["all_stable"] else "[red]NO[/red]",
                   "yes" if r["converged"] else "[red]no[/red]")
    return tb


MARGIN_KEYS = ("time_s", "axis", "kind", "which")


def write_group(f: h5py.File, results: list[CountResult], recommended: int, converged: bool) -> None:
    """Group ``mode_retention`` of ``savant.h5``: attributes ``counts``,
    ``recommended_n_modes``, ``converged``; ``responses/time_s`` and
    ``responses/<name>`` (counts × time, NaN where a count lacks the response);
    ``margins/{n_modes, time_s, axis, kind, which, value}`` (critical margins: ``which`` is
    ``all`` or ``rigid/aero``; dB or deg); ``stable/{n_modes, time_s, closed_loop_stable}``."""
    g = f.create_group("mode_retention", track_order=True)
    g.attrs.update({"counts": [r.n_modes for r in results], "recommended_n_modes": recommended,
                    "converged": bool(converged)})
    rg = g.create_group("responses", track_order=True)
    t = results[-1].time_s
    rg.create_dataset("time_s", data=t)
    for name in sorted({k for r in results for k in r.histories}):
        rg.create_dataset(name, data=np.array([r.histories.get(name, np.full(t.size, np.nan)) for r in results]))
    items = [(r.n_modes, *k, v) for r in results for k, v in r.margins.items()]
    mg = g.create_group("margins", track_order=True)
    mg.create_dataset("n_modes", data=np.array([i[0] for i in items], dtype=np.int64))
    for j, key in enumerate(MARGIN_KEYS, start=1):
        vals = [i[j] for i in items]
        mg.create_dataset(key, data=np.asarray(vals, dtype=float) if key == "time_s"
                          else np.array(vals, dtype=h5py.string_dtype()))
    mg.create_dataset("value", data=np.array([i[-1] for i in items], dtype=float))
    sg = g.create_group("stable", track_order=True)
    st = [(r.n_modes, t_s, ok) for r in results for t_s, ok in r.stable.items()]
    sg.create_dataset("n_modes", data=np.array([s[0] for s in st], dtype=np.int64))
    sg.create_dataset("time_s", data=np.array([s[1] for s in st], dtype=float))
    sg.create_dataset("closed_loop_stable", data=np.array([s[2] for s in st], dtype=bool))


def read_group(path: Path) -> list[CountResult]:
    """Every count's responses, critical margins and stability from a mode-retention
    ``savant.h5`` (the inverse of :func:`write_group`)."""
    with h5py.File(path, "r") as f:
        g = f["mode_retention"]
        counts = [int(n) for n in g.attrs["counts"]]
        rg = g["responses"]
        t = rg["time_s"][()]
        results = [CountResult(n, t, {}) for n in counts]
        for name in rg:
            if name == "time_s":
                continue
            data = rg[name][()]
            for r, y in zip(results, data):
                if np.isfinite(y).any():
                    r.histories[name] = y
        by_count = {r.n_modes: r for r in results}
        mg = g["margins"]
        cols = [mg[k].asstr()[()] if k != "time_s" else mg[k][()] for k in MARGIN_KEYS]
        for n, *key, v in zip(mg["n_modes"][()], *cols, mg["value"][()]):
            by_count[int(n)].margins[(float(key[0]), str(key[1]), str(key[2]), str(key[3]))] = float(v)
        sg = g["stable"]
        for n, t_s, ok in zip(sg["n_modes"][()], sg["time_s"][()], sg["closed_loop_stable"][()]):
            by_count[int(n)].stable[float(t_s)] = bool(ok)
    return results


def draw(results: list[CountResult], folder: Path) -> list[Path]:
    """The step-response overlays and the critical margins against the count."""
    from savant_cli.plots.mode_retention import plot_mode_retention

    responses = {name: {r.n_modes: r.histories[name] for r in results if name in r.histories}
                 for name in sorted(results[0].histories)}
    margins: dict[tuple[float, str, str], dict[int, float]] = {}
    for key in sorted({k for r in results for k in r.margins if k[3] == "all"}):
        margins[key[:3]] = {r.n_modes: r.margins[key] for r in results if key in r.margins}
    return plot_mode_retention(results[-1].time_s, responses, margins, folder)
