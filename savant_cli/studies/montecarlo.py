"""``study=montecarlo``: dispersed ascents, reproducible, resumable, shardable.

``savant run study=montecarlo`` flies runs 0 … n−1 (run 0 the nominal) of the configured
vehicle with the dispersions of its dispersion set (``dispersions``, docs/montecarlo.md), on
``study.workers`` processes, journaling each finished run in ``<out>/runs/``. Restarting
the same command into the same folder (``hydra.run.dir=…``) skips the runs already
there. With ``study.shards``/``study.shard`` one job flies one block of run numbers;
``savant collect DIR`` merges the shards. ``savant rerun DIR run=N`` flies one run again
with its whole time history.
"""

from __future__ import annotations

import copy
import json
import time
from functools import partial
from pathlib import Path
from typing import Any, Callable

import numpy as np
import yaml
from omegaconf import DictConfig, OmegaConf
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from savant_cli import lifecycle
from savant_cli.config import MonteCarloStudyConfig, SavantConfig, linear_settings, shipped_option, validate
from savant_cli.errors import ConfigError, DamagedFileError, OutputWriteError, RunInterrupted
from savant_cli.io.console import study_console
from savant_cli.io.guidance_file import read_guidance
from savant_cli.io.provenance import collect_provenance
from savant_cli.io.record import FLOWN
from savant_cli.montecarlo.batch import (
    BatchStop, Case, Journal, RunOutcome, batch_slosh_tanks, execute, fingerprint, fly_run, history_columns,
    read_outcome, shard_runs
)
from savant_cli.montecarlo.inventory import inventory, ranges_text
from savant_cli.montecarlo.outputs import write_outputs
from savant_cli.montecarlo.spec import DispersionSet, parse
from savant_cli.montecarlo.targets import table_target
from savant_cli.paths import hydra_search_dirs, resolve_data_path
from savant_cli.plots.montecarlo_batch import draw_figures
from savant_cli.processes import default_workers
from savant_cli.sim import engine
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare, start_from_staging


def _history_names(model, requested: list[str]) -> list[str]:
    """Check the requested history signals on a 0.1 s flight; their column names."""
    probe = copy.copy(model)
    probe.sched = model.sched._replace(max_time_s=model.k0 * model.rates.dt + 0.1)
    sig = signals(simulate(probe, progress=False), probe)
    for i, name in enumerate(requested):
        if name not in sig or name == "time":
            raise ConfigError(f"study.histories.signals[{i}]", name,
                              "unknown signal; known: " + ", ".join(k for k in sig if k != "time"))
    return [c[0] for c in history_columns(sig, requested)]


def make_case(cfg: SavantConfig, search_dirs: list[Path] | None = None) -> tuple[Case, list[str]]:
    """Load the vehicle and guidance once and check the whole spec (nothing flies but a
    0.1 s probe); the case and the history column names."""
    study: MonteCarloStudyConfig = cfg.study
    dirs = search_dirs or hydra_search_dirs()
    prep = prepare(cfg, dirs)
    dset = parse(cfg.dispersions, study.seed, cfg, prep.vehicle, dirs)
    staging = None
    if cfg.phase.start == "staging":
        staging = partial(start_from_staging, path=resolve_data_path("phase.staging_state_file", "phase",
                                                                    cfg.phase.staging_state_file, dirs))
    names = _history_names(prep.model, list(study.histories.signals))
    grid = np.arange(0.0, cfg.sim.max_time_s + 1e-9, 1.0 / study.histories.rate_hz)
    case = Case(cfg=cfg, vehicle=prep.vehicle, guidance=read_guidance(prep.command_file), dispersions=dset,
                history_signals=list(study.histories.signals), history_time=grid,
                linear=linear_settings(sorted(study.linear_times)) if study.linear_times else None, staging=staging,
                tailoff_lead_s=_tailoff_lead(prep.model, cfg) if study.linear_times else None)
    return case, names


def _tailoff_lead(model, cfg: SavantConfig) -> float | None:
    """The nominal flight's first-stage tail-off window (the criteria of
    ``conf/study/linear.yaml``, ``linear/frozen_time.py``) as its lead before separation
    (s; None: no window). A dispersed motor's tail-off scales with its burn rate (a few per cent), so
    each run's window is its own separation less this lead."""
    from savant_cli.linear.point_analysis import scan_tailoff

    nominal = simulate(model, progress=False)
    t_sep = float(nominal.events[engine.EV_SEPARATION])
    window, _ = scan_tailoff(model, t_sep, shipped_option("study", "linear"), model.rates.dt * model.rates.n_fcs,
                             cfg.requirements)
    return None if window is None or window.start_s is None else window.separation_s - window.start_s


def dispersion_table(dset: DispersionSet) -> list[dict[str, Any]]:
    """Name, target, apply, distribution and units of each dispersion (HDF5 attributes)."""
    rows = []
    for d in dset.items:
        units = table_target(d.target.key)[0] if d.target.kind == "tables" else d.target.units
        row = {"name": d.name, "target": d.target.key, "apply": d.apply, "dist": d.dist,
               "units": "1" if d.apply == "scale" else units, "source": d.source}
        if d.target.kind == "group":
            row["choices"] = list(d.values) or [d.constant]  # the recorded number is the index
        if d.target.kind == "inactive":
            row["inactive"] = d.target.note  # drawn and recorded, applied to nothing
        rows.append(row)
    return rows


def fly_batch(cfg: SavantConfig, config_yaml: str, out_dir: Path, console: Console, title: str = "monte carlo",
              print_tables: bool = True) -> tuple[dict, BatchStop]:
    """Fly this job's runs of the batch of ``cfg`` (resuming from ``out_dir/runs``) and
    write the batch outputs into ``out_dir``; the ``summary.json`` content and how the
    execution ended."""
    study: MonteCarloStudyConfig = cfg.study
    t0 = time.perf_counter()
    case, names = make_case(cfg)
    journal = Journal(out_dir / "runs", cfg, case.dispersions.names, batch_slosh_tanks(case.vehicle))
    by_reason: dict[str, list[str]] = {}  # one line per reason: the navigation set alone has 21 items
    for d in case.dispersions.items:
        if d.target.kind == "inactive":
            by_reason.setdefault(d.target.note, []).append(d.name)
    for note, inactive in by_reason.items():
        console.print(f"inactive dispersions, drawn but applied to nothing ({note}): {', '.join(inactive)}")
    mine = shard_runs(study.n_runs, study.shards, study.shard)
    found = journal.scan()
    done = set(found.good)
    for path in journal.removed_temps:
        console.print(f"removed {path.name}, a journal entry a killed batch left half written", highlight=False)
    for run, exc in sorted(found.damaged.items()):
        if run in mine:
            console.print(f"[bold red]damaged journal entry[/] {exc.path} (run {run}): {exc.problem}; "
                          f"flying run {run} again", highlight=False)
    todo = [r for r in mine if r not in done]
    workers = min(study.workers or default_workers(), max(len(todo), 1))
    if done & set(mine):
        console.print(f"resuming: {len(done & set(mine))} of {len(mine)} runs already in {journal.folder}")
    failures = [0]
    bar = Progress(TextColumn(f"[bold]{title}"), BarColumn(), MofNCompleteColumn(),
                   TextColumn("failed {task.fields[failed]}"), TimeElapsedColumn(), TextColumn("eta"),
                   TimeRemainingColumn(), disable=not cfg.sim.progress)

    flown: set[int] = set()

    def on_done(o: RunOutcome) -> None:
        flown.add(o.run)
        if o.status != "complete":
            failures[0] += 1
        bar.update(task, advance=1, failed=failures[0])
        lifecycle.stage("runs")  # after each journaled run (where a test may interrupt it)

    with bar:
        task = bar.add_task("runs", total=len(todo), failed=0)
        stop = execute(case, todo, journal, workers, on_done)
    if stop.reason == "interrupted":
        # the journal holds every run that finished; the batch's tables wait for its end
        in_journal = len(journal.done() & set(mine))
        raise RunInterrupted("runs", f"{len(flown)} run(s) flown this time, {in_journal} of {len(mine)} in "
                             f"{journal.folder}; run the same command (hydra.run.dir={out_dir}) to resume")
    lifecycle.stage("outputs")
    inv = inventory([journal.folder])
    for run, exc in found.damaged.items():  # not flown again (the batch stopped first): missing, not read
        if run not in flown:
            inv.files.pop(run, None)
            inv.damaged[run] = exc
    try:
        summary = write_outputs(out_dir, inv, list(mine), dispersion_table(case.dispersions),
                                config_yaml, collect_provenance(), names, case.history_time, cfg.requirements,
                                draw_figures if cfg.output.plots else None, console if print_tables else None,
                                reliability_spec=cfg.study.reliability)
    except OutputWriteError:
        if stop.reason == "write failed":  # said before the outputs' own failure
            console.print(f"[bold red]batch stopped[/]: {stop.detail}", highlight=False)
        raise
    console.print(f"{title}: {len(flown)} of {len(todo)} runs flown on {workers} worker(s) in "
                  f"{time.perf_counter() - t0:.1f} s; outputs: {out_dir}")
    return summary, stop


def check_folder(cfg: SavantConfig, out_dir: Path) -> None:
    """Refuse a folder whose journal holds runs of another configuration, before
    anything is written into it (what :class:`~savant_cli.montecarlo.batch.Journal`
    refuses again when it opens the journal).

    Raises
    ------
    ConfigError
        Naming ``hydra.run.dir`` and the folder.
    """
    path = Path(out_dir) / "runs" / "manifest.json"
    if not path.is_file():
        return
    try:
        old = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError("hydra.run.dir", str(out_dir), f"holds an unreadable journal manifest {path} ({exc}): "
                          "choose a new output folder") from None
    if not isinstance(old, dict) or old.get("fingerprint") != fingerprint(cfg):
        raise ConfigError("hydra.run.dir", str(out_dir), "holds runs of a different configuration: choose a new "
                          "output folder (only study.workers, study.shard(s), sim.progress and output.* may change "
                          "on resume)")


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly this job's runs (resuming), then write the batch outputs into ``out_dir``."""
    console = study_console(cfg.output.console)
    summary, stop = fly_batch(cfg, OmegaConf.to_yaml(raw_cfg, resolve=True), out_dir, console)
    if stop.reason != "done":
        console.print(f"[bold red]batch stopped[/]: {stop.detail}; run the same command with "
                      f"hydra.run.dir={out_dir} to resume")
        return 1
    return 0 if not summary["missing_runs"] else 1


# ---------------------------------------------------------------- rerun and collect


def _load_config(run_dir: Path) -> tuple[SavantConfig, DictConfig]:
    """The validated config of a batch folder (or of the first shard of a multirun folder)."""
    path = run_dir / ".hydra" / "config.yaml"
    if not path.is_file():
        path = next(iter(sorted(run_dir.glob("*/.hydra/config.yaml"))), path)
    if not path.is_file():
        raise ConfigError("RUN_DIR", str(run_dir), "is not a savant run folder (no .hydra/config.yaml)")
    try:
        raw = OmegaConf.load(path)
        if not isinstance(raw, DictConfig):
            raise ValueError(f"a YAML {type(raw).__name__}, not a mapping of config groups")
    except (OSError, UnicodeDecodeError, ValueError, yaml.YAMLError) as exc:
        raise DamagedFileError(path, f"unreadable: {type(exc).__name__}: {str(exc).strip().splitlines()[0]}",
                               "savant run writes it when the batch starts: run the batch's command again into a "
                               "new folder") from None
    cfg = validate(raw)
    if cfg.study.name != "montecarlo":
        raise ConfigError("RUN_DIR", str(run_dir), f"holds a study={cfg.study.name} run, not a Monte Carlo batch")
    return cfg, raw


def rerun(run_dir: Path, run_number: int, console: Console | None = None) -> int:
    """Fly run ``run_number`` of the batch in ``run_dir`` again with its whole time
    history; write it like a nominal run into ``run_dir/rerun_<N>/`` and check it
    against the batch's record of that run."""
    from savant_cli.studies import flight as flight_mod

    console = console or Console()
    cfg, raw = _load_config(run_dir)
    if not 0 <= run_number < cfg.study.n_runs:
        raise ConfigError("run", run_number, f"must be a run number of the batch, 0 to {cfg.study.n_runs - 1}")
    case, _ = make_case(cfg)
    outcome, extra = fly_run(case, run_number, keep=True)
    out = run_dir / f"rerun_{run_number:06d}"
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputWriteError(out / "savant.h5", exc) from exc
    if extra is None:
        console.print(f"[bold red]run {run_number} {outcome.status}[/]: {outcome.message}")
        return 1
    model, result, sig, summ = extra
    summ["dispersions"] = dict(zip(case.dispersions.names, outcome.values.tolist()))
    record = flight_mod.record(result, sig, {k: v for k, v in summ.items() if not isinstance(v, dict)}, raw)
    flight_mod.write(out, record, cfg, json_summary=summ)
    stored = next(iter(sorted(run_dir.rglob(f"runs/run_{run_number:06d}.npz"))), None)
    if stored is not None:
        try:
            ref = read_outcome(stored)
        except DamagedFileError as exc:  # the flight is written; only the comparison is lost
            console.print(f"run {run_number} ({outcome.status}) written to {out}", highlight=False)
            console.print(f"[bold red]cannot compare with the batch record[/]: {exc}", highlight=False)
            return DamagedFileError.exit_code
        same = ref.summary_keys == outcome.summary_keys and np.array_equal(ref.summary, outcome.summary) \
            and np.array_equal(ref.values, outcome.values, equal_nan=True)
        console.print(f"run {run_number}: {'identical to' if same else '[bold red]DIFFERENT from[/]'} the batch record")
        if not same:
            return 1
    console.print(f"run {run_number} ({outcome.status}) written to {out}")
    return 0 if outcome.status in FLOWN else 1  # flown to its end (its health is in its status)


def _shard_gaps(run_dirs: list[Path], n_runs: int, missing: list[int]) -> list[str]:
    """Where the missing runs belong, one line per shard of the batch that lacks runs
    (``study.shards`` and ``study.shard`` of the shard folders' ``.hydra/config.yaml``,
    when they all agree on ``study.shards``): ``shard k (FOLDER): runs …``, or
    ``shard k (no shard folder with a journal): runs …``; empty when that cannot be told."""
    lost = set(missing)
    found: dict[int, Path] = {}
    counts = set()
    for d in run_dirs:
        path = d / ".hydra" / "config.yaml"
        if not path.is_file():
            return []
        try:
            study = OmegaConf.load(path).get("study", {})
        except (OSError, UnicodeDecodeError, ValueError, AttributeError, yaml.YAMLError):
            return []  # an unreadable shard config: only the run numbers tell
        counts.add(int(study.get("shards", 1)))
        found[int(study.get("shard", 0))] = d
    if len(counts) != 1:
        return []  # shards of different splits (allowed on resume): only the run numbers tell
    shards = counts.pop()
    lines = []
    for k in range(shards):
        gap = [r for r in shard_runs(n_runs, shards, k) if r in lost]
        if not gap:
            continue
        where = f"({found[k]})" if k in found else "(no shard folder with a journal)"
        lines.append(f"shard {k} {where}: runs {ranges_text(gap)}")
    return lines


def collect(folder: Path, console: Console | None = None, allow_missing: bool = False,
            before_write: Callable[[], Any] | None = None) -> int:
    """Merge the shard folders under ``folder`` (a Hydra multirun folder) into one
    ``savant.h5``, tables and ``summary.json`` there.

    Parameters
    ----------
    folder : Path
        The multirun folder holding the shard folders (``*/runs/manifest.json``).
    console : rich.console.Console, optional
        Where the tables and the missing runs are printed.
    allow_missing : bool
        With runs missing, write the partial result anyway (its ``summary.json``
        ``missing_runs`` and the ``savant.h5`` attribute name them). Without it a partial
        set writes nothing into ``folder``.
    before_write : callable, optional
        Called once it is decided that ``folder`` will be written, before the first
        write (the command line locks the folder there: a refused collect writes nothing).

    Returns
    -------
    int
        0 when every run of the batch is present exactly once and the result was
        written; 1 when runs are missing (written or not: a partial result never exits
        0).
    """
    console = console or Console()
    run_dirs = sorted(p.parent for p in folder.rglob("runs/manifest.json"))
    if not run_dirs:
        raise ConfigError("collect", str(folder), "has no Monte Carlo shard folders (*/runs/manifest.json)")
    inv = inventory(run_dirs, verify=True)
    if inv.duplicates:
        dup = ", ".join(f"run {r} in {', '.join(str(p.parent.parent) for p in ps)}" for r, ps in inv.duplicates.items())
        raise ConfigError("collect", str(folder), f"holds runs more than once ({dup}): shards overlap")
    cfg, raw = _load_config(run_dirs[0].parent)
    expected = list(range(cfg.study.n_runs))
    missing = inv.missing(expected)
    for run, exc in sorted(inv.damaged.items()):
        console.print(f"[bold red]damaged journal entry[/] {exc.path} (run {run}): {exc.problem}"
                      + ("" if run in inv.files else "; counted as missing"), highlight=False)
    if missing:
        console.print(f"[bold red]missing runs[/] ({len(missing)} of {len(expected)}): {ranges_text(missing)}")
        for line in _shard_gaps([d.parent for d in run_dirs], cfg.study.n_runs, missing):
            console.print(f"  {line}", highlight=False)
        if not allow_missing:
            console.print(f"nothing written into {folder}: resume the missing shards (docs/montecarlo.md, "
                          "\"Resume a batch with missing shards\"), or collect the partial set with --allow-missing")
            return 1
    case, names = make_case(cfg)
    if before_write is not None:
        before_write()
    write_outputs(folder, inv, expected, dispersion_table(case.dispersions), OmegaConf.to_yaml(raw, resolve=True),
                  collect_provenance(), names, case.history_time, cfg.requirements,
                  draw_figures if cfg.output.plots else None, console,
                  reliability_spec=cfg.study.reliability)
    console.print(f"collected {len(inv.files)} runs from {len(run_dirs)} shard folder(s) into {folder}")
    if missing:
        console.print(f"[bold red]PARTIAL result[/] (--allow-missing): {len(missing)} of {len(expected)} runs "
                      f"missing ({ranges_text(missing)}), listed in summary.json missing_runs")
        return 1
    return 0
