"""``winds``: the wind profile, the discrete gust and the wind shear."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import finite, increasing, non_negative, positive
from savant_cli.errors import ConfigError


@dataclass
class WindProfile:
    """``winds.profile``: the horizontal wind against altitude.

    Attributes
    ----------
    altitude_m : list of float
        Altitudes above the WGS84 ellipsoid (m), strictly increasing.
    north_mps, east_mps : list of float
        Wind toward north and east at each altitude (m/s)."""

    altitude_m: list[float] = field(default_factory=list)
    north_mps: list[float] = field(default_factory=list)
    east_mps: list[float] = field(default_factory=list)


class GustOnset(StrEnum):
    """``winds.gust.onset``: what the gust coordinate runs in, geodetic altitude (m) or
    mission time (s)."""

    altitude = "altitude"
    time = "time"


class GustFrame(StrEnum):
    """``winds.gust.frame``: ``ned``, horizontal toward an azimuth; ``flight_path``,
    across the flight path at a clock angle."""

    ned = "ned"
    flight_path = "flight_path"


class ShearShape(StrEnum):
    """``winds.shear.shape``: the build-up across the band, a linear or a cosine ramp."""

    linear = "linear"
    cosine = "cosine"


@dataclass
class GustConfig:
    """``winds.gust``: a discrete 1 − cos gust (``models/winds.py``, docs/models.md)."""

    enabled: bool = MISSING
    amplitude_mps: float = MISSING  # peak speed A, reached at mid-length
    onset: GustOnset = MISSING  # what the gust coordinate s runs in
    onset_altitude_m: float = MISSING  # onset: altitude: where the gust starts (geodetic)
    length_m: float = MISSING  # onset: altitude: full thickness d (build-up d/2, peak at d/2)
    onset_time_s: float = MISSING  # onset: time: when the gust starts (mission time)
    duration_s: float = MISSING  # onset: time: full duration d
    frame: GustFrame = MISSING  # ned: horizontal toward direction_deg; flight_path: across the path
    direction_deg: float = MISSING  # ned: azimuth from north; flight_path: clock angle (0 up: +alpha, 90 left: +beta)


@dataclass
class ShearConfig:
    """``winds.shear``: a build-up of the horizontal wind by ``delta_mps`` over an altitude band."""

    enabled: bool = MISSING
    delta_mps: float = MISSING  # Δv over the band (m/s, may be negative)
    base_altitude_m: float = MISSING  # bottom of the band (geodetic)
    thickness_m: float = MISSING  # band thickness Δh
    return_thickness_m: float = MISSING  # > 0: Δv is removed again over this thickness above the band
    shape: ShearShape = MISSING
    direction_deg: float = MISSING  # azimuth the added wind blows toward, from north


@dataclass
class WindsConfig:
    """``winds``: a wind profile with an optional gust and shear (``conf/winds/<name>.yaml``).

    Attributes
    ----------
    name : str
        The profile's name.
    enabled : bool
        Whether any wind blows.
    scale : float
        Multiplies the profile (–, within [0, :data:`MAX_WINDS_SCALE`]).
    profile : WindProfile
        Wind against altitude (m, m/s).
    gust : GustConfig
        Discrete 1 − cos gust.
    shear : ShearConfig
        Wind shear over an altitude band."""

    name: str = "none"
    enabled: bool = MISSING
    scale: float = MISSING
    profile: WindProfile = field(default_factory=WindProfile)
    gust: GustConfig = field(default_factory=GustConfig)
    shear: ShearConfig = field(default_factory=ShearConfig)


#: Largest ``winds.scale``: the shipped strong-jet profile peaks at 53 m/s, five times it
#: at 266 m/s, more than twice the fastest jet-stream winds measured (about 110 m/s);
#: beyond that the profile is no longer a wind but a modelling error (docs/outputs.md).
MAX_WINDS_SCALE = 5.0


def check_gust_shear(w: WindsConfig) -> None:
    """``winds.gust`` and ``winds.shear`` (checked whether enabled or not, so a switched-off
    gust is ready to fly): a gust amplitude within ±50 m/s, a
    positive length (``onset: altitude``) or duration (``onset: time``), an onset above
    the ground or after liftoff, a shear of at most ±100 m/s over a positive band."""
    g = w.gust
    if not (np.isfinite(g.amplitude_mps) and abs(g.amplitude_mps) <= 50.0):
        raise ConfigError("winds.gust.amplitude_mps", g.amplitude_mps, "must be a finite speed within ±50 m/s")
    finite("winds.gust.direction_deg", g.direction_deg)
    if g.onset == "altitude":
        non_negative("winds.gust.onset_altitude_m", g.onset_altitude_m)
        positive("winds.gust.length_m", g.length_m)
    else:
        non_negative("winds.gust.onset_time_s", g.onset_time_s)
        positive("winds.gust.duration_s", g.duration_s)
    s = w.shear
    if not (np.isfinite(s.delta_mps) and abs(s.delta_mps) <= 100.0):
        raise ConfigError("winds.shear.delta_mps", s.delta_mps, "must be a finite speed within ±100 m/s")
    finite("winds.shear.base_altitude_m", s.base_altitude_m)
    positive("winds.shear.thickness_m", s.thickness_m)
    non_negative("winds.shear.return_thickness_m", s.return_thickness_m)
    finite("winds.shear.direction_deg", s.direction_deg)


def check_winds_scale(w: WindsConfig) -> None:
    """``winds.scale`` within [0, :data:`MAX_WINDS_SCALE`]."""
    if not (np.isfinite(w.scale) and 0.0 <= w.scale <= MAX_WINDS_SCALE):
        raise ConfigError("winds.scale", w.scale, f"must lie between 0 and {MAX_WINDS_SCALE:g} (five times the "
                          "strongest shipped profile is already twice the fastest jet stream measured)")


def check_winds(w: WindsConfig) -> None:
    """An enabled profile's altitudes strictly increasing with one speed per altitude; the
    gust and the shear (:func:`check_gust_shear`)."""
    if w.enabled:
        increasing("winds.profile.altitude_m", list(w.profile.altitude_m))
        n = len(w.profile.altitude_m)
        for comp in ("north_mps", "east_mps"):
            vals = list(getattr(w.profile, comp))
            if len(vals) != n:
                raise ConfigError(f"winds.profile.{comp}", vals, f"must have one value per altitude ({n})")
    check_gust_shear(w)
