"""``actuator``: the TVC actuator variants (third order, simplex) and their checks."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive, small_angles
from savant_cli.config.model_group import ModelGroup
from savant_cli.errors import ConfigError


@dataclass
class ActuatorStageCommon:
    """Keys of one stage's TVC actuator common to both variants. The values live in the
    option's YAML (``conf/actuator/<option>.yaml``); the schema gives no defaults.

    Attributes
    ----------
    loop_gain_rad_s : float
        Position-loop gain (rad/s).
    rate_limit_deg_s : float
        Gimbal rate limit (deg/s).
    null_bias_deg : list of float
        Thrust-line misalignment from the actuator null, pitch and yaw (deg, each within ±2).
    """

    loop_gain_rad_s: float = MISSING
    rate_limit_deg_s: float = MISSING
    null_bias_deg: list[float] = MISSING


@dataclass
class ThirdOrderStage(ActuatorStageCommon):
    """``actuator=third_order``: position loop of gain ``loop_gain_rad_s`` driving a
    second-order load.

    Attributes
    ----------
    natural_frequency_hz : float
        Natural frequency of the second-order load (Hz).
    damping : float
        Damping ratio of the load (–).
    """

    natural_frequency_hz: float = MISSING
    damping: float = MISSING


class SimplexFeedback(StrEnum):
    """``actuator.<stage>.feedback`` of ``actuator=simplex``: the position loop is closed
    on the ram's LVDT (``piston``) or on the nozzle angle (``nozzle``)."""

    piston = "piston"
    nozzle = "nozzle"


@dataclass
class SimplexStage(ActuatorStageCommon):
    """``actuator=simplex``: power valve, hydraulic ram and compliant nozzle mount (load
    inertia: the vehicle's engine inertia about the gimbal).

    Attributes
    ----------
    valve_frequency_hz : float
        Power-valve natural frequency (Hz), below a quarter of ``sim.plant_rate_hz``.
    valve_damping : float
        Power-valve damping ratio (–).
    stiffness_Nm_per_rad : float
        Nozzle-mount stiffness K (N·m/rad).
    damping_Nms_per_rad : float
        Nozzle-mount damping C (N·m·s/rad).
    leakage_rad_s_per_Nm : float
        Ram leakage: rate lost per load torque (rad/s per N·m; 0: none).
    feedback : SimplexFeedback
        What the position loop is closed on, the ram's LVDT or the nozzle angle.
    """

    valve_frequency_hz: float = MISSING
    valve_damping: float = MISSING
    stiffness_Nm_per_rad: float = MISSING
    damping_Nms_per_rad: float = MISSING
    leakage_rad_s_per_Nm: float = MISSING
    feedback: SimplexFeedback = MISSING


@dataclass
class ThirdOrderActuatorConfig:
    """``actuator=third_order``: both stages' third-order actuators and the strap-on
    boosters' (:class:`ThirdOrderStage`; ``boosters`` is read only for boosters with TVC)."""

    name: str = "third_order"
    first_stage: ThirdOrderStage = field(default_factory=ThirdOrderStage)
    upper_stage: ThirdOrderStage = field(default_factory=ThirdOrderStage)
    boosters: ThirdOrderStage = field(default_factory=ThirdOrderStage)


@dataclass
class SimplexActuatorConfig:
    """``actuator=simplex``: both stages' simplex actuators and the strap-on boosters'
    (:class:`SimplexStage`; ``boosters`` is read only for boosters with TVC)."""

    name: str = "simplex"
    first_stage: SimplexStage = field(default_factory=SimplexStage)
    upper_stage: SimplexStage = field(default_factory=SimplexStage)
    boosters: SimplexStage = field(default_factory=SimplexStage)


#: The sections of the ``actuator`` group: each stage's actuators, then the strap-on boosters'.
STAGES = ("first_stage", "upper_stage", "boosters")


def check_actuator(a: ThirdOrderActuatorConfig | SimplexActuatorConfig, plant_rate_hz: float) -> None:
    """Physical checks of the ``actuator`` group (either variant)."""
    for stage in STAGES:
        st = getattr(a, stage)
        names = ["loop_gain_rad_s", "rate_limit_deg_s"]
        names += ["natural_frequency_hz", "damping"] if a.name == "third_order" else [
            "valve_frequency_hz", "valve_damping", "stiffness_Nm_per_rad", "damping_Nms_per_rad"]
        for name in names:
            positive(f"actuator.{stage}.{name}", getattr(st, name))
        small_angles(f"actuator.{stage}.null_bias_deg", st.null_bias_deg, 2, 2.0, "pitch, yaw")
        if a.name == "simplex":
            non_negative(f"actuator.{stage}.leakage_rad_s_per_Nm", st.leakage_rad_s_per_Nm)
            # the valve is integrated by the plant's RK4: keep it well inside its stability
            nyq = 0.25 * plant_rate_hz
            if st.valve_frequency_hz >= nyq:
                raise ConfigError(f"actuator.{stage}.valve_frequency_hz", st.valve_frequency_hz,
                                  f"must be below a quarter of sim.plant_rate_hz ({nyq} Hz) for RK4 stability")


GROUP = ModelGroup("actuator", {"third_order": ThirdOrderActuatorConfig, "simplex": SimplexActuatorConfig},
                   lambda a, cfg: check_actuator(a, cfg.sim.plant_rate_hz))
