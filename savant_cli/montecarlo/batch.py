"""Fly a batch of dispersed runs: one run (:func:`fly_run`), the per-run journal that
makes a batch resumable, and the process pool.

Journal. Each finished run is one small ``.npz`` file in ``<out>/runs/``, written to a
temporary name and renamed (atomic), by the main process only (the one writer), with the
SHA-256 of its content inside (``montecarlo/journal.py``). A killed batch loses at most
the runs in flight; restarting into the same folder skips the runs already there whose
entry reads back whole and matches its checksum (a damaged entry is named and flown
again), after checking that the folder's ``runs/manifest.json`` was written for the same
configuration (:func:`fingerprint`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import time
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from savant_cli.config import LinearStudyConfig, SavantConfig
from savant_cli.errors import ConfigError, DamagedFileError, OutputWriteError
from savant_cli.io.atomic import write_text_atomic
from savant_cli.linear.requirements import (
    AXIS_NAMES, CHECK_ARRAY_COLUMNS, DEFAULT_SLOSH_TANKS, checks_array, mode_code, slosh_mode_tanks
)
from savant_cli.montecarlo.journal import read_entry, write_entry
from savant_cli.montecarlo.spec import DispersionSet
from savant_cli.montecarlo.targets import apply_samples, build_dispersed
from savant_cli.processes import process_context, terminate_workers, worker_initializer
from savant_cli.sim.build import SimModel
from savant_cli.sim.engine import EVENT_NAMES
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.run_summary import run_summary

#: summary keys that vary from machine to machine, kept out of the run tables
WALL_KEYS = ("sim_wall_time_s", "compile_time_s", "realtime_factor", "study_wall_time_s")
AXIS_CODES = AXIS_NAMES
KIND_CODES = ("gain", "phase")
BAND_CODES = ("rigid/aero", "slosh", "flex")
#: Columns of a run's margin rows (codes for the strings; modes as ``mode_code``).
MARGIN_ARRAY_COLUMNS = ("time_s", "axis", "kind", "band", "value", "frequency_hz", "mode", "meets_requirement")


@dataclass
class Case:
    """Everything a worker needs to fly any run of the batch (picklable)."""

    cfg: SavantConfig
    vehicle: Any
    guidance: Any
    dispersions: DispersionSet
    history_signals: list[str]
    history_time: np.ndarray
    # the margins of every run: study=linear's settings (conf/study/linear.yaml) at the
    # study's linear_times; None: no margins
    linear: LinearStudyConfig | None
    staging: Callable | None = None
    # the nominal's first-stage tail-off window, as its lead before separation (s; None:
    # no window): each run's window is its own separation less this
    tailoff_lead_s: float | None = None


#: The stages of one run whose wall time (s) each outcome keeps (``stage_wall_s``): drawing
#: and applying the dispersions and building the model; the simulation; signals, flight
#: health and summary; the linearization and margins at ``study.linear_times``; and the
#: histories' decimation.
RUN_STAGES = ("build", "simulate", "assess", "margins", "histories")


@dataclass
class RunOutcome:
    """What one run leaves in the journal."""

    run: int
    status: str  # complete | diverged | failed (an exception) | invalid (a sample the config refuses)
    message: str
    t_final: float
    wall_s: float
    values: np.ndarray  # per dispersion, as numbers (see DispersionSet.numbers)
    summary_keys: list[str] = field(default_factory=list)
    summary: np.ndarray = field(default_factory=lambda: np.zeros(0))
    events: np.ndarray = field(default_factory=lambda: np.full(len(EVENT_NAMES), np.nan))
    histories: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.float32))
    margins: np.ndarray = field(default_factory=lambda: np.zeros((0, len(MARGIN_ARRAY_COLUMNS))))
    checks: np.ndarray = field(default_factory=lambda: np.zeros((0, len(CHECK_ARRAY_COLUMNS))))  # requirement checks
    stage_wall_s: np.ndarray = field(default_factory=lambda: np.zeros(len(RUN_STAGES)))  # s, per RUN_STAGES


def history_columns(sig: dict, names: list[str]) -> list[tuple[str, str, int | None]]:
    """``(output name, signal, column)`` of each requested history; a vector signal
    gives one history per column, ``<signal>_<column>``."""
    out = []
    for name in names:
        s = sig[name]
        if s.data.ndim == 1:
            out.append((name, name, None))
        else:
            out.extend((f"{name}_{c}", name, j) for j, c in enumerate(s.columns))
    return out


def _decimate(sig: dict, names: list[str], grid: np.ndarray) -> np.ndarray:
    t = sig["time"].data
    cols = history_columns(sig, names)
    out = np.full((len(cols), grid.size), np.nan, dtype=np.float32)
    if t.size:
        inside = grid <= t[-1]
        for i, (_, name, j) in enumerate(cols):
            data = sig[name].data if j is None else sig[name].data[:, j]
            out[i, inside] = np.interp(grid[inside], t, data)
    return out


def _margins(case: Case, model: SimModel, result, sig: dict) -> tuple[np.ndarray, np.ndarray]:
    """The run's margin rows (:data:`MARGIN_ARRAY_COLUMNS`) at its linear times, and the
    requirement checks (``linear/requirements.py::CHECK_ARRAY_COLUMNS``) of those outside
    the run's own first-stage tail-off window: its separation less the nominal's window
    lead (``Case.tailoff_lead_s``; docs/requirements.md): the window's margins are kept,
    its points not judged."""
    from savant_cli.linear.point_analysis import analyse

    rows, verdicts = [], []
    tanks = batch_slosh_tanks(case.vehicle)
    dt_fcs = model.rates.dt * model.rates.n_fcs
    lin_cfg = case.linear
    t_sep = float(result.events[EVENT_NAMES.index("separation")])
    window = (t_sep - case.tailoff_lead_s, t_sep) if case.tailoff_lead_s is not None and np.isfinite(t_sep) else None
    for k, snap in sorted(result.snapshots.items()):
        if any(abs(snap.t - te) < lin_cfg.event_clearance_s for te in result.events if te == te):
            continue  # on this run's event: no frozen-time point there
        a = analyse(model, snap, lin_cfg, dt_fcs, case.cfg.requirements)
        if window is None or not window[0] <= snap.t < window[1]:
            verdicts.append(a.verdict)
        rows += [(r.time_s, AXIS_CODES.index(r.axis), KIND_CODES.index(r.kind), BAND_CODES.index(r.band), r.value,
                  r.frequency_hz, mode_code(r.mode, tanks), float(r.meets_requirement)) for r in a.rows]
    return np.array(rows, dtype=float).reshape(-1, len(MARGIN_ARRAY_COLUMNS)), checks_array(verdicts, tanks)


def batch_slosh_tanks(vehicle: Any) -> tuple[str, ...]:
    """The sloshing tanks a batch's slosh mode codes name (``linear/requirements.py::
    mode_code``): the vehicle's (:func:`slosh_mode_tanks`)."""
    return slosh_mode_tanks(tuple(vehicle.slosh_spec or ()))


def fly_run(case: Case, run: int, keep: bool = False):
    """Fly run ``run``; the :class:`RunOutcome`, plus ``(model, result, signals)`` with
    ``keep`` (for ``savant rerun``). Never raises for a failing run: the error is the
    outcome's status and message."""
    import warnings

    t0 = time.perf_counter()
    stages = np.zeros(len(RUN_STAGES))
    clock = [t0, 0]  # start of the current stage, its index

    def lap(stage: int) -> None:  # the time since the last lap was stage `stage`'s
        now = time.perf_counter()
        stages[stage] += now - clock[0]
        clock[0], clock[1] = now, min(stage + 1, len(RUN_STAGES) - 1)

    samples = case.dispersions.sample(run)
    values = case.dispersions.numbers(run, samples)
    extra = None
    try:
        applied = apply_samples(case.cfg, case.vehicle, case.dispersions.triples(samples),
                                case.dispersions.group_sections)
        model = build_dispersed(applied, case.guidance, case.staging)
        rt = model.rates
        steps = tuple(int(round(t / (rt.dt * rt.n_fcs))) * rt.n_fcs for t in case.linear.times) if case.linear else ()
        lap(0)
        result = simulate(model, progress=False, snapshot_steps=steps)
        lap(1)
        sig = signals(result, model)
        summ = run_summary(result, sig, model, applied.cfg, applied.vehicle.qalpha_limit_Pa_deg)
        keys = [k for k, v in summ.items() if isinstance(v, (int, float)) and not isinstance(v, bool)
                and k not in WALL_KEYS]
        lap(2)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            margins, checks = _margins(case, model, result, sig) if case.linear else (None, None)
        lap(3)
        outcome = RunOutcome(run, result.status, result.message, float(result.t_final), 0.0, values, keys,
                             np.array([float(summ[k]) for k in keys]), np.asarray(result.events, float),
                             _decimate(sig, case.history_signals, case.history_time))
        lap(4)
        if margins is not None:
            outcome.margins, outcome.checks = margins, checks
        if keep:
            extra = (model, result, sig, summ)
    except ConfigError as exc:
        outcome = RunOutcome(run, "invalid", str(exc), float("nan"), 0.0, values)
    except Exception as exc:  # noqa: BLE001 - a failing run is recorded, the batch goes on
        last = traceback.extract_tb(exc.__traceback__)[-1]
        outcome = RunOutcome(run, "failed", f"{type(exc).__name__}: {exc} ({Path(last.filename).name}:{last.lineno})",
                             float("nan"), 0.0, values)
    lap(clock[1])  # the rest (or a failing run's stage up to its exception)
    outcome.wall_s = clock[0] - t0  # the sum of the stages
    outcome.stage_wall_s = stages
    return (outcome, extra) if keep else outcome


# --------------------------------------------------------------------------- journal


def fingerprint(cfg: SavantConfig) -> str:
    """Hash of everything that decides the runs' results (not the worker count, the
    sharding, the progress bar or the outputs)."""
    d = dataclasses.asdict(cfg)
    for k in ("workers", "shard", "shards"):
        d["study"].pop(k, None)
    d.pop("output", None)
    d["sim"].pop("progress", None)
    d["sim"].pop("chunk_s", None)
    return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()


#: A journal entry's file name; group 1 is the run number.
ENTRY_NAME = re.compile(r"run_(\d{6,})\.npz")
#: Temporary names of entries being written (``.run_NNNNNN.npz.<pid>.<random>.tmp``, and
#: ``.run_NNNNNN.<pid>.tmp.npz`` of earlier versions); group 1 is the writer's PID.
TEMP_NAME = re.compile(r"\.run_\d+(?:\.npz)?\.(\d+)\.(?:[0-9a-f]+\.tmp|tmp\.npz)")


def rebuild_hint(path: Path, run: int) -> str:
    """What flies run ``run`` of the journal entry ``path`` (``<batch>/runs/…``) again."""
    return (f"running the batch's command again with hydra.run.dir={path.parent.parent} flies run {run} "
            "again (the other runs are kept)")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # someone else's process
    return True


@dataclass
class JournalScan:
    """The entries of a journal folder: the run numbers that read back whole, and the
    damaged entries by run number."""

    good: dict[int, Path] = field(default_factory=dict)
    damaged: dict[int, DamagedFileError] = field(default_factory=dict)


def scan_entries(folder: Path) -> JournalScan:
    """Read and check every entry of a journal folder (:func:`read_outcome`)."""
    out = JournalScan()
    for p in sorted(folder.glob("run_*.npz")):
        m = ENTRY_NAME.fullmatch(p.name)
        if m is None:
            continue
        run = int(m.group(1))
        try:
            read_outcome(p)
        except DamagedFileError as exc:
            out.damaged[run] = exc
        else:
            out.good[run] = p
    return out


def read_manifest(path: Path) -> dict:
    """A journal's ``manifest.json``, or a :class:`DamagedFileError` naming it."""
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(manifest, dict) or not isinstance(manifest.get("fingerprint"), str):
            raise ValueError("no configuration fingerprint in it")
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise DamagedFileError(path, f"unreadable: {type(exc).__name__}: {exc}",
                               "it records which configuration the runs beside it were flown with; if they are "
                               "this command's, delete it and run the command again to write it anew, else move "
                               "the folder away") from None
    return manifest


class Journal:
    """The ``runs/`` folder of a batch: one checked ``run_NNNNNN.npz`` per finished run."""

    def __init__(self, folder: Path, cfg: SavantConfig, names: list[str],
                 slosh_tanks: tuple[str, ...] = DEFAULT_SLOSH_TANKS) -> None:
        self.folder = folder
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputWriteError(folder / "manifest.json", exc) from exc
        manifest = {"fingerprint": fingerprint(cfg), "n_runs": cfg.study.n_runs, "seed": cfg.study.seed,
                    "dispersions": names}
        if tuple(slosh_tanks) != DEFAULT_SLOSH_TANKS:  # the tanks the runs' slosh mode codes name
            manifest["slosh_tanks"] = list(slosh_tanks)
        path = folder / "manifest.json"
        if path.is_file():
            old = read_manifest(path)
            if old.get("fingerprint") != manifest["fingerprint"]:
                raise ConfigError("hydra.run.dir", str(folder.parent),
                                  "holds runs of a different configuration: choose a new output folder "
                                  "(only study.workers, study.shard(s), sim.progress and output.* may change on resume)")
        else:
            write_text_atomic(path, json.dumps(manifest, indent=1))
        self.manifest = manifest
        self.removed_temps = self._remove_stale_temps()

    def _remove_stale_temps(self) -> list[Path]:
        """Delete the temporary entries a killed writer left (its PID is gone)."""
        removed = []
        for p in self.folder.iterdir():
            m = TEMP_NAME.fullmatch(p.name)
            if m is not None and int(m.group(1)) != os.getpid() and not _alive(int(m.group(1))):
                try:
                    p.unlink()
                except FileNotFoundError:
                    continue
                removed.append(p)
        return removed

    def scan(self) -> JournalScan:
        """The runs already in the journal (read back and checked) and the damaged entries."""
        return scan_entries(self.folder)

    def done(self) -> set[int]:
        """The run numbers whose entries read back whole."""
        return set(self.scan().good)

    def write(self, o: RunOutcome) -> None:
        """Journal one run (atomically, with its checksum); an :class:`OutputWriteError`
        when it cannot be written."""
        write_entry(self.folder / f"run_{o.run:06d}.npz", {
            "run": o.run, "status": o.status, "message": o.message, "t_final": o.t_final, "wall_s": o.wall_s,
            "values": o.values, "summary_keys": np.array(o.summary_keys, dtype=str), "summary": o.summary,
            "events": o.events, "histories": o.histories, "margins": o.margins, "checks": o.checks,
            "stage_wall_s": o.stage_wall_s})


def read_outcome(path: Path) -> RunOutcome:
    """One journal entry, checked (:func:`savant_cli.montecarlo.journal.read_entry`).

    Raises
    ------
    savant_cli.errors.DamagedFileError
        The entry is unreadable, fails its checksum, lacks a member or holds another
        run than its name says; the message names the file, the run and what flies it
        again.
    """
    m = ENTRY_NAME.fullmatch(path.name)
    run = int(m.group(1)) if m else -1
    hint = rebuild_hint(path, run)
    z = read_entry(path, hint)
    try:
        o = RunOutcome(int(z["run"]), str(z["status"]), str(z["message"]), float(z["t_final"]), float(z["wall_s"]),
                       z["values"], [str(k) for k in z["summary_keys"]], z["summary"], _events(z["events"]),
                       z["histories"], z["margins"], z["checks"],
                       z["stage_wall_s"] if "stage_wall_s" in z else np.full(len(RUN_STAGES), np.nan))
    except (KeyError, ValueError, TypeError) as exc:
        raise DamagedFileError(path, f"run {run}: member missing or malformed ({type(exc).__name__}: {exc})",
                               hint) from None
    if m is not None and o.run != run:
        raise DamagedFileError(path, f"holds run {o.run}, not run {run} as its name says", hint)
    return o


# ------------------------------------------------------------------------- execution

_CASE: Case | None = None


def _init_worker(case: Case) -> None:
    global _CASE
    _CASE = case  # SIGINT is ignored by every pool worker (processes.ignore_interrupts)


def _fly(run: int) -> RunOutcome:
    assert _CASE is not None
    return fly_run(_CASE, run)


@dataclass
class BatchStop:
    """How the execution ended: ``"done"``, ``"interrupted"``, ``"worker died"`` or
    ``"write failed"`` (a journal entry could not be written: disk full, folder not
    writable; ``detail`` names it)."""

    reason: str = "done"
    detail: str = ""


def execute(case: Case, todo: Iterable[int], journal: Journal, workers: int,
            on_done: Callable[[RunOutcome], None]) -> BatchStop:
    """Fly ``todo`` on ``workers`` processes (1: in this process), journaling each run
    as it finishes. At most ``2 × workers`` runs are in flight. The workers die with
    this process (:func:`savant_cli.processes.worker_initializer`). A journal entry that
    cannot be written stops the batch (``"write failed"``) with the runs journaled so
    far kept."""
    todo = list(todo)
    if workers <= 1:
        try:
            for run in todo:
                o = fly_run(case, run)
                journal.write(o)
                on_done(o)
        except KeyboardInterrupt:
            return BatchStop("interrupted", "interrupted by the user")
        except OutputWriteError as exc:
            return BatchStop("write failed", str(exc))
        return BatchStop()
    pending: dict[Future, int] = {}
    queue = iter(todo)
    stop = BatchStop()
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=process_context(),
                               **worker_initializer(_init_worker, (case,)))
    try:
        for run in queue:
            pending[pool.submit(_fly, run)] = run
            if len(pending) >= 2 * workers:
                break
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                pending.pop(fut)
                o = fut.result()
                journal.write(o)
                on_done(o)
                nxt = next(queue, None)
                if nxt is not None:
                    pending[pool.submit(_fly, nxt)] = nxt
    except BrokenProcessPool:
        stop = BatchStop("worker died", "a worker process died (killed or out of memory); the runs in flight were lost")
    except KeyboardInterrupt:
        stop = BatchStop("interrupted", "interrupted by the user")
    except OutputWriteError as exc:  # the journal cannot take more runs: stop flying them
        stop = BatchStop("write failed", str(exc))
    finally:
        if stop.reason == "interrupted":
            terminate_workers(pool)  # the runs in flight are abandoned, not waited for
        # An interrupted pool is joined too: its manager thread closes its wake-up pipe as it
        # ends, and one still running at exit races the interpreter's own wake-up call on
        # that pipe ("OSError: Bad file descriptor" printed at exit, CPython 3.11); with the
        # workers ended the join returns as soon as the thread sees them gone. A failed
        # write or a dead worker is not joined (a join there once hung a full-disk batch).
        pool.shutdown(wait=stop.reason in ("done", "interrupted"), cancel_futures=True)
    return stop


def _events(written: np.ndarray) -> np.ndarray:
    """A journal entry's event times in the slots of :data:`EVENT_NAMES` (an entry
    written before the later slots existed has NaN there: those events had no slot)."""
    events = np.full(len(EVENT_NAMES), np.nan)
    written = np.asarray(written, dtype=float)
    events[:written.size] = written
    return events


def shard_runs(n_runs: int, shards: int, shard: int) -> range:
    """The contiguous block of run numbers of one shard."""
    return range(shard * n_runs // shards, (shard + 1) * n_runs // shards)
