"""Exceptions that the command line turns into clear messages and exit codes.

The errors the command line reports in one line, without a traceback, are
:class:`SavantError`: the message is the whole story (what, where, what is allowed or
what rebuilds it) and ``exit_code`` is the status the command line exits with, 2 for bad
input or a damaged file, 1 for an output that could not be written. A diverging flight
(:class:`SimulationDiverged`) is a result, not an error of the command.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any


class SavantError(Exception):
    """Base of the errors savant reports as one line, without a traceback."""

    exit_code = 1


class ConfigError(SavantError, ValueError):
    """A configuration or data-file problem found before any computation.

    Parameters
    ----------
    key : str
        Dotted config path (``vehicle.stages.first.isp_vac_s``) or a file path with
        its column (``conf/vehicle/ares_i/mass_stack.csv:mass_kg``).
    value : Any
        The offending value (shortened when long).
    allowed : str
        What would have been accepted.
    """

    exit_code = 2

    def __init__(self, key: str, value: Any, allowed: str) -> None:
        self.key = key
        self.value = value
        self.allowed = allowed
        text = repr(value)
        if len(text) > 120:
            text = text[:117] + "..."
        super().__init__(f"{key} = {text}: {allowed}")


class DamagedFileError(SavantError, OSError):
    """A file savant wrote earlier that cannot be read back (truncated, overwritten,
    wrong checksum).

    Parameters
    ----------
    path : pathlib.Path or str
        The damaged file.
    problem : str
        What is wrong with it (``truncated: 1,024 of 88,310 bytes``, ``checksum mismatch``).
    rebuild : str
        What writes it again (``run the same command again: …``).
    """

    exit_code = 2

    def __init__(self, path: Path | str, problem: str, rebuild: str) -> None:
        self.path = Path(path)
        self.problem = problem
        self.rebuild = rebuild
        super().__init__(f"{self.path} is damaged ({problem}); {rebuild}")


def _reason(exc: BaseException) -> str:
    """The operating system's words for why a write failed: ``strerror`` of the errno,
    found on the exception or in h5py's message (``errno = 28``), else the message."""
    errno = getattr(exc, "errno", None)
    if not isinstance(errno, int):
        found = re.search(r"errno = (\d+)", str(exc))
        errno = int(found.group(1)) if found else None
    if isinstance(errno, int) and errno > 0:
        return f"{os.strerror(errno)} (errno {errno})"
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


class OutputWriteError(SavantError, OSError):
    """An output file that could not be written (disk full, folder not writable); the
    file keeps its previous content, or does not exist.

    Parameters
    ----------
    path : pathlib.Path or str
        The file that could not be written.
    cause : BaseException
        The operating system's (or h5py's) error.
    """

    exit_code = 1

    def __init__(self, path: Path | str, cause: BaseException) -> None:
        self.path = Path(path)
        self.reason = _reason(cause)
        super().__init__(f"could not write {self.path.name} in {self.path.parent}: {self.reason}")

    def __reduce__(self) -> tuple:
        # rebuilt from its path and reason when it crosses a process boundary (a figure
        # drawn by a worker process into a full disk)
        return (_output_write_error, (str(self.path), self.reason))


def _output_write_error(path: str, reason: str) -> OutputWriteError:
    """An :class:`OutputWriteError` rebuilt from its path and its reason's words."""
    return OutputWriteError(path, OSError(reason))


class SimulationDiverged(RuntimeError):
    """A run stopped because a signal became non-finite or nonsensical."""

    def __init__(self, time_s: float, signal: str, detail: str) -> None:
        self.time_s = time_s
        self.signal = signal
        self.detail = detail
        super().__init__(f"run diverged at t = {time_s:.3f} s: {signal} {detail}")


class RunInterrupted(KeyboardInterrupt):
    """A Ctrl-C that a study has already answered: it wrote what it had computed and
    says so in ``detail`` (the flight time reached, the runs flown), which the interrupt
    line and the folder's ``interrupted.json`` repeat (:mod:`savant_cli.lifecycle`).

    A ``KeyboardInterrupt`` so that every ``except Exception`` lets it through.

    Parameters
    ----------
    stage : str
        The stage it stopped in (``flight``, ``runs`` …).
    detail : str
        What was written and how to finish, one sentence.
    """

    def __init__(self, stage: str, detail: str) -> None:
        self.stage = stage
        self.detail = detail
        super().__init__(detail)
