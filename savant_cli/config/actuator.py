"""``actuator``: the TVC actuator variants (third order, simplex) and their checks."""

from __future__ import annotations

from dataclasses import dataclass, field

from savant_cli.errors import ConfigError
from savant_cli.config.checks import non_negative, one_of, positive, small_angles


@dataclass
class ActuatorStageCommon:
    """Keys of one stage's TVC actuator common to both variants."""

    loop_gain_rad_s: float = 25.0
    rate_limit_deg_s: float = 10.0
    # thrust-line misalignment from the actuator null, pitch and yaw, deg
    null_bias_deg: list[float] = field(default_factory=lambda: [0.0, 0.0])


@dataclass
class ThirdOrderStage(ActuatorStageCommon):
    """``actuator=third_order``: position loop of gain ``loop_gain_rad_s`` driving a
    second-order load."""

    natural_frequency_hz: float = 12.0
    damping: float = 0.6


@dataclass
class SimplexStage(ActuatorStageCommon):
    """``actuator=simplex``: power valve, hydraulic ram and compliant nozzle mount (load
    inertia: the vehicle's engine inertia about the gimbal)."""

    valve_frequency_hz: float = 50.0
    valve_damping: float = 0.7
    stiffness_Nm_per_rad: float = 1.99e8  # the first stage's: ω_n = 12 Hz with J = 35,000 kg m²
    damping_Nms_per_rad: float = 3.17e6  # ζ = C / (2 √(K J)) = 0.6 with that J
    leakage_rad_s_per_Nm: float = 0.0
    feedback: str = "piston"  # piston (ram LVDT) | nozzle


@dataclass
class ThirdOrderActuatorConfig:
    name: str = "third_order"
    first_stage: ThirdOrderStage = field(default_factory=ThirdOrderStage)
    upper_stage: ThirdOrderStage = field(default_factory=ThirdOrderStage)


@dataclass
class SimplexActuatorConfig:
    name: str = "simplex"
    first_stage: SimplexStage = field(default_factory=SimplexStage)
    upper_stage: SimplexStage = field(default_factory=SimplexStage)


def check_actuator(a: ThirdOrderActuatorConfig | SimplexActuatorConfig, plant_rate_hz: float) -> None:
    """Physical checks of the ``actuator`` group (either variant)."""
    for stage in ("first_stage", "upper_stage"):
        st = getattr(a, stage)
        names = ["loop_gain_rad_s", "rate_limit_deg_s"]
        names += ["natural_frequency_hz", "damping"] if a.name == "third_order" else [
            "valve_frequency_hz", "valve_damping", "stiffness_Nm_per_rad", "damping_Nms_per_rad"]
        for name in names:
            positive(f"actuator.{stage}.{name}", getattr(st, name))
        small_angles(f"actuator.{stage}.null_bias_deg", st.null_bias_deg, 2, 2.0, "pitch, yaw")
        if a.name == "simplex":
            non_negative(f"actuator.{stage}.leakage_rad_s_per_Nm", st.leakage_rad_s_per_Nm)
            one_of(f"actuator.{stage}.feedback", st.feedback, ("piston", "nozzle"))
            # the valve is integrated by the plant's RK4: keep it well inside its stability
            nyq = 0.25 * plant_rate_hz
            if st.valve_frequency_hz >= nyq:
                raise ConfigError(f"actuator.{stage}.valve_frequency_hz", st.valve_frequency_hz,
                                  f"must be below a quarter of sim.plant_rate_hz ({nyq} Hz) for RK4 stability")
