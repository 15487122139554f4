"""``output``: what a run writes and what the console shows."""

from __future__ import annotations

from dataclasses import dataclass

from omegaconf import MISSING

from savant_cli.config.checks import one_of


@dataclass
class OutputConfig:
    """``output``: what a run writes and what the console shows.

    Attributes
    ----------
    hdf5 : bool
        Write ``savant.h5``.
    plots : bool
        Draw PNG figures into ``plots/``.
    console : str
        What the console shows, one of :data:`CONSOLE_MODES`."""

    hdf5: bool = MISSING
    plots: bool = MISSING
    console: str = MISSING  # full | summary | quiet (savant_cli.io.console.CONSOLE_MODES)


#: ``output.console`` options (``savant_cli.io.console.CONSOLE_MODES``).
CONSOLE_MODES = ("full", "summary", "quiet")


def check_output(o: OutputConfig) -> None:
    """``output.console`` one of :data:`CONSOLE_MODES`."""
    one_of("output.console", o.console, CONSOLE_MODES)
