"""``study=fcs_design``: the flight-control design search."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, Optional

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive
from savant_cli.config.study.common import MAX_WORKERS, WORKERS_ALLOWED, LoopAxis
from savant_cli.errors import ConfigError


class OptimizerMethod(StrEnum):
    """``study.optimizer.method`` (``scipy.optimize.minimize``): ``nelder_mead``, goal
    attainment then max-min on the normalized parameters; ``cobyla``, the margins as
    constraints."""

    nelder_mead = "nelder_mead"
    cobyla = "cobyla"


class DesignSchedule(StrEnum):
    """A gain schedule ``study=fcs_design`` tunes: the stack's or the upper stage's."""

    stack = "stack"
    upper = "upper"


@dataclass
class DesignParameter:
    """One free parameter of ``study=fcs_design``: its starting value (``None``: the design
    rules' own) and bounds."""

    initial: Any = None
    low: float = 0.0
    high: float = 0.0


@dataclass
class ScheduleParameters:
    """The tuned parameters of one gain schedule (``null``: not tuned;
    ``savant_cli/design/parameters.py``)."""

    omega: Optional[DesignParameter] = None  # rad/s, pole-placement natural frequency (first breakpoint)
    omega_end: Optional[DesignParameter] = None  # rad/s, at the last breakpoint (linear in between)
    zeta: Optional[DesignParameter] = None  # pole-placement damping
    integral_ratio: Optional[DesignParameter] = None  # integral gain / (omega x attitude stiffness)
    kir_share: Optional[DesignParameter] = None  # attitude stiffness in the integrated-rate path
    lowpass_hz: Optional[DesignParameter] = None  # Butterworth corner of the rate paths, Hz
    notch1_hz: Optional[DesignParameter] = None
    notch1_q: Optional[DesignParameter] = None
    notch2_hz: Optional[DesignParameter] = None
    notch2_q: Optional[DesignParameter] = None
    blend_first: Optional[DesignParameter] = None  # stack only: first-stage gyro weight in the rate blend
    tailoff_kp_cap: Optional[DesignParameter] = None  # stack only: tail-off attitude-stiffness cap (x last regular)
    tailoff_kd_cap: Optional[DesignParameter] = None  # stack only: tail-off rate-gain cap (x last regular)


#: Design parameters only the stack schedule has, and why.
STACK_ONLY_PARAMETERS = {"blend_first": "only the stack blends its gyros",
                         "tailoff_kp_cap": "only the first stage has a thrust tail-off",
                         "tailoff_kd_cap": "only the first stage has a thrust tail-off"}


@dataclass
class DesignParameters:
    """``study.parameters``: the tuned parameters of each gain schedule.

    Attributes
    ----------
    stack, upper : ScheduleParameters
        The integrated vehicle's and the upper stage's (units per parameter)."""

    stack: ScheduleParameters = field(default_factory=ScheduleParameters)
    upper: ScheduleParameters = field(default_factory=ScheduleParameters)


@dataclass
class DesignOptimizer:
    """The search of ``study=fcs_design`` (``scipy.optimize.minimize``)."""

    method: OptimizerMethod = MISSING
    max_evaluations: int = MISSING  # per schedule
    tolerance: float = MISSING  # on the normalized parameters and the ratio
    initial_step: float = MISSING  # first simplex / trust radius, fraction of each parameter's range
    stop_ratio: float = MISSING  # > 0: stop a schedule's search once every point's ratio reaches it
    restarts: int = MISSING  # fresh starts from the best point after a search converges (budget permitting)


@dataclass
class FcsDesignStudyConfig:
    """``study=fcs_design``: tune the flight control's free parameters against the
    requirement set at frozen points over the flight and the uncertainty corners, and
    write the controller config (docs/design_studies.md)."""

    name: str = "fcs_design"
    design: str = MISSING  # design rules it starts from (savant_cli/datagen/fcs_gains.py CONTROLLERS)
    controller_name: str = MISSING  # name of the controller written ("": <design>_tuned, or <design> with install)
    install: bool = MISSING  # also write conf/controller/<name>.yaml of the shipped config tree
    schedules: list[DesignSchedule] = MISSING  # tuned in turn
    every_s: dict[DesignSchedule, float] = MISSING  # design points
    verify_every_s: float = MISSING  # the before/after envelope
    event_window_s: float = MISSING  # points this close to an event are skipped
    axes: list[LoopAxis] = MISSING  # loops judged in the search (both verified)
    workers: int = MISSING  # processes judging a candidate's points; 0: all cores
    corners: dict[str, dict[str, Any]] = field(default_factory=dict)  # name → {config key: value}
    parameters: DesignParameters = field(default_factory=DesignParameters)
    optimizer: DesignOptimizer = field(default_factory=DesignOptimizer)


def design_controller_name(s: FcsDesignStudyConfig) -> str:
    """The name ``study=fcs_design`` writes its controller under: ``study.controller_name``,
    else the design's own with ``study.install`` and ``<design>_tuned`` without."""
    return s.controller_name or (s.design if s.install else f"{s.design}_tuned")


def check_fcs_design(s: FcsDesignStudyConfig) -> None:
    from savant_cli.paths import shipped_config_dir

    name = design_controller_name(s)
    if not s.install and (shipped_config_dir() / "controller" / f"{name}.yaml").is_file():
        # Hydra searches the shipped config tree before --config-dir: the copy would be shadowed
        raise ConfigError("study.controller_name", name,
                          "names a shipped controller, which would shadow the run folder's copy "
                          "(--config-dir is searched after the shipped configs): choose another name, "
                          "or set study.install=true to replace the shipped file")
    for name, step in s.every_s.items():
        positive(f"study.every_s.{name}", step)
    for name in s.schedules:
        if name not in s.every_s:
            raise ConfigError("study.every_s", dict(s.every_s), f"must give the design-point spacing of {name}")
    positive("study.verify_every_s", s.verify_every_s)
    non_negative("study.event_window_s", s.event_window_s)
    if not 0 <= s.workers <= MAX_WORKERS:
        raise ConfigError("study.workers", s.workers, WORKERS_ALLOWED)
    if not s.axes:
        raise ConfigError("study.axes", [], "must name at least one loop (pitch, yaw)")
    for sched in DesignSchedule:
        params = getattr(s.parameters, sched)
        for name, why in STACK_ONLY_PARAMETERS.items():
            if sched != "stack" and getattr(params, name) is not None:
                raise ConfigError(f"study.parameters.{sched}.{name}", "set", why)
        for f in dataclasses.fields(params):
            prm = getattr(params, f.name)
            if prm is None:
                continue
            key = f"study.parameters.{sched}.{f.name}"
            if not (np.isfinite(prm.low) and np.isfinite(prm.high) and prm.low < prm.high):
                raise ConfigError(f"{key}.high", prm.high, f"must be finite and above low = {prm.low}")
            if prm.initial is not None and not prm.low <= prm.initial <= prm.high:
                raise ConfigError(f"{key}.initial", prm.initial, f"must lie within [{prm.low}, {prm.high}]")
    o = s.optimizer
    if o.max_evaluations < 1:
        raise ConfigError("study.optimizer.max_evaluations", o.max_evaluations, "must be a positive count")
    positive("study.optimizer.tolerance", o.tolerance)
    if not 0.0 < o.initial_step <= 1.0:
        raise ConfigError("study.optimizer.initial_step", o.initial_step, "must lie in (0, 1]")
    non_negative("study.optimizer.stop_ratio", o.stop_ratio)
    if o.restarts < 0:
        raise ConfigError("study.optimizer.restarts", o.restarts, "must be 0 or a positive count")
