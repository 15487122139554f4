"""``sensors``: the rate gyros' dynamics and the sensors' mounting misalignment."""

from __future__ import annotations

from dataclasses import dataclass, field

from omegaconf import MISSING

from savant_cli.config.checks import positive, small_angles
from savant_cli.config.run import SimConfig
from savant_cli.errors import ConfigError


@dataclass
class RateGyroConfig:
    """``sensors.rate_gyro``: each rate gyro's second-order transfer function.

    Attributes
    ----------
    natural_frequency_hz : float
        Natural frequency (Hz), below the sensor Nyquist frequency.
    damping : float
        Damping ratio (–)."""

    natural_frequency_hz: float = MISSING
    damping: float = MISSING


@dataclass
class SensorMisalignment:
    """Mounting misalignment of each sensor package: a small rotation vector from the body
    axes to the sensor's axes (x, y, z body axes, deg)."""

    imu: list[float] = MISSING
    rate_gyro_upper_stage: list[float] = MISSING
    rate_gyro_first_stage: list[float] = MISSING


@dataclass
class SensorsConfig:
    """``sensors``: the rate gyros and the sensors' mounting misalignment.

    Attributes
    ----------
    name : str
        The sensor set's name.
    rate_gyro : RateGyroConfig
        Gyro dynamics (Hz, –).
    misalignment_deg : SensorMisalignment
        Mounting misalignments (deg)."""

    name: str = "ares_i_gyros"
    rate_gyro: RateGyroConfig = field(default_factory=RateGyroConfig)
    misalignment_deg: SensorMisalignment = field(default_factory=SensorMisalignment)


def check_sensors(s: SensorsConfig, sim: SimConfig) -> None:
    """A positive gyro bandwidth below the sensor Nyquist frequency, a positive damping,
    misalignments of 3 angles within ±1 deg."""
    positive("sensors.rate_gyro.natural_frequency_hz", s.rate_gyro.natural_frequency_hz)
    positive("sensors.rate_gyro.damping", s.rate_gyro.damping)
    for name in ("imu", "rate_gyro_upper_stage", "rate_gyro_first_stage"):
        small_angles(f"sensors.misalignment_deg.{name}", getattr(s.misalignment_deg, name), 3, 1.0,
                     "about body x, y, z")
    nyquist = 0.5 * sim.sensor_rate_hz
    if s.rate_gyro.natural_frequency_hz >= nyquist:
        raise ConfigError("sensors.rate_gyro.natural_frequency_hz", s.rate_gyro.natural_frequency_hz,
                          f"must be below the sensor Nyquist frequency {nyquist} Hz")
