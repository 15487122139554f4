"""``study=time_margins``: gain and delay margins in the nonlinear time simulation."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive
from savant_cli.config.study.common import MAX_WORKERS, WORKERS_ALLOWED, Jacobian, LoopAxis, flight_times
from savant_cli.errors import ConfigError


class MarginKind(StrEnum):
    """``study.kinds``: the gain-increase (``gain_high``), gain-reduction (``gain_low``)
    and delay margin measured in the time domain (``timedomain/search.py``)."""

    gain_high = "gain_high"
    gain_low = "gain_low"
    delay = "delay"


@dataclass
class TimeMarginsStudyConfig:
    """``study=time_margins``: gain and delay margins measured in the nonlinear time
    simulation, beside the frequency-domain ones (docs/design_studies.md)."""

    name: str = "time_margins"
    times: list[float] = MISSING
    axes: list[LoopAxis] = MISSING
    kinds: list[MarginKind] = MISSING
    lead_s: float = MISSING  # the perturbation starts this long before the point
    window_s: float = MISSING  # and is held this long
    min_periods: float = MISSING  # the window stretched to hold this many periods of the frequency-domain crossing
    max_window_s: float = MISSING  # longest stretched window
    event_clearance_s: float = MISSING  # the window keeps this far from events
    gain_bound_dB: float = MISSING  # search bound of the gain margins
    delay_bound_ms: float = MISSING  # search bound of the delay margin
    gain_tolerance_dB: float = MISSING  # bisection tolerance
    delay_tolerance_ms: float = MISSING
    scan_points: int = MISSING  # coarse scan before the bisection
    excitation_deg: float = MISSING  # doublet amplitude at the gimbal command
    excitation_s: float = MISSING  # doublet duration
    settle_s: float = MISSING  # left out of the growth analysis after the window starts
    min_damping_ratio: float = MISSING  # stable only when the envelope decays per period as a mode of this damping
    workers: int = MISSING  # processes; 0: all cores
    jacobian: Jacobian = MISSING  # of the frequency-domain side (as study=linear)
    jacobian_step: float = MISSING


def check_time_margins(s: TimeMarginsStudyConfig) -> None:
    flight_times(s.times)
    if not s.axes:
        raise ConfigError("study.axes", [], "must name at least one loop (pitch, yaw)")
    if not s.kinds:
        raise ConfigError("study.kinds", [], f"must name at least one of {', '.join(MarginKind)}")
    for key in ("window_s", "max_window_s", "gain_bound_dB", "delay_bound_ms", "gain_tolerance_dB",
                "delay_tolerance_ms", "excitation_deg", "excitation_s"):
        positive(f"study.{key}", getattr(s, key))
    for key in ("lead_s", "min_periods", "event_clearance_s", "settle_s"):
        non_negative(f"study.{key}", getattr(s, key))
    if s.lead_s > s.window_s:
        raise ConfigError("study.lead_s", s.lead_s, f"must not exceed study.window_s ({s.window_s} s)")
    if s.max_window_s < s.window_s:
        raise ConfigError("study.max_window_s", s.max_window_s, f"must be at least study.window_s ({s.window_s} s)")
    if s.settle_s >= s.window_s:
        raise ConfigError("study.settle_s", s.settle_s, f"must be shorter than study.window_s ({s.window_s} s)")
    if s.scan_points < 1:
        raise ConfigError("study.scan_points", s.scan_points, "must be a positive count")
    if not 0.0 < s.min_damping_ratio < 1.0:
        raise ConfigError("study.min_damping_ratio", s.min_damping_ratio,
                          "must lie in (0, 1): the damping ratio whose decay per period a stable response must "
                          "reach (0 would leave the verdict on a neutral oscillation to round-off)")
    if not 0 <= s.workers <= MAX_WORKERS:
        raise ConfigError("study.workers", s.workers, WORKERS_ALLOWED)
    positive("study.jacobian_step", s.jacobian_step)
