"""Say so when the plant is about to compile, and time the kernels' compile or load.

The first run on a machine (or after an upgrade that changes the compiled sources:
``jit_cache.source_key``) compiles the plant, which takes minutes (:data:`ESTIMATE_S`); every later
run loads it from numba's on-disk cache in a fraction of a second. :func:`load_kernels`
calls the flight's compiled entry points once, with the flight's own arguments and
nothing to do (no step flown), before the flight loop starts, so that

* whether numba's cache holds them is known *before* the call (:func:`kernels_cached`:
  an overload for the arguments' types already in the process, or an entry for them in
  the dispatcher's on-disk index), and on a cold cache ONE line on stderr says that the
  plant compiles, why, for about how long and where it is kept, with a spinner while it
  does when stderr is a terminal (rich's status);
* the compile (or load) time is measured apart from the flight: the summary's
  ``compile_time_s``, left out of ``realtime_factor``.

``output.console=quiet`` silences the line (:func:`silenced`).

A cold compile holds an exclusive lock on the cache directory (:func:`compile_lock`):
processes that find the cache cold at the same moment (a test suite's workers, shards
starting together, cluster nodes sharing ``SAVANT_CACHE_DIR``) compile once; the others
wait for it and load what it compiled.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, nullcontext
from typing import Any

#: The cold compile of the nominal flight's kernels, s, on the 2-core reference machine
#: (``benchmarks/cold_start.py``: ``compile_time_s`` 174 s at 4667790, quiet machine):
#: the "about" of the line.
ESTIMATE_S = 175

_state = {"silenced": False}


@contextmanager
def silenced(on: bool = True) -> Iterator[None]:
    """Within the block, no compile line (``on`` False: no change)."""
    before = _state["silenced"]
    _state["silenced"] = before or on
    try:
        yield
    finally:
        _state["silenced"] = before


def _signature(dispatcher: Any, args: Sequence[Any]) -> tuple:
    return tuple(dispatcher.typeof_pyval(a) for a in args)


def kernel_cached(dispatcher: Any, args: Sequence[Any]) -> bool:
    """Whether calling the numba ``dispatcher`` with ``args`` will not compile: the
    process holds an overload for their types, or numba's on-disk cache has one for
    this machine (its index, read without loading the code). A dispatcher that cannot
    be inspected counts as cached (no false line)."""
    try:
        sig = _signature(dispatcher, args)
        if sig in dispatcher.overloads:
            return True
        cache = dispatcher._cache
        key = cache._index_key(sig, dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - a numba without these internals: say nothing
        return True


def kernels_cached(calls: Sequence[tuple[Any, Sequence[Any]]]) -> bool:
    """Whether every ``(dispatcher, args)`` of ``calls`` is cached (:func:`kernel_cached`)."""
    return all(kernel_cached(f, a) for f, a in calls)


def cache_dir(dispatcher: Any | None = None) -> str:
    """Where the compiled kernels are kept: numba's cache directory (set by
    :mod:`savant_cli.jit_cache`), else the dispatcher's own cache path."""
    where = os.environ.get("NUMBA_CACHE_DIR")
    if not where and dispatcher is not None:
        where = getattr(getattr(dispatcher, "_cache", None), "cache_path", None)
    return str(where or "numba's default cache")


def compile_line(where: str, estimate_s: float = ESTIMATE_S) -> str:
    """The line said before a cold compile."""
    return f"compiling the plant for this machine, once (about {estimate_s:.0f} s); cached in {where}"


@contextmanager
def compiling(where: str, estimate_s: float = ESTIMATE_S) -> Iterator[None]:
    """Say :func:`compile_line` on stderr (unless :func:`silenced`), with a spinner
    while the block runs when stderr is a terminal."""
    if _state["silenced"]:
        yield
        return
    from rich.console import Console

    from savant_cli.io.console import live_display_ok

    console = Console(stderr=True)
    line = compile_line(where, estimate_s)
    if not (console.is_terminal and live_display_ok(console)):
        sys.stderr.write(f"savant: {line}\n")
        sys.stderr.flush()
        yield
        return
    console.print(f"savant: {line}", highlight=False, soft_wrap=True)
    with console.status("compiling the plant …", spinner="dots"):
        yield


def _compile_in_child(dispatcher: Any, args: Sequence[Any]) -> None:
    dispatcher(*args)  # compiles, and numba saves it to the on-disk cache


@contextmanager
def compiled_apart(dispatcher: Any, args: Sequence[Any]) -> Iterator[None]:
    """Within the block, a forked helper process compiles ``dispatcher`` for ``args``
    (into numba's on-disk cache) while this process compiles the rest; when this
    process comes to need ``dispatcher`` it waits for the helper and loads its result
    from the cache rather than compiling it again. Both cores work on a cold compile.

    Nothing happens when ``dispatcher`` is already cached or the platform cannot fork.
    The call in the helper must do nothing the caller would see (it writes only into
    the helper's copies of ``args``)."""
    import multiprocessing

    if not hasattr(os, "fork") or kernel_cached(dispatcher, args):
        yield
        return
    helper = multiprocessing.get_context("fork").Process(target=_compile_in_child, args=(dispatcher, args),
                                                          name="savant-compile", daemon=True)
    helper.start()
    own_compile = dispatcher.compile

    def compile_after_helper(sig: Any) -> Any:
        helper.join()
        return own_compile(sig)

    dispatcher.compile = compile_after_helper  # numba compiles a callee through this method
    try:
        yield
    finally:
        del dispatcher.compile
        if helper.is_alive():
            helper.terminate()
        helper.join()


#: The lock file a cold compile holds in the cache directory.
LOCK_NAME = ".savant-compile.lock"


@contextmanager
def compile_lock(where: str) -> Iterator[None]:
    """Within the block, an exclusive ``flock`` on :data:`LOCK_NAME` in the directory
    ``where`` (waiting for the process that holds it); no lock when the directory or
    ``fcntl`` is not there or the file cannot be opened (a compile then goes ahead
    unserialised, as numba's cache allows)."""
    try:
        import fcntl
        fd = os.open(os.path.join(where, LOCK_NAME), os.O_RDWR | os.O_CREAT, 0o666)
    except (ImportError, OSError):
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        fcntl.flock(fd, fcntl.LOCK_UN)  # (a helper forked meanwhile shares the descriptor: release it explicitly)
        os.close(fd)


def load_kernels(calls: Sequence[tuple[Callable[..., Any], Sequence[Any]]],
                 apart: tuple[Any, Sequence[Any]] | None = None) -> float:
    """Call each compiled ``(dispatcher, args)`` of ``calls`` once (they must do nothing
    the flight would see), announcing the compile on a cold cache (:func:`compiling`);
    ``apart``, a ``(dispatcher, args)`` the calls compile on the way, is compiled by a
    helper process meanwhile (:func:`compiled_apart`). A cold compile holds
    :func:`compile_lock` on the cache directory; a process that waited for another's finds
    the kernels cached and loads them. Returns the wall time, s."""
    t0 = time.perf_counter()
    if kernels_cached(calls):
        for f, args in calls:
            f(*args)
        return time.perf_counter() - t0
    where = cache_dir(calls[0][0] if calls else None)
    with compiling(where), compile_lock(where):
        with nullcontext() if kernels_cached(calls) or apart is None else compiled_apart(*apart):
            for f, args in calls:
                f(*args)
    return time.perf_counter() - t0
