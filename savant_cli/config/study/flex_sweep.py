"""``study=flex_sweep``: margins over scaled bending frequencies and shapes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import non_negative, one_of
from savant_cli.config.study.common import LOOP_AXES, flight_times
from savant_cli.errors import ConfigError

#: ``study.parameters`` options: what is scaled.
SWEEP_PARAMETERS = ("frequency", "shape")


@dataclass
class FlexSweepStudyConfig:
    """``study=flex_sweep``: margins and Nichols charts with the bending frequencies, and
    separately the mode-shape magnitudes, scaled over a grid (the GVT decision study)."""

    name: str = "flex_sweep"
    times: list[float] = MISSING
    parameters: list[str] = MISSING  # frequency | shape
    levels: list[float] = MISSING
    modes: list[int] = MISSING  # 1-based retained modes varied; empty: all
    chart_axes: list[str] = MISSING  # loops overlaid in the Nichols charts
    event_clearance_s: float = MISSING
    exclusion_zones: bool = MISSING


def check_flex_sweep(s: FlexSweepStudyConfig) -> None:
    flight_times(s.times)
    if not s.parameters:
        raise ConfigError("study.parameters", list(s.parameters), "must list frequency and/or shape")
    for i, prm in enumerate(s.parameters):
        one_of(f"study.parameters[{i}]", prm, SWEEP_PARAMETERS)
    if not s.levels:
        raise ConfigError("study.levels", list(s.levels), "must list at least one scale factor")
    for i, v in enumerate(s.levels):
        if not (v > 0.0 and np.isfinite(v)):
            raise ConfigError(f"study.levels[{i}]", v, "must be a positive scale factor (1.0 = nominal)")
    for i, m in enumerate(s.modes):
        if m < 1:
            raise ConfigError(f"study.modes[{i}]", m, "must be a mode number, 1 = the lowest retained mode")
    for i, a in enumerate(s.chart_axes):
        one_of(f"study.chart_axes[{i}]", a, LOOP_AXES)
    non_negative("study.event_clearance_s", s.event_clearance_s)
