"""In-memory form of one run: what the simulation hands to the writers and plots.

A :class:`RunRecord` holds plain numpy arrays (:class:`Signal`) sampled on a common time
base (the ``"time"`` signal), the discrete events, the scalar summary, the resolved
configuration and the provenance of the run. ``savant_cli.io.hdf5`` stores it as
``savant.h5`` and reads it back; ``savant_cli.plots`` draws it. The on-disk layout is
documented in ``docs/outputs.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Values a summary entry may take (``None`` for "did not happen", e.g. no separation).
SummaryValue = float | int | str | None

#: ``RunRecord.status`` values.
STATUSES = ("complete", "loss_of_control", "limit_cycle", "slow_divergence", "saturated", "diverged",
            "guidance_failed", "interrupted", "failed")
#: The statuses of a run that flew to its end (its health in its status): ``complete`` is
#: healthy; ``loss_of_control``, ``limit_cycle``, ``slow_divergence`` and ``saturated``
#: are not, in this priority (``savant_cli/sim/health.py``).
FLOWN = ("complete", "loss_of_control", "limit_cycle", "slow_divergence", "saturated")
#: A run's mission failure classes, most severe first (``savant_cli/sim/mission.py``
#: holds their rules; the requirement set names those counted as failures).
FAILURE_CLASSES = ("loss_of_control", "guidance_failure", "propellant_depletion", "time_limit",
                   "insertion_tolerance", "structural_allowable", "separation_state", "unhealthy_flight",
                   "run_error")


@dataclass(frozen=True)
class Signal:
    """One time history.

    Parameters
    ----------
    data : numpy.ndarray
        Shape ``(n,)`` or ``(n, k)`` with ``n`` the number of time samples; float64, or an
        integer type for flags.
    units : str
        SI units of ``data`` (``"m"``, ``"m/s"``, ``"rad/s"``, ``"Pa"``, ``"1"`` for
        dimensionless ...).
    description : str
        One line saying what the signal is.
    columns : tuple of str, optional
        Names of the ``k`` columns of a 2-D signal (``("x", "y", "z")``); empty for 1-D.
    frame : str, optional
        Reference frame of a vector signal (``"ECI"``, ``"body"``, ``"NED"``); empty for
        scalars.
    """

    data: np.ndarray
    units: str
    description: str
    columns: tuple[str, ...] = ()
    frame: str = ""


@dataclass
class RunRecord:
    """Everything one run leaves behind, independent of the file format.

    Parameters
    ----------
    signals : dict of str to Signal
        Time histories; must include ``"time"`` (s). Order is preserved on disk.
    events : list of (str, float)
        ``(name, time_s)`` of the discrete events that happened, e.g.
        ``("separation", 130.2)``.
    summary : dict
        Scalar results, keys carry their unit as a suffix (``max_dynamic_pressure_Pa``);
        values are float, int, str or None.
    config_yaml : str
        The resolved configuration as YAML text.
    provenance : dict of str to str
        ``savant_version``, ``git_commit``, ``python``, ``numba``, ``host``,
        ``created_utc`` ... (see :func:`savant_cli.io.provenance.collect_provenance`).
    complete : bool
        False when the run diverged, was interrupted or failed (it did not fly to its end).
    status : str
        One of :data:`STATUSES`: ``"complete"`` (flew to its end, healthy),
        ``"loss_of_control"``, ``"limit_cycle"``, ``"slow_divergence"`` or ``"saturated"``
        (flew to its end, unhealthy: :data:`FLOWN`), ``"diverged"``,
        ``"guidance_failed"`` (closed-loop guidance stopped the run), ``"interrupted"`` or
        ``"failed"``.
    message : str
        Why the run stopped (``"cutoff on target energy"``, ``"NaN in body_rate at t=..."``).
    """

    signals: dict[str, Signal]
    events: list[tuple[str, float]] = field(default_factory=list)
    summary: dict[str, SummaryValue] = field(default_factory=dict)
    config_yaml: str = ""
    provenance: dict[str, str] = field(default_factory=dict)
    complete: bool = True
    status: str = "complete"
    message: str = ""

    @property
    def time(self) -> np.ndarray:
        """The time base (s) of every signal."""
        return self.signals["time"].data

    def event_time(self, name: str) -> float | None:
        """Time (s) of the first event called ``name``, or None when it did not happen."""
        for ev_name, t in self.events:
            if ev_name == name:
                return float(t)
        return None
