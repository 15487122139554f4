"""One writer per run folder: an exclusive OS file lock held for the life of a run.

Every command that writes into a run folder (``savant run`` and every study,
``savant_cli.run``, ``savant report``, ``savant collect``, ``savant rerun``) first takes
an exclusive :func:`fcntl.flock` on the file ``.savant.lock`` in that folder and holds it
until the process ends. A second writer finds the lock taken and is refused with
:class:`FolderBusy` (a :class:`~savant_cli.errors.ConfigError`, exit status 2) naming the
folder and the holder's PID, host and start time, which the holder writes into the lock
file once it holds the lock.

The lock is the kernel's, not the file's existence: the kernel releases it when the
holder's last descriptor closes, so a holder killed by any signal (``kill -9``
included) never leaves a stale lock, and the lock file stays in the folder after the run
(deleting it would let a waiting writer lock a file no longer in the folder). Forked
children (the Monte Carlo workers) close their inherited copy of the descriptor at once
(:func:`os.register_at_fork`): the lock belongs to the command, and dies with it even if
a worker outlives it. On NFS, Linux emulates ``flock`` with POSIX record locks, which
the server arbitrates between hosts (NFSv4, or NFSv3 with the lock manager); the holder's
host in the message says which machine to look at.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import socket
import sys
import time
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from savant_cli.errors import ConfigError

#: The lock file's name in a run folder.
LOCK_NAME = ".savant.lock"

#: How long a refused writer waits for the holder to write its PID and host into a lock
#: file it has just locked (s): the holder writes them right after taking the lock.
HOLDER_WAIT_S = 1.0


class FolderBusy(ConfigError):
    """A run folder is locked by another process (exit status 2).

    Parameters
    ----------
    key : str
        The config key or argument that named the folder (``hydra.run.dir``, ``RUN_DIR``).
    folder : pathlib.Path
        The folder.
    holder : dict
        What the holder wrote into the lock file (``pid``, ``host``, ``started_utc``,
        ``command``); empty when it could not be read.
    """

    def __init__(self, key: str, folder: Path, holder: dict[str, Any]) -> None:
        self.folder = folder
        self.holder = holder
        if holder.get("pid"):
            who = f"PID {holder['pid']} on host {holder.get('host', '?')}"
            if holder.get("started_utc"):
                who += f", since {holder['started_utc']}"
            if holder.get("command"):
                who += f": {holder['command']}"
        else:
            who = "another process (it has not written its PID and host yet)"
        super().__init__(key, str(folder), f"is being written by {who}; one writer per run folder: wait for it to "
                                           "finish, or choose another folder")


class RunFolderLock:
    """An exclusive lock on a run folder (module notes), held until :meth:`release` or
    the end of the process.

    Use :func:`acquire` to take one.

    Attributes
    ----------
    folder : pathlib.Path
        The locked folder (absolute).
    created : bool
        Whether this lock created the folder (it did not exist before): what an
        interrupted command may remove again (:mod:`savant_cli.lifecycle`).
    """

    def __init__(self, folder: Path, fd: int, created: bool) -> None:
        self.folder = folder
        self.created = created
        self._fd = fd

    @property
    def held(self) -> bool:
        """Whether this process still holds the lock."""
        return self._fd >= 0

    def release(self) -> None:
        """Unlock and close (the lock file stays)."""
        if self._fd >= 0:
            _HELD.pop(self.folder, None)
            os.close(self._fd)  # closing the last descriptor releases the flock
            self._fd = -1

    def discard(self) -> None:
        """Release, and remove the folder again when this lock created it and it holds
        nothing but the lock file (a command refused before writing anything)."""
        self.release()
        if self.created and self.folder.is_dir() and {p.name for p in self.folder.iterdir()} <= {LOCK_NAME}:
            (self.folder / LOCK_NAME).unlink(missing_ok=True)
            try:
                self.folder.rmdir()
            except OSError:  # something appeared meanwhile: keep it
                pass

    def __enter__(self) -> "RunFolderLock":
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


#: The locks this process holds, by folder.
_HELD: dict[Path, RunFolderLock] = {}


def _close_in_child() -> None:
    """After a fork: close the child's copies of the lock descriptors (the parent keeps
    the lock; only a ``LOCK_UN`` or the close of the last copy would release it)."""
    for lock in list(_HELD.values()):
        try:
            os.close(lock._fd)
        except OSError:
            pass
        lock._fd = -1
    _HELD.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_close_in_child)


def held(folder: Path | str | None = None) -> list[RunFolderLock]:
    """The locks this process holds (on ``folder`` only, when given), oldest first."""
    if folder is None:
        return list(_HELD.values())
    lock = _HELD.get(Path(folder).expanduser().resolve())
    return [lock] if lock is not None else []


def read_holder(folder: Path | str) -> dict[str, Any]:
    """What the last holder wrote into ``folder``'s lock file (empty when absent or not
    readable)."""
    try:
        text = (Path(folder) / LOCK_NAME).read_text(encoding="utf-8")
        data = json.loads(text) if text.strip() else {}
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _holder_record() -> dict[str, Any]:
    return {"pid": os.getpid(), "host": socket.gethostname(),
            "started_utc": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "command": " ".join(["savant" if i == 0 else a for i, a in enumerate(sys.argv)])[:300]}


def acquire(folder: Path | str, key: str = "hydra.run.dir") -> RunFolderLock:
    """Lock ``folder`` for this process, creating it when missing.

    Returns at once: a folder held by another process is refused, not waited for. A
    folder this process already holds returns the lock it holds.

    Parameters
    ----------
    folder : pathlib.Path or str
        The run folder.
    key : str
        The config key or argument that named it, for the refusal's message.

    Returns
    -------
    RunFolderLock
        The lock (its ``created`` says whether the folder is new).

    Raises
    ------
    FolderBusy
        Another process holds the folder.
    ConfigError
        The folder cannot be created, or is not a folder.
    """
    path = Path(folder).expanduser().resolve()
    if path in _HELD:
        return _HELD[path]
    lock_file = path / LOCK_NAME
    created = False
    if path.exists() and not path.is_dir():
        raise ConfigError(key, str(path), "exists and is not a folder")
    if not path.exists():
        try:
            path.mkdir(parents=True)
            created = True
        except FileExistsError:  # another writer made it just now: the lock decides
            pass
        except OSError as exc:
            raise ConfigError(key, str(path), f"cannot be created: {exc.strerror or exc}") from None
    try:
        fd = os.open(lock_file, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        raise ConfigError(key, str(path), f"cannot hold a lock file ({lock_file}): {exc.strerror or exc}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        os.close(fd)
        if exc.errno not in (errno.EWOULDBLOCK, errno.EACCES, errno.EAGAIN):
            raise ConfigError(key, str(path), f"cannot be locked: {exc.strerror or exc}") from None
        raise FolderBusy(key, path, _wait_for_holder(path)) from None
    record = json.dumps(_holder_record(), indent=1).encode()
    os.ftruncate(fd, 0)
    os.pwrite(fd, record, 0)
    os.fsync(fd)
    lock = RunFolderLock(path, fd, created)
    _HELD[path] = lock
    return lock


def refuse_if_busy(folder: Path | str, key: str = "hydra.run.dir") -> None:
    """Raise :class:`FolderBusy` when another process holds ``folder``; create and
    write nothing (a folder without a lock file is free).

    Raises
    ------
    FolderBusy
        Another process holds the folder.
    """
    path = Path(folder).expanduser().resolve()
    if path in _HELD:
        return
    try:
        fd = os.open(path / LOCK_NAME, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return  # no lock file: nobody ever locked it, or it is not readable
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        raise FolderBusy(key, path, _wait_for_holder(path)) from None
    finally:
        os.close(fd)  # a shared probe lock ends with its descriptor


def _wait_for_holder(path: Path) -> dict[str, Any]:
    """The holder's record; a holder that has just taken the lock writes it at once,
    so an empty or foreign record is read again for up to :data:`HOLDER_WAIT_S`."""
    deadline = time.monotonic() + HOLDER_WAIT_S
    while True:
        holder = read_holder(path)
        if holder.get("pid") or time.monotonic() > deadline:
            return holder
        time.sleep(0.05)
