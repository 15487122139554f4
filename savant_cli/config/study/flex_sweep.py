"""``study=flex_sweep``: margins over scaled bending frequencies and shapes."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import non_negative
from savant_cli.config.study.common import LoopAxis, flight_times
from savant_cli.errors import ConfigError


class SweepParameter(StrEnum):
    """``study.parameters``: what is scaled, the bending frequencies or the mode shapes."""

    frequency = "frequency"
    shape = "shape"


@dataclass
class FlexSweepStudyConfig:
    """``study=flex_sweep``: margins and Nichols charts with the bending frequencies, and
    separately the mode-shape magnitudes, scaled over a grid (the GVT decision study)."""

    name: str = "flex_sweep"
    times: list[float] = MISSING
    parameters: list[SweepParameter] = MISSING
    levels: list[float] = MISSING
    modes: list[int] = MISSING  # 1-based retained modes varied; empty: all
    chart_axes: list[LoopAxis] = MISSING  # loops overlaid in the Nichols charts
    event_clearance_s: float = MISSING
    exclusion_zones: bool = MISSING


def check_flex_sweep(s: FlexSweepStudyConfig) -> None:
    flight_times(s.times)
    if not s.parameters:
        raise ConfigError("study.parameters", list(s.parameters), "must list frequency and/or shape")
    if not s.levels:
        raise ConfigError("study.levels", list(s.levels), "must list at least one scale factor")
    for i, v in enumerate(s.levels):
        if not (v > 0.0 and np.isfinite(v)):
            raise ConfigError(f"study.levels[{i}]", v, "must be a positive scale factor (1.0 = nominal)")
    for i, m in enumerate(s.modes):
        if m < 1:
            raise ConfigError(f"study.modes[{i}]", m, "must be a mode number, 1 = the lowest retained mode")
    non_negative("study.event_clearance_s", s.event_clearance_s)
