"""``study=mode_retention``: bending modes added until nothing changes."""

from __future__ import annotations

from dataclasses import dataclass

from omegaconf import MISSING

from savant_cli.config.checks import positive
from savant_cli.config.study.common import flight_times
from savant_cli.errors import ConfigError


@dataclass
class ModeRetentionStudyConfig:
    """``study=mode_retention``: add bending modes lowest first until the response and
    the margins stop changing."""

    name: str = "mode_retention"
    times: list[float] = MISSING
    step: int = MISSING  # modes added per step (2: a bending mode in both planes)
    max_modes: int = MISSING  # 0: as many as the modal data and the plant rate allow
    response_duration_s: float = MISSING  # closed-loop attitude-command step responses compared
    response_tolerance: float = MISSING  # of the response's peak
    margin_tolerance_dB: float = MISSING
    margin_tolerance_deg: float = MISSING


def check_mode_retention(s: ModeRetentionStudyConfig) -> None:
    flight_times(s.times)
    if s.step < 1:
        raise ConfigError("study.step", s.step, "must be a positive number of modes")
    if s.max_modes < 0:
        raise ConfigError("study.max_modes", s.max_modes, "must be 0 (as many as allowed) or a positive count")
    positive("study.response_duration_s", s.response_duration_s)
    positive("study.response_tolerance", s.response_tolerance)
    positive("study.margin_tolerance_dB", s.margin_tolerance_dB)
    positive("study.margin_tolerance_deg", s.margin_tolerance_deg)
