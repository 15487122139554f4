"""Read a vehicle YAML node into a :class:`~savant_cli.vehicle.tree.VehicleTree`.

The schema (``docs/vehicles.md`` documents every key): ordered mappings of name →
section for the stages (firing order, 1 to 4), boosters, jettisoned items, their tanks
and engines, the configurations and the events. Every refusal names its key, the value
and what is allowed. Beyond the keys, the tree is checked whole:

* names are unique across the vehicle and every name a section uses exists;
* the event sequence, in the order written: a trigger counts from liftoff or an earlier
  event; nothing is jettisoned twice or after the stage carrying it; an engine is ignited
  only while its part is attached, not burning, and its tanks hold propellant; only a
  burning engine is shut down;
* the configurations: the parts attached at liftoff and after every jettison are those
  of exactly one configuration, and every configuration is reached.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from savant_cli.config.checks import no_negative_entries, non_negative, positive
from savant_cli.errors import ConfigError
from savant_cli.io.table_order import table_key
from savant_cli.vehicle.composition import composed_table, full_row
from savant_cli.vehicle.keys import MAPPING, NAMED, NAMES, ROWS3, VEC2, VEC3, VEC6, check_keys, opt
from savant_cli.vehicle.tables import MASS_TOLERANCE_KG, check_inertia, read_aero, read_mass, read_table, vec3
from savant_cli.vehicle.tree import (
    BOOSTER, CONDITION_QUANTITIES, GIMBAL_AXES, ITEM, LIFTOFF, LIQUID, STAGE, TRACE, Condition, ConfigurationSpec,
    EngineSpec, EventSpec, LiquidThrust, MovingMass, Part, RollJets, Sensors, Tank, Throttle, ThrustTrace, VehicleTree
)

MAX_STAGES = 4

MOVING_MASS_KEYS = {"mass_kg": float, "cg_from_gimbal_m": float, "inertia_about_gimbal_kgm2": float}
ENGINE_COMMON = {"source": str, "tanks": NAMES, "nozzle_exit_area_m2": float, "gimbal_m": VEC3,
                 "cant_deg": opt(VEC2), "gimbal_axes": opt(NAMES), "gimbal_limit_deg": opt(float),
                 "moving_mass": opt(MOVING_MASS_KEYS)}
THROTTLE_KEYS = {"minimum": float, "maximum": opt(float), "rate_per_s": float, "table": opt(str),
                 "axial_acceleration_limit_mps2": opt(float)}
ENGINE_KEYS = {
    TRACE: {**ENGINE_COMMON, "thrust_table": str, "isp_vac_s": float, "isp_sl_s": float},
    LIQUID: {**ENGINE_COMMON, "thrust_vac_N": float, "isp_vac_s": float, "mixture_ratio": float,
             "startup_table": str, "shutdown_impulse_Ns": float, "throttle": opt(THROTTLE_KEYS)},
}
SLOSH_KEYS = {"table": str, "radius_m": float, "bottom_station_m": float, "density_kgm3": float,
              "reference_accel_mps2": float}
TANK_KEYS = {"propellant_kg": float, "slosh": opt(SLOSH_KEYS)}
ROLL_JET_KEYS = {"thrust_table": str, "exit_area_m2": float, "jets_per_direction": int, "moment_arm_m": float,
                 "ramp_up_s": float, "ramp_down_s": float, "location_m": VEC3,
                 "pitch_yaw_thrust_N": opt(float), "pitch_yaw_jets_per_direction": opt(int)}
STAGE_KEYS = {"inert_mass_kg": opt(float), "tanks": NAMED, "engines": NAMED, "roll_jets": opt(ROLL_JET_KEYS),
              "mass_table": opt(str), "mixing_matrix": opt(ROWS3)}
BOOSTER_KEYS = {"attached_to": str, "inert_mass_kg": float, "tanks": NAMED, "engines": NAMED,
                "roll_jets": opt(ROLL_JET_KEYS), "mass_table": opt(str)}
ITEM_KEYS = {"mass_kg": float, "attached_to": opt(str), "cg_m": opt(VEC3), "inertia_kgm2": opt(VEC6)}
CONFIG_KEYS = {"parts": NAMES, "aero_table": str, "base_force_table": str, "mass_table": opt(str), "mass_tanks": NAMES,
               "reference_area_m2": float, "reference_length_m": VEC3, "moment_reference_m": VEC3}
CONDITION_KEYS = {"quantity": str, "of": opt(str), "below": opt(float), "above": opt(float)}
EVENT_KEYS = {"after": opt(str), "delay_s": opt(float), "when": opt(CONDITION_KEYS), "jettison": opt(NAMES),
              "ignite": opt(NAMES), "shutdown": opt(NAMES)}
SENSOR_KEYS = {"imu_m": VEC3, "rate_gyro_upper_stage_m": VEC3, "rate_gyro_first_stage_m": VEC3}
SCHEMA: dict[str, Any] = {
    "name": str, "description": opt(str), "data_dir": str, "length_m": float,
    "stages": NAMED, "boosters": opt(NAMED), "items": opt(NAMED), "configurations": NAMED, "events": NAMED,
    "sensors": SENSOR_KEYS, "flex": opt(MAPPING), "loads": opt({"qalpha_limit_Pa_deg": float}),
}


def _gimbal_limit(key: str, deg: float) -> float:
    if not 0.0 < deg < 90.0:
        raise ConfigError(key, deg, "must be within (0, 90) deg")
    return float(np.radians(deg))


class _Reader:
    """One vehicle node read into the tree's records (names registered as they come)."""

    def __init__(self, node: Mapping, vdir: Path) -> None:
        self.node = node
        self.vdir = vdir
        self.names: dict[str, str] = {}  # every name → the key that defines it
        self.parts: dict[str, Part] = {}
        self.tanks: dict[str, Tank] = {}
        self.engines: dict[str, EngineSpec] = {}

    def name(self, name: Any, key: str) -> str:
        if not isinstance(name, str) or not name.isidentifier():
            raise ConfigError(key, name, "a name must be an identifier (letters, digits, _; not starting with a digit)")
        if name == LIFTOFF:
            raise ConfigError(key, name, f"'{LIFTOFF}' is the event every trigger counts from; choose another name")
        if name in self.names:
            raise ConfigError(key, name, f"names are unique across the vehicle; {self.names[name]} has it")
        self.names[name] = key
        return name

    # ------------------------------------------------------------------ parts
    def part(self, name: str, section: Mapping, kind: str, key: str, stages: list[str]) -> None:
        schema = {STAGE: STAGE_KEYS, BOOSTER: BOOSTER_KEYS, ITEM: ITEM_KEYS}[kind]
        check_keys(section, schema, key)
        attached = section.get("attached_to")
        if kind != STAGE:
            if attached is None:  # an item rides on the last stage unless it says
                attached = stages[-1]
            if attached not in stages:
                raise ConfigError(f"{key}.attached_to", attached, f"must name a stage: {', '.join(stages)}")
        if kind == ITEM:
            mass = non_negative(f"{key}.mass_kg", section["mass_kg"])
            cg = vec3(section["cg_m"]) if section.get("cg_m") is not None else None
            inertia = np.zeros(6)  # a point mass unless given
            if section.get("inertia_kgm2") is not None:
                inertia = np.asarray(section["inertia_kgm2"], float)
                check_inertia(f"{key}.inertia_kgm2", inertia[None, :])
            self.parts[name] = Part(name, kind, attached, mass, (), (), None, key, cg_m=cg, inertia_kgm2=inertia)
            return
        inert = section.get("inert_mass_kg")
        if inert is not None:
            inert = non_negative(f"{key}.inert_mass_kg", inert)
        tanks = tuple(self.tank(self.name(t, f"{key}.tanks.{t}"), s, name, f"{key}.tanks.{t}")
                      for t, s in section["tanks"].items())
        engines = tuple(self.engine(self.name(e, f"{key}.engines.{e}"), s, name, f"{key}.engines.{e}", tanks)
                        for e, s in section["engines"].items())
        if not engines:
            raise ConfigError(f"{key}.engines", {}, "a stage or booster needs at least one engine")
        jets = self.roll_jets(section["roll_jets"], f"{key}.roll_jets") if section.get("roll_jets") else None
        table = None
        if section.get("mass_table") is not None:
            table = read_mass(section, self.vdir, float(self.node["length_m"]))
            load = sum(self.tanks[t].propellant_kg for t in tanks)
            if table.propellant_kg[0] > MASS_TOLERANCE_KG or abs(table.propellant_kg[-1] - load) > MASS_TOLERANCE_KG:
                loads = " + ".join(f"{self.tanks[t].key}.propellant_kg" for t in tanks)
                raise ConfigError(loads, load, f"must equal the largest propellant_remaining of {key}.mass_table "
                                               f"({section['mass_table']}, from {table.propellant_kg[0]:.1f} to "
                                               f"{table.propellant_kg[-1]:.1f} kg: the part's own propellant, from 0)")
        mixing = None
        if section.get("mixing_matrix") is not None:
            mixing = np.asarray(section["mixing_matrix"], float)
            if mixing.shape[0] != 2 * len(engines):
                raise ConfigError(f"{key}.mixing_matrix", section["mixing_matrix"],
                                  f"needs one row per gimbal channel, {2 * len(engines)}: the pitch then the yaw "
                                  f"channel of each engine ({', '.join(engines)}), each row the channel's angle per "
                                  "radian of the roll, pitch and yaw commands")
        self.parts[name] = Part(name, kind, attached, inert, tanks, engines, jets, key, mass=table,
                                mixing_matrix=mixing)

    def tank(self, name: str, section: Mapping, part: str, key: str) -> str:
        check_keys(section, TANK_KEYS, key)
        load = positive(f"{key}.propellant_kg", section["propellant_kg"])
        self.tanks[name] = Tank(name, part, load, section.get("slosh"), key)
        return name

    def engine(self, name: str, section: Mapping, part: str, key: str, part_tanks: tuple[str, ...]) -> str:
        source = section.get("source") if isinstance(section, Mapping) else None
        if source not in ENGINE_KEYS:
            raise ConfigError(f"{key}.source", source, f"must be one of {', '.join(ENGINE_KEYS)}")
        check_keys(section, ENGINE_KEYS[source], key)
        tanks = tuple(section["tanks"])
        n_tanks = 1 if source == TRACE else 2
        if len(tanks) != n_tanks:
            what = "its one tank (a solid motor's grain)" if source == TRACE else \
                "its oxidizer tank, then its fuel tank"
            raise ConfigError(f"{key}.tanks", list(tanks), f"a {source} engine names {what}")
        for t in tanks:
            if t not in part_tanks:
                raise ConfigError(f"{key}.tanks", t, f"must name tanks of its own part: {', '.join(part_tanks)}")
        if source == TRACE:
            thrust = self.trace(section, key)
        else:
            thrust = self.liquid(section, key)
        axes = tuple(section.get("gimbal_axes", GIMBAL_AXES))
        for i, a in enumerate(axes):
            if a not in GIMBAL_AXES or a in axes[:i]:
                raise ConfigError(f"{key}.gimbal_axes", list(axes), f"a subset of {', '.join(GIMBAL_AXES)}, each once")
        limit, moving = 0.0, None
        if axes:
            for k in ("gimbal_limit_deg", "moving_mass"):
                if section.get(k) is None:
                    raise ConfigError(f"{key}.{k}", None,
                                      "missing (a gimbaled engine needs it; gimbal_axes: [] for a fixed nozzle)")
            limit = _gimbal_limit(f"{key}.gimbal_limit_deg", section["gimbal_limit_deg"])
            mm = section["moving_mass"]
            moving = MovingMass(**{k: positive(f"{key}.moving_mass.{k}", mm[k]) for k in MOVING_MASS_KEYS})
        cant = np.radians(np.asarray(section.get("cant_deg", [0.0, 0.0]), float))
        if np.any(np.abs(cant) >= np.pi / 2):
            raise ConfigError(f"{key}.cant_deg", section["cant_deg"], "must be within (−90, 90) deg")
        self.engines[name] = EngineSpec(
            name=name, part=part, thrust=thrust, tanks=tanks,
            nozzle_exit_area_m2=non_negative(f"{key}.nozzle_exit_area_m2", section["nozzle_exit_area_m2"]),
            gimbal_m=vec3(section["gimbal_m"]), cant_rad=np.ascontiguousarray(cant), gimbal_axes=axes,
            gimbal_limit_rad=limit, moving_mass=moving, key=key)
        return name

    def trace(self, section: Mapping, key: str) -> ThrustTrace:
        path = self.vdir / section["thrust_table"]
        t, tn = read_table(path, "first_stage_thrust")
        column = f"{table_key(path)}:{tn['thrust_vac']}"
        no_negative_entries(column, t["thrust_vac"], "thrust")
        if t["thrust_vac"].max() <= 0.0:
            raise ConfigError(column, 0.0, "thrust must be positive somewhere")
        isp_vac = positive(f"{key}.isp_vac_s", section["isp_vac_s"])
        isp_sl = positive(f"{key}.isp_sl_s", section["isp_sl_s"])
        if isp_sl > isp_vac:
            raise ConfigError(f"{key}.isp_sl_s", isp_sl, f"must not exceed isp_vac_s ({isp_vac})")
        return ThrustTrace(time_s=t["time"], thrust_vac_N=t["thrust_vac"], isp_vac_s=isp_vac, isp_sl_s=isp_sl)

    def liquid(self, section: Mapping, key: str) -> LiquidThrust:
        path = self.vdir / section["startup_table"]
        st, _ = read_table(path, "startup")
        frac = st["thrust_fraction"]
        if np.any((frac < 0.0) | (frac > 1.0)):
            raise ConfigError(f"{table_key(path)}:thrust_fraction", float(frac[np.argmax((frac < 0) | (frac > 1))]),
                              "thrust fraction must be within [0, 1]")
        return LiquidThrust(
            thrust_vac_N=positive(f"{key}.thrust_vac_N", section["thrust_vac_N"]),
            isp_vac_s=positive(f"{key}.isp_vac_s", section["isp_vac_s"]),
            mixture_ratio=positive(f"{key}.mixture_ratio", section["mixture_ratio"]),
            startup_time_s=st["time"], startup_fraction=frac,
            shutdown_impulse_Ns=non_negative(f"{key}.shutdown_impulse_Ns", section["shutdown_impulse_Ns"]),
            throttle=self.throttle(section["throttle"], f"{key}.throttle") if section.get("throttle") else None)

    def throttle(self, section: Mapping, key: str) -> Throttle:
        """A liquid engine's throttle section (fractions of rated thrust)."""
        check_keys(section, THROTTLE_KEYS, key)
        maximum = float(section.get("maximum", 1.0))
        if not 0.0 < maximum <= 1.0:
            raise ConfigError(f"{key}.maximum", maximum, "must be within (0, 1] (a fraction of rated thrust)")
        minimum = float(section["minimum"])
        if not 0.0 < minimum <= maximum:
            raise ConfigError(f"{key}.minimum", minimum, f"must be within (0, maximum = {maximum:g}]")
        rate = positive(f"{key}.rate_per_s", section["rate_per_s"])
        time_s = setting = None
        if section.get("table") is not None:
            path = self.vdir / section["table"]
            tt, _ = read_table(path, "throttle")
            setting = tt["throttle"]
            outside = (setting < minimum) | (setting > maximum)
            if np.any(outside):
                raise ConfigError(f"{table_key(path)}:throttle", float(setting[np.argmax(outside)]),
                                  f"a throttle setting must be within [minimum, maximum] = [{minimum:g}, {maximum:g}]")
            time_s = tt["time"]
        limit = section.get("axial_acceleration_limit_mps2")
        if limit is not None:
            limit = positive(f"{key}.axial_acceleration_limit_mps2", limit)
        if time_s is None and limit is None:
            raise ConfigError(key, dict(section), "a throttle needs a table, an axial_acceleration_limit_mps2 or both")
        return Throttle(minimum=minimum, maximum=maximum, rate_per_s=rate, time_s=time_s, setting=setting,
                        axial_acceleration_limit_mps2=limit)

    def roll_jets(self, rn: Mapping, key: str) -> RollJets:
        path = self.vdir / rn["thrust_table"]
        rt, rtn = read_table(path, "rcs_thrust")
        no_negative_entries(f"{table_key(path)}:{rtn['thrust_vac']}", rt["thrust_vac"], "thrust")
        return RollJets(altitude_m=rt["altitude"], thrust_vac_N=rt["thrust_vac"],
                        exit_area_m2=non_negative(f"{key}.exit_area_m2", rn["exit_area_m2"]),
                        jets_per_direction=int(positive(f"{key}.jets_per_direction", rn["jets_per_direction"])),
                        moment_arm_m=positive(f"{key}.moment_arm_m", rn["moment_arm_m"]),
                        ramp_up_s=non_negative(f"{key}.ramp_up_s", rn["ramp_up_s"]),
                        ramp_down_s=non_negative(f"{key}.ramp_down_s", rn["ramp_down_s"]),
                        location_m=vec3(rn["location_m"]), **self.pitch_yaw_jets(rn, key))

    @staticmethod
    def pitch_yaw_jets(rn: Mapping, key: str) -> dict:
        """The roll-jet pods' pitch and yaw jets: both keys or neither."""
        thrust, count = rn.get("pitch_yaw_thrust_N"), rn.get("pitch_yaw_jets_per_direction")
        if (thrust is None) != (count is None):
            missing = "pitch_yaw_jets_per_direction" if count is None else "pitch_yaw_thrust_N"
            raise ConfigError(f"{key}.{missing}", None, "pitch and yaw jets need both pitch_yaw_thrust_N (vacuum "
                                                        "thrust of one jet, N) and pitch_yaw_jets_per_direction")
        if thrust is None:
            return {}
        return {"pitch_yaw_thrust_N": positive(f"{key}.pitch_yaw_thrust_N", thrust),
                "pitch_yaw_jets_per_direction": int(positive(f"{key}.pitch_yaw_jets_per_direction", count))}

    # ----------------------------------------------------------------- events
    def event(self, name: str, section: Mapping, key: str, earlier: list[str]) -> EventSpec:
        check_keys(section, EVENT_KEYS, key)
        after = section.get("after", LIFTOFF)
        if after != LIFTOFF and after not in earlier:
            allowed = ", ".join([LIFTOFF, *earlier])
            raise ConfigError(f"{key}.after", after,
                              f"must name liftoff or an event written before this one: {allowed}")
        when = None
        if section.get("when") is not None:
            when = self.condition(section["when"], f"{key}.when")
        lists = {k: tuple(section.get(k) or ()) for k in ("jettison", "ignite", "shutdown")}
        for k, allowed_names in (("jettison", self.parts), ("ignite", self.engines), ("shutdown", self.engines)):
            for n in lists[k]:
                if n not in allowed_names:
                    what = "parts" if k == "jettison" else "engines"
                    raise ConfigError(f"{key}.{k}", n, f"must name {what}: {', '.join(allowed_names)}")
        if not any(lists.values()):
            raise ConfigError(key, dict(section), "an event needs an action: jettison, ignite or shutdown")
        return EventSpec(name=name, after=after, delay_s=non_negative(f"{key}.delay_s", section.get("delay_s", 0.0)),
                         when=when, key=key, **lists)

    def condition(self, section: Mapping, key: str) -> Condition:
        quantity = section["quantity"]
        if quantity not in CONDITION_QUANTITIES:
            raise ConfigError(f"{key}.quantity", quantity, f"must be one of {', '.join(CONDITION_QUANTITIES)}")
        of = section.get("of")
        needs = CONDITION_QUANTITIES[quantity]
        if needs is None and of is not None:
            raise ConfigError(f"{key}.of", of, f"{quantity} is the vehicle's: leave 'of' out")
        if needs is not None:
            pool = {"engine or part": {**self.engines, **self.parts}, "tank": self.tanks}[needs]
            if of not in pool:
                raise ConfigError(f"{key}.of", of, f"{quantity} needs the {needs} it watches: one of {', '.join(pool)}")
        below, above = section.get("below"), section.get("above")
        if (below is None) == (above is None):
            raise ConfigError(key, dict(section), "give exactly one of below, above")
        side, value = ("below", below) if below is not None else ("above", above)
        if quantity == "thrust_fraction" and not 0.0 < value < 1.0:
            raise ConfigError(f"{key}.{side}", value, "a thrust fraction must be within (0, 1)")
        return Condition(quantity, of, None if below is None else float(below), None if above is None else float(above))


def read_tree(node: Mapping, vdir: Path) -> VehicleTree:
    """A vehicle node (plain containers) and its table folder → the checked tree."""
    check_keys(node, SCHEMA, "vehicle")
    r = _Reader(node, vdir)
    length = positive("vehicle.length_m", node["length_m"])
    stages = list(node["stages"])
    if not 1 <= len(stages) <= MAX_STAGES:
        raise ConfigError("vehicle.stages", stages, f"1 to {MAX_STAGES} stages, in firing order")
    for kind, group in ((STAGE, "stages"), (BOOSTER, "boosters"), (ITEM, "items")):
        for name, section in (node.get(group) or {}).items():
            key = f"vehicle.{group}.{name}"
            r.part(r.name(name, key), section, kind, key, stages)
    events: dict[str, EventSpec] = {}
    for name, section in node["events"].items():
        key = f"vehicle.events.{name}"
        events[name] = r.event(r.name(name, key), section, key, list(events))
    specs = {name: _configuration(r, name, section) for name, section in node["configurations"].items()}
    sequence = walk_sequence(r.parts, r.tanks, r.engines, events, specs)
    configurations = {c: specs[c] for _, c in sequence}
    sensors = Sensors(**{k: vec3(node["sensors"][k]) for k in SENSOR_KEYS})
    qalpha = None
    if node.get("loads") is not None:
        qalpha = positive("vehicle.loads.qalpha_limit_Pa_deg", node["loads"]["qalpha_limit_Pa_deg"])
    return VehicleTree(name=str(node["name"]), description=str(node.get("description") or ""), length_m=length,
                       parts=r.parts, tanks=r.tanks, engines=r.engines, configurations=configurations, events=events,
                       sequence=sequence, sensors=sensors, data_dir=vdir, flex_spec=node.get("flex"),
                       qalpha_limit_Pa_deg=qalpha)


def _configuration(r: _Reader, name: str, section: Mapping) -> ConfigurationSpec:
    key = f"vehicle.configurations.{name}"
    r.name(name, key)
    check_keys(section, CONFIG_KEYS, key)
    for k, pool in (("parts", r.parts), ("mass_tanks", r.tanks)):
        for n in section[k]:
            if n not in pool:
                raise ConfigError(f"{key}.{k}", n, f"must name {k.replace('mass_', '')}: {', '.join(pool)}")
    if section.get("mass_table") is not None:
        mass, mass_file = read_mass(section, r.vdir, float(r.node["length_m"])), str(section["mass_table"])
    else:
        mass, mass_file = _composed(r, section, key), f"{key} (composed from its parts)"
    return ConfigurationSpec(name=name, parts=frozenset(section["parts"]), key=key,
                             aero=read_aero(section, r.vdir, key), mass=mass,
                             mass_tanks=tuple(section["mass_tanks"]), mass_file=mass_file)


def _composed(r: _Reader, section: Mapping, key: str):
    """The mass table of a configuration without one, composed from its parts: the part
    owning ``mass_tanks`` at its table's rows, the other stages and boosters full, the
    items as they are (:mod:`savant_cli.vehicle.composition`)."""
    owners = {r.tanks[t].part for t in section["mass_tanks"]}
    burning = r.parts[owners.pop()] if len(owners) == 1 else None
    if burning is None or set(burning.tanks) != set(section["mass_tanks"]):
        raise ConfigError(f"{key}.mass_tanks", section["mass_tanks"], "a configuration composed from its parts is "
                          "tabulated against the tanks of one part, all of them")
    fixed = []
    for name in section["parts"]:
        part = r.parts[name]
        what = {ITEM: "cg_m (and inertia_kgm2 unless a point mass)"}.get(part.kind, "mass_table")
        if (part.kind == ITEM and part.cg_m is None) or (part.kind != ITEM and part.mass is None):
            raise ConfigError(f"{part.key}", name, f"{key} has no mass_table: it is composed from its parts, and "
                                                   f"this part needs its {what}")
        if part is not burning:
            fixed.append((part.inert_mass_kg, part.cg_m, part.inertia_kgm2) if part.kind == ITEM
                         else full_row(part.mass))
    return composed_table(burning.mass, fixed)


def walk_sequence(parts: dict[str, Part], tanks: dict, engines: dict[str, EngineSpec], events: dict[str, EventSpec],
                  configurations: dict[str, ConfigurationSpec]) -> tuple[tuple[str, str], ...]:
    """Walk the events in the order written; refuse an impossible sequence; return the
    configuration at liftoff and after each jettison, ``(event, configuration)``."""
    attached = set(parts)
    ignited_later = {e for ev in events.values() for e in ev.ignite}
    burning = {e for e in engines if e not in ignited_later}
    by_parts = {}
    for c in configurations.values():
        if c.parts in by_parts:
            raise ConfigError(f"{c.key}.parts", sorted(c.parts), f"the same parts as {by_parts[c.parts].key}")
        by_parts[c.parts] = c

    def configuration(event: str, key: str) -> str:
        c = by_parts.get(frozenset(attached))
        if c is None:
            raise ConfigError(key, sorted(attached), f"after {event} these parts fly; no configuration lists exactly "
                                                     f"them in its parts: add one (vehicle.configurations)")
        return c.name

    sequence = [(LIFTOFF, configuration(LIFTOFF, "vehicle.configurations"))]
    for ev in events.values():
        for p in ev.jettison:
            if p not in attached:
                raise ConfigError(f"{ev.key}.jettison", p,
                                  "is no longer attached (jettisoned before, or with its stage)")
        for p in ev.jettison:  # a stage takes along what is mounted on it
            attached -= {p} | {q for q in attached if parts[q].attached_to == p}
        burning -= {e for e in burning if engines[e].part not in attached}
        for e in ev.shutdown:
            if e not in burning:
                raise ConfigError(f"{ev.key}.shutdown", e, "is not burning at this point of the sequence")
            burning.discard(e)
        for e in ev.ignite:
            eng = engines[e]
            if eng.part not in attached:
                raise ConfigError(f"{ev.key}.ignite", e, f"its part {eng.part} is jettisoned at this point")
            if e in burning:
                raise ConfigError(f"{ev.key}.ignite", e, "is already burning (shut it down first to restart it)")
            burning.add(e)
        if ev.jettison:
            sequence.append((ev.name, configuration(ev.name, f"{ev.key}.jettison")))
    reached = {c for _, c in sequence}
    for c in configurations.values():
        if c.name not in reached:
            raise ConfigError(f"{c.key}.parts", sorted(c.parts), "this configuration is never reached by the events")
        for t in c.mass_tanks:
            if tanks[t].part not in c.parts:
                raise ConfigError(f"{c.key}.mass_tanks", t, f"its part {tanks[t].part} is not in this configuration")
    return tuple(sequence)
