"""``navigation``: perfect or strapdown inertial navigation and its error bounds."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from omegaconf import MISSING

from savant_cli.config.model_group import ModelGroup
from savant_cli.errors import ConfigError


@dataclass
class NavigationPerfectConfig:
    """``navigation=perfect``: the flight software reads the true state (the source paper's
    §III.H assumption), apart from the navigation unit's mounting misalignment
    (``sensors.misalignment_deg.imu``)."""

    name: str = "perfect"


@dataclass
class GyroErrorsConfig:
    """The IMU gyro triad's errors (body x, y, z)."""

    bias_deg_per_h: list[float] = MISSING
    scale_factor_ppm: list[float] = MISSING
    misalignment_arcsec: list[float] = MISSING


@dataclass
class AccelerometerErrorsConfig:
    """The IMU accelerometer triad's errors (body x, y, z)."""

    bias_micro_g: list[float] = MISSING
    scale_factor_ppm: list[float] = MISSING
    misalignment_arcsec: list[float] = MISSING


@dataclass
class NavigationInertialConfig:
    """``navigation=inertial``: strapdown inertial navigation from an IMU with errors
    (``models/navigation.py``); nominal errors zero, their spread in the dispersion set."""

    name: str = "inertial"
    gyro: GyroErrorsConfig = field(default_factory=GyroErrorsConfig)
    accelerometer: AccelerometerErrorsConfig = field(default_factory=AccelerometerErrorsConfig)
    alignment_arcsec: list[float] = MISSING


#: Bounds of the inertial-navigation errors, ``key: (limit, units)``. The error model is
#: first order in the errors (small-angle attitude error, scale factors ≪ 1): a 1°
#: (3600 arcsec) attitude error keeps the neglected second-order terms below 1 % of the
#: first-order ones, and the bias bounds keep a 10-minute ascent's attitude drift (10 deg/h:
#: 1.7°) and tilt-equivalent (10,000 µg = 0.57°) within that regime. The bounds span
#: navigation to tactical grade; a worse IMU is outside what this model represents.
NAVIGATION_BOUNDS: dict[str, tuple[float, str]] = {
    "gyro.bias_deg_per_h": (10.0, "deg/h"),
    "gyro.scale_factor_ppm": (10000.0, "ppm"),
    "gyro.misalignment_arcsec": (3600.0, "arcsec"),
    "accelerometer.bias_micro_g": (10000.0, "µg"),
    "accelerometer.scale_factor_ppm": (10000.0, "ppm"),
    "accelerometer.misalignment_arcsec": (3600.0, "arcsec"),
    "alignment_arcsec": (3600.0, "arcsec"),
}


def check_navigation(n: NavigationPerfectConfig | NavigationInertialConfig) -> None:
    """Physical checks of the ``navigation`` group: three finite values per error, each
    within :data:`NAVIGATION_BOUNDS`."""
    if n.name != "inertial":
        return
    for path, (limit, units) in NAVIGATION_BOUNDS.items():
        node: Any = n
        for part in path.split("."):
            node = getattr(node, part)
        vals = list(node)
        key = f"navigation.{path}"
        if len(vals) != 3:
            raise ConfigError(key, vals, f"must list 3 values in {units} (body x, y, z)")
        for i, v in enumerate(vals):
            if not (isinstance(v, (int, float)) and np.isfinite(v) and abs(v) <= limit):
                raise ConfigError(f"{key}[{i}]", v, f"must be a finite value within ±{limit:g} {units} (the first-order "
                                                    "error model's range, config.NAVIGATION_BOUNDS)")


GROUP = ModelGroup("navigation", {"perfect": NavigationPerfectConfig, "inertial": NavigationInertialConfig},
                   lambda n, cfg: check_navigation(n))
