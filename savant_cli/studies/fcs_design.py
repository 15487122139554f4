"""``study=fcs_design``: the flight control tuned against its own requirement set.

1. The design rules ``study.design`` (``savant_cli/datagen/fcs_gains.py``) give the
   starting controller: the pole-placement gain schedules at the reference ascent's
   control power and aerodynamic instability, and the rate-path filters and blend.
2. The nominal vehicle flies with it; its state is kept at every design point
   (``study.every_s`` per schedule) and every verification point (``study.verify_every_s``),
   each at least ``study.event_window_s`` from an event.
3. At each point the plant of the nominal vehicle and of every uncertainty corner
   (``study.corners``: config overrides, e.g. ``flex.frequency_scale: 0.8``) is linearized
   once about the nominal state. A corner is judged against the requirement set times its
   ``requirement_fraction`` (default 1; 0: closed-loop stability alone).
4. Schedule by schedule (``study.schedules``), the free parameters (``study.parameters``,
   ``savant_cli/design/parameters.py``) are searched (``savant_cli/design/search.py``) to
   maximize the smallest margin-to-requirement ratio over the schedule's design points and
   corners (the loops of ``study.axes``); each candidate's points are judged on
   ``study.workers`` processes (``savant_cli/design/pool.py``).
5. The tuned controller is judged at every verification point and corner, both loops,
   and written.

Outputs: ``controller/<name>.yaml`` (``savant run --config-dir <run dir>
controller=<name>`` loads it; the name is ``<design>_tuned`` unless
``study.controller_name`` says otherwise; ``study.install=true`` writes it under the
design's name to the shipped ``conf/controller/<name>.yaml`` as well),
``fcs_design.csv`` (every point and corner, ratio and worst offender before and after), ``summary.json``, ``savant.h5`` (the nominal flight and
group ``fcs_design``), ``plots/fcs_design/`` (the margin envelopes before and after, the
Nichols charts of the worst points with the corners overlaid), the console tables and the
verdict lines before and after.
"""

from __future__ import annotations

import copy
import csv
import io
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
from omegaconf import DictConfig, OmegaConf
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from savant_cli.config import FcsDesignStudyConfig, SavantConfig, design_controller_name, validate
from savant_cli.datagen import fcs_gains, flex_filters
from savant_cli.design import parameters as dp
from savant_cli.design.points import DesignPoint, point_score
from savant_cli.design.pool import ScorePool
from savant_cli.design.search import search
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_text_atomic
from savant_cli.io.console import print_verdict, study_console
from savant_cli.io.record import FLOWN
from savant_cli.linear.charts import LoopResponse, loop_response
from savant_cli.linear.evaluate import candidate_loops, freeze, judge_controller
from savant_cli.linear.margins import MarginRow
from savant_cli.linear.requirements import PointVerdict, scaled_requirements, verdict_line
from savant_cli.linear.store import read_loop_response, read_margins, write_loop_response, write_margin_table
from savant_cli.paths import shipped_config_dir
from savant_cli.processes import default_workers
from savant_cli.sim.setup import prepare
from savant_cli.studies import flight as flight_mod

#: Flight-control phase → the schedule tuned for it (the coast has no thrust: no design).
SCHEDULE_OF_PHASE = {"stack": "stack", "upper": "upper"}
#: Nichols charts drawn: this many worst verification points of the tuned controller.
N_WORST = 2


@dataclass
class Judged:
    """A controller's verdicts at the verification points, per corner."""

    verdicts: dict[str, list[PointVerdict]]  # corner ("" nominal) → one per point
    rows: list[MarginRow]  # the nominal plant's margins (both loops), for the envelope
    requirement_names: dict[str, str]  # corner → the name of the set it is judged against

    def line(self, name: str) -> str:
        groups = [(self.label(c), [v]) for c, vs in self.verdicts.items() for v in vs]
        return verdict_line(groups, name, "points")

    def label(self, corner: str) -> str:
        """``nominal``, or the corner's name with its set when that is not the nominal's."""
        own = self.requirement_names[corner]
        return (corner or "nominal") if own == self.requirement_names[""] else f"{corner} ({own})"

    @property
    def passed(self) -> bool:
        return all(v.passed for vs in self.verdicts.values() for v in vs)

    @property
    def failed_times(self) -> list[float]:
        """Times (s) where the nominal plant or a corner fails the requirement set."""
        return sorted({v.time_s for vs in self.verdicts.values() for v in vs if not v.passed})


def _times(study: FcsDesignStudyConfig, t_end: float) -> dict[str, list[float]]:
    """Candidate design times per schedule (every ``every_s`` from half of it: 5, 15, …
    125 s for the stack's 10 s) and the verification times (key ``verify``)."""
    out = {s: [float(t) for t in np.arange(0.5 * study.every_s[s], t_end, study.every_s[s])] for s in study.schedules}
    out["verify"] = [float(t) for t in np.arange(study.verify_every_s, t_end, study.verify_every_s)]
    return out


#: The corner key that is not a config override: the fraction of the requirement set the
#: corner is judged against.
REQUIREMENT_FRACTION = "requirement_fraction"
#: Corner keys applied to the nominal model's flex tables (as ``study=flex_sweep`` does),
#: not through the config: a linearization needs no RK4 step bound on the mode frequency.
FLEX_TABLE_KEYS = {"flex.frequency_scale": "frequency", "flex.shape_scale": "shape"}


def corner_models(cfg: SavantConfig, raw_cfg: DictConfig, controller: object, corners: dict[str, dict],
                  nominal) -> dict[str, object]:
    """The nominal model (key ``""``) and every corner's: its config keys applied to the
    run's config (with the starting ``controller``), its flex scale factors to the
    model's flex tables (:data:`FLEX_TABLE_KEYS`, relative to the run's own)."""
    from savant_cli.studies.flex_sweep import variant

    out = {"": nominal}
    for name, overrides in corners.items():
        keys = {k: v for k, v in overrides.items() if k not in FLEX_TABLE_KEYS and k != REQUIREMENT_FRACTION}
        model = nominal
        if keys:
            raw = copy.deepcopy(raw_cfg)
            for key, value in keys.items():
                if OmegaConf.select(raw, key, default=None) is None:
                    raise ConfigError(f"study.corners.{name}", key, "must be a config key of this run (e.g. "
                                      "slosh.damping_scale, flex.damping) or flex.frequency_scale/shape_scale")
                OmegaConf.update(raw, key, value, merge=False)
            c = validate(raw)
            c.controller = controller
            model = prepare(c).model
            if model.x0.size != nominal.x0.size:
                raise ConfigError(f"study.corners.{name}", dict(overrides),
                                  "must not change the plant's states (flex.n_modes, slosh, twd)")
        for key, parameter in FLEX_TABLE_KEYS.items():
            if key in overrides:
                if not cfg.flex.enabled:
                    raise ConfigError(f"study.corners.{name}", key, "needs the flexible body (flex=on)")
                model = variant(model, parameter, float(overrides[key]), [])
        out[name] = model
    return out


def corner_requirements(requirements, corners: dict[str, dict]) -> dict[str, object]:
    """The requirement set of the nominal plant (key ``""``) and of every corner: the set
    times the corner's ``requirement_fraction`` (in [0, 1]; 1 when absent)."""
    out = {"": requirements}
    for name, overrides in corners.items():
        fraction = overrides.get(REQUIREMENT_FRACTION, 1.0)
        if isinstance(fraction, bool) or not isinstance(fraction, (int, float)) or not 0.0 <= fraction <= 1.0:
            raise ConfigError(f"study.corners.{name}.{REQUIREMENT_FRACTION}", fraction,
                              "must be a number in [0, 1] (1: the full requirement set, 0: closed-loop stability)")
        out[name] = requirements if fraction == 1.0 else scaled_requirements(requirements, float(fraction))
    return out


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Tune, verify and write the controller (module notes)."""
    study: FcsDesignStudyConfig = cfg.study
    console = study_console(cfg.output.console)
    t_start = time.perf_counter()
    if study.design not in fcs_gains.CONTROLLERS:
        raise ConfigError("study.design", study.design, f"must be one of {', '.join(fcs_gains.CONTROLLERS)}")
    spec = copy.deepcopy(fcs_gains.CONTROLLERS[study.design])
    spec["name"] = design_controller_name(study)
    prep = prepare(cfg)
    vehicle_name = cfg.vehicle["name"]
    stack_blend = flex_filters.vehicle_stack_blend(cfg.vehicle, prep.vehicle_dir)
    params = dp.free_parameters(study.parameters, list(study.schedules), spec, stack_blend)
    console.print("reference ascent and the control power and aerodynamic instability at the schedule breakpoints")
    design_points = fcs_gains.design_points(cfg, prep.vehicle, spec)
    start = {(p.schedule, p.name): p.initial for p in params}
    spec0 = dp.apply(spec, start)
    text0 = dp.controller_text(spec0, design_points, stack_blend, vehicle_name)

    cfg0 = copy.copy(cfg)
    cfg0.controller = dp.controller_config(text0)
    times = _times(study, cfg.sim.max_time_s)
    steps = flight_mod.control_steps(cfg0, sorted({t for ts in times.values() for t in ts}))
    flight = flight_mod.fly(cfg0, snapshot_steps=steps)
    result = flight.result
    model = flight.prep.model
    rt = model.rates
    dt = rt.dt * rt.n_fcs
    events = [te for _, te in flight_mod.events_of(result)]

    def keep(t: float) -> bool:
        return 0.0 < t < result.t_final and all(abs(t - te) >= study.event_window_s for te in events)

    snaps = {t: result.snapshots[k] for t, k in ((k * rt.dt, k) for k in steps) if keep(t) and k in result.snapshots}
    models = corner_models(cfg, raw_cfg, cfg0.controller, dict(study.corners), model)
    reqs = corner_requirements(cfg.requirements, {k: dict(v) for k, v in study.corners.items()})
    frozen: dict[tuple[str, float], DesignPoint] = {}
    bar = Progress(TextColumn("[bold]{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                   TextColumn("best objective {task.fields[best]}"), TimeElapsedColumn(), disable=not cfg.sim.progress)
    with bar:
        task = bar.add_task("linearize", total=len(snaps) * len(models), best="–")
        for t, snap in snaps.items():
            for name, m in models.items():
                frozen[(name, t)] = DesignPoint(name, freeze(m, snap, dt), reqs[name])
                bar.advance(task)

        def schedule_points(sched: str, ts: list[float]) -> list[DesignPoint]:
            return [frozen[(c, t)] for t in ts for c in models if (c, t) in frozen
                    and SCHEDULE_OF_PHASE.get(frozen[(c, t)].point.phase_name) == sched]

        values = dict(start)
        searches = {}
        with ScorePool(list(frozen.values()), study.workers or default_workers()) as pool:
            for sched in study.schedules:
                pts = schedule_points(sched, times[sched])
                mine = [p for p in params if p.schedule == sched]
                if not pts or not mine:
                    continue
                task = bar.add_task(f"design {sched}", total=study.optimizer.max_evaluations, best="–")

                def tables_of(v: dict, _values=values) -> object:
                    return dp.controller_tables(dp.controller_text(dp.apply(spec, {**_values, **v}),
                                                                   design_points, stack_blend, vehicle_name))

                res = search(mine, tables_of, pts, dt, study.optimizer, tuple(study.axes),
                             progress=lambda n, best, _t=task: bar.update(_t, completed=n, best=f"{best:.3f}"),
                             pool=pool)
                values.update(res.values)
                searches[sched] = res
        spec1 = dp.apply(spec, values)
        text1 = dp.controller_text(spec1, design_points, stack_blend, vehicle_name,
                                   {"rules": study.design, "parameters": values})
        verify = [t for t in times["verify"] if t in snaps]
        before = _judge(frozen, models, verify, dp.controller_tables(text0), dt)
        ft1 = dp.controller_tables(text1)
        after = _judge(frozen, models, verify, ft1, dt)

    worst = sorted(((point_score(v), v.time_s) for v in after.verdicts[""]))[:N_WORST]
    charts = {}
    for _, t in worst:
        charts[t] = [loop_response(name or "nominal", candidate_loops(frozen[(name, t)].point, ft1, dt)["pitch"])
                     for name in models]
    name = spec["name"]
    written = [out_dir / "controller" / f"{name}.yaml"]
    if study.install:
        written.append(shipped_config_dir() / "controller" / f"{name}.yaml")
    for path in written:
        write_text_atomic(path, text1)
    table = _point_table(before, after)
    wall = time.perf_counter() - t_start
    summary = {"study": "fcs_design", "design": study.design, "controller": name, "vehicle": vehicle_name,
               "requirement_set": cfg.requirements.name, "corners": {k: dict(v) for k, v in study.corners.items()},
               "parameters": [{"schedule": p.schedule, "name": p.name, "low": p.low, "high": p.high,
                               "before": p.initial, "after": values[(p.schedule, p.name)]} for p in params],
               "searches": {s: {"evaluations": r.evaluations, "wall_time_s": r.wall_s,
                                "objective_before": r.initial_score, "objective_after": r.score, "message": r.message}
                            for s, r in searches.items()},
               "verdict_before": before.line(cfg.requirements.name), "verdict_after": after.line(cfg.requirements.name),
               "requirements_met": after.passed, "points": table,
               "controller_files": [str(p) for p in written], "study_wall_time_s": wall}
    console.print(_console_table(params, values, searches))  # before the files: shown even if they cannot be written
    print_verdict("before: " + summary["verdict_before"], before.passed, console)
    print_verdict("after:  " + summary["verdict_after"], after.passed, console)
    console.print(f"controller: {written[0]} (savant run --config-dir {out_dir} controller={name})")
    rec = flight_mod.record(result, flight.signals, flight.summary, raw_cfg, wall)
    flight_mod.write(out_dir, rec, cfg0, json_summary=summary,
                     extra=lambda f: write_group(f, text1, summary, before, after, charts,
                                                 cfg.requirements.by_band()))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(table[0]) if table else ["time_s"], lineterminator="\n")
    w.writeheader()
    w.writerows(table)
    write_text_atomic(out_dir / "fcs_design.csv", buf.getvalue())
    if cfg.output.plots:
        draw(before.rows, after.rows, charts, cfg.requirements.by_band(), (before.failed_times, after.failed_times),
             out_dir / "plots")
    console.print(f"outputs: {out_dir} ({wall:.0f} s)")
    return 0 if result.status in FLOWN else 1


def _judge(frozen: dict, models: dict, times: list[float], ft, dt: float) -> Judged:
    verdicts: dict[str, list[PointVerdict]] = {c: [] for c in models}
    rows: list[MarginRow] = []
    names = {}
    for t in times:
        for c in models:
            p = frozen[(c, t)]
            r, _, v = judge_controller(p.point, ft, dt, p.requirements)
            verdicts[c].append(v)
            names[c] = p.requirements.name
            if not c:
                rows += r
    return Judged(verdicts, rows, names)


def _point_table(before: Judged, after: Judged) -> list[dict]:
    out = []
    for c in before.verdicts:
        for b, a in zip(before.verdicts[c], after.verdicts[c]):
            out.append({"time_s": b.time_s, "corner": c or "nominal", "requirements": before.requirement_names[c],
                        "stage": b.stage,
                        "ratio_before": point_score(b), "passed_before": b.passed,
                        "worst_before": b.worst.text() if b.worst else "",
                        "ratio_after": point_score(a), "passed_after": a.passed,
                        "worst_after": a.worst.text() if a.worst else ""})
    return out


def _console_table(params: list[dp.FreeParameter], values: dict, searches: dict) -> Table:
    tb = Table(title="flight-control design: free parameters (before → after); objective: the smallest ratio "
                     "if every design point passes, else minus the total shortfall")
    for col in ("schedule", "parameter", "range", "before", "after"):
        tb.add_column(col, justify="right" if col in ("before", "after") else "left")
    for p in params:
        tb.add_row(p.schedule, p.name, f"{p.low:g}–{p.high:g}", f"{p.initial:.4g}", f"{values[(p.schedule, p.name)]:.4g}")
    for s, r in searches.items():
        tb.add_row(s, "objective", "", f"{r.initial_score:.3f}", f"{r.score:.3f}")
        tb.add_row(s, "evaluations", "", "", f"{r.evaluations} in {r.wall_s:.0f} s")
    return tb


def write_group(f: h5py.File, text: str, summary: dict, before: Judged, after: Judged,
                charts: dict[float, list[LoopResponse]], bands: dict) -> None:
    """Group ``fcs_design``: attributes ``controller_yaml`` (the tuned controller),
    ``parameters`` (JSON), ``verdict_before``, ``verdict_after``; ``margins_before``,
    ``margins_after`` (the nominal margin tables at the verification points,
    ``linear/store.py`` layout, attribute ``failed_times``: the points where the nominal
    plant or a corner fails); ``nichols/<nnn>`` (attribute ``time_s``, one ``loop_<k>`` per
    corner)."""
    import json

    g = f.create_group("fcs_design", track_order=True)
    g.attrs["controller_yaml"] = text
    g.attrs["parameters"] = json.dumps(summary["parameters"])
    g.attrs["verdict_before"] = summary["verdict_before"]
    g.attrs["verdict_after"] = summary["verdict_after"]
    for key, judged in (("before", before), ("after", after)):
        mg = g.create_group(f"margins_{key}")
        write_margin_table(mg.create_group("margins"), judged.rows, None, True)
        mg["margins"].attrs["requirements"] = json.dumps({b: list(r) for b, r in bands.items()})
        mg.attrs["failed_times"] = np.array(judged.failed_times, dtype=float)
    ng = g.create_group("nichols", track_order=True)
    for n, (t, loops) in enumerate(charts.items()):
        cg = ng.create_group(f"{n:03d}", track_order=True)
        cg.attrs["time_s"] = t
        for k, lp in enumerate(loops):
            write_loop_response(cg.create_group(f"loop_{k:02d}"), lp)


def read_group(path: Path) -> tuple[list[MarginRow], list[MarginRow], dict[float, list[LoopResponse]], dict,
                                    tuple[list[float], list[float]]]:
    """The inverse of :func:`write_group` for the figures: margins before and after, the
    Nichols data, the band requirements and the failing times before and after."""
    with h5py.File(path, "r") as f:
        g = f["fcs_design"]
        before, bands, _ = read_margins(g["margins_before"])
        after, _, _ = read_margins(g["margins_after"])
        failed = tuple([float(t) for t in g[f"margins_{k}"].attrs["failed_times"]] for k in ("before", "after"))
        charts = {float(c.attrs["time_s"]): [read_loop_response(c[k]) for k in c] for c in g["nichols"].values()}
    return before, after, charts, bands, failed


def draw(before: list[MarginRow], after: list[MarginRow], charts: dict[float, list[LoopResponse]], bands: dict,
         failed: tuple[list[float], list[float]], folder: Path) -> list[Path]:
    """The margin envelopes before and after (the nominal plant's margins; the points where
    it or a corner fails marked), and one Nichols chart per worst point with the corners
    overlaid."""
    from savant_cli.plots.linear import plot_margin_envelope, plot_nichols_overlay

    out = folder / "fcs_design"
    paths = [plot_margin_envelope(rows, out / f"margin_envelope_{key}.png", requirements=bands, failed_times=times,
                                  failed_label="fails at the nominal\nplant or a corner")
             for key, rows, times in (("before", before, failed[0]), ("after", after, failed[1]))]
    for t, loops in charts.items():
        paths.append(plot_nichols_overlay(t, loops, out / f"nichols_pitch_t{t:06.1f}.png",
                                          title="pitch loop, tuned controller, uncertainty corners"))
    return paths
