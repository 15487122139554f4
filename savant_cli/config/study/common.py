"""Keys several studies share: worker counts and flight times."""

from __future__ import annotations

from enum import StrEnum

import numpy as np

from savant_cli.errors import ConfigError


class LoopAxis(StrEnum):
    """A loop a study judges (``study.axes``, ``study.chart_axes``)."""

    pitch = "pitch"
    yaw = "yaw"


class Jacobian(StrEnum):
    """``study.jacobian``: per-state steps (``auto``), or one fixed step
    (``study.jacobian_step``, rad)."""

    auto = "auto"
    fixed = "fixed"


#: Most worker processes of a study: each holds a copy of the built model and its
#: compiled plant, about 170 MB measured, so 256 are about 43 GB; a machine with more cores
#: is better used by shards.
MAX_WORKERS = 256
WORKERS_ALLOWED = f"must be 0 (all cores) or a process count up to {MAX_WORKERS} (about 170 MB each)"


def flight_times(times: list[float]) -> None:
    """``study.times``: at least one positive, finite flight time (s)."""
    if not times:
        raise ConfigError("study.times", list(times), "must list at least one flight time (s)")
    for i, t in enumerate(times):
        if not (t > 0.0 and np.isfinite(t)):
            raise ConfigError(f"study.times[{i}]", t, "must be a positive flight time in s")
