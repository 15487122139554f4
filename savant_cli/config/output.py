"""``output``: what a run writes and what the console shows."""

from __future__ import annotations

from dataclasses import dataclass

from omegaconf import MISSING

from savant_cli.io.console import ConsoleMode


@dataclass
class OutputConfig:
    """``output``: what a run writes and what the console shows.

    Attributes
    ----------
    hdf5 : bool
        Write ``savant.h5``.
    plots : bool
        Draw PNG figures into ``plots/``.
    console : ConsoleMode
        What the console shows: ``full``, ``summary`` or ``quiet``."""

    hdf5: bool = MISSING
    plots: bool = MISSING
    console: ConsoleMode = MISSING
