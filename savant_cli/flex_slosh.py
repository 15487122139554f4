"""Flexible-body and slosh data of a vehicle, loaded only when the model is switched on,
checked against the config and arranged as the compiled plant's tables.

Modal sets come from ``vehicle.flex`` (files read by :mod:`savant_cli.io.modal_data`);
slosh tables from ``vehicle.slosh``, read by the vehicle tables' unit-aware reader
(:func:`savant_cli.vehicle.read_table`: any unit of ``io.units.UNITS`` in a column's
suffix, converted to SI). Every problem is a ConfigError naming the key
(``<folder>/<file>.csv:<column>`` for a table's cell), the value and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from savant_cli.config import FlexOnConfig, SloshOnConfig
from savant_cli.errors import ConfigError
from savant_cli.io.modal_data import ModalSet, read_modal_set
from savant_cli.io.table_order import table_key
from savant_cli.vehicle import Vehicle, read_table

#: The plant's points that use mode shapes, by their key under the vehicle YAML's
#: ``flex.nodes`` (a point may average several nodes), in the order of the shape tables'
#: point axis (``models/flex.py``'s ``PT_*`` indices); each sloshing tank's point
#: (``slosh_<tank>``) follows them, in the order of the slosh tanks (:func:`point_keys`).
POINT_KEYS = ("imu", "rate_gyro_upper_stage", "rate_gyro_first_stage", "rcs", "gimbal_first_stage",
              "gimbal_upper_stage")
#: The points on the first stage: absent from the upper-stage modal sets (zero shapes).
FIRST_STAGE_KEYS = ("rate_gyro_first_stage", "gimbal_first_stage")
#: The modal data sets (file names in the flex folder), in the order of the tables.
FLEX_SETS = ("first_stage_liftoff", "first_stage_burnout", "second_stage_ignition", "second_stage_burnout")
#: The sets of the configuration with strap-on boosters (after :data:`FLEX_SETS`): at
#: liftoff and at the boosters' burnout.
BOOSTED_SETS = ("boosted_liftoff", "boosted_burnout")


#: Modal sets one configuration may blend between (``vehicle.flex.sets``).
MAX_SETS_PER_CONFIGURATION = 8
#: The sets' roles: the stage a set's structure is (its points off that structure are zero).
BOOSTED, FIRST_STAGE, UPPER_STAGE = "boosted", "first stage", "upper stage"


@dataclass(frozen=True)
class SetPlan:
    """Which modal sets each configuration flies.

    Attributes
    ----------
    names : tuple of str
        The sets, in the order of the tables (each once).
    roles : tuple of str
        Each set's structure: :data:`BOOSTED` (the stack with the boosters),
        :data:`FIRST_STAGE` or :data:`UPPER_STAGE`.
    by_configuration : tuple of tuple of (int, float)
        For each of the vehicle's configurations (in the plant's order), its sets as
        ``(index in names, burned fraction)``, the fractions strictly increasing: the
        fraction of the burning stage's propellant (the boosters' own while they are
        attached) at which the set holds.
    """

    names: tuple[str, ...]
    roles: tuple[str, ...]
    by_configuration: tuple[tuple[tuple[int, float], ...], ...]

    def table(self) -> np.ndarray:
        """The plant's ``flex_set_map`` rows: ``count, (set, burned fraction) × count``,
        zero-padded to :data:`MAX_SETS_PER_CONFIGURATION` pairs."""
        rows = np.zeros((len(self.by_configuration), 1 + 2 * MAX_SETS_PER_CONFIGURATION))
        for c, entries in enumerate(self.by_configuration):
            rows[c, 0] = len(entries)
            for k, (index, burned) in enumerate(entries):
                rows[c, 1 + 2 * k], rows[c, 2 + 2 * k] = index, burned
        return rows


def _role(vehicle: Vehicle, configuration: int) -> str:
    if vehicle.boosters is not None and configuration == 0:
        return BOOSTED
    return FIRST_STAGE if configuration < vehicle.first_stage_configurations else UPPER_STAGE


#: The sets a configuration flies by default, by its role: the paper's two per stage.
DEFAULT_SETS = {BOOSTED: BOOSTED_SETS, FIRST_STAGE: FLEX_SETS[:2], UPPER_STAGE: FLEX_SETS[2:]}


def set_plan(vehicle: Vehicle) -> SetPlan:
    """The modal sets of each configuration: ``vehicle.flex.sets`` (by the vehicle file's
    configuration names: a list of ``{set, burned_fraction}``), or by default the
    stage's liftoff (ignition) set at 0 and its burnout set at 1 (the boosted pair while
    the boosters are attached). Refused naming the key: a configuration the sequence
    reaches without sets, a name that is not a configuration, fractions outside 0 to 1
    or not increasing, more than :data:`MAX_SETS_PER_CONFIGURATION` sets, or a set
    flown by configurations of different structures (the stack with and without the
    boosters, the first stage and the upper stage)."""
    roles = [_role(vehicle, c) for c in range(len(vehicle.configurations))]
    given = (vehicle.flex_spec or {}).get("sets")
    key = "vehicle.flex.sets"
    if given is None:
        return default_plan(roles)
    sources = vehicle.configuration_sources
    if not isinstance(given, dict):
        raise ConfigError(key, given, "a mapping of the vehicle's configurations to lists of {set, burned_fraction}")
    for name in given:
        if name not in sources:
            raise ConfigError(f"{key}.{name}", given[name], f"not a configuration the sequence reaches; those are "
                                                            f"{', '.join(dict.fromkeys(sources))}")
    names: list[str] = []
    set_roles: list[str] = []
    by_configuration = []
    for c, source in enumerate(sources):
        listed = given.get(source)
        ckey = f"{key}.{source}"
        if not isinstance(listed, (list, tuple)) or not listed:
            raise ConfigError(ckey, listed, "a non-empty list of {set: <modal set name>, burned_fraction: 0 to 1}")
        if len(listed) > MAX_SETS_PER_CONFIGURATION:
            raise ConfigError(ckey, len(listed), f"at most {MAX_SETS_PER_CONFIGURATION} sets per configuration")
        entries = []
        for k, item in enumerate(listed):
            ikey = f"{ckey}[{k}]"
            if not isinstance(item, dict) or set(item) != {"set", "burned_fraction"}:
                raise ConfigError(ikey, item, "{set: <modal set name>, burned_fraction: 0 to 1}")
            try:
                burned = float(item["burned_fraction"])
            except (TypeError, ValueError):
                burned = float("nan")
            if not 0.0 <= burned <= 1.0 or entries and burned <= entries[-1][1]:
                raise ConfigError(f"{ikey}.burned_fraction", item["burned_fraction"],
                                  "0 to 1, increasing along the list (the fraction of the burning stage's "
                                  "propellant burned)")
            name = str(item["set"])
            if name not in names:
                names.append(name)
                set_roles.append(roles[c])
            index = names.index(name)
            if set_roles[index] != roles[c]:
                raise ConfigError(f"{ikey}.set", name, f"a set of one structure: it is flown by a configuration of the "
                                                       f"{set_roles[index]} and by {source} of the {roles[c]}")
            entries.append((index, burned))
        by_configuration.append(tuple(entries))
    return SetPlan(tuple(names), tuple(set_roles), tuple(by_configuration))


def default_plan(roles: list[str] | tuple[str, ...]) -> SetPlan:
    """The default :class:`SetPlan` of configurations of the given roles: each its
    stage's :data:`DEFAULT_SETS` at 0 and 1 burned, the sets in the order
    :data:`FLEX_SETS`, then :data:`BOOSTED_SETS` if a configuration carries the boosters."""
    names = FLEX_SETS + (BOOSTED_SETS if BOOSTED in roles else ())
    entries = tuple(((names.index(DEFAULT_SETS[r][0]), 0.0), (names.index(DEFAULT_SETS[r][1]), 1.0)) for r in roles)
    set_roles = tuple(r for n in names for r, default in DEFAULT_SETS.items() if n in default)
    return SetPlan(names, set_roles, entries)


@dataclass(frozen=True)
class FlexTables:
    """Modal data at the plant's points, every set of the :class:`SetPlan` (by default
    :data:`FLEX_SETS`, then :data:`BOOSTED_SETS` with boosters)."""

    frequency_rad_s: np.ndarray  # (sets, n_modes)
    damping: np.ndarray  # (n_modes,)
    shapes: np.ndarray  # (sets, n_modes, points, 6), body axes, SI
    sets: tuple[ModalSet, ...]
    #: each configuration's sets and their burned fractions (:meth:`SetPlan.table`)
    set_map: np.ndarray


def point_keys(vehicle: Vehicle) -> tuple[str, ...]:
    """The keys of every flex point of ``vehicle``: :data:`POINT_KEYS`, then
    ``slosh_<tank>`` for each tank with a slosh section, in the order of its slosh tanks,
    then ``nozzle_<booster>`` for each strap-on booster (:func:`booster_keys`)."""
    return POINT_KEYS + tuple(f"slosh_{t}" for t in (vehicle.slosh_spec or {})) + booster_keys(vehicle)


def booster_keys(vehicle: Vehicle) -> tuple[str, ...]:
    """The boosters' nozzle points, ``nozzle_<booster>`` (only in the boosted sets)."""
    return tuple(f"nozzle_{b}" for b in (vehicle.boosters.names if vehicle.boosters is not None else ()))


def first_stage_keys(vehicle: Vehicle) -> tuple[str, ...]:
    """The flex points on the first stage (zero shapes in the upper-stage sets):
    :data:`FIRST_STAGE_KEYS` and the first stage's sloshing tanks'."""
    return FIRST_STAGE_KEYS + tuple(f"slosh_{t}" for t in (vehicle.slosh_spec or {})
                                    if t in vehicle.first_stage_tanks)


@dataclass(frozen=True)
class SloshTank:
    """One tank: table vs liquid level and geometry (SI), its reference acceleration and
    the configurations its stage is aboard in (the first ``configurations``)."""

    name: str
    level_m: np.ndarray
    frequency_rad_s: np.ndarray  # at the reference acceleration
    damping: np.ndarray
    mass_kg: np.ndarray
    height_m: np.ndarray  # spring-mass height above the tank bottom
    radius_m: float
    bottom_station_m: float
    density_kgm3: float
    reference_accel_mps2: float
    configurations: int


@dataclass(frozen=True)
class SloshData:
    """Every sloshing tank, in the order of the vehicle's propellant states."""

    tanks: tuple[SloshTank, ...]


def _spec(vehicle: Vehicle, section: str) -> dict:
    spec = vehicle.flex_spec if section == "flex" else vehicle.slosh_spec
    if not spec:
        where = vehicle.keys.get(section, f"vehicle.{section}")
        raise ConfigError(where, None, f"missing: {section}=on needs it (or use {section}=off)")
    return spec


@lru_cache(maxsize=32)
def _modal_set_cached(folder: Path, name: str, units: tuple[str, str], key: str, stamp: tuple) -> ModalSet:
    return read_modal_set(folder, name, units, key)


def _modal_set(folder: Path, name: str, units: tuple[str, str], key: str) -> ModalSet:
    """One modal set, read once per process while its files are unchanged (a Monte Carlo
    batch builds a model per run; the sets are not modified by their users)."""
    stamp = tuple((f.name, f.stat().st_mtime_ns, f.stat().st_size) for f in sorted(folder.glob(f"{name}*")))
    return _modal_set_cached(folder, name, units, key, stamp)


def load_flex(vehicle: Vehicle, fcfg: FlexOnConfig, plant_rate_hz: float) -> FlexTables:
    """Read the modal sets of the :func:`set_plan` (by default the four of
    :data:`FLEX_SETS`, and :data:`BOOSTED_SETS` with strap-on boosters), keep
    ``fcfg.n_modes`` and evaluate them at the points."""
    spec = _spec(vehicle, "flex")
    key = "vehicle.flex"
    for k in spec:
        if k not in ("directory", "units", "nodes", "sets"):
            raise ConfigError(f"{key}.{k}", spec[k], "unknown key; allowed: directory, units, nodes, sets")
    plan = set_plan(vehicle)
    units = spec.get("units") or {}
    folder = Path(vehicle.data_dir or ".") / str(spec.get("directory", "flex"))
    if not folder.is_dir():
        raise ConfigError(f"{key}.directory", str(folder), "modal data folder not found")
    nodes = spec.get("nodes") or {}
    keys, first_keys = point_keys(vehicle), first_stage_keys(vehicle)
    for pk in keys:
        ids = nodes.get(pk)
        if not isinstance(ids, (list, tuple)) or not ids or not all(isinstance(i, int) for i in ids):
            raise ConfigError(f"{key}.nodes.{pk}", ids, "must be a non-empty list of integer node ids")
    unit_pair = (str(units.get("length", "")), str(units.get("force", "")))
    sets = tuple(_modal_set(folder, name, unit_pair, f"{key} set {name}") for name in plan.names)
    n = fcfg.n_modes
    for ms in sets:
        if ms.frequency_rad_s.size < n:
            raise ConfigError("flex.n_modes", n, f"modal set {ms.name!r} has only {ms.frequency_rad_s.size} modes")
    freq = np.array([ms.frequency_rad_s[:n] for ms in sets]) * fcfg.frequency_scale
    # RK4 resolves a mode well (numerical damping < 0.2 % of critical) below 1/8 of the step rate
    # with separation switching each configuration flies its first set only
    in_use = freq if fcfg.switching == "propellant" else freq[sorted({e[0][0] for e in plan.by_configuration})]
    limit = 2.0 * np.pi * plant_rate_hz / 8.0
    if in_use.max() >= limit:
        raise ConfigError("flex.n_modes", n, f"the highest retained mode ({in_use.max() / 2 / np.pi:.1f} Hz) must stay "
                          f"below sim.plant_rate_hz / 8 = {plant_rate_hz / 8:g} Hz for the RK4 step; keep fewer "
                          "modes or raise sim.plant_rate_hz")
    shapes = np.zeros((len(sets), n, len(keys), 6))
    nozzles = booster_keys(vehicle)
    for s, ms in enumerate(sets):
        upper, boosted = plan.roles[s] == UPPER_STAGE, plan.roles[s] == BOOSTED
        for pt, pk in enumerate(keys):
            if upper and pk in first_keys or pk in nozzles and not boosted:
                continue  # the first stage is gone in the upper-stage sets, the boosters in all but theirs
            shapes[s, :, pt, :] = ms.at_nodes(nodes[pk], f"{key}.nodes.{pk}")[:n]
    shapes *= fcfg.shape_scale
    zeta = np.asarray(fcfg.damping_per_mode[:n] if fcfg.damping_per_mode else [fcfg.damping] * n, float)
    return FlexTables(frequency_rad_s=freq, damping=zeta, shapes=shapes, sets=sets, set_map=plan.table())


def _tank(name: str, key: str, node: dict, vdir: Path, load_kg: float, configurations: int) -> SloshTank:
    for k in ("table", "radius_m", "bottom_station_m", "density_kgm3", "reference_accel_mps2"):
        if k not in node:
            raise ConfigError(f"{key}.{k}", None, "missing")
    for k in ("radius_m", "density_kgm3", "reference_accel_mps2"):
        if not float(node[k]) > 0.0:
            raise ConfigError(f"{key}.{k}", node[k], "must be positive")
    path = vdir / str(node["table"])
    # the vehicle tables' reader: columns in any unit of io.units.UNITS, converted to SI;
    # the level axis refused out of order (TABLE_COLUMNS["slosh"], TABLE_AXES["slosh"])
    cols, names = read_table(path, "slosh")
    level = cols["level"]
    tkey = table_key(path)
    column = {base: f"{tkey}:{names[base]}" for base in names}
    radius, density = float(node["radius_m"]), float(node["density_kgm3"])
    full = load_kg / (density * np.pi * radius**2)
    if level[0] > 0.0 or level[-1] < full * (1.0 - 1e-9):
        raise ConfigError(column["level"], [float(level[0]), float(level[-1])],
                          f"must cover the tank from 0 to the full-load level {full:.4f} m")
    for base in ("frequency", "slosh_mass", "slosh_height"):
        if np.any(cols[base] < 0.0):
            raise ConfigError(column[base], float(cols[base].min()), "must be zero or positive")
    if np.any(cols["damping"] < 0.0):
        raise ConfigError(column["damping"], float(cols["damping"].min()), "damping must not be negative")
    if np.any(cols["slosh_mass"] > density * np.pi * radius**2 * level + 1e-6 * load_kg):
        raise ConfigError(column["slosh_mass"], float(cols["slosh_mass"].max()), "exceeds the liquid mass at its level")
    return SloshTank(name=name, level_m=level, frequency_rad_s=2.0 * np.pi * cols["frequency"],
                     damping=cols["damping"], mass_kg=cols["slosh_mass"], height_m=cols["slosh_height"],
                     radius_m=radius, bottom_station_m=float(node["bottom_station_m"]), density_kgm3=density,
                     reference_accel_mps2=float(node["reference_accel_mps2"]), configurations=configurations)


def load_slosh(vehicle: Vehicle, scfg: SloshOnConfig) -> SloshData:
    """Read every sloshing tank's table and check it covers the tank."""
    spec = _spec(vehicle, "slosh")
    vdir = Path(vehicle.data_dir or ".")
    n_configs = len(vehicle.configurations)
    tanks = []
    for name, node in spec.items():
        aboard = vehicle.first_stage_configurations if name in vehicle.first_stage_tanks else n_configs
        tanks.append(_tank(name, vehicle.keys.get(f"slosh.{name}", f"vehicle.slosh.{name}"), node, vdir,
                           vehicle.tank_load_kg(name), aboard))
    return SloshData(tanks=tuple(tanks))
