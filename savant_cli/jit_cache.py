"""Where numba keeps the compiled kernels.

numba's on-disk cache of a function is invalidated only when the file defining *that*
function changes, not when a function it calls (and inlines) changes in another file.
An edited plant would then keep running the old compiled engine. Keying the cache
directory on a hash of every compiled module's source (and the numba version) makes any
such edit start a fresh cache. It also keeps caches out of a possibly read-only
``site-packages``.

The directory is ``$NUMBA_CACHE_DIR`` when the user sets it (then no keying is done),
else ``$XDG_CACHE_HOME/savant/numba-<hash>`` (``~/.cache`` by default). Directories of
other source versions unused for a week are removed.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
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


def configure() -> None:
    """Point numba's cache at the source-keyed directory (before anything compiles)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "savant"
    cache = base / f"numba-{source_key()}"
    try:
        cache.mkdir(parents=True, exist_ok=True)
        os.utime(cache)  # marks it as in use for the pruning of old versions
    except OSError:
        return  # unwritable home: numba falls back to its own default locations
    _prune(base, cache)
    os.environ["NUMBA_CACHE_DIR"] = str(cache)
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before us: numba reads its config at import
        numba.config.CACHE_DIR = str(cache)
