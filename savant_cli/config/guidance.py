"""``guidance``: launch site, target orbit, command smoother, PEG; and their checks."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, Optional

from omegaconf import MISSING

from savant_cli import constants
from savant_cli.config.checks import non_negative, positive
from savant_cli.config.run import SimConfig
from savant_cli.errors import ConfigError


class FirstStageSchedule(StrEnum):
    """``guidance.first_stage_schedule``: what indexes the stored profile in the first
    stage, mission time (s) or the speed relative to the atmosphere (m/s)."""

    time = "time"
    relative_velocity = "relative_velocity"

@dataclass
class LaunchSite:
    """``guidance.launch_site``: where the vehicle lifts off.

    Attributes
    ----------
    latitude_deg : float
        Geodetic latitude (deg, within ±90).
    longitude_deg : float
        Longitude (deg, −180 to 360).
    base_altitude_m : float
        Altitude of the pad above the WGS84 ellipsoid (m).
    pad_heading_deg : float
        Heading of the vehicle's reference axis on the pad (deg)."""

    latitude_deg: float = MISSING
    longitude_deg: float = MISSING
    base_altitude_m: float = 0.0
    pad_heading_deg: float = 0.0


@dataclass
class InsertionTolerance:
    """``guidance.target.tolerance``: the largest |error| of the cut-off orbit against the
    target that is still a successful insertion (mission class ``insertion_tolerance``).
    No schema default: each guidance option gives its own; the shipped ones give the 3σ
    LEO injection accuracies launcher users' guides quote (±10 km in each apsis altitude,
    ±0.1° in inclination) [E]."""

    perigee_km: float = MISSING
    apogee_km: float = MISSING
    inclination_deg: float = MISSING


@dataclass
class OrbitTarget:
    """``guidance.target``: the insertion orbit (apsis altitudes above the WGS84
    equatorial radius) and the cutoff altitude on it; every key is required. The plane
    has the inclination and passes through the launch site, northbound, at
    ``in_plane_time_s`` after liftoff (its node follows from the site and that time)."""

    perigee_altitude_km: Optional[float] = None
    apogee_altitude_km: Optional[float] = None
    inclination_deg: Optional[float] = None
    cutoff_altitude_km: Optional[float] = None
    in_plane_time_s: float = 0.0
    tolerance: InsertionTolerance = field(default_factory=InsertionTolerance)


@dataclass
class FirstStageBurn:
    """``guidance.peg.first_stage_burn``: PEG flies a liquid first stage's burn as well, to
    its own cutoff orbit, and commands that stage's cutoff (the SLS core stage's MECO).

    The orbit is given by its apsis altitudes above the WGS84 equatorial radius, km (the
    perigee may lie below the surface: a suborbital cutoff) and the cutoff altitude on it,
    in the plane of ``guidance.target`` (``plane: target``) or in the vehicle's osculating
    plane at PEG's engagement (``plane: engagement``: in-plane steering only, the upper
    stage steers into the target's plane); PEG engages at ``start_s`` after liftoff, with
    the stage's own I-loads: ``isp_vac_s`` (s) and ``shutdown_impulse_time_s`` (its
    engines' shutdown impulse over their rated thrust, s). Every key but ``plane`` is
    required."""

    start_s: float = MISSING
    isp_vac_s: float = MISSING
    shutdown_impulse_time_s: float = MISSING
    perigee_altitude_km: float = MISSING
    apogee_altitude_km: float = MISSING
    cutoff_altitude_km: float = MISSING
    plane: str = "target"


@dataclass
class UpperStageFirstBurn:
    """``guidance.peg.upper_stage_first_burn``: PEG flies the upper stage's first burn to
    its own cutoff orbit, commands that burn's cutoff, holds the attitude through the
    coast and flies the restarted burn to ``guidance.target`` (a parking-orbit or
    perigee-raise burn, then the final one: Centaur's MECO-1 and MES-2, the ICPS's
    perigee raise). The vehicle's events hold the upper stage's cutoff (a backup) and its
    restart. The orbit, as ``first_stage_burn``'s: apsis altitudes above the WGS84
    equatorial radius (km; the perigee may lie below the surface) and the cutoff altitude
    on it, in the target's plane; the I-loads are the upper stage's
    (``guidance.peg.isp_vac_s``, ``shutdown_impulse_time_s``). PEG engages in the first
    burn ``guidance.peg.start_after_ignition_s`` after the ignition, and in the second
    ``start_after_restart_s`` after the restart (s; a short circularization burn needs an
    early engagement). Every key is required."""

    perigee_altitude_km: float = MISSING
    apogee_altitude_km: float = MISSING
    cutoff_altitude_km: float = MISSING
    start_after_restart_s: float = MISSING


#: ``guidance.peg.coast_attitude``'s choices.
COAST_ATTITUDES = ("inertial", "local_horizontal")
#: ``guidance.peg.first_stage_burn.plane``'s choices.
FIRST_STAGE_PLANES = ("target", "engagement")


@dataclass
class PegConfig:
    """``guidance.peg``: closed-loop upper-stage guidance (``models/peg.py``)."""

    enabled: bool = MISSING
    start_after_ignition_s: float = MISSING  # engages this long after upper-stage ignition
    isp_vac_s: Optional[float] = MISSING  # guidance's value of the engine's Isp (an I-load), s
    convergence_tolerance: float = MISSING  # largest relative change of t_go of a converged cycle
    terminal_time_to_go_s: float = MISSING  # steering frozen below this time to go
    max_iterations: int = MISSING  # passes allowed at engagement
    steering_tolerance_deg: float = MISSING  # engagement: thrust-direction change between passes of a converged solution
    blend_s: float = MISSING  # the command turns from the stored profile to PEG's over this time
    max_unconverged_cycles: int = MISSING  # consecutive unconverged cycles that stop the run
    gravity_steps: int = MISSING  # RK4 steps of the gravity prediction over the time to go
    # the nominal engine shutdown impulse in seconds of rated thrust, I_sd / F_vac (an I-load):
    # the cutoff is commanded this much before t_go runs out, so the tail-off completes the burn
    shutdown_impulse_time_s: float = MISSING
    first_stage_burn: Optional[FirstStageBurn] = None  # None: PEG flies the upper stage's burn alone
    upper_stage_first_burn: Optional[UpperStageFirstBurn] = None  # None: the upper stage burns once
    # the attitude a coast after a guided cutoff holds: "inertial", or "local_horizontal"
    # (fixed in the local-horizontal frame, turning with it: a vehicle with pitch and yaw jets)
    coast_attitude: str = "inertial"


@dataclass
class SmootherConfig:
    """``guidance.smoother``: the second-order command smoother between guidance samples.

    Attributes
    ----------
    damping : float
        Damping ratio (–).
    natural_frequency_rad_s : float
        Natural frequency (rad/s)."""

    damping: float = 0.8
    natural_frequency_rad_s: float = 1.0


@dataclass
class GuidanceConfig:
    """``guidance``: the stored command profile, the launch site, the target orbit and PEG
    (``conf/guidance/<name>.yaml``).

    Attributes
    ----------
    name : str
        The guidance's name.
    vehicle : str
        The vehicle the command file was generated for ("": any).
    allow_other_vehicle : bool
        Fly it on another vehicle anyway.
    command_file : str
        The guidance command file (CSV or HDF5), looked up in ``<config dir>/guidance/``.
    launch_site : LaunchSite
        Where the vehicle lifts off (deg, m).
    target : OrbitTarget
        The insertion orbit (km, deg, s).
    smoother : SmootherConfig
        The command smoother (–, rad/s).
    generator : dict
        How the command file was generated (provenance).
    first_stage_schedule : FirstStageSchedule
        The stored profile's first-stage index.
    peg : PegConfig or None
        Closed-loop upper-stage guidance; ``None`` (the stored-profile options, which
        have no ``peg`` section): the stored profile flies to cutoff."""

    name: str = ""
    vehicle: str = ""  # the vehicle the command file was generated for ("": any); another is refused ...
    allow_other_vehicle: bool = MISSING  # ... unless this is true
    command_file: str = ""
    launch_site: LaunchSite = field(default_factory=LaunchSite)
    target: OrbitTarget = field(default_factory=OrbitTarget)
    smoother: SmootherConfig = field(default_factory=SmootherConfig)
    generator: dict[str, Any] = field(default_factory=dict)
    first_stage_schedule: FirstStageSchedule = MISSING  # the stored profile's index in the first stage
    peg: Optional[PegConfig] = None  # None: no PEG section (the stored profile flies to cutoff)


def check_target(g: GuidanceConfig) -> None:
    """``guidance.target``: present and reachable from the launch site."""
    t = g.target
    for name in ("perigee_altitude_km", "apogee_altitude_km", "inclination_deg", "cutoff_altitude_km"):
        if getattr(t, name) is None:
            raise ConfigError(f"guidance.target.{name}", None,
                              f"is required: guidance={g.name or '?'} flies to (and cuts off on) its target orbit")
    positive("guidance.target.perigee_altitude_km", t.perigee_altitude_km)
    if t.apogee_altitude_km < t.perigee_altitude_km:
        raise ConfigError("guidance.target.apogee_altitude_km", t.apogee_altitude_km,
                          f"must be at least the perigee altitude ({t.perigee_altitude_km} km)")
    if not t.perigee_altitude_km <= t.cutoff_altitude_km <= t.apogee_altitude_km:
        raise ConfigError("guidance.target.cutoff_altitude_km", t.cutoff_altitude_km,
                          f"must lie on the target orbit, between its perigee ({t.perigee_altitude_km} km) and "
                          f"apogee ({t.apogee_altitude_km} km)")
    lat = abs(g.launch_site.latitude_deg)
    if not lat <= t.inclination_deg <= 180.0 - lat:
        raise ConfigError("guidance.target.inclination_deg", t.inclination_deg,
                          f"is unreachable from the launch latitude {g.launch_site.latitude_deg} deg without a plane "
                          f"change: allowed [{lat:g}, {180.0 - lat:g}]")
    if not -86400.0 <= t.in_plane_time_s <= 86400.0:
        raise ConfigError("guidance.target.in_plane_time_s", t.in_plane_time_s, "must be within one day of liftoff")
    for name in ("perigee_km", "apogee_km", "inclination_deg"):
        positive(f"guidance.target.tolerance.{name}", getattr(t.tolerance, name))


def check_first_stage_burn(b: FirstStageBurn) -> None:
    """``guidance.peg.first_stage_burn``: positive I-loads, an engagement after liftoff and a
    cutoff orbit whose perigee radius is positive and whose cutoff altitude lies on it."""
    key = "guidance.peg.first_stage_burn"
    if b.plane not in FIRST_STAGE_PLANES:
        raise ConfigError(f"{key}.plane", b.plane, f"must be one of {', '.join(FIRST_STAGE_PLANES)}")
    positive(f"{key}.start_s", b.start_s)
    positive(f"{key}.isp_vac_s", b.isp_vac_s)
    non_negative(f"{key}.shutdown_impulse_time_s", b.shutdown_impulse_time_s)
    check_cutoff_orbit(key, b)


def check_cutoff_orbit(key: str, b: FirstStageBurn | UpperStageFirstBurn) -> None:
    """A burn's cutoff orbit (``key``: its section): a perigee radius > 0, an apogee at
    least the perigee and a cutoff altitude on the orbit above the surface."""
    floor = -constants.WGS84_A / 1e3
    if not b.perigee_altitude_km > floor:
        raise ConfigError(f"{key}.perigee_altitude_km", b.perigee_altitude_km,
                          f"must be above {floor:g} km (a perigee radius > 0; below 0 km the cutoff is suborbital)")
    if b.apogee_altitude_km < b.perigee_altitude_km:
        raise ConfigError(f"{key}.apogee_altitude_km", b.apogee_altitude_km,
                          f"must be at least the perigee altitude ({b.perigee_altitude_km} km)")
    if not max(b.perigee_altitude_km, 0.0) < b.cutoff_altitude_km <= b.apogee_altitude_km:
        raise ConfigError(f"{key}.cutoff_altitude_km", b.cutoff_altitude_km,
                          f"must lie on the cutoff orbit above the surface: within ({max(b.perigee_altitude_km, 0.0)}, "
                          f"{b.apogee_altitude_km}] km")


def check_peg(peg: PegConfig | None, sim: SimConfig) -> None:
    """``guidance.peg``: its I-loads and tunings (checked only when given and enabled)."""
    if peg is None or not peg.enabled:
        return
    if peg.start_after_ignition_s < 0.0:
        raise ConfigError("guidance.peg.start_after_ignition_s", peg.start_after_ignition_s,
                          "PEG cannot start before upper-stage ignition: must be >= 0 s after it")
    if peg.isp_vac_s is None:
        raise ConfigError("guidance.peg.isp_vac_s", None, "is required: PEG's value of the engine's Isp (s)")
    positive("guidance.peg.isp_vac_s", peg.isp_vac_s)
    non_negative("guidance.peg.shutdown_impulse_time_s", peg.shutdown_impulse_time_s)
    if not 0.0 < peg.convergence_tolerance < 0.5:
        raise ConfigError("guidance.peg.convergence_tolerance", peg.convergence_tolerance, "must be within (0, 0.5)")
    non_negative("guidance.peg.terminal_time_to_go_s", peg.terminal_time_to_go_s)
    positive("guidance.peg.steering_tolerance_deg", peg.steering_tolerance_deg)
    non_negative("guidance.peg.blend_s", peg.blend_s)
    for name, low in (("max_iterations", 1), ("max_unconverged_cycles", 1), ("gravity_steps", 1)):
        if getattr(peg, name) < low:
            raise ConfigError(f"guidance.peg.{name}", getattr(peg, name), f"must be at least {low}")
    if peg.first_stage_burn is not None:
        check_first_stage_burn(peg.first_stage_burn)
    if peg.coast_attitude not in COAST_ATTITUDES:
        raise ConfigError("guidance.peg.coast_attitude", peg.coast_attitude,
                          f"must be one of {', '.join(COAST_ATTITUDES)}")
    if peg.upper_stage_first_burn is not None:
        check_cutoff_orbit("guidance.peg.upper_stage_first_burn", peg.upper_stage_first_burn)
        non_negative("guidance.peg.upper_stage_first_burn.start_after_restart_s",
                     peg.upper_stage_first_burn.start_after_restart_s)
    if peg.terminal_time_to_go_s < 1.0 / sim.guidance_rate_hz:
        raise ConfigError("guidance.peg.terminal_time_to_go_s", peg.terminal_time_to_go_s,
                          f"must be at least one guidance cycle (1 / sim.guidance_rate_hz = {1.0 / sim.guidance_rate_hz:g} s)")


def check_guidance(g: GuidanceConfig, sim: SimConfig) -> None:
    """A command file, a launch site on the Earth, the target (:func:`check_target`), the
    schedule from its list, PEG (:func:`check_peg`) and a positive smoother."""
    if not g.command_file:
        raise ConfigError("guidance.command_file", g.command_file, "must name a guidance command file (CSV or HDF5)")
    ls = g.launch_site
    if not -90.0 <= ls.latitude_deg <= 90.0:
        raise ConfigError("guidance.launch_site.latitude_deg", ls.latitude_deg, "must be within [-90, 90]")
    if not -180.0 <= ls.longitude_deg <= 360.0:
        raise ConfigError("guidance.launch_site.longitude_deg", ls.longitude_deg, "must be within [-180, 360]")
    check_target(g)
    check_peg(g.peg, sim)
    positive("guidance.smoother.damping", g.smoother.damping)
    positive("guidance.smoother.natural_frequency_rad_s", g.smoother.natural_frequency_rad_s)
