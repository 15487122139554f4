"""A vehicle as a tree of parts: stages, boosters and jettisoned items holding tanks,
engines and roll jets, the configurations the event sequence reaches, and the events.

Every record is loaded, checked and in SI (angles in rad, locations in the structure
frame: x aft of the nose tip, y = body y, z = −body z, m). Names are unique across the
whole vehicle (parts, tanks, engines, events and configurations), so an event, a
condition or a dispersion names any of them without a path. The YAML schema these come
from is documented in ``docs/vehicles.md``; :mod:`savant_cli.vehicle.schema` reads it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from savant_cli.vehicle.tables import AeroTable, MassTable

#: Kinds of part.
STAGE, BOOSTER, ITEM = "stage", "booster", "item"
#: Thrust sources of an engine.
TRACE, LIQUID = "trace", "liquid"
#: Gimbal axes an engine may have, in this order.
GIMBAL_AXES = ("pitch", "yaw")
#: What an event's condition may watch (``when.quantity``), and the part of the vehicle it
#: names with ``of`` (None: the whole vehicle).
CONDITION_QUANTITIES = {
    "thrust_fraction": "engine or part",  # sensed vacuum thrust over its own flown peak (1)
    "axial_acceleration_mps2": None,  # sensed specific force along body x, m/s²
    "altitude_m": None,  # geodetic height, m
    "dynamic_pressure_Pa": None,  # Pa
    "propellant_kg": "tank",  # propellant remaining in a tank, kg
    "radial_speed_mps": None,  # the CG's radial (vertical) inertial speed r·v/|r|, m/s: 0 at apogee
}
#: The event every trigger counts from unless it names another.
LIFTOFF = "liftoff"
#: Tanks with a ``slosh`` section a vehicle may have (the plant's per-tank diagnostics
#: are sized for them: ``models/slosh.py``).
MAX_SLOSH_TANKS = 6


@dataclass(frozen=True)
class MovingMass:
    """Moving engine (nozzle) mass properties about its gimbal, for tail-wags-dog.

    Attributes
    ----------
    mass_kg : float
        Moving mass, kg.
    cg_from_gimbal_m : float
        Distance from the gimbal aft to the moving mass's CG, m.
    inertia_about_gimbal_kgm2 : float
        Transverse moment of inertia about the gimbal, kg m^2.
    """

    mass_kg: float
    cg_from_gimbal_m: float
    inertia_about_gimbal_kgm2: float


@dataclass(frozen=True)
class Tank:
    """A propellant tank (a solid motor's grain is one tank).

    Attributes
    ----------
    name, part : str
        The tank's name and the part it belongs to.
    propellant_kg : float
        Load at liftoff, kg.
    slosh : dict or None
        The slosh section (``table``, ``radius_m``, ``bottom_station_m``,
        ``density_kgm3``, ``reference_accel_mps2``), read by ``savant_cli.flex_slosh``
        when ``slosh=on``; None: the tank does not slosh.
    key : str
        The tank's YAML path, for refusals.
    """

    name: str
    part: str
    propellant_kg: float
    slosh: dict | None
    key: str


@dataclass(frozen=True)
class ThrustTrace:
    """An engine flown by its thrust trace (a solid motor, or any engine described that
    way): the vacuum thrust's shape against time from liftoff (s, N), burning its one
    tank's load at ``isp_vac_s`` (docs/models.md, "Propulsion")."""

    time_s: np.ndarray
    thrust_vac_N: np.ndarray
    isp_vac_s: float
    isp_sl_s: float


@dataclass(frozen=True)
class Throttle:
    """A liquid engine's throttle: its command is ``maximum`` or the schedule's value at
    mission time (``time_s``, ``setting``; None: no schedule), lowered, when
    ``axial_acceleration_limit_mps2`` is set, to hold the sensed axial acceleration at the
    limit; clamped to [``minimum``, ``maximum``] and changed at most ``rate_per_s``
    (fraction of rated thrust per s). Settings are fractions of rated thrust
    (``models/throttle.py``)."""

    minimum: float
    maximum: float
    rate_per_s: float
    time_s: np.ndarray | None = None
    setting: np.ndarray | None = None
    axial_acceleration_limit_mps2: float | None = None


@dataclass(frozen=True)
class LiquidThrust:
    """A liquid engine: rated vacuum thrust (N), Isp (s), oxidizer : fuel mixture ratio,
    start transient (thrust fraction against time since the ignition command, s),
    shutdown impulse (N·s, the vacuum impulse after the cutoff command) and its throttle
    (None: it burns at rated thrust)."""

    thrust_vac_N: float
    isp_vac_s: float
    mixture_ratio: float
    startup_time_s: np.ndarray
    startup_fraction: np.ndarray
    shutdown_impulse_Ns: float
    throttle: Throttle | None = None


@dataclass(frozen=True)
class EngineSpec:
    """One engine: its thrust source, the tanks it draws from, its mounting and gimbal.

    Attributes
    ----------
    name, part : str
        The engine's name and the part it belongs to.
    thrust : ThrustTrace or LiquidThrust
        The thrust source (``source: trace`` or ``liquid``).
    tanks : tuple of str
        A trace engine's one tank (a solid motor's grain); a liquid engine's oxidizer and fuel tanks, in that order.
    nozzle_exit_area_m2 : float
        Delivered thrust is ``F_vac − p A_exit``, m².
    gimbal_m : numpy.ndarray
        ``(3,)`` the gimbal pivot (the thrust's point of application), structure frame, m.
    cant_rad : numpy.ndarray
        ``(2,)`` the nozzle's fixed cant at null, pitch and yaw, rad.
    gimbal_axes : tuple of str
        The axes the nozzle gimbals in (a subset of ``pitch``, ``yaw``; empty: fixed).
    gimbal_limit_rad : float
        Gimbal angle limit per axis, rad (0 for a fixed nozzle).
    moving_mass : MovingMass or None
        The gimbaled mass, for tail-wags-dog (None for a fixed nozzle).
    key : str
        The engine's YAML path.
    """

    name: str
    part: str
    thrust: ThrustTrace | LiquidThrust
    tanks: tuple[str, ...]
    nozzle_exit_area_m2: float
    gimbal_m: np.ndarray
    cant_rad: np.ndarray
    gimbal_axes: tuple[str, ...]
    gimbal_limit_rad: float
    moving_mass: MovingMass | None
    key: str

    @property
    def source(self) -> str:
        """``trace`` or ``liquid``."""
        return TRACE if isinstance(self.thrust, ThrustTrace) else LIQUID


@dataclass(frozen=True)
class RollJets:
    """Roll-control jets: vacuum thrust per jet (N) vs altitude (m), exit area (m^2),
    number of jets per roll direction, moment arm (m), ramp times (s), location
    (structure frame, m); and the same pods' pitch and yaw jets (optional): vacuum
    thrust per jet (N; 0: none) and jets firing together per direction, their lateral
    force at the pods' station (``location_m``'s x), fired in the coasts only."""

    altitude_m: np.ndarray
    thrust_vac_N: np.ndarray
    exit_area_m2: float
    jets_per_direction: int
    moment_arm_m: float
    ramp_up_s: float
    ramp_down_s: float
    location_m: np.ndarray
    pitch_yaw_thrust_N: float = 0.0
    pitch_yaw_jets_per_direction: int = 0


@dataclass(frozen=True)
class Part:
    """A stage, a booster or a jettisoned item.

    Attributes
    ----------
    name, kind : str
        The part's name; ``stage``, ``booster`` or ``item``.
    attached_to : str or None
        The stage a booster or an item is mounted on (None for a stage); jettisoning that
        stage takes it along.
    inert_mass_kg : float or None
        What leaves with the part besides its propellant, kg (an item's whole mass);
        None when not given (a stage never jettisoned).
    tanks, engines : tuple of str
        Its tanks and engines, in the order written.
    roll_jets : RollJets or None
        Its roll-control jets.
    key : str
        The part's YAML path.
    mass : MassTable or None
        A stage's or booster's own mass properties against its own propellant (for
        configurations composed from their parts; None: not given).
    cg_m, inertia_kgm2 : numpy.ndarray or None
        An item's CG (structure frame, m) and inertia about it (body axes, ``[Ixx, Iyy,
        Izz, Ixy, Ixz, Iyz]`` kg m²; zeros: a point mass); None: not given.
    mixing_matrix : numpy.ndarray or None
        A stage's own control mixer, ``(2 n_engines, 3)``: each gimbal channel's angle
        (pitch then yaw of each engine, in order) per radian of the roll, pitch and yaw
        commands (``models/cluster.py``); None: the mixer's own allocation.
    """

    name: str
    kind: str
    attached_to: str | None
    inert_mass_kg: float | None
    tanks: tuple[str, ...]
    engines: tuple[str, ...]
    roll_jets: RollJets | None
    key: str
    mass: MassTable | None = None
    cg_m: np.ndarray | None = None
    inertia_kgm2: np.ndarray | None = None
    mixing_matrix: np.ndarray | None = None


@dataclass(frozen=True)
class Condition:
    """What a condition-triggered event watches: ``quantity`` (a key of
    :data:`CONDITION_QUANTITIES`) of ``of`` (an engine, part or tank; None for the
    vehicle) crossing ``below`` or ``above`` (the quantity's units; one is None)."""

    quantity: str
    of: str | None
    below: float | None
    above: float | None


@dataclass(frozen=True)
class EventSpec:
    """One event of the sequence: its trigger and its actions.

    The trigger: ``delay_s`` after the event ``after`` (``liftoff`` or an earlier event),
    and from then on the first step at which ``when`` holds (None: at once).

    Attributes
    ----------
    name, after : str
    delay_s : float
        s, ≥ 0.
    when : Condition or None
    jettison, ignite, shutdown : tuple of str
        Parts dropped, engines ignited and engines shut down.
    key : str
        The event's YAML path.
    """

    name: str
    after: str
    delay_s: float
    when: Condition | None
    jettison: tuple[str, ...]
    ignite: tuple[str, ...]
    shutdown: tuple[str, ...]
    key: str


@dataclass(frozen=True)
class ConfigurationSpec:
    """A flight configuration: the parts attached, its aerodynamics and its mass table
    against the propellant of ``mass_tanks`` (read from its own file, or composed from
    its parts').

    Attributes
    ----------
    name : str
    parts : frozenset of str
        The parts attached while it flies.
    aero : AeroTable
    mass : MassTable
        Mass properties against the summed propellant of ``mass_tanks``.
    mass_tanks : tuple of str
        The tanks whose propellant remaining is the mass table's argument.
    mass_file : str
        The mass table's file name, or what it was composed from, for refusals.
    key : str
    """

    name: str
    parts: frozenset[str]
    aero: AeroTable
    mass: MassTable
    mass_tanks: tuple[str, ...]
    mass_file: str
    key: str


@dataclass(frozen=True)
class Sensors:
    """Sensor locations, structure frame, m."""

    imu_m: np.ndarray
    rate_gyro_upper_stage_m: np.ndarray
    rate_gyro_first_stage_m: np.ndarray


@dataclass(frozen=True)
class VehicleTree:
    """A loaded, checked vehicle, all SI.

    Attributes
    ----------
    parts : dict of str to Part
        Stages in firing order, then boosters, then items.
    tanks, engines : dict
        Every tank and engine by name, in the order written.
    configurations : dict of str to ConfigurationSpec
        In the order the sequence reaches them (the liftoff configuration first).
    events : dict of str to EventSpec
        In the order written (each trigger counts from liftoff or an earlier event).
    sequence : tuple of (str, str)
        ``(event, configuration)``: the liftoff configuration (event ``liftoff``), then
        the configuration each jettison leaves, in the order written.
    """

    name: str
    description: str
    length_m: float
    parts: dict[str, Part]
    tanks: dict[str, Tank]
    engines: dict[str, EngineSpec]
    configurations: dict[str, ConfigurationSpec]
    events: dict[str, EventSpec]
    sequence: tuple[tuple[str, str], ...]
    sensors: Sensors
    data_dir: Path | None = None
    flex_spec: dict | None = None
    qalpha_limit_Pa_deg: float | None = None

    def stages(self) -> list[Part]:
        """The stages, in firing order."""
        return [p for p in self.parts.values() if p.kind == STAGE]

    def engines_of(self, part: str) -> list[EngineSpec]:
        """The engines of ``part``."""
        return [self.engines[e] for e in self.parts[part].engines]

    def ignited_later(self) -> set[str]:
        """Engines some event ignites (every other engine burns from liftoff)."""
        return {e for ev in self.events.values() for e in ev.ignite}
