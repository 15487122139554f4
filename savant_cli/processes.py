"""Worker processes shared by the studies that spread work over the cores (the Monte
Carlo batch, the flight-control design's candidate judgements, the time-domain margin
searches).

Workers die with their parent. However the main process ends (``kill -9``, out of
memory, a crash), its pool workers must not live on as orphans holding memory and
cores. Every pool therefore starts its workers through :func:`worker_initializer`:

* on Linux the worker asks the kernel for ``SIGKILL`` when its parent dies
  (``prctl(PR_SET_PDEATHSIG, SIGKILL)`` through :mod:`ctypes`), then checks that the
  parent it was forked from is still its parent (it may have died before the request);
* elsewhere (no ``prctl``) a daemon thread polls the parent's PID once a second and
  ends the worker with :func:`os._exit` when the worker has been re-parented.

``SIGKILL`` rather than a polite signal: a worker holds nothing to save (only the main
process writes the journal and the outputs), and a forked worker may have inherited
handlers that would keep it alive.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

#: ``PR_SET_PDEATHSIG`` from ``<linux/prctl.h>``.
PR_SET_PDEATHSIG = 1
#: Seconds between two looks at the parent's PID by the portable watchdog.
WATCHDOG_PERIOD_S = 1.0


def process_context() -> mp.context.BaseContext:
    """``fork`` on Linux: a worker inherits the built model, the frozen plants and the
    loaded compiled engine without pickling them; ``spawn`` elsewhere."""
    return mp.get_context("fork" if sys.platform.startswith("linux") else "spawn")


def default_workers() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _set_parent_death_signal(sig: int) -> bool:
    """Ask the Linux kernel to send ``sig`` to this process when its parent dies; False
    where ``prctl`` does not exist or refuses."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, ctypes.c_ulong(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_parent(parent: int, period_s: float) -> None:
    """Body of the watchdog thread: exit the process once it is no longer ``parent``'s child."""
    while os.getppid() == parent:
        time.sleep(period_s)
    os._exit(1)


def die_with_parent(parent: int) -> str:
    """Make this (worker) process end when process ``parent`` ends.

    Parameters
    ----------
    parent : int
        PID of the process that started this one (the pool's owner).

    Returns
    -------
    str
        ``"prctl"`` (the kernel's parent-death signal) or ``"watchdog"`` (a thread
        polling the parent PID every :data:`WATCHDOG_PERIOD_S` s).
    """
    if _set_parent_death_signal(signal.SIGKILL):
        if os.getppid() != parent:  # the parent died before the request took effect
            os._exit(1)
        return "prctl"
    if os.getppid() != parent:
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent, WATCHDOG_PERIOD_S), name="savant-parent-watchdog",
                     daemon=True).start()
    return "watchdog"


def ignore_interrupts() -> None:
    """Ignore SIGINT in a pool worker. A terminal's Ctrl-C reaches the whole process
    group; the main process answers it (one line, exit 130, docs/outputs.md) and ends
    the workers with :func:`terminate_workers`, where each worker interrupted on its own
    would print a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def terminate_workers(pool: ProcessPoolExecutor) -> None:
    """End a pool's worker processes now (SIGTERM), abandoning the work in flight: what
    the main process does on a Ctrl-C before it shuts the pool down. The standard library
    has no public call for it before Python 3.14 (``terminate_workers``)."""
    if hasattr(pool, "terminate_workers"):
        pool.terminate_workers()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        if proc.is_alive():
            proc.terminate()


def _init(parent: int, initializer: Callable[..., Any] | None, initargs: tuple) -> None:
    die_with_parent(parent)
    ignore_interrupts()
    if initializer is not None:
        initializer(*initargs)


def worker_initializer(initializer: Callable[..., Any] | None = None,
                       initargs: tuple = ()) -> dict[str, Any]:
    """``initializer`` and ``initargs`` for a :class:`~concurrent.futures.ProcessPoolExecutor`
    whose workers die with this process (:func:`die_with_parent`) and leave a Ctrl-C to
    it (:func:`ignore_interrupts`), then run ``initializer(*initargs)``.

    Parameters
    ----------
    initializer : callable, optional
        The pool's own worker initializer (module-level, picklable for ``spawn``).
    initargs : tuple
        Its arguments.

    Returns
    -------
    dict
        Keyword arguments for ``ProcessPoolExecutor(..., **worker_initializer(...))``.
    """
    return {"initializer": _init, "initargs": (os.getpid(), initializer, tuple(initargs))}
