"""``sim``, ``environment`` and ``phase``: the run's rates, bounds, flight health, physics
switches and the phase of flight flown."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Optional

import numpy as np
from omegaconf import MISSING

from savant_cli.config.checks import non_negative, one_of, positive
from savant_cli.errors import ConfigError


@dataclass
class HealthConfig:
    """``sim.health``: when a run that flew to its end is not a clean ``complete``
    (``savant_cli/sim/health.py``)."""

    max_saturation_s: float = MISSING  # s on a rate limit or gimbal stop (per stage) → "saturated"
    min_amplitude_deg: float = MISSING  # limit cycle, slow divergence: smallest amplitude (gimbal angle, attitude error)
    min_periods: float = MISSING  # limit cycle: the oscillation holds for at least this many periods
    tonal_fraction: float = MISSING  # limit cycle: share of the detrended variance in the periodic part
    max_damping_ratio: float = MISSING  # limit cycle: an envelope decaying (or growing) this fast is not sustained
    event_quiet_s: float = MISSING  # limit cycle, slow divergence: s left out after each event
    divergence_growth: float = MISSING  # slow divergence: attitude-error envelope growth (–) to the stage's end
    divergence_min_amplitude_deg: float = MISSING  # slow divergence: ... reaching this (deg): 1/10 of the LOC bound
    max_attitude_error_deg: float = MISSING  # loss of control: pitch/yaw attitude-error magnitude bound
    max_alpha_deg: Optional[float] = MISSING  # loss of control: total angle-of-attack bound (None: off)
    alpha_min_dynamic_pressure_Pa: float = MISSING  # the α bound applies from this dynamic pressure on


def check_health(sim: SimConfig) -> None:
    h = sim.health
    for name in ("max_saturation_s", "event_quiet_s", "alpha_min_dynamic_pressure_Pa"):
        non_negative(f"sim.health.{name}", getattr(h, name))
    for name in ("min_amplitude_deg", "max_damping_ratio"):
        positive(f"sim.health.{name}", getattr(h, name))
    if not (np.isfinite(h.min_periods) and h.min_periods >= 2.0):
        raise ConfigError("sim.health.min_periods", h.min_periods,
                          "must be a finite number of periods of at least 2 (a sustained oscillation repeats)")
    if not 0.0 < h.tonal_fraction <= 1.0:
        raise ConfigError("sim.health.tonal_fraction", h.tonal_fraction, "must lie in (0, 1]")
    if not (np.isfinite(h.divergence_growth) and h.divergence_growth > 1.0):
        raise ConfigError("sim.health.divergence_growth", h.divergence_growth,
                          "must be a finite envelope growth ratio above 1")
    if not (np.isfinite(h.max_attitude_error_deg) and 0.0 < h.max_attitude_error_deg < 180.0):
        raise ConfigError("sim.health.max_attitude_error_deg", h.max_attitude_error_deg,
                          "must be an angle between 0 and 180 deg (exclusive)")
    if not 0.0 < h.divergence_min_amplitude_deg <= h.max_attitude_error_deg:
        raise ConfigError("sim.health.divergence_min_amplitude_deg", h.divergence_min_amplitude_deg,
                          f"must be positive and at most sim.health.max_attitude_error_deg "
                          f"({h.max_attitude_error_deg} deg): a divergence is flagged before it is a loss of control")
    if h.max_alpha_deg is not None and not (np.isfinite(h.max_alpha_deg) and 0.0 < h.max_alpha_deg < 180.0):
        raise ConfigError("sim.health.max_alpha_deg", h.max_alpha_deg,
                          "must be null (no bound) or an angle between 0 and 180 deg (exclusive)")


@dataclass
class SimConfig:
    """``sim``: rates, the run's length and its divergence bound. Rates are bounded by
    :data:`SIM_BOUNDS` and must divide the plant rate into whole steps.

    Attributes
    ----------
    plant_rate_hz : float
        RK4 integration rate of the continuous plant (Hz).
    sensor_rate_hz : float
        Rate-gyro sampling rate (Hz).
    fcs_rate_hz : float
        Flight control, smoother and roll-jet rate (Hz).
    guidance_rate_hz : float
        Rate of new guidance command samples (Hz).
    log_rate_hz : float
        Time-history output rate (Hz).
    max_time_s : float
        Hard stop (s).
    chunk_s : float
        Simulated time per compiled call (s; the progress granularity).
    progress : bool
        Progress bar on the console.
    max_body_rate_deg_s : float
        A body-rate magnitude above this is a divergence (deg/s).
    health : HealthConfig
        When a run that flew to its end is not a clean ``complete``."""

    plant_rate_hz: float = MISSING
    sensor_rate_hz: float = MISSING
    fcs_rate_hz: float = MISSING
    guidance_rate_hz: float = MISSING
    log_rate_hz: float = MISSING
    max_time_s: float = MISSING
    chunk_s: float = MISSING
    progress: bool = MISSING
    max_body_rate_deg_s: float = MISSING
    health: HealthConfig = field(default_factory=HealthConfig)


#: finish in reasonable time or memory (the log holds max_time_s × log_rate_hz rows).
SIM_BOUNDS = {"plant_rate_hz": (20.0, 10000.0), "sensor_rate_hz": (1.0, 10000.0), "fcs_rate_hz": (1.0, 1000.0),
              "guidance_rate_hz": (0.01, 100.0), "log_rate_hz": (0.1, 1000.0), "max_time_s": (1.0, 3600.0)}

#: Most rows of a run's time history, ``sim.max_time_s × sim.log_rate_hz``: the history is
#: allocated whole before the flight, about 280 columns of 8 bytes at full fidelity, so
#: 500,000 rows are about 1.1 GB in memory and again in ``savant.h5`` (ten times the
#: default log rate over the default flight; docs/outputs.md, "Bounds").
MAX_LOG_ROWS = 500_000


def check_sim(sim: SimConfig) -> None:
    for name, (low, high) in SIM_BOUNDS.items():
        value = getattr(sim, name)
        positive(f"sim.{name}", value)
        if not low <= value <= high:
            raise ConfigError(f"sim.{name}", value, f"must lie between {low:g} and {high:g}")
    rows = sim.max_time_s * sim.log_rate_hz
    if rows > MAX_LOG_ROWS:
        raise ConfigError("sim.log_rate_hz", sim.log_rate_hz,
                          f"with sim.max_time_s = {sim.max_time_s:g} s the history would hold {rows:,.0f} rows; at most "
                          f"{MAX_LOG_ROWS:,} (about 1.1 GB): allowed up to {MAX_LOG_ROWS / sim.max_time_s:g} Hz, or a "
                          "shorter sim.max_time_s")
    for name in ("sensor_rate_hz", "fcs_rate_hz", "guidance_rate_hz", "log_rate_hz"):
        ratio = sim.plant_rate_hz / getattr(sim, name)
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ConfigError(f"sim.{name}", getattr(sim, name),
                              f"must divide sim.plant_rate_hz = {sim.plant_rate_hz} into a whole number of steps")
    positive("sim.chunk_s", sim.chunk_s)
    positive("sim.max_body_rate_deg_s", sim.max_body_rate_deg_s)
    check_health(sim)


@dataclass
class EnvironmentConfig:
    """``environment``: the physics switched on.

    Attributes
    ----------
    gravity_order : int
        Highest zonal harmonic, one of :data:`GRAVITY_ORDERS` (0: point mass).
    aero : bool
        Aerodynamic forces and moments.
    thrust : bool
        Propulsion forces and moments."""

    gravity_order: int = MISSING
    aero: bool = MISSING
    thrust: bool = MISSING


class PhaseStart(StrEnum):
    """``phase.start``: at liftoff, or at staging from ``phase.staging_state_file``."""

    liftoff = "liftoff"
    staging = "staging"


class PhaseStop(StrEnum):
    """``phase.stop_at``: upper-stage cutoff, or first-stage separation."""

    cutoff = "cutoff"
    separation = "separation"


@dataclass
class PhaseConfig:
    """``phase``: the part of the flight flown.

    Attributes
    ----------
    name : str
        The phase's name.
    start : str
        ``liftoff``, or ``staging`` from ``staging_state_file``.
    stop_at : PhaseStop
        ``cutoff`` or ``separation``.
    staging_state_file : str
        The staging state a phase starting at staging starts from (looked up in
        ``<config dir>/phase/``)."""

    name: str = "ascent"
    start: PhaseStart = MISSING
    stop_at: PhaseStop = MISSING
    staging_state_file: str = MISSING


#: ``environment.gravity_order`` options: the highest zonal harmonic (0: point mass).
GRAVITY_ORDERS = (0, 2, 3, 4)


def check_environment(e: EnvironmentConfig) -> None:
    """``environment.gravity_order`` one of :data:`GRAVITY_ORDERS`."""
    one_of("environment.gravity_order", e.gravity_order, GRAVITY_ORDERS)


def check_phase(p: PhaseConfig) -> None:
    """A phase starting at staging names its staging-state file and stops at cutoff."""
    if p.start == "staging" and p.stop_at == "separation":
        raise ConfigError("phase.stop_at", p.stop_at, "a phase starting at staging must stop at cutoff")
    if p.start == "staging" and not p.staging_state_file:
        raise ConfigError("phase.staging_state_file", "", "must name a staging-state file when phase.start = staging")
