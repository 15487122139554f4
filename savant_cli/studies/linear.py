"""``study=linear``: stability margins of the closed-loop vehicle at flight times.

A time run (the nominal flight, written like ``study=nominal``) sets the operating
points; at each, the plant is linearized (``linear/plant.py``), assembled with the
discrete flight control (``linear/loops.py``) and analysed (``linear/margins.py``).
Every margin and point is judged against the requirement set (``requirements`` group,
``linear/requirements.py``), except the points of the first stage's tail-off window
(:func:`tailoff_window`, ``study.tailoff_thrust_fraction``): analysed and reported with
what they would score, left out of the verdict (docs/requirements.md). Outputs: ``savant.h5`` (time history + ``linear`` group:
systems, margins, requirement checks, and the chart data of every charted point),
``linear.mat``, ``margins.csv`` (every crossing with its verdict), ``requirements.csv``
(every check of every point), ``summary.json`` (``margins``, ``requirements`` and the
one-line ``requirements_verdict``), charts in ``plots/linear/``, a console table and the
verdict line. ``study.charts`` decides
which points get chart data (``auto``: all when there are at most
:data:`MAX_CHART_POINTS`); it is computed and stored with ``output.plots=false`` too, so
``savant report`` can draw the charts later.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from omegaconf import DictConfig
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from savant_cli.config import LinearStudyConfig, RequirementSet, SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.io.console import print_run_summary, print_verdict
from savant_cli.linear.charts import PointCharts, point_charts
from savant_cli.linear.loops import AXES, LinearPoint, assemble
from savant_cli.linear.evaluate import closed_loop_stability, judge_loops, verdict as judge_verdict
from savant_cli.linear.margins import MarginRow, bandwidth_hz, disk_margins
from savant_cli.linear.modes import ModePeak, aero_unstable, state_groups
from savant_cli.linear.plant import linearize_plant
from savant_cli.linear.requirements import PointVerdict, summary as requirement_summary
from savant_cli.linear.store import write_checks_csv, write_linear_group, write_margins_csv, write_mat
from savant_cli.studies import flight as flight_mod

MAX_CHART_POINTS = 20


def requested_times(study: LinearStudyConfig, t_end: float) -> list[float]:
    """The configured times (or the ``every`` grid up to ``t_end``), sorted, unique."""
    if study.every > 0:
        return [float(t) for t in np.arange(study.every, t_end, study.every)]
    return sorted({float(t) for t in study.times})


def check_times(times: list[float], t_final: float, events: dict[str, float], study: LinearStudyConfig,
                skip: bool) -> list[float]:
    """Refuse (or, with ``skip``, drop) times outside the flight or on an event."""
    keep = []
    key = "study.every" if skip else "study.times"
    for t in times:
        if not 0.0 < t < t_final:
            if skip:
                continue
            raise ConfigError(key, t, f"must lie inside the flight (0, {t_final:.2f}) s")
        near = [n for n, te in events.items() if abs(t - te) < study.event_clearance_s]
        if near:
            if skip:
                continue
            raise ConfigError(key, t, f"falls on the event {near[0]} at {events[near[0]]:.2f} s "
                              f"(keep {study.event_clearance_s} s away, study.event_clearance_s)")
        keep.append(t)
    return keep


def tailoff_window(time_s: np.ndarray, thrust_n: np.ndarray, separation_s: float | None,
                   fraction: float) -> tuple[float, float] | None:
    """The first stage's tail-off window (start, separation) in s: from the first time
    after the stage's thrust peak at which its thrust falls below ``fraction`` of that
    peak (linear between samples), to separation.

    Parameters
    ----------
    time_s, thrust_n : ndarray
        The flight's time (s) and thrust magnitude (N) histories.
    separation_s : float or None
        Separation time (s); None or NaN: no separation in the flight, no window.
    fraction : float
        Of the first stage's peak thrust; 0: no window.
    """
    if fraction <= 0.0 or separation_s is None or not np.isfinite(separation_s):
        return None
    stage = time_s < separation_s
    t, f = time_s[stage], thrust_n[stage]
    if t.size < 2:
        return None
    peak = int(np.argmax(f))
    level = fraction * f[peak]
    below = np.flatnonzero(f[peak:] < level)
    if below.size == 0:
        return None
    i = peak + int(below[0])  # f[i - 1] >= level > f[i]
    start = float(np.interp(level, [f[i], f[i - 1]], [t[i], t[i - 1]]))
    return start, float(separation_s)


def not_judged_line(window: tuple[float, float], fraction: float, verdicts: list[PointVerdict]) -> str:
    """The verdict line's note on the points of the tail-off window: when it runs, and
    each point with what it would score against the requirements."""
    pts = "; ".join(f"{v.time_s:.1f} s passes" if v.passed else f"would fail: {v.worst.text()}"
                    for v in verdicts) or "no point"
    return (f"not judged, first-stage tail-off below {100 * fraction:g} % of peak thrust "
            f"({window[0]:.2f}-{window[1]:.2f} s): {pts}")


@dataclass
class PointAnalysis:
    """Everything ``study=linear`` computes at one operating point."""

    point: LinearPoint
    rows: list[MarginRow]  # every crossing of both loops, labelled by mode
    peaks: list[ModePeak]  # the loops' peak gain at each bending mode they carry
    scalars: dict  # disk margins, bandwidths, closed-loop stability
    verdict: PointVerdict | None  # against the requirement set, when one is given


def analyse(model, snap, study: LinearStudyConfig, dt: float,
            requirements: RequirementSet | None = None) -> PointAnalysis:
    """Linear systems, margins, bending-mode peaks, scalar results and (with
    ``requirements``) the requirement verdict of one point."""
    lin = linearize_plant(model, snap, mode=study.jacobian, rel_step=study.jacobian_step)
    pt = assemble(model, snap, lin, dt)
    groups = state_groups(lin, pt.plant, pt.controller)
    rows, peaks, responses = judge_loops(pt.loops, groups, aero_unstable(lin), snap.t)
    extra: dict[str, float] = {"time_s": snap.t}
    for c, axis in enumerate(AXES):
        for k, v in disk_margins(pt.loops[axis], responses[axis]).items():
            extra[f"{axis}_{k}"] = v
        extra[f"{axis}_bandwidth_hz"] = bandwidth_hz(pt.closed[c, c])
    for k, v in disk_margins(pt.mimo).items():
        extra[f"mimo_{k}"] = v
    stable, max_real = closed_loop_stability(pt.closed.poles(), dt)
    extra["closed_loop_stable"] = stable
    extra["closed_loop_max_real_1_per_s"] = max_real
    verdict = None
    if requirements is not None:
        rows, verdict = judge_verdict(snap.t, pt.phase, rows, peaks, stable, max_real, requirements)
    return PointAnalysis(pt, rows, peaks, extra, verdict)


def _table(rows: list[MarginRow]) -> Table:
    tb = Table(title="stability margins (loop at a time; gain dB, phase deg)")
    for col in ("t (s)", "axis", "kind", "margin", "freq (Hz)", "mode", "band", "meets req."):
        tb.add_column(col, justify="right" if col in ("t (s)", "margin", "freq (Hz)") else "left")
    for r in rows:
        tb.add_row(f"{r.time_s:.1f}", r.axis, r.kind, f"{r.value:.2f}", f"{r.frequency_hz:.3f}", r.mode, r.band,
                   "yes" if r.meets_requirement else "[red]NO[/red]")
    return tb


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly, linearize at the study's times, write everything into ``out_dir``."""
    study: LinearStudyConfig = cfg.study
    console = Console()
    t_start = time.perf_counter()
    t_end = cfg.sim.max_time_s
    for i, t in enumerate(study.times if study.every == 0 else []):
        if t >= t_end:
            raise ConfigError(f"study.times[{i}]", t, f"must lie inside the flight (before sim.max_time_s = {t_end})")
    wanted = requested_times(study, t_end)
    steps = flight_mod.control_steps(cfg, wanted)
    flight = flight_mod.fly(cfg, snapshot_steps=steps)
    model, result, sig, summary = flight.prep.model, flight.result, flight.signals, flight.summary
    rt = model.rates
    events = dict(flight_mod.events_of(result))
    times = check_times([k * rt.dt for k in steps], result.t_final, events, study, skip=study.every > 0)
    snaps = [result.snapshots[int(round(t / rt.dt))] for t in times]

    req = cfg.requirements
    points, rows, scalars, verdicts = [], [], [], []
    dt = rt.dt * rt.n_fcs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # python-control notes on unconnected signals, by design
        bar = Progress(TextColumn("[bold]linearize"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                       transient=True, disable=not cfg.sim.progress)
        with bar:
            task = bar.add_task("points", total=len(snaps))
            for snap in snaps:
                a = analyse(model, snap, study, dt, req)
                points.append(a.point)
                rows += a.rows
                scalars.append(a.scalars)
                verdicts.append(a.verdict)
                bar.advance(task)

    charted = study.charts == "all" or (study.charts == "auto" and len(points) <= MAX_CHART_POINTS)
    charts = {pt.time_s: point_charts(pt.time_s, pt.loops, pt.closed, [r for r in rows if r.time_s == pt.time_s])
              for pt in points} if charted else {}
    summary["margins"] = [{"time_s": r.time_s, "axis": r.axis, "kind": r.kind, "value": r.value,
                           "frequency_hz": r.frequency_hz, "band": r.band, "mode": r.mode,
                           "meets_requirement": r.meets_requirement} for r in rows]
    summary["margins_meeting_requirements"] = f"{sum(r.meets_requirement for r in rows)} of {len(rows)}"
    # the tail-off window's points are analysed and reported, not judged (docs/requirements.md)
    window = tailoff_window(sig["time"].data, sig["thrust"].data, events.get("separation"), study.tailoff_thrust_fraction)
    in_window = [window is not None and window[0] <= v.time_s < window[1] for v in verdicts]
    judged = [v for v, w in zip(verdicts, in_window) if not w]
    aside = [v for v, w in zip(verdicts, in_window) if w]
    verdict = requirement_summary(judged, req)
    if window is not None:
        verdict["line"] += "; " + not_judged_line(window, study.tailoff_thrust_fraction, aside)
        verdict["not_judged"] = requirement_summary(aside, req)["points"]
    summary["tailoff_window_start_s"] = window[0] if window else None
    summary["tailoff_window_end_s"] = window[1] if window else None
    summary["points_not_judged"] = len(aside)
    summary["requirements_met"] = verdict["passed"]
    summary["requirements_verdict"] = verdict["line"]
    summary["requirements"] = verdict
    summary["linear_points"] = scalars
    summary["linear_note"] = "roll (on/off RCS) is left out of the linear analysis"
    summary["study_wall_time_s"] = time.perf_counter() - t_start
    hdf_summary = {k: v for k, v in summary.items() if not isinstance(v, (list, dict))}
    record = flight_mod.record(result, sig, hdf_summary, raw_cfg, summary["study_wall_time_s"])
    flight_mod.write(out_dir, record, cfg, json_summary=summary,
                     extra=lambda f: write_linear_group(f, points, rows, charts, req, study.exclusion_zones, verdicts,
                                                             [not w for w in in_window], verdict["line"]))
    if cfg.output.hdf5:
        write_mat(out_dir / "linear.mat", points)
    write_margins_csv(out_dir / "margins.csv", rows)
    write_checks_csv(out_dir / "requirements.csv", verdicts)
    if cfg.output.plots:
        draw_linear(list(charts.values()), rows, req.by_band(), study.exclusion_zones, out_dir / "plots",
                    [v.time_s for v in judged if not v.passed])
    print_run_summary({k: v for k, v in hdf_summary.items() if k not in ("linear_note", "requirements_verdict")},
                      record.status, record.message, console)
    console.print(_table(rows))
    console.print("roll (on/off jets) is left out of the linear analysis")
    print_verdict(verdict["line"], verdict["passed"], console)
    console.print(f"outputs: {out_dir}")
    return 0 if record.complete else 1


def draw_linear(charts: list[PointCharts], rows: list[MarginRow], requirements: dict[str, tuple[float, float]],
                exclusion_zones: bool, folder: Path, failed_times: list[float] | tuple = ()) -> list[Path]:
    """The linear charts into ``folder/linear`` (the ascent plots are drawn with the run's
    files): six per charted point and the margin envelope (``failed_times``: the points
    failing their requirement set). Returns the PNGs written."""
    from savant_cli.plots.linear import plot_linear_point, plot_margin_envelope

    paths = []
    for c in charts:
        paths += plot_linear_point(c, [r for r in rows if r.time_s == c.time_s], folder / "linear",
                                   exclusion_zones=exclusion_zones)
    paths.append(plot_margin_envelope(rows, folder / "linear" / "margin_envelope.png", requirements=requirements,
                                      failed_times=failed_times))
    return paths
