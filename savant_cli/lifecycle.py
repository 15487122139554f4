"""Where a command is in its life, and what a Ctrl-C leaves behind.

A command names its stage as it goes (:func:`stage`: ``startup``, ``prepare``,
``flight``, ``analysis``, ``writing``, ``plots``, ``report``, ``runs``, ``outputs``).
On ``KeyboardInterrupt`` the command line and :func:`savant_cli.run` call
:func:`settle_interrupt`, which leaves every run folder this process holds
(:mod:`savant_cli.run_lock`) in one of two states and returns the one line to print:

* **nothing written**: a folder this command created that holds nothing but Hydra's
  record (``.hydra/``, the job log) and the lock file is removed again;
* **marked interrupted**: any other folder gets ``interrupted.json`` (stage, time, what
  is complete, how to finish). Every file in it is whole (atomic writes); what the
  stage had not written yet is missing. A later command that completes in the folder
  (the same run again, ``savant report``, a resumed batch) removes the marker.

A study that keeps what it computed before the interrupt (the nominal flight's partial
history, a batch's journaled runs) writes it, then raises
:class:`~savant_cli.errors.RunInterrupted` with its own line (true counts, the flight
time reached). After the first Ctrl-C a second one is ignored while the folder is
settled, so the one line is the last word.

``SAVANT_TEST_PAUSE_AT=<stage>`` makes the process stop at that stage (the first time it
is entered), say ``savant: paused at <stage>`` on stderr and sleep until SIGUSR1 (or
two minutes), so that tests can interrupt, kill or hold it there deterministically.
Nothing else reads it.
"""

from __future__ import annotations

import os
import shutil
import signal
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from savant_cli import run_lock
from savant_cli.errors import RunInterrupted

#: The marker file of an interrupted run folder.
MARKER = "interrupted.json"

#: Environment variable of the test pause (module notes).
PAUSE_ENV = "SAVANT_TEST_PAUSE_AT"

#: How long the test pause sleeps (s) before going on by itself.
PAUSE_S = 120.0

#: What each stage is doing, for the marker and the interrupt line.
STAGES = {"startup": "starting up", "prepare": "loading the vehicle and building the model",
          "flight": "flying", "analysis": "analysing the flight", "writing": "writing the run files",
          "plots": "drawing the plots", "report": "writing report.html", "runs": "flying the batch's runs",
          "outputs": "writing the batch's tables and plots", "study": "running the study",
          "searches": "running the time-margin searches"}

#: What Hydra writes into a run folder before a study runs (besides the lock file).
HYDRA_RECORD = {".hydra", run_lock.LOCK_NAME}

_current = "startup"
_paused: set[str] = set()


def stage(name: str) -> None:
    """Enter stage ``name`` (a key of :data:`STAGES`); the test pause (module notes)."""
    global _current
    _current = name
    if os.environ.get(PAUSE_ENV) == name and name not in _paused:
        _paused.add(name)
        _pause(name)


def _pause(name: str) -> None:
    """The test pause: say so, then sleep until SIGUSR1 (go on), an interrupt or
    :data:`PAUSE_S`."""
    resumed: list[int] = []
    try:
        previous = signal.signal(signal.SIGUSR1, lambda *_: resumed.append(1))
    except ValueError:  # not the main thread
        previous = None
    sys.stderr.write(f"savant: paused at {name} ({PAUSE_ENV})\n")
    sys.stderr.flush()
    deadline = time.monotonic() + PAUSE_S
    try:
        while not resumed and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        if previous is not None:
            signal.signal(signal.SIGUSR1, previous)


def current() -> str:
    """The stage the process is in."""
    return _current


def discard_if_untouched(lock: run_lock.RunFolderLock) -> bool:
    """Release ``lock`` and remove its folder when this command created the folder and
    nothing but Hydra's record is in it (a command refused before its study wrote
    anything); whether it was removed."""
    folder = lock.folder
    if not (lock.created and folder.is_dir() and _only_hydra_record(folder)):
        return False
    lock.release()
    shutil.rmtree(folder, ignore_errors=True)
    return True


def _only_hydra_record(folder: Path) -> bool:
    """Whether ``folder`` holds nothing but Hydra's record, job logs and the lock file."""
    for entry in folder.iterdir():
        if entry.name in HYDRA_RECORD or (entry.suffix == ".log" and entry.is_file()):
            continue
        return False
    return True


def _finish_hint(folder: Path) -> str:
    """What is whole in an interrupted folder and how to finish it."""
    if (folder / "savant.h5").is_file():
        return (f"savant.h5 and the files beside it are whole; `savant report {folder}` draws the missing plots "
                "and report.html, or run the command again")
    return "every file in it is whole, the run's results are not there; run the command again"


def write_marker(folder: Path, stage_name: str, detail: str) -> Path:
    """Write ``folder/interrupted.json``: the stage, its description, the time, the
    files that are complete and ``detail`` (how to finish)."""
    from savant_cli.io.atomic import write_json_atomic

    complete = sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                      if p.is_file() and not p.name.startswith(".") and p.name != MARKER
                      and ".hydra" not in p.relative_to(folder).parts)
    path = folder / MARKER
    write_json_atomic(path, {"status": "interrupted", "stage": stage_name, "doing": STAGES.get(stage_name, stage_name),
                             "time_utc": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
                             "pid": os.getpid(), "complete_files": complete, "detail": detail})
    return path


def clear_marker(folder: Path | str) -> None:
    """Remove ``interrupted.json`` from a folder a command has just completed."""
    try:
        (Path(folder) / MARKER).unlink()
    except FileNotFoundError:
        pass


def settle_interrupt(exc: BaseException, restore: bool = True) -> str:
    """Settle the folders this process holds after ``exc`` (a ``KeyboardInterrupt``)
    and return the one line to print (module notes).

    Parameters
    ----------
    exc : BaseException
        The interrupt (a :class:`~savant_cli.errors.RunInterrupted` carries the study's
        own account of what it wrote).
    restore : bool
        Give Ctrl-C its previous handler back afterwards (a notebook goes on); the
        command line passes False and exits, a further Ctrl-C ignored to the end.

    Returns
    -------
    str
        The line: the stage, and for each held folder whether it was removed or marked.
    """
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: signals are the main thread's
        previous = None
    try:
        return _settle(exc)
    finally:
        if restore and previous is not None:
            signal.signal(signal.SIGINT, previous)


def _settle(exc: BaseException) -> str:
    at = current()
    detail = exc.detail if isinstance(exc, RunInterrupted) else ""
    at = exc.stage if isinstance(exc, RunInterrupted) and exc.stage else at
    doing = STAGES.get(at, at)
    locks = run_lock.held()
    if not locks:
        return f"interrupted while {doing}: nothing was written"
    lines = []
    for lock in reversed(locks):  # innermost (latest) first
        folder = lock.folder
        if not folder.is_dir():
            continue
        if discard_if_untouched(lock):
            lines.append(f"nothing was written ({folder} removed)")
            continue
        how = detail or _finish_hint(folder)
        write_marker(folder, at, how)
        lines.append(f"{folder} is marked interrupted ({MARKER}): {how}")
    if not lines:
        return f"interrupted while {doing}: nothing was written"
    return f"interrupted while {doing}: " + "; ".join(lines)
