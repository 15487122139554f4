"""``study=time_margins``: gain and delay margins measured in the nonlinear,
time-varying simulation, beside the frequency-domain margins of the same points.

One time run (written like ``study=nominal``) stores the state at the start of every
search window. The frequency-domain margins of each point come from ``study=linear``'s
analysis (:func:`savant_cli.linear.point_analysis.analyse`) in the same run; they also size
each window (at least ``study.min_periods`` periods of the crossing that governs the
margin, up to ``study.max_window_s``), which keeps clear of events. Each search
(:mod:`savant_cli.timedomain.search`) runs on the process pool. Outputs:
``time_margins.csv`` (one row per time, axis and kind: :data:`COLUMNS`),
``time_margin_trials.csv`` (every judged change), ``summary.json`` (``time_margins``,
the agreement line), ``savant.h5`` group ``time_margins`` (every trial, and the last
stable and first unstable responses of each search), the figures in
``plots/time_margins/`` and a console table.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import h5py
import numpy as np
from omegaconf import DictConfig
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from savant_cli.config import SavantConfig, TimeMarginsStudyConfig
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_text_atomic
from savant_cli.io.console import print_run_summary, print_verdict, study_console
from savant_cli.linear.margins import MarginRow
from savant_cli.linear.point_analysis import analyse
from savant_cli.processes import default_workers
from savant_cli.studies import flight as flight_mod
from savant_cli.timedomain.growth import Growth, decay_threshold
from savant_cli.timedomain.search import UNITS, Search, SearchResult, Trial, run_searches

COLUMNS = ("time_s", "axis", "kind", "time_domain", "frequency_domain", "unit", "oscillation_hz", "note")
#: Agreement expected where the frozen-time linear model holds (issue 15's acceptance).
AGREE_DB = 1.0
AGREE_DELAY = 0.10


def frequency_margin(rows: list[MarginRow], axis: str, kind: str) -> tuple[float, float, str]:
    """The frequency-domain counterpart of a time-domain margin, from ``study=linear``'s
    rows of one point: ``(value, crossing frequency Hz, mode)``; NaN when the loop has no
    such crossing.

    ``gain_high``: the smallest positive gain margin (dB); ``gain_low``: the gain-reduction
    margin nearest 0 dB (negative); ``delay``: the smallest ``PM / (360 f)`` over the gain
    crossovers (ms), a phase margin taken modulo 360°.
    """
    mine = [r for r in rows if r.axis == axis]
    if kind == "delay":
        cand = [((r.value % 360.0) / (360.0 * r.frequency_hz) * 1000.0, r) for r in mine
                if r.kind == "phase" and r.frequency_hz > 0.0]
        best = min(cand, key=lambda c: c[0], default=None)
    elif kind == "gain_high":
        best = min(((r.value, r) for r in mine if r.kind == "gain" and r.value > 0.0), key=lambda c: c[0], default=None)
    else:
        best = max(((r.value, r) for r in mine if r.kind == "gain" and r.value < 0.0), key=lambda c: c[0], default=None)
    if best is None:
        return float("nan"), float("nan"), ""
    return float(best[0]), float(best[1].frequency_hz), best[1].mode


def window(point_s: float, f_hz: float, study: TimeMarginsStudyConfig, events: list[float],
           t_end: float) -> tuple[float, float, list[str]]:
    """The perturbation window ``(start, end)`` (s) of a point and the notes on how it was
    set: ``study.window_s`` long, stretched to ``study.min_periods`` periods of the
    crossing at ``f_hz`` (up to ``study.max_window_s``; the lead grows in proportion),
    moved (then cut) to keep ``study.event_clearance_s`` from the events around the point
    and from the end of the flight ``t_end``."""
    notes = []
    length = study.window_s
    if f_hz > 0.0 and study.min_periods / f_hz > length:
        length = min(study.min_periods / f_hz, study.max_window_s)
        notes.append(f"window stretched to {length:.1f} s ({length * f_hz:.1f} periods of {f_hz:.3g} Hz)")
    lead = study.lead_s * length / study.window_s
    c = study.event_clearance_s
    lo = max([c] + [e + c for e in events if e < point_s])
    hi = min([t_end - c] + [e - c for e in events if e > point_s])
    start = point_s - lead
    start = min(start, hi - length)  # move back from an event ahead
    start = max(start, lo)  # then forward from one behind
    end = min(start + length, hi)
    if end - start < length - 1e-9:
        notes.append(f"window cut to {end - start:.1f} s by the events")
    if end < point_s:
        notes.append(f"window ends {point_s - end:.2f} s before the point (event)")
    return start, end, notes


def _note(res: SearchResult, value: float, fd: float, f_fd: float, mode: str, window_notes: list[str],
          gain_change: float) -> str:
    """The row's note: what bounds or qualifies the time-domain margin, and why it may
    differ from the frequency-domain one (window, saturation, schedule change)."""
    s = res.search
    parts = []
    if res.unstable_at_zero:
        parts.append("the unperturbed loop's response is not stable")
    elif np.isnan(res.margin):
        parts.append(f"stable up to the search bound ({s.bound:g} {UNITS[s.kind]})")
    if s.kind == "delay" and np.isfinite(res.margin) and np.isfinite(f_fd):
        parts.append(f"= {360.0 * f_fd * res.margin / 1000.0:.1f} deg at {f_fd:.3g} Hz")
    if mode:
        parts.append(f"frequency domain: {mode} crossing at {f_fd:.3g} Hz")
    parts.append(f"window {s.start_s:.2f}-{s.end_s:.2f} s")
    parts += window_notes
    if np.isfinite(value) and np.isfinite(fd):
        diff = value - fd if s.kind != "delay" else (value - fd) / fd
        if (s.kind == "delay" and abs(diff) > AGREE_DELAY) or (s.kind != "delay" and abs(diff) > AGREE_DB):
            parts.append(f"differs by {100 * diff:+.0f} %" if s.kind == "delay" else f"differs by {diff:+.2f} dB")
    if res.saturated_s > 0.25:
        parts.append(f"actuator on a rate or gimbal limit {res.saturated_s:.2f} s after the settling time in the "
                     f"first unstable run")
    if gain_change > 0.05:
        parts.append(f"scheduled gains change by {100 * gain_change:.0f} % over the window")
    return "; ".join(parts)


def _gain_change(sig, axis: str, start: float, end: float) -> float:
    """Largest relative change of the axis's scheduled gains over the window."""
    t = sig["time"].data
    g = sig["fcs_gains"].data[(t >= start) & (t <= end)]
    cols = slice(0, 4) if axis == "pitch" else slice(4, 8)
    g = g[:, cols]
    if g.shape[0] == 0:
        return 0.0
    ref = np.maximum(np.abs(g).max(axis=0), 1e-12)
    return float(np.max((g.max(axis=0) - g.min(axis=0)) / ref))


def _search_spec(study: TimeMarginsStudyConfig, t: float, axis: str, kind: str, snap_index: int,
                 start: float, end: float, max_saturation_s: float) -> Search:
    gain = kind != "delay"
    return Search(t, axis, kind, snap_index, start, end, study.gain_bound_dB if gain else study.delay_bound_ms,
                  study.gain_tolerance_dB if gain else study.delay_tolerance_ms, study.scan_points,
                  float(np.radians(study.excitation_deg)), study.excitation_s, study.settle_s,
                  study.min_damping_ratio, max_saturation_s)


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly, analyse the points in the frequency domain, search every time-domain margin,
    write everything into ``out_dir``."""
    study: TimeMarginsStudyConfig = cfg.study
    console = study_console(cfg.output.console)
    t_start = time.perf_counter()
    for i, t in enumerate(study.times):
        if t >= cfg.sim.max_time_s:
            raise ConfigError(f"study.times[{i}]", t, "must lie inside the flight (before sim.max_time_s)")
    times = sorted({float(t) for t in study.times})
    # first flight: the points' snapshots (frequency domain) and the events
    steps = flight_mod.control_steps(cfg, times)
    flight = flight_mod.fly(cfg, snapshot_steps=steps)
    model, result, sig, summary = flight.prep.model, flight.result, flight.signals, flight.summary
    rt = model.rates
    events = [te for _, te in flight_mod.events_of(result)]
    for i, t in enumerate(study.times):
        if not 0.0 < t < result.t_final:
            raise ConfigError(f"study.times[{i}]", t, f"must lie inside the flight (0, {result.t_final:.2f}) s")
    rows: dict[float, list[MarginRow]] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for t, k in zip(times, steps):
            rows[t] = analyse(model, result.snapshots[k], study, rt.dt * rt.n_fcs).rows
    # the windows, then a second pass for their starting states (same flight, bit for bit)
    plan = []
    for t in times:
        for axis in study.axes:
            for kind in study.kinds:
                fd, f_fd, mode = frequency_margin(rows[t], axis, kind)
                start, end, notes = window(t, f_fd if np.isfinite(f_fd) else 0.0, study, events, result.t_final)
                plan.append((t, axis, kind, fd, f_fd, mode, start, end, notes))
    start_steps = sorted({flight_mod.control_steps(cfg, [p[6]])[0] for p in plan})
    starts = flight_mod.fly(cfg, progress=False, snapshot_steps=tuple(start_steps)).result.snapshots
    snaps = [starts[k] for k in start_steps]
    searches = []
    for (t, axis, kind, fd, f_fd, mode, start, end, notes) in plan:
        k = flight_mod.control_steps(cfg, [start])[0]
        searches.append(_search_spec(study, t, axis, kind, start_steps.index(k), k * rt.dt, end,
                                     cfg.sim.health.max_saturation_s))
    workers = study.workers or default_workers()
    bar = Progress(TextColumn("[bold]time margins"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   transient=True, disable=not cfg.sim.progress)
    with bar:
        task = bar.add_task("searches", total=len(searches))
        results = run_searches(model, snaps, searches, workers, progress=lambda: bar.advance(task))

    table, out_rows = [], []
    for (t, axis, kind, fd, f_fd, mode, start, end, notes), res in zip(plan, results):
        value = res.margin if kind != "gain_low" else -res.margin
        note = _note(res, value, fd, f_fd, mode, notes, _gain_change(sig, axis, res.search.start_s, res.search.end_s))
        row = {"time_s": t, "axis": axis, "kind": kind, "time_domain": float(value), "frequency_domain": fd,
               "unit": UNITS[kind], "oscillation_hz": res.frequency_hz, "note": note,
               "window_start_s": res.search.start_s, "window_end_s": res.search.end_s,
               "frequency_domain_hz": f_fd, "frequency_domain_mode": mode, "trials": len(res.trials),
               "unstable_at_zero": res.unstable_at_zero}
        if kind == "delay" and np.isfinite(res.margin) and np.isfinite(f_fd):
            row["phase_equivalent_deg"] = 360.0 * f_fd * res.margin / 1000.0
        out_rows.append(row)
        table.append((row, res))
    grows = [r for r in out_rows if r["unstable_at_zero"]]
    found = [r for r in out_rows if np.isfinite(r["time_domain"])]
    differ = [r for r in found if "differs by" in r["note"]]
    line = (f"time-domain margins (stable: envelope x{decay_threshold(study.min_damping_ratio):.3f} or less per "
            f"period, damping ratio {study.min_damping_ratio:g}): {len(found)} of {len(out_rows)} found within the "
            f"search bounds; "
            f"{len(differ)} differ from the frequency domain by more than {AGREE_DB:g} dB / {100 * AGREE_DELAY:g} %"
            + (f"; the unperturbed response is not stable at {len(grows)}" if grows else ""))
    summary["time_margins"] = out_rows
    summary["time_margins_verdict"] = line
    summary["study_wall_time_s"] = time.perf_counter() - t_start
    hdf_summary = {k: v for k, v in summary.items() if not isinstance(v, (list, dict))}
    record = flight_mod.record(result, sig, hdf_summary, raw_cfg, summary["study_wall_time_s"])

    def write() -> None:
        flight_mod.write(out_dir, record, cfg, json_summary=summary, extra=lambda f: write_group(f, results))
        write_csv(out_dir / "time_margins.csv", out_rows)
        write_trials_csv(out_dir / "time_margin_trials.csv", results)
        if cfg.output.plots:
            draw(results, out_dir / "plots")

    def show() -> None:
        print_run_summary({k: v for k, v in hdf_summary.items() if k != "time_margins_verdict"}, record.status,
                          record.message, console, cfg.output.console)
        console.print(_table(out_rows))
        console.print("notes with their numbers: time_margins.csv")
        print_verdict(line, not grows and not differ, console)

    flight_mod.write_then_show(write, show)
    console.print(f"outputs: {out_dir}")
    return 0 if record.complete else 1


def _fmt(v: float) -> str:
    return f"{v:.2f}" if np.isfinite(v) else "-"


def _table(rows: list[dict]) -> Table:
    tb = Table(title="time-domain margins (nonlinear simulation) beside the frequency-domain margins")
    for col in ("t (s)", "axis", "kind", "time domain", "freq. domain", "unit", "osc. (Hz)", "flags"):
        tb.add_column(col, justify="left" if col in ("axis", "kind", "unit", "flags") else "right")
    for r in rows:
        tb.add_row(f"{r['time_s']:.1f}", r["axis"], r["kind"], _fmt(r["time_domain"]), _fmt(r["frequency_domain"]),
                   r["unit"], _fmt(r["oscillation_hz"]) if r["oscillation_hz"] else "-", _flags(r["note"]))
    return tb


#: Short console flags for the notes of ``time_margins.csv`` (the notes have the numbers).
_FLAGS = (("differs by", "[red]differs[/red]"), ("stable up to", "beyond bound"),
          ("response is not stable", "[red]not stable at 0[/red]"),
          ("stretched", "long window"), ("cut to", "window cut"), ("actuator on", "saturates"),
          ("scheduled gains", "gains vary"))


def _flags(note: str) -> str:
    return ", ".join(flag for key, flag in _FLAGS if key in note)


def _csv_text(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}" if np.isfinite(v) else ""
    s = str(v)
    return '"' + s.replace('"', '""') + '"' if ("," in s or '"' in s) else s


def write_csv(path: Path, rows: list[dict]) -> None:
    """``time_margins.csv``: :data:`COLUMNS`, one row per time, axis and kind (empty
    values: no margin within the search bound, or no frequency-domain crossing)."""
    lines = [",".join(COLUMNS)] + [",".join(_csv_text(r[c]) for c in COLUMNS) for r in rows]
    write_text_atomic(path, "\n".join(lines) + "\n")


def write_trials_csv(path: Path, results: list[SearchResult]) -> None:
    """``time_margin_trials.csv``: every judged change of every search, in order."""
    lines = ["time_s,axis,kind,value,unit,unstable,growth_rate_1_per_s,decay_per_period,oscillation_hz,saturated_s,"
             "reason"]
    for res in results:
        s = res.search
        for tr in res.trials:
            g = tr.growth
            lines.append(",".join(_csv_text(v) for v in (s.time_s, s.axis, s.kind, tr.value, UNITS[s.kind],
                                                         "yes" if g.unstable else "no", g.rate_per_s,
                                                         g.decay_per_period, g.frequency_hz, tr.saturated_s,
                                                         g.reason)))
    write_text_atomic(path, "\n".join(lines) + "\n")


#: the :class:`Search` fields stored as attributes of each search's group
_SEARCH_ATTRS = ("time_s", "axis", "kind", "snapshot", "start_s", "end_s", "bound", "tolerance", "scan_points",
                 "pulse_rad", "pulse_s", "settle_s", "min_damping_ratio", "max_saturation_s")


def write_group(f: h5py.File, results: list[SearchResult]) -> None:
    """Group ``time_margins``: per search, its settings, its trials (value, verdict,
    growth rate, frequency, amplitude, time saturated, reason) and the bracketing
    responses; :func:`read_group` reads it back."""
    root = f.create_group("time_margins")
    for i, res in enumerate(results):
        s = res.search
        g = root.create_group(f"{i:03d}_{s.time_s:g}s_{s.axis}_{s.kind}")
        for key in _SEARCH_ATTRS:  # the choices (axis, kind: StrEnum) as plain str, which h5py takes
            value = getattr(s, key)
            g.attrs[key] = str(value) if isinstance(value, str) else value
        g.attrs["margin"] = res.margin
        g.attrs["unit"] = UNITS[s.kind]
        g.attrs["oscillation_hz"] = res.frequency_hz
        g.attrs["unstable_at_zero"] = res.unstable_at_zero
        g.attrs["bracket"] = np.asarray(res.bracket, dtype=np.float64)
        g.create_dataset("trial_value", data=np.array([tr.value for tr in res.trials]))
        g.create_dataset("trial_unstable", data=np.array([tr.growth.unstable for tr in res.trials]))
        g.create_dataset("trial_growth_rate", data=np.array([tr.growth.rate_per_s for tr in res.trials]))
        g.create_dataset("trial_decay_per_period", data=np.array([tr.growth.decay_per_period for tr in res.trials]))
        g.create_dataset("trial_frequency_hz", data=np.array([tr.growth.frequency_hz for tr in res.trials]))
        g.create_dataset("trial_amplitude", data=np.array([tr.growth.amplitude for tr in res.trials]))
        g.create_dataset("trial_saturated_s", data=np.array([tr.saturated_s for tr in res.trials]))
        g.create_dataset("trial_reason", data=np.array([tr.growth.reason for tr in res.trials], dtype=h5py.string_dtype()))
        for name, resp in (("last_stable", res.last_stable), ("first_unstable", res.first_unstable)):
            if resp is not None:
                g.create_dataset(f"{name}_time", data=resp[0])
                g.create_dataset(f"{name}_gimbal_deg", data=resp[1])


def read_group(h5: Path) -> list[SearchResult]:
    """The searches of a ``savant.h5`` group ``time_margins``, in the order they were
    run (what ``savant report`` redraws the figures from)."""
    out = []
    with h5py.File(h5, "r") as f:
        for name in sorted(f["time_margins"]):
            g = f["time_margins"][name]
            a = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in g.attrs.items()}
            search = Search(**{k: a.get(k, np.nan) for k in _SEARCH_ATTRS})  # files before issue 26: no threshold
            n = g["trial_value"].shape[0]

            def col(key: str, default):
                return g[key][()] if key in g else np.full(n, default)
            reasons = [r.decode() if isinstance(r, bytes) else str(r) for r in col("trial_reason", "")]
            trials = [Trial(value=float(v), saturated_s=float(sat),
                            growth=Growth(unstable=bool(u), rate_per_s=float(r), frequency_hz=float(fr),
                                          amplitude=float(am), reason=why, decay_per_period=float(rho)))
                      for v, u, r, fr, am, sat, why, rho in zip(g["trial_value"][()], g["trial_unstable"][()],
                                                                g["trial_growth_rate"][()],
                                                                col("trial_frequency_hz", np.nan),
                                                                col("trial_amplitude", np.nan),
                                                                col("trial_saturated_s", np.nan), reasons,
                                                                col("trial_decay_per_period", np.nan))]
            resp = {r: (g[f"{r}_time"][()], g[f"{r}_gimbal_deg"][()]) if f"{r}_time" in g else None
                    for r in ("last_stable", "first_unstable")}
            out.append(SearchResult(search=search, margin=float(a["margin"]), frequency_hz=float(a["oscillation_hz"]),
                                    trials=trials, last_stable=resp["last_stable"],
                                    first_unstable=resp["first_unstable"],
                                    unstable_at_zero=bool(a.get("unstable_at_zero", False)),
                                    bracket=tuple(float(b) for b in a.get("bracket", (np.nan, np.nan)))))
    return out


def draw(results: list[SearchResult], folder: Path) -> list[Path]:
    """One figure per search into ``folder/time_margins`` (:func:`plot_search`)."""
    from savant_cli.plots.time_margins import plot_search  # matplotlib only when drawing

    return [plot_search(res, folder / "time_margins") for res in results]
