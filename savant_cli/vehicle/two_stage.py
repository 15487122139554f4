"""The two-stage vehicle the compiled plant flies today, as a view of the vehicle tree.

The plant's models (``savant_cli/models/``) read a vehicle of one shape: a first stage
of engines flown by their thrust trace (a solid motor) or of liquid engines (each drawing
from the stage's oxidizer and fuel tank, optionally throttled), an upper stage of liquid
engines drawing from an oxidizer and a fuel tank and carrying the roll jets (each stage
one engine or a cluster of identical ones, ``models/cluster.py``), optionally identical
strap-on solid boosters on the first stage (fixed or gimbaled nozzles, lit at liftoff,
jettisoned together first), up to four item jettisons (LES, fairing, interstage) in any
phase after the boosters' jettison, and the configurations the sequence reaches
(``boosted`` with boosters, then ``stack`` and ``stack_2`` … while items leave the first
stage's flight, ``upper_les``, ``upper_les_2`` … while items leave the upper stage's, and
``upper``: the slots' names, whatever the file calls them). :func:`two_stage_view` derives these records from a loaded
:class:`~savant_cli.vehicle.tree.VehicleTree` and refuses, naming the key, a tree the
plant cannot fly yet (more stages, other boosters, other event sequences).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from savant_cli.constants import G0, P0
from savant_cli.errors import ConfigError
from savant_cli.vehicle.tables import MASS_TOLERANCE_KG, AeroTable, MassTable
from savant_cli.vehicle.tree import (
    BOOSTER, GIMBAL_AXES, ITEM, LIFTOFF, LIQUID, MAX_SLOSH_TANKS, TRACE, EngineSpec, LiquidThrust, MovingMass, RollJets,
    Sensors, Throttle, ThrustTrace, VehicleTree
)

#: The vehicle's configurations, in the order the aero and mass tables are stacked
#: (models/configurations.py numbers them).
CONFIG_NAMES = ("stack", "upper_les", "upper")
#: The consistency check's keys for a view built without a tree.
LEGACY_KEYS = {"propellant_first": "first_stage.propellant_kg", "propellant_upper": "upper_stage.lox_kg + lh2_kg",
               "jettison_mass": "first_stage.jettison_mass_kg", "les_mass": "upper_stage.les_mass_kg"}


@dataclass(frozen=True)
class Configuration:
    """One flight configuration (``stack``, ``upper_les``, ``upper``)."""

    name: str
    aero: AeroTable
    mass: MassTable


#: The moving engine (nozzle) mass properties about its gimbal, for tail-wags-dog.
Engine = MovingMass


@dataclass(frozen=True)
class Mount:
    """Where one engine of a stage's cluster sits: its gimbal's offset from the stage's
    gimbal point (structure frame, m; the stage's ``gimbal_m`` is the engines' mean) and
    its nozzle's fixed cant at null (pitch, yaw, rad: added to the thrust-line angles)."""

    name: str
    offset_m: np.ndarray
    cant_rad: np.ndarray


@dataclass(frozen=True)
class FirstStage:
    """First stage. Thrust is vacuum thrust (N) vs time from liftoff (s); the
    delivered thrust is ``F_vac - p A_exit``; mass flow ``F_vac / (g0 Isp_vac)``.
    Gimbal location in the structure frame (m); limit in rad.

    A solid stage (``liquid`` None) is flown by its thrust table and burns
    ``propellant_kg`` from one tank. A liquid stage (``liquid``: the engines' sums of
    rated thrust and shutdown impulse, their Isp, mixture ratio, start transient and
    throttle) burns its ``oxidizer_kg`` and ``fuel_kg`` (``propellant_kg`` is their sum)
    at the mixture ratio until a tank is empty; its thrust table is the rated trace (the
    start transient completing at liftoff, then rated thrust until the usable load,
    :func:`usable_load`, is burned): an unthrottled stage's nominal trace. The flight
    throttles a throttled stage by its law (``models/throttle.py``), and its nominal
    trace is that law's (``sim/build.py::nominal_first_stage_trace``).

    A cluster of identical engines is one record of the whole stage: the thrust table and
    the exit area are the engines' sums, ``gimbal_m`` their mean gimbal point, ``engine``
    (the moving mass) and the limit each engine's; ``mounts`` places each engine (empty:
    one engine at ``gimbal_m``, not canted), and each carries an equal share of the thrust;
    ``mixing_matrix`` is the vehicle file's own control mixer for them (None: the mixer's
    allocation, ``models/cluster.py``)."""

    thrust_time_s: np.ndarray
    thrust_vac_N: np.ndarray
    isp_vac_s: float
    isp_sl_s: float
    nozzle_exit_area_m2: float
    propellant_kg: float
    jettison_mass_kg: float
    gimbal_m: np.ndarray
    gimbal_limit_rad: float
    engine: Engine
    mounts: tuple[Mount, ...] = ()
    mixing_matrix: np.ndarray | None = None
    liquid: LiquidThrust | None = None
    oxidizer_kg: float = 0.0
    fuel_kg: float = 0.0


#: The rated trace's fall from burnout thrust to zero (s): the plant's first-stage thrust
#: stops at the step a tank empties; the table only needs a strictly increasing time axis.
BURNOUT_DROP_S = 0.01


def usable_load(mixture_ratio: float, oxidizer_kg: float, fuel_kg: float) -> float:
    """Propellant (kg) burned at the oxidizer : fuel ``mixture_ratio`` r before the first
    tank is empty: ``min(M_ox, r M_fuel) (1 + 1/r)``."""
    return min(oxidizer_kg, mixture_ratio * fuel_kg) * (1.0 + 1.0 / mixture_ratio)


def startup_duration(liquid: LiquidThrust) -> float:
    """The start transient's length (s): the last time of its table."""
    return float(liquid.startup_time_s[-1])


def rated_liquid_trace(liquid: LiquidThrust, oxidizer_kg: float, fuel_kg: float) -> tuple[np.ndarray, np.ndarray]:
    """A liquid stage's rated trace: vacuum thrust (N) against mission time (s) with the
    start transient ending at liftoff (ignition at ``−startup_duration``; what burns
    before liftoff is not the liftoff load's), then the transient's final thrust until
    the usable load is burned at ``F / (g0 Isp)``, then zero."""
    t = liquid.startup_time_s - startup_duration(liquid)
    f = liquid.startup_fraction * liquid.thrust_vac_N
    t_burn = usable_load(liquid.mixture_ratio, oxidizer_kg, fuel_kg) * G0 * liquid.isp_vac_s / f[-1]
    return np.concatenate([t, [t_burn, t_burn + BURNOUT_DROP_S]]), np.concatenate([f, [f[-1], 0.0]])


@dataclass(frozen=True)
class UpperStage:
    """J-2X upper stage: rated vacuum thrust (N), Isp (s), LOX/LH2 mixture ratio and
    loads (kg), start transient (thrust fraction vs time since the ignition command, s),
    shutdown impulse (N·s: the vacuum impulse delivered after the cutoff command), gimbal
    (structure frame, m; limit rad) and the launch abort system mass (kg). A cluster of
    identical engines is one record, as :class:`FirstStage`'s: the rated thrust, the
    exit area and the shutdown impulse are the engines' sums. ``throttle``: a throttle
    that holds an axial-acceleration limit (no schedule; None: rated thrust), flown by
    PEG's constant-acceleration mode (``models/peg.py``)."""

    thrust_vac_N: float
    isp_vac_s: float
    mixture_ratio: float
    nozzle_exit_area_m2: float
    lox_kg: float
    lh2_kg: float
    startup_time_s: np.ndarray
    startup_fraction: np.ndarray
    shutdown_impulse_Ns: float
    gimbal_m: np.ndarray
    gimbal_limit_rad: float
    les_mass_kg: float
    engine: Engine
    mounts: tuple[Mount, ...] = ()
    mixing_matrix: np.ndarray | None = None
    throttle: Throttle | None = None


@dataclass(frozen=True)
class Boosters:
    """Strap-on boosters on the first stage: identical solid motors (each one ``trace``
    engine on its own tank), lit at liftoff, with fixed nozzles or with TVC (each nozzle
    gimbaled in pitch and yaw), jettisoned together by one event. Each burns its
    ``propellant_kg`` in the shape of the thrust table (vacuum thrust N vs mission time
    s) at ``isp_vac_s``, as a solid first stage does (docs/models.md, "Propulsion"), its delivered thrust ``F_vac − p A_exit`` along
    its nozzle's cant (pitch, yaw, rad) at its nozzle (structure frame, m). ``mass``: each
    booster's own mass properties against its own propellant, exchanged in flight for its
    full-load row of the liftoff configuration's table (``models/boosters.py``);
    ``burn_rate``: each booster's burn-rate factor (None: 1 each). With TVC
    (``gimbal_limit_rad`` > 0) each nozzle pivots at its ``nozzle_m`` on its own pitch
    and yaw actuator within ``gimbal_limit_rad`` (rad), its moving mass ``engine``
    (tail-wags-dog); the control mixer allocates over the first stage's engines and the
    boosters' nozzles together while they are attached (``models/cluster.py``).

    Attributes
    ----------
    names, tanks, engines : tuple of str
        Each booster's part, tank and engine name, in the order written.
    """

    names: tuple[str, ...]
    tanks: tuple[str, ...]
    engines: tuple[str, ...]
    thrust_time_s: np.ndarray
    thrust_vac_N: np.ndarray
    isp_vac_s: float
    isp_sl_s: float
    nozzle_exit_area_m2: float
    propellant_kg: float
    inert_mass_kg: float
    nozzle_m: np.ndarray
    cant_rad: np.ndarray
    mass: tuple[MassTable, ...]
    #: each booster's burn-rate factor k (None: 1 each): it burns ``k F_tab(k t)``, its
    #: load and impulse the same in a burn ``1/k`` as long (a Monte Carlo dispersion)
    burn_rate: np.ndarray | None = None
    #: each nozzle's gimbal limit per axis (rad; 0: fixed nozzles, no TVC)
    gimbal_limit_rad: float = 0.0
    #: each gimbaled nozzle's moving mass (None: fixed nozzles)
    engine: Engine | None = None

    @property
    def count(self) -> int:
        """The number of boosters."""
        return len(self.names)

    @property
    def tvc(self) -> bool:
        """Whether the boosters' nozzles gimbal (in pitch and yaw)."""
        return self.gimbal_limit_rad > 0.0


#: Roll-control jets (the upper stage's).
Rcs = RollJets


@dataclass(frozen=True)
class Trigger:
    """When one of the plant's events fires: armed ``delay_s`` (s) after the event
    ``after`` (its position in :data:`EVENT_ORDER`, −1 liftoff), at the first step from
    then on at which the condition holds: ``quantity`` (a key of
    ``tree.CONDITION_QUANTITIES``; None: at once) ``above`` or below ``threshold`` (its
    units); a propellant condition reads the tank ``tank`` (its name in the vehicle
    file: one of :attr:`Vehicle.tanks`)."""

    after: int
    delay_s: float
    quantity: str | None = None
    tank: str | None = None
    above: bool = False
    threshold: float = 0.0
    #: a thrust fraction's booster (its position in :attr:`Boosters.names`; None: the
    #: first stage's)
    booster: int | None = None
    #: the jettison slot that must have fired before this jettison (−1: none): the
    #: jettisons happen in the order written
    waits_for: int = -1


#: The plant's events, in slot order (sim/engine.py: EVENT_NAMES): the ``cutoff`` is
#: guidance's (no trigger of the vehicle's arms it), the ``first_stage_cutoff`` a liquid
#: first stage's shutdown before its separation, the ``booster_jettison`` the strap-on
#: boosters' before it, the ``upper_stage_cutoff`` the end of a restarting upper stage's
#: first burn and the ``upper_stage_restart`` its second ignition.
EVENT_ORDER = ("separation", "upper_stage_ignition", "les_jettison", "cutoff", "first_stage_cutoff", "booster_jettison",
               "item_jettison_2", "item_jettison_3", "item_jettison_4", "upper_stage_cutoff", "upper_stage_restart")
#: The item jettisons' slots, in the order written (``sim/engine.py::EV_ITEMS``).
ITEM_SLOTS = (2, 6, 7, 8)


@dataclass(frozen=True)
class Jettison:
    """One jettison of the sequence, from a configuration to the next (the order of
    :attr:`Vehicle.configurations`): the event (its name in the vehicle file and its slot
    in :data:`EVENT_ORDER`), what leaves (``boosters``, ``stage``: the first stage with
    anything still mounted on it, ``items``), the mass that leaves besides the first
    stage's and the boosters' propellant (kg; the boosters' own: ``check_boosters``) and
    the YAML key of that mass."""

    name: str
    slot: int
    kind: str
    mass_kg: float
    key: str


@dataclass(frozen=True)
class Events:
    """Staging events: separation when the first stage's vacuum thrust falls below
    ``separation_thrust_fraction`` of its peak (from liftoff, or a delay after a liquid
    first stage's cutoff); the upper-stage ignition command ``ignition_delay_s`` later;
    the first item's jettison ``les_jettison_delay_s`` after the ignition (infinite: none,
    or it counts from another event). ``triggers``: each event's whole trigger, in
    :data:`EVENT_ORDER`, where the ignition, the items' jettisons, the first-stage cutoff
    and the boosters' jettison may also wait for a condition (the guidance cutoff's, and
    those of events a vehicle does not have, never arm).
    ``names``: each slot's event name in the vehicle file ("" for none; empty: built
    without a file)."""

    separation_thrust_fraction: float
    ignition_delay_s: float
    les_jettison_delay_s: float
    triggers: tuple[Trigger, ...]
    names: tuple[str, ...] = ()

    def trigger(self, slot: int) -> Trigger:
        """Event ``slot``'s trigger."""
        return self.triggers[slot]

    def has(self, slot_name: str) -> bool:
        """Whether the vehicle has the event of slot ``slot_name`` (a name of :data:`EVENT_ORDER`)."""
        return bool(self.names) and self.names[EVENT_ORDER.index(slot_name)] != ""


@dataclass(frozen=True)
class Vehicle:
    """A loaded, checked vehicle, all SI."""

    name: str
    description: str
    length_m: float
    configurations: dict[str, Configuration]
    first_stage: FirstStage
    upper_stage: UpperStage
    rcs: Rcs
    sensors: Sensors
    events: Events
    data_dir: Path | None = None
    flex_spec: dict | None = None  # raw ``flex`` section, loaded by savant_cli.flex_slosh when flex is on
    #: each sloshing tank's raw ``slosh`` section by the tank's name, in the order of
    #: :attr:`tanks` (None: no tank sloshes), loaded when slosh is on
    slosh_spec: dict | None = None
    #: structural load allowable on the total q·α (Pa·deg, ``loads.qalpha_limit_Pa_deg``;
    #: None: no limit declared). The run summary reports the time above it.
    qalpha_limit_Pa_deg: float | None = None
    #: the YAML keys of the quantities the consistency check names (``propellant_first``,
    #: ``propellant_upper``, ``jettison_mass``, ``les_mass``, and ``slosh.<tank>``)
    keys: dict = field(default_factory=dict)
    #: the vehicle tree this view was derived from (None: built directly, as tests do)
    tree: VehicleTree | None = None
    #: the plant's propellant states, by the tanks' names in the vehicle file: the first
    #: stage's (a solid motor's one, or a liquid stage's oxidizer and fuel), then the
    #: upper stage's oxidizer and fuel
    tanks: tuple[str, ...] = ("first_stage_propellant", "lox", "lh2")
    #: the configurations flown with the first stage attached: the first n of
    #: :attr:`configurations` (which are in the order the sequence reaches them)
    first_stage_configurations: int = 1
    #: the strap-on boosters (None: none); their tanks' states follow :attr:`tanks`
    boosters: Boosters | None = None
    #: each jettison, in the order of :attr:`configurations` (empty: built without a
    #: tree: the separation, then the LES's)
    jettisons: tuple[Jettison, ...] = ()

    @property
    def configuration_sources(self) -> tuple[str, ...]:
        """The vehicle file's configuration each of :attr:`configurations` is (one upper
        configuration in the file stands for both ``upper_les`` and ``upper``); the slot
        names when built without a tree."""
        if self.tree is None:
            return tuple(self.configurations)
        names = [c for _, c in self.tree.sequence]
        return tuple(names + names[-1:] * (len(self.configurations) - len(names)))

    @property
    def first_stage_engine_count(self) -> int:
        """The first stage's engines (1 without a cluster)."""
        return max(len(self.first_stage.mounts), 1)

    @property
    def gimbaled_boosters(self) -> int:
        """The boosters whose nozzles gimbal (0: none, or fixed nozzles); their channel
        pairs follow the first stage's engines'."""
        return self.boosters.count if self.boosters is not None and self.boosters.tvc else 0

    @property
    def booster_tanks(self) -> tuple[str, ...]:
        """Each booster's tank (empty without boosters)."""
        return self.boosters.tanks if self.boosters is not None else ()

    @property
    def first_stage_tanks(self) -> tuple[str, ...]:
        """The first stage's tanks: its motor's, or its oxidizer's and fuel's."""
        return self.tanks[:-2]

    @property
    def upper_stage_tanks(self) -> tuple[str, str]:
        """The upper stage's oxidizer and fuel tanks."""
        return self.tanks[-2], self.tanks[-1]

    def tank_load_kg(self, name: str) -> float:
        """Tank ``name``'s propellant load, kg, from this view's records (so a dispersed
        load is the dispersed one, where the tree keeps the file's)."""
        if name in self.booster_tanks:
            return self.boosters.propellant_kg
        fs, us = self.first_stage, self.upper_stage
        first = (fs.propellant_kg,) if len(self.first_stage_tanks) == 1 else (fs.oxidizer_kg, fs.fuel_kg)
        return dict(zip(self.first_stage_tanks + self.upper_stage_tanks, first + (us.lox_kg, us.lh2_kg)))[name]


def check_consistency(v: Vehicle, mass_files: Mapping[str, str] | None = None) -> None:
    """Refuse mass tables that disagree with the loads and the jettisoned masses.

    * every table starts at 0 propellant; those of the configurations flown with the
      first stage end at its load, the others' at the upper stage's;
    * at the separation, the last first-stage configuration's mass at 0 propellant minus
      the first stage's jettisoned mass (its inert mass and any item still on it) equals
      the next configuration's at full propellant;
    * at an item's jettison, the mass before minus the mass after equals the items'
      masses at every propellant level of the configuration after (the one before
      interpolated there; mass is linear in propellant);
    * the boosters' jettison is :func:`check_boosters`'.

    All within :data:`MASS_TOLERANCE_KG`. A view built without a tree (``jettisons``
    empty) has the separation (``first_stage.jettison_mass_kg``) and the LES's jettison
    (``upper_stage.les_mass_kg``; 0: none).
    """
    names = list(v.configurations)
    files = dict(mass_files or {n: f"mass_{n}.csv" for n in names})
    keys = {**LEGACY_KEYS, **v.keys}
    tol = MASS_TOLERANCE_KG
    n_fs = v.first_stage_configurations
    us_prop = v.upper_stage.lox_kg + v.upper_stage.lh2_kg
    for i, name in enumerate(names):
        table = v.configurations[name].mass
        full, key = (v.first_stage.propellant_kg, keys["propellant_first"]) if i < n_fs \
            else (us_prop, keys["propellant_upper"])
        if table.propellant_kg[0] > tol:
            raise ConfigError(f"{files[name]}:propellant_remaining", float(table.propellant_kg[0]),
                              "the table must start at 0 propellant remaining")
        if abs(table.propellant_kg[-1] - full) > tol:
            raise ConfigError(key, full, f"must equal the largest propellant_remaining of {files[name]} "
                                         f"({table.propellant_kg[-1]:.1f} kg)")
    jettisons = list(v.jettisons) or [
        Jettison("separation", 0, "stage", v.first_stage.jettison_mass_kg, keys["jettison_mass"]),
        Jettison("les_jettison", 2, "items", v.upper_stage.les_mass_kg, keys["les_mass"])]
    jettisons += [Jettison("", -1, "items", 0.0, "vehicle.items")] * (len(names) - 1 - len(jettisons))
    for k, jet in enumerate(jettisons):
        before, after = (v.configurations[n].mass for n in names[k:k + 2])
        if jet.kind == "stage":
            left = before.mass_kg[0] - jet.mass_kg
            if abs(left - after.mass_kg[-1]) > tol:
                raise ConfigError(jet.key, jet.mass_kg,
                                  f"{names[k]} mass at burnout ({before.mass_kg[0]:.1f} kg, {files[names[k]]}) minus "
                                  f"the jettison mass must equal the {names[k + 1]} mass at full propellant "
                                  f"({after.mass_kg[-1]:.1f} kg, {files[names[k + 1]]}) within {tol:g} kg")
        elif jet.kind == "items":
            diff = np.interp(after.propellant_kg, before.propellant_kg, before.mass_kg) - after.mass_kg
            worst = int(np.argmax(np.abs(diff - jet.mass_kg)))
            if abs(diff[worst] - jet.mass_kg) > tol:
                raise ConfigError(jet.key, jet.mass_kg,
                                  f"must equal {names[k]} mass minus {names[k + 1]} mass at every propellant level "
                                  f"within {tol:g} kg; at {after.propellant_kg[worst]:.1f} kg propellant the "
                                  f"difference is {diff[worst]:.1f} kg")


def _jettisoned(tree: VehicleTree, order: list[str], slot_of: dict[str, int], first: str) -> tuple[Jettison, ...]:
    """Each jettison of ``order`` (the events in the order written): what leaves and its
    mass besides the propellant (the first stage takes along the items still on it)."""
    gone: set[str] = set()
    out = []
    for name in order:
        ev = tree.events[name]
        parts = [tree.parts[j] for j in ev.jettison]
        if parts[0].kind == BOOSTER:
            out.append(Jettison(name, slot_of[name], "boosters", 0.0, f"{ev.key}.jettison"))
        elif parts[0].name == first:
            riders = [p for p in tree.parts.values() if p.kind == ITEM and p.attached_to == first
                      and p.name not in gone]
            leaving = (parts[0], *riders)
            key = " + ".join(f"{p.key}.{'inert_mass_kg' if p.name == first else 'mass_kg'}" for p in leaving)
            out.append(Jettison(name, slot_of[name], "stage", sum(p.inert_mass_kg for p in leaving), key))
        else:
            out.append(Jettison(name, slot_of[name], "items", sum(p.inert_mass_kg for p in parts),
                                " + ".join(f"{p.key}.mass_kg" for p in parts)))
        gone.update(ev.jettison)
    return tuple(out)


def _refuse(key: str, value, what: str) -> None:
    raise ConfigError(key, value, f"the plant flies one vehicle shape today (docs/vehicles.md, \"What flies today\"): "
                                  f"{what}")


def _stage_engines(tree: VehicleTree, part: str, source: str) -> tuple[EngineSpec, ...]:
    """The stage's engines: one or a cluster of identical ``source`` engines (the same
    thrust data, exit area, tanks, gimbal limit and moving mass; each gimbaled in pitch
    and yaw, anywhere and at any cant), drawing on all of the stage's tanks (a mixed
    stage is refused: ``source`` is its first engine's)."""
    engines = tree.engines_of(part)
    key = tree.parts[part].key
    if not engines or any(e.source != source for e in engines):
        what = "liquid engines" if part != tree.stages()[0].name else "all trace or all liquid engines"
        _refuse(f"{key}.engines", [e.name for e in engines], f"the {part} stage's engines are {what}")
    first = engines[0]
    for eng in engines:
        if eng.gimbal_axes != GIMBAL_AXES:
            _refuse(f"{eng.key}.gimbal_axes", list(eng.gimbal_axes), "each stage's engines gimbal in pitch and yaw")
        for name, value, other in (("thrust", eng.thrust, first.thrust), ("tanks", eng.tanks, first.tanks),
                                   ("nozzle_exit_area_m2", eng.nozzle_exit_area_m2, first.nozzle_exit_area_m2),
                                   ("gimbal_limit_deg", eng.gimbal_limit_rad, first.gimbal_limit_rad),
                                   ("moving_mass", eng.moving_mass, first.moving_mass)):
            if not _same(value, other):
                _refuse(f"{eng.key}.{name}", eng.name,
                        f"a stage's engines are identical but for their place and cant (as {first.name})")
    if set(tree.parts[part].tanks) != set(first.tanks):
        _refuse(f"{key}.tanks", list(tree.parts[part].tanks),
                f"the stage's tanks are its engines', {list(first.tanks)}")
    return engines


def _first_stage(tree: VehicleTree, first, engines: tuple[EngineSpec, ...]) -> FirstStage:
    """The first stage's record: a cluster's sums, n × each engine's (exact for one)."""
    n, gimbal, mounts = _cluster(engines)
    eng = engines[0]
    common = dict(nozzle_exit_area_m2=n * eng.nozzle_exit_area_m2, jettison_mass_kg=first.inert_mass_kg,
                  gimbal_m=gimbal, gimbal_limit_rad=eng.gimbal_limit_rad, engine=eng.moving_mass, mounts=mounts,
                  mixing_matrix=first.mixing_matrix)
    if isinstance(eng.thrust, ThrustTrace):
        grain = tree.tanks[eng.tanks[0]]
        return FirstStage(thrust_time_s=eng.thrust.time_s, thrust_vac_N=n * eng.thrust.thrust_vac_N,
                          isp_vac_s=eng.thrust.isp_vac_s, isp_sl_s=eng.thrust.isp_sl_s,
                          propellant_kg=grain.propellant_kg, **common)
    liquid = dataclasses.replace(eng.thrust, thrust_vac_N=n * eng.thrust.thrust_vac_N,
                                 shutdown_impulse_Ns=n * eng.thrust.shutdown_impulse_Ns)
    ox, fuel = (tree.tanks[t].propellant_kg for t in eng.tanks)
    time_s, thrust = rated_liquid_trace(liquid, ox, fuel)
    # sea-level Isp: the rated vacuum thrust less the back-pressure loss, at the same flow
    isp_sl = liquid.isp_vac_s * max(1.0 - P0 * common["nozzle_exit_area_m2"] / liquid.thrust_vac_N, 0.0)
    return FirstStage(thrust_time_s=time_s, thrust_vac_N=thrust, isp_vac_s=liquid.isp_vac_s, isp_sl_s=isp_sl,
                      propellant_kg=ox + fuel, liquid=liquid, oxidizer_kg=ox, fuel_kg=fuel, **common)


def _same(a, b) -> bool:
    """Equal values, the arrays of a dataclass element by element."""
    if dataclasses.is_dataclass(a) and dataclasses.is_dataclass(b):
        return type(a) is type(b) and all(_same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and bool(np.all(np.asarray(a) == np.asarray(b)))
    return a == b


def _cluster(engines: tuple[EngineSpec, ...]) -> tuple[float, np.ndarray, tuple[Mount, ...]]:
    """The number of engines, their mean gimbal point (structure frame, m) and each one's
    :class:`Mount` about it."""
    gimbals = np.array([e.gimbal_m for e in engines], dtype=float)
    mean = gimbals.sum(axis=0) / len(engines)
    mounts = tuple(Mount(e.name, g - mean, np.array(e.cant_rad, dtype=float)) for e, g in zip(engines, gimbals))
    return float(len(engines)), mean, mounts


def _event(tree: VehicleTree, name: str, after: tuple[str, ...], jettison: tuple = (), ignite: tuple = (),
           shutdown: tuple = ()):
    """The event ``name``, refused unless it counts from one of ``after`` and its actions
    are exactly these (``shutdown`` in any order)."""
    ev = tree.events[name]
    if ev.after not in after or ev.jettison != jettison or ev.ignite != ignite \
            or sorted(ev.shutdown) != sorted(shutdown):
        what = (f"after {' or '.join(after)}" + (f", jettison {list(jettison)}" if jettison else "")
                + (f", ignite {list(ignite)}" if ignite else "")
                + (f", shut down {list(shutdown)}" if shutdown else ""))
        _refuse(ev.key, name, f"this event is: {what}")
    return ev


def _first_stage_cutoff(tree: VehicleTree, name: str, first, engines: tuple[EngineSpec, ...]):
    """The first event when it shuts the first stage's engines down: a liquid stage's
    cutoff, a delay after liftoff and optionally once a first-stage tank's propellant or
    the axial acceleration crosses a value, the quantities the nominal trace can place
    (``sim/build.py::first_stage_march``). None: the first event is the separation."""
    ev = tree.events[name]
    if not ev.shutdown:
        return None
    if engines[0].source != LIQUID:
        _refuse(f"{ev.key}.shutdown", list(ev.shutdown), f"{first.name} is a solid motor, which burns to its end: only "
                                                         f"a liquid first stage shuts down before its separation")
    ev = _event(tree, name, (LIFTOFF,), shutdown=tuple(e.name for e in engines))
    if not ev.delay_s > 0.0:
        _refuse(f"{ev.key}.delay_s", ev.delay_s, "a cutoff armed after liftoff: a delay > 0 s (a condition then waits "
                                                 "for its quantity)")
    if ev.when is not None and ev.when.quantity not in ("propellant_kg", "axial_acceleration_mps2"):
        _refuse(f"{ev.key}.when.quantity", ev.when.quantity,
                "propellant_kg of a first-stage tank or axial_acceleration_mps2 (what the first stage's nominal "
                "trace can place)")
    if ev.when is not None and ev.when.quantity == "propellant_kg" and ev.when.of not in first.tanks:
        _refuse(f"{ev.key}.when.of", ev.when.of, f"a tank of {first.name}: {list(first.tanks)}")
    return ev


def _upper_stage_restart(tree: VehicleTree, names: list[str], ign_name: str | None,
                         engines: tuple[EngineSpec, ...]) -> tuple:
    """A restarting upper stage's two events after its ignition (empty: it burns once): its
    first burn's cutoff (shutting down all of its engines, a delay > 0 s after the
    ignition, optionally when a condition holds: a backup of guidance's cutoff) and its
    restart (igniting them all again, a delay after that cutoff, optionally when a
    condition holds: ``radial_speed_mps`` below 0 waits for apogee)."""
    if ign_name is None:
        return ()
    later = names[names.index(ign_name) + 1:]
    cut_name = next((n for n in later if tree.events[n].shutdown), None)
    if cut_name is None:
        return ()
    all_engines = tuple(e.name for e in engines)
    cut = _event(tree, cut_name, (ign_name,), shutdown=all_engines)
    if not cut.delay_s > 0.0:
        _refuse(f"{cut.key}.delay_s", cut.delay_s, "an upper-stage cutoff armed after its ignition: a delay > 0 s "
                                                   "(a condition then waits for its quantity)")
    again = next((n for n in later if tree.events[n].ignite), None)
    if again is None or later.index(again) < later.index(cut_name):
        _refuse(cut.key, cut_name, "an upper-stage cutoff before its restart: an event igniting "
                                   f"{list(all_engines)} again, written after it")
    return cut, _event(tree, again, (cut_name,), ignite=all_engines)


def _trigger(ev, slot_of: Mapping[str, int], tanks: tuple[str, ...]) -> Trigger:
    """The plant's trigger of a non-separation event: a delay after liftoff or an event
    (its slot in ``slot_of``), and optionally a condition on the vehicle or a tank (a
    thrust fraction is the first-stage motor's alone)."""
    slot_after = -1 if ev.after == LIFTOFF else slot_of[ev.after]
    if ev.when is None:
        return Trigger(slot_after, ev.delay_s)
    if ev.when.quantity == "thrust_fraction":
        _refuse(f"{ev.key}.when.quantity", ev.when.quantity, "a thrust fraction triggers the separation only")
    above = ev.when.above is not None
    return Trigger(slot_after, ev.delay_s, ev.when.quantity, ev.when.of if ev.when.of in tanks else None, above,
                   ev.when.above if above else ev.when.below)


def two_stage_view(tree: VehicleTree) -> Vehicle:
    """The plant's two-stage records of a vehicle tree (module docstring), or a refusal
    naming the first key that leaves the shape."""
    stages = tree.stages()
    if len(stages) != 2:
        _refuse("vehicle.stages", [s.name for s in stages], "two stages")
    first, upper = stages
    boosters = _boosters(tree, first, [p for p in tree.parts.values() if p.kind == BOOSTER])
    fs_source = tree.engines_of(first.name)[0].source if first.engines else TRACE
    fs_engines, us_engines = _stage_engines(tree, first.name, fs_source), _stage_engines(tree, upper.name, LIQUID)
    fs, us = fs_engines[0], us_engines[0]
    us_throttle = us.thrust.throttle if isinstance(us.thrust, LiquidThrust) else None
    tabled = us_throttle is not None and us_throttle.time_s is not None
    if us_throttle is not None and (tabled or us_throttle.axial_acceleration_limit_mps2 is None):
        _refuse(f"{us.key}.throttle", "table" if tabled else None,
                "the upper stage's throttle holds an axial_acceleration_limit_mps2 and has no table: its guidance, "
                "PEG, flies a constant-thrust burn, then a constant-acceleration one at that limit")
    if first.roll_jets is not None or upper.roll_jets is None:
        _refuse(f"{upper.key}.roll_jets", None, "roll jets on the upper stage only")
    if first.inert_mass_kg is None:
        _refuse(f"{first.key}.inert_mass_kg", None, "the first stage's inert mass, dropped at separation")
    names = list(tree.events)
    drop = _booster_jettison(tree, names.pop(0), boosters) if boosters is not None and names else None
    cut = _first_stage_cutoff(tree, names[0], first, fs_engines) if names else None
    if cut is not None:
        names.pop(0)
    sep_name = next((n for n in names if first.name in tree.events[n].jettison), None)
    ign_name = next((n for n in names if tree.events[n].ignite), None)
    restart = _upper_stage_restart(tree, names, ign_name, us_engines)
    item_names = [n for n in names if n not in (sep_name, ign_name, *(ev.name for ev in restart))]
    if sep_name is None or ign_name is None or len(item_names) > len(ITEM_SLOTS) \
            or names.index(ign_name) < names.index(sep_name):
        _refuse("vehicle.events", list(tree.events),
                ("the boosters' jettison, " if boosters is not None else "")
                + "a liquid first stage's cutoff (optional), separation, the upper-stage ignition, its cutoff and "
                + f"restart (optional), and up to {len(ITEM_SLOTS)} item jettisons (anywhere after the boosters' "
                + "jettison and the cutoff)")
    sep = _event(tree, sep_name, (LIFTOFF,) if cut is None else (LIFTOFF, cut.name), jettison=(first.name,))
    if sep.when is None or sep.when.quantity != "thrust_fraction" \
            or sep.when.of not in (first.name, *(e.name for e in fs_engines)) \
            or sep.when.below is None or (sep.delay_s != 0.0 and sep.after == LIFTOFF):
        _refuse(f"{sep.key}.when", sep.when.quantity if sep.when else None,
                f"separation when the thrust fraction of {first.name} (or one of its identical engines) falls below "
                f"a value, from liftoff (or a delay after the first stage's cutoff)")
    ign = _event(tree, ign_name, (sep.name,), ignite=tuple(e.name for e in us_engines))
    jets = []
    for name in item_names:
        ev = tree.events[name]
        if ev.ignite or ev.shutdown or not ev.jettison or any(tree.parts[j].kind != ITEM for j in ev.jettison):
            _refuse(ev.key, name, "an event after the first stage's cutoff is the separation, the upper-stage "
                                  "ignition, its cutoff and restart, or an item's jettison (items only, no engine)")
        jets.append(ev)
    configs = [tree.configurations[c] for _, c in tree.sequence]
    order = [e for e, _ in tree.sequence[1:]]  # the jettisons, in the order written
    n_fs = 1 + order.index(sep.name)  # the configurations flown with the first stage
    for i, c in enumerate(configs):
        tanks = fs.tanks if i < n_fs else us.tanks
        if set(c.mass_tanks) != set(tanks):
            _refuse(f"{c.key}.mass_tanks", list(c.mass_tanks),
                    f"this configuration's mass table is against {list(tanks)}")
    n_items = n_fs - 1 - (boosters is not None)  # the items' jettisons before the separation
    slots = (("boosted",) if boosters is not None else ()) + ("stack",) + tuple(
        f"stack_{k}" for k in range(2, n_items + 2))
    n_upper = len(configs) - n_fs
    slots += ("upper_les",) + tuple(f"upper_les_{k}" for k in range(2, n_upper)) + ("upper",)
    if n_upper == 1:  # the upper stage alone from separation on
        configs.append(configs[-1])
    slot_of = {ev.name: ITEM_SLOTS[k] for k, ev in enumerate(jets)}
    slot_of.update({sep.name: EVENT_ORDER.index("separation"), ign.name: EVENT_ORDER.index("upper_stage_ignition")})
    if cut is not None:
        slot_of[cut.name] = EVENT_ORDER.index("first_stage_cutoff")
    for ev, slot in zip(restart, ("upper_stage_cutoff", "upper_stage_restart")):
        slot_of[ev.name] = EVENT_ORDER.index(slot)
    if drop is not None:
        slot_of[drop.name] = EVENT_ORDER.index("booster_jettison")
    waits = {}  # each jettison waits for the one written before it (the separation takes the boosters along)
    for before, ev in zip(order, order[1:]):
        if not (ev == sep.name and before == (drop.name if drop is not None else None)):
            waits[ev] = slot_of[before]
    jettisons = _jettisoned(tree, order, slot_of, first.name)
    sep_jet = jettisons[order.index(sep.name)]
    upper_items = jettisons[n_fs:]
    us_thrust = us.thrust
    assert isinstance(us_thrust, LiquidThrust)
    ox, fuel = (tree.tanks[t] for t in us.tanks)
    first_stage = _first_stage(tree, first, fs_engines)
    n_us, us_gimbal, us_mounts = _cluster(us_engines)
    upper_stage = UpperStage(
        thrust_vac_N=n_us * us_thrust.thrust_vac_N, isp_vac_s=us_thrust.isp_vac_s,
        mixture_ratio=us_thrust.mixture_ratio, nozzle_exit_area_m2=n_us * us.nozzle_exit_area_m2,
        lox_kg=ox.propellant_kg, lh2_kg=fuel.propellant_kg, startup_time_s=us_thrust.startup_time_s,
        startup_fraction=us_thrust.startup_fraction, shutdown_impulse_Ns=n_us * us_thrust.shutdown_impulse_Ns,
        gimbal_m=us_gimbal, gimbal_limit_rad=us.gimbal_limit_rad,
        les_mass_kg=upper_items[0].mass_kg if upper_items else 0.0,
        engine=us.moving_mass, mounts=us_mounts, mixing_matrix=upper.mixing_matrix, throttle=us_throttle)
    fs_tanks = tuple(tree.tanks[t] for t in fs.tanks)
    tanks = (*(t.name for t in fs_tanks), ox.name, fuel.name)
    all_tanks = tanks + (boosters.tanks if boosters is not None else ())
    fs_cut_slot = EVENT_ORDER.index("first_stage_cutoff")
    separation = Trigger(-1 if sep.after == LIFTOFF else fs_cut_slot, sep.delay_s, "thrust_fraction", None, False,
                         sep.when.below)
    never = Trigger(-1, float("inf"))  # an event this vehicle does not have, or guidance's cutoff
    triggers = [never] * len(EVENT_ORDER)
    triggers[slot_of[sep.name]] = dataclasses.replace(separation, waits_for=waits.get(sep.name, -1))
    triggers[slot_of[ign.name]] = _trigger(ign, slot_of, all_tanks)
    for ev in jets:
        triggers[slot_of[ev.name]] = dataclasses.replace(_trigger(ev, slot_of, all_tanks),
                                                         waits_for=waits.get(ev.name, -1))
    if cut is not None:
        triggers[slot_of[cut.name]] = _trigger(cut, slot_of, all_tanks)
    for ev in restart:
        triggers[slot_of[ev.name]] = _trigger(ev, slot_of, all_tanks)
    if drop is not None:
        triggers[slot_of[drop.name]] = _booster_trigger(drop, boosters, all_tanks)
    first_item = jets[0] if jets else None
    les_delay = first_item.delay_s if first_item is not None and first_item.after == ign.name else float("inf")
    events = Events(separation_thrust_fraction=sep.when.below, ignition_delay_s=ign.delay_s,
                    les_jettison_delay_s=les_delay, triggers=tuple(triggers),
                    names=tuple(next((n for n, k in slot_of.items() if k == slot), "")
                                for slot in range(len(EVENT_ORDER))))
    keys = {"propellant_first": " + ".join(f"{t.key}.propellant_kg" for t in fs_tanks),
            "propellant_upper": f"{ox.key}.propellant_kg + {fuel.name}.propellant_kg",
            "jettison_mass": sep_jet.key,
            "les_mass": upper_items[0].key if upper_items else "vehicle.items",
            **{f"slosh.{t}": f"{tree.tanks[t].key}.slosh" for t in all_tanks},
            "slosh": "the tanks' slosh sections",
            "mixing_matrix.first_stage": f"{first.key}.mixing_matrix",
            "mixing_matrix.upper_stage": f"{upper.key}.mixing_matrix"}
    vehicle = Vehicle(
        name=tree.name, description=tree.description, length_m=tree.length_m,
        configurations={n: Configuration(n, c.aero, c.mass) for n, c in zip(slots, configs)},
        first_stage=first_stage, upper_stage=upper_stage, rcs=upper.roll_jets, sensors=tree.sensors, events=events,
        data_dir=tree.data_dir, flex_spec=tree.flex_spec, slosh_spec=_slosh_spec(tree, all_tanks),
        qalpha_limit_Pa_deg=tree.qalpha_limit_Pa_deg, keys=keys, tree=tree, tanks=tanks,
        first_stage_configurations=n_fs, boosters=boosters, jettisons=jettisons)
    check_consistency(vehicle, {n: c.mass_file for n, c in zip(slots, configs)})
    if boosters is not None:
        check_boosters(vehicle, configs[0], [tree.parts[b].key for b in boosters.names])
    return vehicle


def _boosters(tree: VehicleTree, first, parts: list) -> Boosters | None:
    """The strap-on boosters' record (:class:`Boosters`), or a refusal naming the first
    key outside what the plant flies: identical boosters on the first stage, each one
    trace engine on its own tank with a fixed nozzle or one gimbaled in pitch and yaw,
    lit at liftoff, with its own inert mass and mass table."""
    if not parts:
        return None
    engines = []
    for part in parts:
        if part.attached_to != first.name:
            _refuse(f"{part.key}.attached_to", part.attached_to, f"boosters on the first stage, {first.name}")
        if part.roll_jets is not None:
            _refuse(f"{part.key}.roll_jets", "roll_jets", "a booster has no roll jets")
        if len(part.engines) != 1 or len(part.tanks) != 1:
            _refuse(f"{part.key}.engines", list(part.engines), "a booster is one trace engine (a solid motor) on its "
                                                               "one tank")
        eng = tree.engines[part.engines[0]]
        if eng.source != TRACE:
            _refuse(f"{eng.key}.source", eng.source, "a booster is a solid motor: source trace")
        if eng.gimbal_axes and eng.gimbal_axes != GIMBAL_AXES:
            _refuse(f"{eng.key}.gimbal_axes", list(eng.gimbal_axes), "a booster's nozzle is fixed, [], or gimbals "
                                                                     "in pitch and yaw, [pitch, yaw]")
        if eng.name in tree.ignited_later():
            _refuse(f"{eng.key}", eng.name, "a booster lights at liftoff (no event ignites it)")
        for what, value in (("mass_table", part.mass), ("inert_mass_kg", part.inert_mass_kg)):
            if value is None:
                _refuse(f"{part.key}.{what}", None, "each booster's own mass table and inert mass: its mass is "
                                                    "composed in flight against its own propellant")
        engines.append(eng)
    first_part, first_engine = parts[0], engines[0]
    for part, eng in zip(parts, engines):
        for key, value, other in (
                (f"{eng.key}.thrust", eng.thrust, first_engine.thrust),
                (f"{eng.key}.nozzle_exit_area_m2", eng.nozzle_exit_area_m2, first_engine.nozzle_exit_area_m2),
                (f"{tree.tanks[eng.tanks[0]].key}.propellant_kg", tree.tanks[eng.tanks[0]].propellant_kg,
                 tree.tanks[first_engine.tanks[0]].propellant_kg),
                (f"{part.key}.inert_mass_kg", part.inert_mass_kg, first_part.inert_mass_kg),
                (f"{eng.key}.gimbal_axes", eng.gimbal_axes, first_engine.gimbal_axes),
                (f"{eng.key}.gimbal_limit_deg", eng.gimbal_limit_rad, first_engine.gimbal_limit_rad),
                (f"{eng.key}.moving_mass", eng.moving_mass, first_engine.moving_mass)):
            if not _same(value, other):
                _refuse(key, part.name, f"the boosters are identical but for their place, cant and mass table "
                                        f"(as {first_part.name})")
    trace = first_engine.thrust
    assert isinstance(trace, ThrustTrace)
    return Boosters(
        names=tuple(p.name for p in parts), tanks=tuple(e.tanks[0] for e in engines),
        engines=tuple(e.name for e in engines), thrust_time_s=trace.time_s, thrust_vac_N=trace.thrust_vac_N,
        isp_vac_s=trace.isp_vac_s, isp_sl_s=trace.isp_sl_s, nozzle_exit_area_m2=first_engine.nozzle_exit_area_m2,
        propellant_kg=tree.tanks[first_engine.tanks[0]].propellant_kg, inert_mass_kg=float(first_part.inert_mass_kg),
        nozzle_m=np.array([e.gimbal_m for e in engines], dtype=float),
        cant_rad=np.array([e.cant_rad for e in engines], dtype=float), mass=tuple(p.mass for p in parts),
        gimbal_limit_rad=float(first_engine.gimbal_limit_rad) if first_engine.gimbal_axes else 0.0,
        engine=first_engine.moving_mass if first_engine.gimbal_axes else None)


def _booster_jettison(tree: VehicleTree, name: str, boosters: Boosters):
    """The first event of a vehicle with boosters: their jettison, all together, from
    liftoff (a delay and optionally a condition: a booster's thrust fraction, its tail-off,
    or any quantity of the vehicle or a tank)."""
    ev = tree.events[name]
    if sorted(ev.jettison) != sorted(boosters.names):
        _refuse(f"{ev.key}.jettison", list(ev.jettison), f"the first event jettisons the boosters, all together: "
                                                         f"{list(boosters.names)}")
    return _event(tree, name, (LIFTOFF,), jettison=ev.jettison)


def _booster_trigger(ev, boosters: Boosters, tanks: tuple[str, ...]) -> Trigger:
    """The boosters' jettison's trigger: a thrust fraction is one booster's (named, or by
    its engine), below a value; any other condition as :func:`_trigger`'s."""
    if ev.when is None or ev.when.quantity != "thrust_fraction":
        return _trigger(ev, {}, tanks)
    which = boosters.names if ev.when.of in boosters.names else boosters.engines
    if ev.when.of not in which or ev.when.below is None:
        _refuse(f"{ev.key}.when", ev.when.of, f"the thrust fraction of a booster ({', '.join(boosters.names)}, or its "
                                              f"engine) below a value")
    return Trigger(-1, ev.delay_s, "thrust_fraction", None, False, ev.when.below, booster=which.index(ev.when.of))


def check_boosters(v: Vehicle, boosted, keys: list[str]) -> None:
    """Refuse boosters' mass tables that disagree with their load and inert mass, or
    with the liftoff configuration's table (which holds the boosters at their full
    load: minus their full masses it must equal the stack without them at every
    propellant level of the stage), all within :data:`MASS_TOLERANCE_KG`."""
    b = v.boosters
    tol = MASS_TOLERANCE_KG
    for table, key in zip(b.mass, keys):
        if table.propellant_kg[0] > tol or abs(table.propellant_kg[-1] - b.propellant_kg) > tol:
            raise ConfigError(f"{key}.mass_table", [float(table.propellant_kg[0]), float(table.propellant_kg[-1])],
                              f"a booster's table runs from 0 to its load, {b.propellant_kg:.1f} kg")
        if abs(table.mass_kg[0] - b.inert_mass_kg) > tol:
            raise ConfigError(f"{key}.inert_mass_kg", b.inert_mass_kg, f"must equal the booster's mass at 0 "
                                                                       f"propellant ({table.mass_kg[0]:.1f} kg) "
                                                                       f"within {tol:g} kg")
    stack = v.configurations["stack"].mass
    full = sum(float(t.mass_kg[-1]) for t in b.mass)
    diff = np.interp(stack.propellant_kg, boosted.mass.propellant_kg, boosted.mass.mass_kg) - full - stack.mass_kg
    worst = int(np.argmax(np.abs(diff)))
    if abs(diff[worst]) > tol:
        raise ConfigError(boosted.mass_file, float(diff[worst] + stack.mass_kg[worst] + full),
                          f"the liftoff configuration's mass with the boosters full minus their full masses "
                          f"({full:.1f} kg) must equal the stack's without them ({stack.mass_kg[worst]:.1f} kg at "
                          f"{stack.propellant_kg[worst]:.1f} kg of the stage's propellant) within {tol:g} kg")


def _slosh_spec(tree: VehicleTree, tanks: tuple[str, ...]) -> dict | None:
    """Every tank's slosh section, by the tank's name, in the order of the plant's
    propellant ``tanks``; None without slosh data. A solid motor's grain does not slosh."""
    sloshing = [tree.tanks[t] for t in tanks if tree.tanks[t].slosh is not None]
    if not sloshing:
        return None
    for tank in sloshing:
        feeding = [e for e in tree.engines.values() if tank.name in e.tanks]
        if any(e.source == TRACE for e in feeding):
            _refuse(f"{tank.key}.slosh", tank.name, "slosh in a liquid engine's tank: a solid motor's grain does "
                    "not slosh")
    if len(sloshing) > MAX_SLOSH_TANKS:
        _refuse(f"{sloshing[MAX_SLOSH_TANKS].key}.slosh", [t.name for t in sloshing],
                f"at most {MAX_SLOSH_TANKS} tanks with a slosh section")
    return {t.name: t.slosh for t in sloshing}
