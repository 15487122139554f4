"""The result of a batch: its scalar tables (:class:`Tables`), one row per run present,
as the journal streams them in (``montecarlo/storage.py::write_tables``) or ``savant.h5``
gives them back (``montecarlo/storage.py::read_tables``); what every other output of a
batch is computed from (``montecarlo/analysis.py``, ``console_summary.py``,
``figures.py``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from savant_cli.io.record import FLOWN
from savant_cli.linear.requirements import CHECK_ARRAY_COLUMNS, DEFAULT_SLOSH_TANKS
from savant_cli.montecarlo.batch import MARGIN_ARRAY_COLUMNS

N_MARGIN = 1 + len(MARGIN_ARRAY_COLUMNS)  # run, then the margin row
N_CHECK = 1 + len(CHECK_ARRAY_COLUMNS)  # run, then the check


@dataclass
class Tables:
    """The batch's scalar tables (rows: the runs present, by run number)."""

    runs: np.ndarray
    status: list[str]
    message: list[str]
    t_final: np.ndarray
    wall_s: np.ndarray
    values: np.ndarray  # (n, n_dispersions)
    summary_keys: list[str]
    summary: np.ndarray  # (n, n_keys)
    events: np.ndarray  # (n, n_events)
    margins: np.ndarray  # (m, 9): run, then batch.MARGIN_ARRAY_COLUMNS
    history_names: list[str]
    checks: np.ndarray = field(default_factory=lambda: np.zeros((0, 1 + len(CHECK_ARRAY_COLUMNS))))  # run, checks
    #: the sloshing tanks the slosh mode codes of ``margins`` and ``checks`` name
    slosh_tanks: tuple[str, ...] = DEFAULT_SLOSH_TANKS

    @property
    def ok(self) -> np.ndarray:
        """Runs with usable results: those that flew to their end (healthy or not) and the
        diverged or guidance-failed ones (they still flew, up to their stop)."""
        return np.array([s in (*FLOWN, "diverged", "guidance_failed") for s in self.status])
