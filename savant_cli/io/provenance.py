"""Where a run came from: software versions, source revision, machine and time.

Stored as string attributes on the root of ``savant.h5`` (see ``docs/outputs.md``).
"""

from __future__ import annotations

import os
import platform
import socket
import subprocess
import sys
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from savant_cli.version import __version__

_GIT_TIMEOUT_S = 5.0


def _git(args: list[str], cwd: Path) -> str | None:
    """Output of a read-only git command in ``cwd``; None when git or the repo is absent.

    ``--no-optional-locks`` keeps ``git status`` from rewriting the index, so collecting
    provenance never modifies the repository.
    """
    env = dict(os.environ, GIT_OPTIONAL_LOCKS="0", LC_ALL="C")
    try:
        out = subprocess.run(
            ["git", "--no-optional-locks", *args], cwd=cwd, env=env, capture_output=True, text=True,
            timeout=_GIT_TIMEOUT_S, check=True, stdin=subprocess.DEVNULL,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip()


def git_state(directory: Path) -> tuple[str, str]:
    """Commit and dirty flag of the git work tree containing ``directory``.

    Parameters
    ----------
    directory : pathlib.Path
        Any directory inside the work tree.

    Returns
    -------
    commit : str
        ``git rev-parse HEAD``, or ``""`` when ``directory`` is not in a git repository
        (or git is not installed, or the repository has no commit yet).
    dirty : str
        ``"true"`` when tracked files have uncommitted changes, ``"false"`` when clean,
        ``""`` when not a repository.
    """
    if not directory.is_dir():
        return "", ""
    commit = _git(["rev-parse", "HEAD"], directory)
    if not commit:
        return "", ""
    status = _git(["status", "--porcelain", "--untracked-files=no"], directory)
    dirty = "" if status is None else ("true" if status else "false")
    return commit, dirty


def _dist_version(name: str) -> str:
    try:
        return version(name)
    except PackageNotFoundError:
        return ""


def collect_provenance(wall_time_s: float | None = None) -> dict[str, str]:
    """Describe the software and machine producing a run.

    Parameters
    ----------
    wall_time_s : float, optional
        Wall-clock duration of the run (s), recorded as ``wall_time_s`` when given.

    Returns
    -------
    dict of str to str
        ``savant_version``; ``git_commit`` and ``git_dirty`` of the repository holding the
        current working directory; ``source_git_commit`` and ``source_git_dirty`` of the
        repository holding the ``savant_cli`` package source (``""`` when it is an
        installed copy, not a checkout); ``python``, ``numpy``, ``scipy``, ``numba``,
        ``h5py`` versions (``""`` when not installed); ``platform``; ``host``;
        ``created_utc`` (ISO 8601, seconds); ``command`` (the process argv) and, if given,
        ``wall_time_s``. Every value is a string; git failures give ``""``, never an
        exception.
    """
    commit, dirty = git_state(Path.cwd())
    src_commit, src_dirty = git_state(Path(__file__).resolve().parents[1])  # the savant_cli source folder
    prov = {
        "savant_version": str(__version__),
        "git_commit": commit,
        "git_dirty": dirty,
        "source_git_commit": src_commit,
        "source_git_dirty": src_dirty,
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "numpy": _dist_version("numpy"),
        "scipy": _dist_version("scipy"),
        "numba": _dist_version("numba"),
        "h5py": _dist_version("h5py"),
        "platform": platform.platform(),
        "host": socket.gethostname(),
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join(sys.argv),
    }
    if wall_time_s is not None:
        prov["wall_time_s"] = f"{float(wall_time_s):.3f}"
    return prov
