"""``controller``: gain tables, flex filters, blending, roll control, ignition fade,
transport delay; and their checks."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import increasing, non_negative, one_of
from savant_cli.config.run import SimConfig
from savant_cli.errors import ConfigError


@dataclass
class FilterSection:
    """One fourth-order section of a discrete flex filter, z-domain coefficients at the
    flight-control rate.

    Attributes
    ----------
    b : list of float
        Numerator coefficients, 5 (–).
    a : list of float
        Denominator coefficients, 5, ``a[0]`` non-zero, poles inside the unit circle (–)."""

    b: list[float] = field(default_factory=list)
    a: list[float] = field(default_factory=list)


@dataclass
class FilterSet:
    """One schedule's flex filters: two fourth-order sections per path.

    Attributes
    ----------
    rate : list of FilterSection
        The blended rate path.
    integrated_rate : list of FilterSection
        The integrated-rate path.
    roll : list of FilterSection
        The roll-rate path."""

    rate: list[FilterSection] = field(default_factory=list)
    integrated_rate: list[FilterSection] = field(default_factory=list)
    roll: list[FilterSection] = field(default_factory=list)


@dataclass
class FilterSets:
    """``controller.flex_filters``: the filters of the stack and upper-stage schedules.

    Attributes
    ----------
    stack, upper : FilterSet
        The integrated vehicle's and the upper stage's filters."""

    stack: FilterSet = field(default_factory=FilterSet)
    upper: FilterSet = field(default_factory=FilterSet)


@dataclass
class Blending:
    """``controller.blending``: the rate-gyro blend weights (–), upper-stage gyro, IMU,
    first-stage gyro; three non-negative weights summing to 1.

    Attributes
    ----------
    stack, upper : list of float
        The integrated vehicle's and the upper stage's weights."""

    stack: list[float] = field(default_factory=list)
    upper: list[float] = field(default_factory=list)


@dataclass
class AxisGains:
    """One axis's PID gains, one value per breakpoint of its table.

    Attributes
    ----------
    kp : list of float
        Attitude gain (deg of gimbal per deg).
    ki : list of float
        Integral gain (deg of gimbal per deg·s).
    kd : list of float
        Rate gain (deg of gimbal per deg/s).
    kir : list of float
        Integrated-rate gain (deg of gimbal per deg)."""

    kp: list[float] = field(default_factory=list)
    ki: list[float] = field(default_factory=list)
    kd: list[float] = field(default_factory=list)
    kir: list[float] = field(default_factory=list)


@dataclass
class GainTable:
    """A gain schedule: gains per axis tabulated against one scheduling variable.

    Attributes
    ----------
    schedule : str
        The scheduling variable: ``altitude_m`` (stack) or ``velocity_mps`` (coast, upper).
    breakpoints : list of float
        Strictly increasing breakpoints, in the unit the schedule's name carries (m or m/s).
    pitch, yaw : AxisGains
        Each axis's gains at the breakpoints."""

    schedule: str = MISSING
    breakpoints: list[float] = field(default_factory=list)
    pitch: AxisGains = field(default_factory=AxisGains)
    yaw: AxisGains = field(default_factory=AxisGains)


@dataclass
class GainTables:
    """``controller.gains``: the three gain schedules.

    Attributes
    ----------
    stack : GainTable
        First-stage flight (by altitude, m).
    coast : GainTable
        Between separation and upper-stage ignition (by velocity, m/s).
    upper : GainTable
        Upper-stage flight (by velocity, m/s)."""

    stack: GainTable = field(default_factory=GainTable)
    coast: GainTable = field(default_factory=GainTable)
    upper: GainTable = field(default_factory=GainTable)


@dataclass
class RollGimbalGains:
    """One flight-control phase's roll-by-gimbal gains (``models/roll_gimbal.py``).

    Attributes
    ----------
    kp : float
        Equivalent roll angle per roll-attitude error (rad/rad).
    ki : float
        Per integrated roll-attitude error (1/s).
    kd : float
        Per roll-rate error (s)."""

    kp: float = MISSING
    ki: float = MISSING
    kd: float = MISSING


@dataclass
class RollGimbal:
    """``controller.roll.gimbal``: roll by the engines' gimbals, for the stages whose
    engines can roll the vehicle (a cluster, ``models/cluster.py``); gains of 0 (the
    shipped controllers'): none."""

    stack: RollGimbalGains = field(default_factory=RollGimbalGains)
    upper: RollGimbalGains = field(default_factory=RollGimbalGains)


@dataclass
class RollControl:
    """``controller.roll``: the roll jets' phase plane, and roll by the engines' gimbals.

    Attributes
    ----------
    attitude_deadband_deg : float
        Roll-attitude deadband (deg).
    rate_deadband_deg_s : float
        Roll-rate deadband (deg/s).
    lead_time_s : float
        Lead time of the switching line (s).
    gimbal : RollGimbal
        Roll-by-gimbal gains of the stack and the upper stage."""

    attitude_deadband_deg: float = MISSING
    rate_deadband_deg_s: float = MISSING
    lead_time_s: float = 1.0
    gimbal: RollGimbal = field(default_factory=RollGimbal)


@dataclass
class IgnitionFade:
    """``controller.ignition_fade``: the upper-stage loop's engagement at the J-2X start
    (``models/fcs.py::engagement``). The gains fade linearly from the coast table to the
    upper-stage table from ``start_s`` to ``end_s`` after the ignition command (s); the
    integrators are held until ``start_s``. The design rules write the engine's thrust
    build-up: its last zero-thrust time and the time it reaches rated thrust."""

    start_s: float = MISSING
    end_s: float = MISSING


@dataclass
class ControllerDesign:
    """How a controller file was made: the design rules (``datagen/fcs_gains.py``) and the
    values ``study=fcs_design`` tuned (schedule → parameter → value; empty: the rules'
    own values). Provenance only: the flight uses the tables."""

    rules: str = ""
    parameters: dict[str, dict[str, float]] = field(default_factory=dict)


@dataclass
class ControllerConfig:
    """``controller``: a flight-control design (``conf/controller/<name>.yaml``).

    Attributes
    ----------
    name : str
        The design's name.
    vehicle : str
        The vehicle the design is for ("": any); another is refused unless
        ``allow_other_vehicle``.
    allow_other_vehicle : bool
        Fly it on another vehicle anyway.
    blending : Blending
        Rate-gyro blend weights (–).
    flex_filters : FilterSets
        Discrete flex filters.
    gains : GainTables
        PID gain schedules.
    roll : RollControl
        Roll phase plane.
    ignition_fade : IgnitionFade
        Upper-stage engagement at ignition (s).
    delay_s : float
        Transport delay from the sensor sample to the actuator command (s): a whole number
        of plant steps, shorter than the control period.
    design : ControllerDesign
        Provenance: the design rules and tuned values."""

    name: str = "msfc_pid"
    vehicle: str = ""  # the vehicle the design is for ("": any); another is refused ...
    allow_other_vehicle: bool = MISSING  # ... unless this is true
    blending: Blending = field(default_factory=Blending)
    flex_filters: FilterSets = field(default_factory=FilterSets)
    gains: GainTables = field(default_factory=GainTables)
    roll: RollControl = field(default_factory=RollControl)
    ignition_fade: IgnitionFade = field(default_factory=IgnitionFade)
    # transport delay from the sensor sample to the actuator command (s): a whole number
    # of plant steps, shorter than the control period; the same in the time run and the
    # linear model
    delay_s: float = MISSING
    design: ControllerDesign = field(default_factory=ControllerDesign)


def check_controller(c: ControllerConfig) -> None:
    for name in ("stack", "upper"):
        weights = list(getattr(c.blending, name))
        key = f"controller.blending.{name}"
        if len(weights) != 3:
            raise ConfigError(key, weights, "must list 3 weights: upper-stage gyro, IMU, first-stage gyro")
        if any(w < 0 for w in weights) or abs(sum(weights) - 1.0) > 1e-9:
            raise ConfigError(key, weights, "weights must be non-negative and sum to 1")
        fs = getattr(c.flex_filters, name)
        for path in ("rate", "integrated_rate", "roll"):
            sections = getattr(fs, path)
            key = f"controller.flex_filters.{name}.{path}"
            if len(sections) != 2:
                raise ConfigError(key, len(sections), "must hold exactly 2 fourth-order sections")
            for i, sec in enumerate(sections):
                for coef in ("b", "a"):
                    vals = list(getattr(sec, coef))
                    if len(vals) != 5:
                        raise ConfigError(f"{key}[{i}].{coef}", vals, "must hold 5 coefficients (4th order)")
                if sec.a[0] == 0.0:
                    raise ConfigError(f"{key}[{i}].a", list(sec.a), "a[0] must be non-zero")
                roots = np.roots(np.asarray(sec.a, float) / sec.a[0])
                if np.any(np.abs(roots) >= 1.0):
                    raise ConfigError(f"{key}[{i}].a", list(sec.a), "filter must be stable (poles inside the unit circle)")
    for name, sched in (("stack", "altitude_m"), ("coast", "velocity_mps"), ("upper", "velocity_mps")):
        table = getattr(c.gains, name)
        key = f"controller.gains.{name}"
        one_of(f"{key}.schedule", table.schedule, (sched,))
        increasing(f"{key}.breakpoints", list(table.breakpoints))
        n = len(table.breakpoints)
        for axis in ("pitch", "yaw"):
            for g in ("kp", "ki", "kd", "kir"):
                vals = list(getattr(getattr(table, axis), g))
                if len(vals) != n:
                    raise ConfigError(f"{key}.{axis}.{g}", vals, f"must have one value per breakpoint ({n})")
    non_negative("controller.roll.attitude_deadband_deg", c.roll.attitude_deadband_deg)
    non_negative("controller.roll.rate_deadband_deg_s", c.roll.rate_deadband_deg_s)
    non_negative("controller.roll.lead_time_s", c.roll.lead_time_s)
    for name in ("stack", "upper"):
        for g in ("kp", "ki", "kd"):
            non_negative(f"controller.roll.gimbal.{name}.{g}", getattr(getattr(c.roll.gimbal, name), g))
    fade = c.ignition_fade
    non_negative("controller.ignition_fade.start_s", fade.start_s)
    if not (np.isfinite(fade.end_s) and fade.end_s >= fade.start_s):
        raise ConfigError("controller.ignition_fade.end_s", fade.end_s,
                          f"must be finite and at least controller.ignition_fade.start_s = {fade.start_s} s "
                          "(the fade from the coast gains to the upper-stage gains after the ignition command)")


def check_delay(delay_s: float, sim: SimConfig) -> None:
    """``controller.delay_s``: 0 or more, a whole number of plant steps, below one
    flight-control period."""
    non_negative("controller.delay_s", delay_s)
    steps = delay_s * sim.plant_rate_hz
    if abs(steps - round(steps)) > 1e-6:
        raise ConfigError("controller.delay_s", delay_s,
                          f"must be a whole number of plant steps (1 / sim.plant_rate_hz = {1.0 / sim.plant_rate_hz:g} s)")
    if delay_s >= 1.0 / sim.fcs_rate_hz - 1e-12:
        raise ConfigError("controller.delay_s", delay_s,
                          f"must be shorter than the flight-control period (1 / sim.fcs_rate_hz = {1.0 / sim.fcs_rate_hz:g} s)")
