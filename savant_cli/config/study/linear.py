"""``study=linear``: frozen-time linearization and stability margins."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive
from savant_cli.config.study.common import Jacobian, flight_times
from savant_cli.errors import ConfigError


class FrozenTimeCriterion(StrEnum):
    """``study.frozen_time.criteria``: what opens the tail-off window
    (``linear/frozen_time.py``)."""

    period = "period"
    control_power = "control_power"


class ChartMode(StrEnum):
    """``study.charts``: per-point charts for every point, none, or up to 20 points."""

    auto = "auto"
    all = "all"
    none = "none"


@dataclass
class FrozenTimeSpec:
    """``study.frozen_time``: the first-stage tail-off window, where frozen-time margins
    are analysed and reported but not judged, and the time domain judges instead
    (``linear/frozen_time.py``, ``timedomain/tailoff.py``; docs/requirements.md)."""

    # period: crossover period >= time to separation; control_power: the control power
    # falls within one period by the rigid gain requirement; []: no window, judge every point
    criteria: list[FrozenTimeCriterion] = MISSING
    scan_s: float = MISSING  # s before the flown separation scanned for the criteria
    step_s: float = MISSING  # s between scan points
    excitation_deg: float = MISSING  # time-domain checks: doublet at the gimbal command, deg ...
    excitation_s: float = MISSING  # ... and its duration, s


def check_frozen_time(f: FrozenTimeSpec, key: str) -> None:
    """Each criterion once; positive scan span and step, the step at most the span; a
    positive excitation."""
    if len(set(f.criteria)) != len(f.criteria):
        raise ConfigError(f"{key}.criteria", list(f.criteria), "names each criterion at most once")
    positive(f"{key}.scan_s", f.scan_s)
    positive(f"{key}.step_s", f.step_s)
    if f.step_s > f.scan_s:
        raise ConfigError(f"{key}.step_s", f.step_s, f"must be at most {key}.scan_s ({f.scan_s} s)")
    positive(f"{key}.excitation_deg", f.excitation_deg)
    positive(f"{key}.excitation_s", f.excitation_s)


@dataclass
class LinearStudyConfig:
    """``study=linear``: frozen-time linearization and stability margins."""

    name: str = "linear"
    times: list[float] = MISSING
    every: float = MISSING  # > 0: points every `every` s over the whole flight instead of `times`
    event_clearance_s: float = MISSING  # a time this close to an event is refused (skipped with `every`)
    # the first-stage tail-off window: points in it are analysed and reported but judged
    # in the time domain (separation state with the required margins inserted)
    frozen_time: FrozenTimeSpec = field(default_factory=FrozenTimeSpec)
    jacobian: Jacobian = MISSING  # auto: per-state steps; fixed: one user step
    jacobian_step: float = MISSING  # the fixed step, as an attitude perturbation in rad
    charts: ChartMode = MISSING
    exclusion_zones: bool = MISSING  # Nichols exclusion zones


def check_linear(s: LinearStudyConfig) -> None:
    if s.every < 0:
        raise ConfigError("study.every", s.every, "must be zero (use study.times) or a positive interval in s")
    if s.every == 0:
        flight_times(s.times)
    non_negative("study.event_clearance_s", s.event_clearance_s)
    check_frozen_time(s.frozen_time, "study.frozen_time")
    positive("study.jacobian_step", s.jacobian_step)
