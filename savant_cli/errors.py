"""Exceptions that the command line turns into clear messages and exit codes."""

from __future__ import annotations

from typing import Any


class ConfigError(ValueError):
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
