"""``study=linear``: stability margins of the closed-loop vehicle at flight times.

A time run (the nominal flight, written like ``study=nominal``) sets the operating
points; at each, the plant is linearized (``linear/plant.py``), assembled with the
discrete flight control (``linear/loops.py``) and analysed (``linear/margins.py``).
Every margin and point is judged against the requirement set (``requirements`` group,
``linear/requirements.py``), except the points of the first stage's tail-off window
(``linear/point_analysis.py::scan_tailoff``, ``study.frozen_time``: where frozen time fails on physical
criteria): analysed and reported with what they would score; the time domain judges the
window instead (``timedomain/tailoff.py``; docs/requirements.md). Outputs: ``savant.h5`` (time history + ``linear`` group:
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
from pathlib import Path

import numpy as np
from omegaconf import DictConfig
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from savant_cli.config import LinearStudyConfig, SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.io.console import print_run_summary, print_verdict, study_console
from savant_cli.linear.charts import PointCharts, point_charts
from savant_cli.linear.frozen_time import FrozenTimeWindow
from savant_cli.linear.margins import MarginRow
from savant_cli.linear.point_analysis import analyse, scan_tailoff
from savant_cli.linear.requirements import PointVerdict, summary as requirement_summary
from savant_cli.linear.store import write_checks_csv, write_linear_group, write_margins_csv, write_mat
from savant_cli.studies import flight as flight_mod
from savant_cli.timedomain.tailoff import checks as tailoff_checks, verdict_text as tailoff_verdict

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


def not_judged_line(window: FrozenTimeWindow, verdicts: list[PointVerdict]) -> str:
    """The verdict line's note on the points of the tail-off window: each with what it
    would score against the requirements in the frequency domain."""
    pts = "; ".join(f"{v.time_s:.1f} s passes" if v.passed else f"would fail: {v.worst.text()}"
                    for v in verdicts) or "no point"
    return f"not judged in the frequency domain inside the window: {pts}"


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
    console = study_console(cfg.output.console)
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
    # the tail-off window's points are analysed and reported, judged in the time domain
    # instead (docs/requirements.md, "The tail-off window")
    window, scan_snaps = scan_tailoff(model, events.get("separation"), study, dt, req)
    in_window = [window is not None and window.contains(v.time_s) for v in verdicts]
    judged = [v for v, w in zip(verdicts, in_window) if not w]
    aside = [v for v, w in zip(verdicts, in_window) if w]
    verdict = requirement_summary(judged, req)
    summary["tailoff_window"] = window.as_dict() if window is not None else None
    summary["tailoff_window_start_s"] = window.start_s if window is not None else None
    summary["tailoff_window_end_s"] = window.separation_s if window is not None and window.start_s is not None else None
    summary["points_not_judged"] = len(aside)
    if window is not None and window.start_s is not None:
        start_snap = max((sn for sn in scan_snaps if sn.t <= window.start_s), key=lambda sn: sn.t, default=scan_snaps[0])
        checks = tailoff_checks(model, start_snap, window.separation_s, window.crossover_at_start(), req,
                                study.frozen_time.excitation_deg, study.frozen_time.excitation_s)
        clause, td_ok = tailoff_verdict(window.describe(), checks)
        if verdict["passed"] and not td_ok:  # the head names the whole verdict
            verdict["line"] = verdict["line"].replace(": PASS, ", ": FAIL, ", 1)
        verdict["line"] += f" in the frequency domain before {window.start_s:.2f} s; {clause}"
        if aside:
            verdict["line"] += "; " + not_judged_line(window, aside)
        verdict["not_judged"] = requirement_summary(aside, req)["points"]
        verdict["passed"] = bool(verdict["passed"] and td_ok)
        summary["tailoff_checks"] = [c.as_dict() for c in checks]
        summary["tailoff_checks_met"] = td_ok
    summary["requirements_met"] = verdict["passed"]
    summary["requirements_verdict"] = verdict["line"]
    summary["requirements"] = verdict
    summary["linear_points"] = scalars
    summary["linear_note"] = "roll (on/off RCS) is left out of the linear analysis"
    summary["study_wall_time_s"] = time.perf_counter() - t_start
    hdf_summary = {k: v for k, v in summary.items() if not isinstance(v, (list, dict))}
    record = flight_mod.record(result, sig, hdf_summary, raw_cfg, summary["study_wall_time_s"])

    def write() -> None:
        flight_mod.write(out_dir, record, cfg, json_summary=summary,
                         extra=lambda f: write_linear_group(f, points, rows, charts, req, study.exclusion_zones,
                                                            verdicts, [not w for w in in_window], verdict["line"]))
        if cfg.output.hdf5:
            write_mat(out_dir / "linear.mat", points)
        write_margins_csv(out_dir / "margins.csv", rows)
        write_checks_csv(out_dir / "requirements.csv", verdicts)
        if cfg.output.plots:
            draw_linear(list(charts.values()), rows, req.by_band(), study.exclusion_zones, out_dir / "plots",
                        [v.time_s for v in judged if not v.passed])

    def show() -> None:
        print_run_summary({k: v for k, v in hdf_summary.items() if k not in ("linear_note", "requirements_verdict")},
                          record.status, record.message, console, cfg.output.console)
        console.print(_table(rows))
        console.print("roll (on/off jets) is left out of the linear analysis")
        print_verdict(verdict["line"], verdict["passed"], console)

    flight_mod.write_then_show(write, show)
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
