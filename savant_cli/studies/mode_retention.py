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
``summary.json`` (the recommendation and its evidence), a console table and the plots
``plots/mode_retention_<time>_<output>.png`` (step response per count) and
``plots/mode_retention_margins.png`` (critical margins vs count).
"""

from __future__ import annotations

import copy
import dataclasses
import csv
import io
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import control as ct
import numpy as np
from omegaconf import DictConfig
from rich.console import Console
from rich.table import Table

from savant_cli.config import (
    FlexOffConfig, FlexOnConfig, LinearStudyConfig, ModeRetentionStudyConfig, SavantConfig, check_physics,
)
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_json_atomic, write_text_atomic
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.studies import flight as flight_mod
from savant_cli.studies.linear import analyse


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
    on = c.flex if c.flex.enabled else FlexOnConfig()
    c.flex = dataclasses.replace(on, n_modes=n) if n > 0 else FlexOffConfig()
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
    lin = LinearStudyConfig(times=list(study.times))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k in steps:
            snap = res.snapshots.get(k)
            if snap is None:
                continue
            pt, rows, extra = analyse(model, snap, lin, dt)
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
    console = Console()
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
    out_dir.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    write_text_atomic(out_dir / "mode_retention.csv", buf.getvalue())
    margins = {str(r.n_modes): {f"t{k[0]:g}_{k[1]}_{k[2]}_{k[3]}": v for k, v in r.margins.items()} for r in results}
    note = ("the changes settle within the tolerances" if converged else
            f"the changes had not settled at {counts[-1]} modes, the most the modal data and sim.plant_rate_hz "
            "allow: raise sim.plant_rate_hz (or supply more modes) and run again")
    write_json_atomic(out_dir / "summary.json", {
        "study": "mode_retention", "counts": counts, "recommended_n_modes": recommended, "converged": converged,
        "note": note, "steps": rows, "critical_margins": margins,
        "tolerances": {"response": study.response_tolerance, "gain_dB": study.margin_tolerance_dB,
                       "phase_deg": study.margin_tolerance_deg},
        "study_wall_time_s": time.perf_counter() - t0})
    if cfg.output.plots:
        _plots(out_dir / "plots", results)
    console.print(_table(rows, study))
    console.print(f"recommended: [bold]{recommended} modes[/] ({note})")
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


def _plots(folder: Path, results: list[CountResult]) -> None:
    from savant_cli.plots.flyoff import plot_history_overlays
    from savant_cli.plots.montecarlo import _figure, _save, _style

    t = results[-1].time_s
    hist = {name: {f"{r.n_modes} modes": r.histories[name] for r in results if name in r.histories}
            for name in sorted(results[0].histories)}
    plot_history_overlays(t, hist, folder, prefix="mode_retention", title="attitude-command step response")
    keys = sorted({k for r in results for k in r.margins if k[3] == "all"})
    fig = _figure(8.0, 4.5)
    axes = [fig.add_subplot(1, 2, i + 1) for i in range(2)]
    for ax, kind, unit in zip(axes, ("gain", "phase"), ("dB", "deg")):
        _style(ax)
        for k in (k for k in keys if k[2] == kind):
            ns = [r.n_modes for r in results if k in r.margins]
            ax.plot(ns, [r.margins[k] for r in results if k in r.margins], marker="o", lw=1.0,
                    label=f"{k[1]} t={k[0]:g}")
        ax.set_xlabel("retained modes", fontsize=8)
        ax.set_ylabel(f"critical {kind} margin ({unit})", fontsize=8)
        ax.legend(fontsize=6)
    fig.suptitle("critical margins vs retained modes", fontsize=10)
    _save(fig, folder / "mode_retention_margins.png")
