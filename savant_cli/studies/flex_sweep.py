"""``study=flex_sweep``: the flex parameter study behind the GVT decision (source paper
§IV, Figures 15–22).

One time run of the configured vehicle (flex on) sets the operating points. At each of
``study.times``, for each parameter (``frequency``: the bending frequencies;
``shape``: the mode-shape magnitudes, i.e. every modal slope and deflection) and each
scale factor of ``study.levels``, the retained modes (or ``study.modes``) are scaled in
the model's flex tables, the plant is linearized about the same state and the loops are
assembled and analysed as in ``study=linear``. Outputs: ``flex_sweep.csv`` (every margin
of every case, flagged against the requirements), ``summary.json``, a console table of
the worst margin per band and case with losses of stability, and one Nichols chart per
time, parameter and chart axis with the levels overlaid (``plots/flex_sweep/``).
"""

from __future__ import annotations

import copy
import csv
import io
import time
import warnings
from pathlib import Path

from omegaconf import DictConfig
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from savant_cli.config import FlexSweepStudyConfig, LinearStudyConfig, SavantConfig
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_json_atomic, write_text_atomic
from savant_cli.sim.build import SimModel
from savant_cli.studies import flight as flight_mod
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.studies.linear import analyse, check_times

COLUMNS = ("time_s", "parameter", "level", "axis", "kind", "band", "value", "frequency_hz", "meets_requirement",
           "closed_loop_stable")


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
    console = Console()
    t_start = time.perf_counter()
    if not cfg.flex.enabled:
        raise ConfigError("flex", cfg.flex.name, "study=flex_sweep needs the flexible body: add flex=on")
    for i, m in enumerate(study.modes):
        if m > cfg.flex.n_modes:
            raise ConfigError(f"study.modes[{i}]", m, f"must be a retained mode, 1 to flex.n_modes = {cfg.flex.n_modes}")
    model = prepare(cfg).model
    rt = model.rates
    dt = rt.dt * rt.n_fcs
    steps = flight_mod.control_steps(cfg, study.times)
    result = simulate(model, progress=cfg.sim.progress, chunk_s=cfg.sim.chunk_s, snapshot_steps=steps)
    events = dict(flight_mod.events_of(result))
    times = check_times(sorted({k * rt.dt for k in steps}), result.t_final, events, study, skip=False)
    lin = LinearStudyConfig(times=times)
    cases = [(t, prm, lvl) for t in times for prm in study.parameters for lvl in study.levels]
    rows, charts, stable = [], {}, {}
    bar = Progress(TextColumn("[bold]flex sweep"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   transient=True, disable=not cfg.sim.progress)
    with warnings.catch_warnings(), bar:
        warnings.simplefilter("ignore")
        task = bar.add_task("cases", total=len(cases))
        for t, prm, lvl in cases:
            snap = result.snapshots[int(round(t / rt.dt))]
            pt, margin_rows, extra = analyse(variant(model, prm, lvl, list(study.modes)), snap, lin, dt)
            stable[(t, prm, lvl)] = extra["closed_loop_stable"]
            for axis in study.chart_axes:
                charts.setdefault((t, prm, axis), {})[f"{prm} × {lvl:g}"] = pt.loops[axis]
            for r in margin_rows:
                rows.append({"time_s": t, "parameter": prm, "level": lvl, "axis": r.axis, "kind": r.kind,
                             "band": r.band, "value": r.value, "frequency_hz": r.frequency_hz,
                             "meets_requirement": bool(abs(r.value) >= study.requirements.required(r.band, r.kind)),
                             "closed_loop_stable": bool(extra["closed_loop_stable"])})
            bar.advance(task)
    out_dir.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(COLUMNS), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_text_atomic(out_dir / "flex_sweep.csv", buf.getvalue())
    worst = _worst(rows, stable, study)
    write_json_atomic(out_dir / "summary.json", {
        "study": "flex_sweep", "times_s": times, "parameters": list(study.parameters), "levels": list(study.levels),
        "modes": list(study.modes) or list(range(1, cfg.flex.n_modes + 1)), "cases": worst,
        "unstable_cases": [c for c in worst if not c["closed_loop_stable"]],
        "study_wall_time_s": time.perf_counter() - t_start})
    if cfg.output.plots:
        from savant_cli.plots.linear import plot_nichols_overlay

        for (t, prm, axis), loops in charts.items():
            plot_nichols_overlay(t, loops, out_dir / "plots" / "flex_sweep" / f"nichols_{axis}_{prm}_t{t:06.1f}.png",
                                 title=f"{axis} loop, flex {prm} scaled", exclusion_zones=study.exclusion_zones)
    console.print(_table(worst))
    console.print(f"{len(cases)} cases in {time.perf_counter() - t_start:.1f} s; outputs: {out_dir}")
    return 0 if result.status == "complete" else 1


def _worst(rows: list[dict], stable: dict, study: FlexSweepStudyConfig) -> list[dict]:
    """Per case: stability, the smallest |margin| per band and kind, and the violations."""
    out = []
    for (t, prm, lvl), ok in stable.items():
        case = {"time_s": t, "parameter": prm, "level": lvl, "closed_loop_stable": bool(ok), "violations": 0}
        for r in rows:
            if (r["time_s"], r["parameter"], r["level"]) != (t, prm, lvl):
                continue
            key = f"{r['band']}_{r['kind']}"
            if key not in case or abs(r["value"]) < abs(case[key]):
                case[key] = r["value"]
            case["violations"] += not r["meets_requirement"]
        out.append(case)
    return out


def _table(cases: list[dict]) -> Table:
    tb = Table(title="flex sweep: smallest |margin| per band (gain dB, phase deg); red = below requirement")
    cols = ("rigid/aero_gain", "rigid/aero_phase", "flex_gain", "flex_phase")
    for c in ("t (s)", "parameter", "level", "stable", *cols, "violations"):
        tb.add_column(c, justify="right")
    for c in cases:
        tb.add_row(f"{c['time_s']:.1f}", c["parameter"], f"{c['level']:g}",
                   "yes" if c["closed_loop_stable"] else "[red]NO[/red]",
                   *[f"{c[k]:.2f}" if k in c else "–" for k in cols],
                   f"[red]{c['violations']}[/red]" if c["violations"] else "0")
    return tb
