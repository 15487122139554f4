"""Where numba keeps the compiled kernels.

numba's on-disk cache of a function is invalidated only when the file defining *that*
function changes, not when a function it calls (and inlines) changes in another file.
An edited plant would then keep running the old compiled engine. Keying the cache
directory on a hash of every compiled module's source (and the numba version) makes any
such edit start a fresh cache. It also keeps caches out of a possibly read-only
``site-packages``.

The directory is, in this order:

1. ``$NUMBA_CACHE_DIR`` when the user sets it (then no keying is done);
2. ``$SAVANT_CACHE_DIR/numba-<hash>``: savant's cache root, for a read-only home or a
   cluster (a node-local disk such as ``/tmp`` or ``$TMPDIR``, or one shared folder that
   every node writes: the key keeps different source versions apart);
3. ``$XDG_CACHE_HOME/savant/numba-<hash>`` (``~/.cache`` by default).

The chosen directory is created and checked by writing a probe file. When it cannot be
written (a read-only home, a full disk, a permission), the kernels go to
``<tempdir>/savant-<uid>/numba-<hash>`` instead and ONE warning on stderr names the
directory, the reason and the variable to set, rather than numba silently compiling
every run anew. Directories of other source versions unused for a week are removed.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import tempfile
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

# packages whose modules hold numba-compiled functions
_COMPILED_PACKAGES = ("models", "sim")
_STALE_AFTER_S = 7 * 86400


def source_key() -> str:
    """Hash of the compiled modules' sources and the numba version."""
    h = hashlib.sha256()
    try:
        h.update(version("numba").encode())
    except PackageNotFoundError:  # pragma: no cover - numba is a hard dependency
        pass
    root = Path(__file__).resolve().parent
    for pkg in _COMPILED_PACKAGES:
        for path in sorted((root / pkg).glob("*.py")):
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _prune(parent: Path, keep: Path) -> None:
    now = time.time()
    for d in parent.glob("numba-*"):
        try:
            if d != keep and d.is_dir() and now - d.stat().st_mtime > _STALE_AFTER_S:
                shutil.rmtree(d, ignore_errors=True)
        except OSError:
            pass


def writable(folder: Path) -> str | None:
    """Create ``folder`` and write and remove a probe file in it; None when that works,
    else the reason (the OS error)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".savant-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
        os.utime(folder)  # marks it as in use for the pruning of old versions
    except OSError as exc:
        return f"{type(exc).__name__}: {exc.strerror or exc}"
    return None


def _use(cache: Path) -> None:
    os.environ["NUMBA_CACHE_DIR"] = str(cache)
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before us: numba reads its config at import
        numba.config.CACHE_DIR = str(cache)


def configure() -> None:
    """Point numba's cache at the source-keyed directory (before anything compiles);
    warn once on stderr and use a temporary directory when it is not writable."""
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        cache, var = Path(user), "NUMBA_CACHE_DIR"
    elif os.environ.get("SAVANT_CACHE_DIR"):
        cache, var = Path(os.environ["SAVANT_CACHE_DIR"]) / f"numba-{source_key()}", "SAVANT_CACHE_DIR"
    else:
        cache, var = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "savant" / f"numba-{source_key()}", ""
    reason = writable(cache)
    if reason is None:
        if not user:
            _prune(cache.parent, cache)
            _use(cache)
        return
    fallback = Path(tempfile.gettempdir()) / f"savant-{os.getuid() if hasattr(os, 'getuid') else 'user'}" \
        / f"numba-{source_key()}"
    fallback_reason = writable(fallback)
    where = (f"compiled kernels go to {fallback} for now (node-local, lost on a reboot)" if fallback_reason is None
             else f"nor is {fallback} ({fallback_reason}): numba compiles anew in every process")
    hint = (f"set {var} to a writable directory" if var == "NUMBA_CACHE_DIR"
            else "set SAVANT_CACHE_DIR to a writable directory (docs/montecarlo.md, \"The numba cache on clusters\")")
    sys.stderr.write(f"savant: warning: the numba cache {cache} is not writable ({reason}); {where}; {hint}\n")
    if fallback_reason is None:
        _use(fallback)  # child processes inherit it: one warning per command
