"""Load a vehicle: its YAML config (``conf/vehicle/<name>.yaml``) and CSV tables, convert
to SI once, and refuse bad data before any computation.

Table format
------------
CSV, ``#`` comment lines allowed, one header row of column names, then numbers. A
column name's suffix after the last ``_`` is its unit when it is one of ``UNITS``
(:mod:`savant_cli.io.units`, shared with the modal data files)
(``thrust_vac_N``, ``alpha_deg``, ``cg_x_in``); the loader converts to SI and checks the
unit's dimension against the column's. Names without a unit suffix are dimensionless
(``mach``, ``CA``, ``thrust_fraction``).

Frames and conventions (``docs/architecture.md``)
------------------------------------------------
* Locations (CG, moment reference point, gimbals, sensors) are in the structure frame:
  x aft of the nose tip (a station), y = body y, z = -body z, metres.
* Inertias are about the CG in body axes; the columns ``ixy, ixz, iyz`` are products of
  inertia (``Ixy = integral of x y dm``), so the tensor's off-diagonal elements are their
  negatives.
* Aerodynamic coefficients are body-axis: force ``q S [-CA, CY, -CN]``, moment about the
  moment reference point ``q S [l_x Cl, l_y Cm, l_z Cn]``.

Every refusal raises :class:`savant_cli.errors.ConfigError` with the key (``vehicle.<path>``
or ``<folder>/<file>.csv:<column>``), the offending value and what is allowed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig, OmegaConf

from savant_cli.config.checks import no_negative_entries, non_negative, positive
from savant_cli.errors import ConfigError
from savant_cli.io.data_csv import read_numeric_csv
from savant_cli.io.table_order import require_grid_order, require_increasing, table_key
from savant_cli.io.units import UNITS, split_unit, units_of

#: The vehicle's configurations, in the order the aero and mass tables are stacked
#: (models/configurations.py numbers them).
CONFIG_NAMES = ("stack", "upper_les", "upper")
#: The coefficient columns of an aero table (body axes, dimensionless), in the order of
#: the packed table's coefficient axis (models/aero.py).
AERO_COEFFICIENTS = ("CA", "CY", "CN", "Cl", "Cm", "Cn")

_INERTIA = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")

#: table kind -> required columns (base name, dimension); ``None`` = dimensionless
TABLE_COLUMNS: dict[str, tuple[tuple[str, str | None], ...]] = {
    "mass": (("propellant_remaining", "mass"), ("mass", "mass"), ("cg_x", "length"), ("cg_y", "length"),
             ("cg_z", "length")) + tuple((c, "inertia") for c in _INERTIA),
    "aero": (("mach", None), ("alpha", "angle"), ("beta", "angle")) + tuple((c, None) for c in AERO_COEFFICIENTS),
    "base_force": (("time", "time"), ("base_force", "force")),
    "first_stage_thrust": (("time", "time"), ("thrust_vac", "force")),
    "startup": (("time", "time"), ("thrust_fraction", None)),
    "rcs_thrust": (("altitude", "length"), ("thrust_vac", "force")),
    # one tank's slosh parameters vs liquid level (savant_cli/flex_slosh.py); the frequency
    # at the slosh section's reference acceleration, the mass's height above the tank bottom
    "slosh": (("level", "length"), ("frequency", "frequency"), ("damping", None), ("slosh_mass", "mass"),
              ("slosh_height", "length")),
}

#: table kind -> its axis columns (base names), slowest first: checked in the order written,
#: strictly increasing (a grid's rows with the first column slowest); refused, never sorted
TABLE_AXES: dict[str, tuple[str, ...]] = {
    "mass": ("propellant_remaining",), "aero": ("mach", "alpha", "beta"), "base_force": ("time",),
    "first_stage_thrust": ("time",), "startup": ("time",), "rcs_thrust": ("altitude",), "slosh": ("level",),
}

MASS_TOLERANCE_KG = 1.0   # staging consistency of the mass tables


# ----------------------------------------------------------------------- data classes
@dataclass(frozen=True)
class AeroTable:
    """Aerodynamic coefficients of one configuration on a (Mach, alpha, beta) grid.

    Attributes
    ----------
    mach, alpha_rad, beta_rad : numpy.ndarray
        Strictly increasing grid axes (-, rad, rad).
    coeffs : numpy.ndarray
        Shape ``(6, n_mach, n_alpha, n_beta)``: CA, CY, CN, Cl, Cm, Cn (body axes; the
        moments about the moment reference point).
    base_time_s, base_force_N : numpy.ndarray
        Base force along body X (N, negative = drag) vs time from liftoff (s).
    area_m2 : float
        Reference area, m^2.
    lref_m : numpy.ndarray
        ``(3,)`` reference lengths of the roll, pitch and yaw moments, m.
    mrp_m : numpy.ndarray
        ``(3,)`` moment reference point, structure frame, m.
    """

    mach: np.ndarray
    alpha_rad: np.ndarray
    beta_rad: np.ndarray
    coeffs: np.ndarray
    base_time_s: np.ndarray
    base_force_N: np.ndarray
    area_m2: float
    lref_m: np.ndarray
    mrp_m: np.ndarray


@dataclass(frozen=True)
class MassTable:
    """Mass properties vs propellant remaining of the configuration's burning stage.

    Attributes
    ----------
    propellant_kg : numpy.ndarray
        ``(n,)`` strictly increasing, from 0 to the full load, kg.
    mass_kg : numpy.ndarray
        ``(n,)`` total mass, kg.
    cg_m : numpy.ndarray
        ``(n, 3)`` CG in the structure frame, m.
    inertia_kgm2 : numpy.ndarray
        ``(n, 6)`` about the CG in body axes: Ixx, Iyy, Izz, Ixy, Ixz, Iyz (products of
        inertia; the tensor's off-diagonal elements are their negatives), kg m^2.
    """

    propellant_kg: np.ndarray
    mass_kg: np.ndarray
    cg_m: np.ndarray
    inertia_kgm2: np.ndarray


@dataclass(frozen=True)
class Configuration:
    """One flight configuration (``stack``, ``upper_les``, ``upper``)."""

    name: str
    aero: AeroTable
    mass: MassTable


@dataclass(frozen=True)
class Engine:
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
class FirstStage:
    """Solid first stage. Thrust is vacuum thrust (N) vs time from liftoff (s); the
    delivered thrust is ``F_vac - p A_exit``; mass flow ``F_vac / (g0 Isp_vac)``.
    Gimbal location in the structure frame (m); limit in rad."""

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


@dataclass(frozen=True)
class UpperStage:
    """J-2X upper stage: rated vacuum thrust (N), Isp (s), LOX/LH2 mixture ratio and
    loads (kg), start transient (thrust fraction vs time since the ignition command, s),
    shutdown impulse (N·s: the vacuum impulse delivered after the cutoff command), gimbal
    (structure frame, m; limit rad) and the launch abort system mass (kg)."""

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


@dataclass(frozen=True)
class Rcs:
    """Roll-control jets: vacuum thrust per jet (N) vs altitude (m), exit area (m^2),
    number of jets per roll direction, moment arm (m), ramp times (s), location
    (structure frame, m)."""

    altitude_m: np.ndarray
    thrust_vac_N: np.ndarray
    exit_area_m2: float
    jets_per_direction: int
    moment_arm_m: float
    ramp_up_s: float
    ramp_down_s: float
    location_m: np.ndarray


@dataclass(frozen=True)
class Sensors:
    """Sensor locations, structure frame, m."""

    imu_m: np.ndarray
    rate_gyro_upper_stage_m: np.ndarray
    rate_gyro_first_stage_m: np.ndarray


@dataclass(frozen=True)
class Events:
    """Staging event parameters: separation when first-stage vacuum thrust falls below
    ``separation_thrust_fraction`` of its peak; J-2X ignition command
    ``ignition_delay_s`` later; LES jettison ``les_jettison_delay_s`` after that."""

    separation_thrust_fraction: float
    ignition_delay_s: float
    les_jettison_delay_s: float


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
    slosh_spec: dict | None = None  # raw ``slosh`` section, loaded when slosh is on
    #: structural load allowable on the total q·α (Pa·deg, ``loads.qalpha_limit_Pa_deg``;
    #: None: no limit declared). The run summary reports the time above it.
    qalpha_limit_Pa_deg: float | None = None


# ------------------------------------------------------------------------- key schema
_VEC3 = "vec3"
ENGINE_KEYS = {"mass_kg": float, "cg_from_gimbal_m": float, "inertia_about_gimbal_kgm2": float}
CONFIG_KEYS = {"aero_table": str, "base_force_table": str, "mass_table": str, "reference_area_m2": float,
               "reference_length_m": _VEC3, "moment_reference_m": _VEC3}
SCHEMA: dict[str, Any] = {
    "name": str, "description": str, "data_dir": str, "length_m": float,
    "configurations": {n: CONFIG_KEYS for n in CONFIG_NAMES},
    "first_stage": {"thrust_table": str, "isp_vac_s": float, "isp_sl_s": float, "nozzle_exit_area_m2": float,
                    "propellant_kg": float, "jettison_mass_kg": float, "gimbal_m": _VEC3,
                    "gimbal_limit_deg": float, "engine": ENGINE_KEYS},
    "upper_stage": {"thrust_vac_N": float, "isp_vac_s": float, "mixture_ratio": float,
                    "nozzle_exit_area_m2": float, "lox_kg": float, "lh2_kg": float, "startup_table": str,
                    "shutdown_impulse_Ns": float,
                    "gimbal_m": _VEC3, "gimbal_limit_deg": float, "les_mass_kg": float, "engine": ENGINE_KEYS},
    "rcs": {"thrust_table": str, "exit_area_m2": float, "jets_per_direction": int, "moment_arm_m": float,
            "ramp_up_s": float, "ramp_down_s": float, "location_m": _VEC3},
    "sensors": {"imu_m": _VEC3, "rate_gyro_upper_stage_m": _VEC3, "rate_gyro_first_stage_m": _VEC3},
    "events": {"separation_thrust_fraction": float, "ignition_delay_s": float, "les_jettison_delay_s": float},
    "loads": {"qalpha_limit_Pa_deg": float},
}
_MAPPING = "mapping"  # a free-form section checked by its own loader (savant_cli.flex_slosh)
SCHEMA["flex"] = _MAPPING
SCHEMA["slosh"] = _MAPPING
_OPTIONAL = {"description", "flex", "slosh", "loads"}


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and bool(np.isfinite(v))


def _check_keys(node: Mapping, schema: Mapping, path: str) -> None:
    """Refuse unknown, missing and mistyped keys of the vehicle YAML."""
    for key in node:
        if key not in schema:
            raise ConfigError(f"{path}.{key}", node[key], f"unknown key; allowed: {', '.join(schema)}")
    for key, kind in schema.items():
        full = f"{path}.{key}"
        if key not in node or node[key] is None:
            if key in _OPTIONAL:
                continue
            raise ConfigError(full, None, "missing")
        value = node[key]
        if isinstance(kind, Mapping):
            if not isinstance(value, Mapping):
                raise ConfigError(full, value, "must be a mapping with keys " + ", ".join(kind))
            _check_keys(value, kind, full)
        elif kind == _MAPPING:
            if not isinstance(value, Mapping):
                raise ConfigError(full, value, "must be a mapping")
        elif kind is float:
            if not _is_number(value):
                raise ConfigError(full, value, "must be a finite number")
        elif kind is int:
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ConfigError(full, value, "must be an integer")
        elif kind == _VEC3:
            if not isinstance(value, (list, tuple)) or len(value) != 3 or not all(_is_number(v) for v in value):
                raise ConfigError(full, value, "must be a list of 3 finite numbers [x, y, z] (structure frame, m)")
        elif kind is str and not isinstance(value, str):
            raise ConfigError(full, value, "must be a string")


def _vec3(value: Any) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(value, dtype=np.float64))


# ----------------------------------------------------------------------------- tables
_table_key = table_key


def read_table(path: Path, kind: str) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Read one CSV table of the given kind (a key of :data:`TABLE_COLUMNS`).

    Parameters
    ----------
    path : pathlib.Path
        The CSV file.
    kind : str
        Table kind; fixes the required columns and their dimensions.

    Returns
    -------
    columns : dict of str to numpy.ndarray
        SI float64 columns by base name (unit suffix stripped).
    names : dict of str to str
        The header's full column name (with its unit suffix) by base name.

    Raises
    ------
    ConfigError
        Missing or unreadable file, missing/duplicate/unknown columns, wrong units,
        ragged rows, non-numeric or non-finite cells, fewer than 2 rows, an axis
        (:data:`TABLE_AXES`) out of order: ``<folder>/<file>.csv:<column>``, the row
        (and its line) and the value; the table is never re-sorted.
    """
    key = _table_key(path)
    spec = dict(TABLE_COLUMNS[kind])
    allowed = ", ".join(f"{b}_<{d} unit>" if d else b for b, d in spec.items())
    columns: dict[str, tuple[int, str | None]] = {}

    def check_header(header: list[str]) -> None:  # the columns, before any row is read
        for j, name in enumerate(header):
            base, unit = split_unit(name)
            if base not in spec:
                raise ConfigError(f"{key}:{name or '<empty>'}", header, f"unknown column; the columns are {allowed}")
            if base in columns:
                raise ConfigError(f"{key}:{name}", header, "duplicate column")
            dim = spec[base]
            if dim is None and unit is not None:
                raise ConfigError(f"{key}:{name}", unit, "dimensionless column: no unit suffix")
            if dim is not None and (unit is None or UNITS[unit][0] != dim):
                units = ", ".join(units_of(dim))
                raise ConfigError(f"{key}:{name}", unit, f"needs a {dim} unit suffix: one of {units}")
            columns[base] = (j, unit)
        for base, dim in spec.items():
            if base not in columns:
                raise ConfigError(f"{key}:{base}", header, f"missing column; the columns are {allowed}")

    header, data, rows = read_numeric_csv(path, min_rows=2, check_header=check_header)
    out: dict[str, np.ndarray] = {}
    for base, (j, unit) in columns.items():
        col = data[:, j]
        out[base] = np.ascontiguousarray(col * UNITS[unit][1] if unit else col)
    names = {base: header[j] for base, (j, _) in columns.items()}
    axes = TABLE_AXES[kind]  # checked as written (in the file's units), before anything uses the order
    if len(axes) == 1:
        require_increasing(f"{key}:{names[axes[0]]}", data[:, columns[axes[0]][0]], rows)
    else:
        require_grid_order([f"{key}:{names[a]}" for a in axes], [data[:, columns[a][0]] for a in axes], rows)
    return out, names


def _aero(cfg: Mapping, vdir: Path, cname: str) -> AeroTable:
    path = vdir / cfg["aero_table"]
    key = _table_key(path)
    t, tn = read_table(path, "aero")  # rows in grid order, refused otherwise (TABLE_AXES)
    names = ("mach", "alpha", "beta")
    # the distinct breakpoints of each axis; the rows must be exactly their product, in order
    axes = [np.unique(t[c]) for c in names]
    for c, a in zip(names, axes):
        if a.size < 2:
            raise ConfigError(f"{key}:{tn[c]}", a.tolist(), "needs at least 2 distinct values")
    shape = tuple(a.size for a in axes)
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    rows = np.column_stack([t[c] for c in names])
    if rows.shape != grid.shape or not np.array_equal(rows, grid):
        # the rows are a strictly ordered subset of the grid (read_table): the first that differs marks a gap
        mismatch = np.any(rows != grid[:rows.shape[0]], axis=1)
        first = int(np.argmax(mismatch)) if mismatch.any() else rows.shape[0]
        factor = [UNITS[split_unit(tn[c])[1]][1] if split_unit(tn[c])[1] else 1.0 for c in names]
        at = ", ".join(f"{tn[c]} = {grid[first, j] / factor[j]:.9g}" for j, c in enumerate(names))
        raise ConfigError(key, f"{rows.shape[0]} rows", f"must be a full rectangular grid: every (mach, alpha, beta) "
                                                         f"combination of {shape[0]}x{shape[1]}x{shape[2]} = "
                                                         f"{grid.shape[0]} exactly once, in order; "
                                                         f"{grid.shape[0] - rows.shape[0]} missing, the first at "
                                                         f"row {first + 1} ({at})")
    if axes[0][0] < 0.0:
        raise ConfigError(f"{key}:{tn['mach']}", float(axes[0][0]), "Mach must not be negative")
    for c, a in zip(("alpha", "beta"), axes[1:]):
        if a[0] < -np.pi / 2 or a[-1] > np.pi / 2:
            raise ConfigError(f"{key}:{tn[c]}", [float(a[0]), float(a[-1])], "angles must be within ±90 deg")
    coeffs = np.stack([t[c] for c in AERO_COEFFICIENTS])  # row i of the file is grid point i (C order)
    bpath = vdir / cfg["base_force_table"]
    b, _ = read_table(bpath, "base_force")
    p = f"vehicle.configurations.{cname}"
    return AeroTable(
        mach=axes[0], alpha_rad=axes[1], beta_rad=axes[2],
        coeffs=np.ascontiguousarray(coeffs.reshape((6,) + shape)),
        base_time_s=b["time"], base_force_N=b["base_force"],
        area_m2=positive(f"{p}.reference_area_m2", cfg["reference_area_m2"]),
        lref_m=_vec3([positive(f"{p}.reference_length_m", v) for v in cfg["reference_length_m"]]),
        mrp_m=_vec3(cfg["moment_reference_m"]),
    )


def _mass(cfg: Mapping, vdir: Path, length_m: float) -> MassTable:
    path = vdir / cfg["mass_table"]
    key = _table_key(path)
    t, tn = read_table(path, "mass")
    prop = t["propellant_remaining"]
    no_negative_entries(f"{key}:{tn['propellant_remaining']}", prop, "propellant remaining")
    for c in ("mass", "ixx", "iyy", "izz"):
        bad = np.nonzero(t[c] <= 0.0)[0]
        if bad.size:
            raise ConfigError(f"{key}:{tn[c]}", float(t[c][bad[0]]), "mass and moments of inertia must be positive")
    below = np.nonzero(t["mass"] < prop)[0]
    if below.size:
        raise ConfigError(f"{key}:{tn['mass']}", float(t["mass"][below[0]]),
                          f"total mass must be at least the propellant remaining ({prop[below[0]]:.1f} kg)")
    cg = np.column_stack([t["cg_x"], t["cg_y"], t["cg_z"]])
    out = np.nonzero((cg[:, 0] < 0.0) | (cg[:, 0] > length_m))[0]
    if out.size:
        raise ConfigError(f"{key}:{tn['cg_x']}", float(cg[out[0], 0]),
                          f"CG station must lie on the vehicle, within [0, {length_m:g}] m of the nose tip")
    inertia = np.column_stack([t[c] for c in _INERTIA])
    tensor = np.empty((inertia.shape[0], 3, 3))
    tensor[:, 0, 0], tensor[:, 1, 1], tensor[:, 2, 2] = inertia[:, 0], inertia[:, 1], inertia[:, 2]
    tensor[:, 0, 1] = tensor[:, 1, 0] = -inertia[:, 3]
    tensor[:, 0, 2] = tensor[:, 2, 0] = -inertia[:, 4]
    tensor[:, 1, 2] = tensor[:, 2, 1] = -inertia[:, 5]
    ev = np.linalg.eigvalsh(tensor)  # ascending principal moments, per row
    scale = ev[:, 2]
    bad = np.nonzero((ev[:, 0] <= 1e-12 * scale) | (ev[:, 0] + ev[:, 1] < ev[:, 2] * (1.0 - 1e-9)))[0]
    if bad.size:
        i = int(bad[0])
        raise ConfigError(f"{key}:{tn['ixx']}", inertia[i].tolist(),
                          f"row {i + 1}: the inertia tensor must be positive definite and its principal moments "
                          f"must satisfy the triangle inequality (I1 + I2 >= I3); principal moments {ev[i].tolist()}")
    return MassTable(propellant_kg=prop, mass_kg=t["mass"], cg_m=np.ascontiguousarray(cg),
                     inertia_kgm2=np.ascontiguousarray(inertia))


def _engine(node: Mapping, path: str) -> Engine:
    return Engine(**{k: positive(f"{path}.{k}", node[k]) for k in ENGINE_KEYS})


def _gimbal_limit(key: str, deg: float) -> float:
    if not 0.0 < deg < 90.0:
        raise ConfigError(key, deg, "must be within (0, 90) deg")
    return float(np.radians(deg))


def _to_plain(vehicle_cfg: Mapping) -> dict:
    """The vehicle section as plain Python containers (interpolations resolved)."""
    if isinstance(vehicle_cfg, DictConfig):
        return OmegaConf.to_container(vehicle_cfg, resolve=True)  # type: ignore[return-value]
    if not isinstance(vehicle_cfg, Mapping):
        raise ConfigError("vehicle", vehicle_cfg, "must be a mapping (the vehicle YAML)")
    return dict(vehicle_cfg)


def load_vehicle(vehicle_cfg: Mapping, data_dir: Path) -> Vehicle:
    """Load and check a vehicle.

    Parameters
    ----------
    vehicle_cfg : Mapping
        The ``vehicle`` config node (OmegaConf DictConfig or plain dict) of
        ``conf/vehicle/<name>.yaml``.
    data_dir : pathlib.Path
        Resolved folder of the vehicle's CSV tables.

    Returns
    -------
    Vehicle
        Frozen dataclasses of float64 contiguous arrays, SI units (angles in rad,
        locations in the structure frame, inertias about the CG in body axes).

    Raises
    ------
    ConfigError
        Unknown, missing or mistyped keys; missing or malformed files; non-monotonic
        table axes; an aero grid that is not full and rectangular; negative mass,
        inertia, thrust or Isp; an inertia tensor that is not positive definite or
        violates the triangle inequality; a location that is not 3 numbers; mass tables
        inconsistent with the propellant loads and the jettisoned masses.
    """
    node = _to_plain(vehicle_cfg)
    _check_keys(node, SCHEMA, "vehicle")
    vdir = Path(data_dir)
    length = positive("vehicle.length_m", node["length_m"])

    configs = {}
    for cname in CONFIG_NAMES:
        c = node["configurations"][cname]
        configs[cname] = Configuration(name=cname, aero=_aero(c, vdir, cname), mass=_mass(c, vdir, length))

    p = "vehicle.first_stage"
    fs_node = node["first_stage"]
    fpath = vdir / fs_node["thrust_table"]
    ft, ftn = read_table(fpath, "first_stage_thrust")
    no_negative_entries(f"{_table_key(fpath)}:{ftn['thrust_vac']}", ft["thrust_vac"], "thrust")
    if ft["thrust_vac"].max() <= 0.0:
        raise ConfigError(f"{_table_key(fpath)}:{ftn['thrust_vac']}", 0.0, "thrust must be positive somewhere")
    fs = FirstStage(
        thrust_time_s=ft["time"], thrust_vac_N=ft["thrust_vac"],
        isp_vac_s=positive(f"{p}.isp_vac_s", fs_node["isp_vac_s"]),
        isp_sl_s=positive(f"{p}.isp_sl_s", fs_node["isp_sl_s"]),
        nozzle_exit_area_m2=non_negative(f"{p}.nozzle_exit_area_m2", fs_node["nozzle_exit_area_m2"]),
        propellant_kg=positive(f"{p}.propellant_kg", fs_node["propellant_kg"]),
        jettison_mass_kg=non_negative(f"{p}.jettison_mass_kg", fs_node["jettison_mass_kg"]),
        gimbal_m=_vec3(fs_node["gimbal_m"]),
        gimbal_limit_rad=_gimbal_limit(f"{p}.gimbal_limit_deg", fs_node["gimbal_limit_deg"]),
        engine=_engine(fs_node["engine"], f"{p}.engine"),
    )
    if fs.isp_sl_s > fs.isp_vac_s:
        raise ConfigError(f"{p}.isp_sl_s", fs.isp_sl_s, f"must not exceed isp_vac_s ({fs.isp_vac_s})")

    p = "vehicle.upper_stage"
    us_node = node["upper_stage"]
    spath = vdir / us_node["startup_table"]
    st, _ = read_table(spath, "startup")
    frac = st["thrust_fraction"]
    if np.any((frac < 0.0) | (frac > 1.0)):
        raise ConfigError(f"{_table_key(spath)}:thrust_fraction", float(frac[np.argmax((frac < 0) | (frac > 1))]),
                          "thrust fraction must be within [0, 1]")
    us = UpperStage(
        thrust_vac_N=positive(f"{p}.thrust_vac_N", us_node["thrust_vac_N"]),
        isp_vac_s=positive(f"{p}.isp_vac_s", us_node["isp_vac_s"]),
        mixture_ratio=positive(f"{p}.mixture_ratio", us_node["mixture_ratio"]),
        nozzle_exit_area_m2=non_negative(f"{p}.nozzle_exit_area_m2", us_node["nozzle_exit_area_m2"]),
        lox_kg=positive(f"{p}.lox_kg", us_node["lox_kg"]),
        lh2_kg=positive(f"{p}.lh2_kg", us_node["lh2_kg"]),
        startup_time_s=st["time"], startup_fraction=frac,
        shutdown_impulse_Ns=non_negative(f"{p}.shutdown_impulse_Ns", us_node["shutdown_impulse_Ns"]),
        gimbal_m=_vec3(us_node["gimbal_m"]),
        gimbal_limit_rad=_gimbal_limit(f"{p}.gimbal_limit_deg", us_node["gimbal_limit_deg"]),
        les_mass_kg=non_negative(f"{p}.les_mass_kg", us_node["les_mass_kg"]),
        engine=_engine(us_node["engine"], f"{p}.engine"),
    )

    p = "vehicle.rcs"
    rn = node["rcs"]
    rpath = vdir / rn["thrust_table"]
    rt, rtn = read_table(rpath, "rcs_thrust")
    no_negative_entries(f"{_table_key(rpath)}:{rtn['thrust_vac']}", rt["thrust_vac"], "thrust")
    rcs = Rcs(altitude_m=rt["altitude"], thrust_vac_N=rt["thrust_vac"],
              exit_area_m2=non_negative(f"{p}.exit_area_m2", rn["exit_area_m2"]),
              jets_per_direction=int(positive(f"{p}.jets_per_direction", rn["jets_per_direction"])),
              moment_arm_m=positive(f"{p}.moment_arm_m", rn["moment_arm_m"]),
              ramp_up_s=non_negative(f"{p}.ramp_up_s", rn["ramp_up_s"]),
              ramp_down_s=non_negative(f"{p}.ramp_down_s", rn["ramp_down_s"]),
              location_m=_vec3(rn["location_m"]))

    sensors = Sensors(**{k: _vec3(node["sensors"][k]) for k in SCHEMA["sensors"]})
    en = node["events"]
    frac_sep = en["separation_thrust_fraction"]
    if not 0.0 < frac_sep < 1.0:
        raise ConfigError("vehicle.events.separation_thrust_fraction", frac_sep, "must be within (0, 1)")
    events = Events(separation_thrust_fraction=float(frac_sep),
                    ignition_delay_s=non_negative("vehicle.events.ignition_delay_s", en["ignition_delay_s"]),
                    les_jettison_delay_s=non_negative("vehicle.events.les_jettison_delay_s",
                                                  en["les_jettison_delay_s"]))
    qalpha_limit = None
    if node.get("loads") is not None:
        qalpha_limit = positive("vehicle.loads.qalpha_limit_Pa_deg", node["loads"]["qalpha_limit_Pa_deg"])
    vehicle = Vehicle(name=str(node["name"]), description=str(node.get("description") or ""), length_m=length,
                      configurations=configs, first_stage=fs, upper_stage=us, rcs=rcs, sensors=sensors,
                      events=events, data_dir=vdir, flex_spec=node.get("flex"), slosh_spec=node.get("slosh"),
                      qalpha_limit_Pa_deg=qalpha_limit)
    check_consistency(vehicle, {n: node["configurations"][n]["mass_table"] for n in CONFIG_NAMES})
    return vehicle


def check_consistency(v: Vehicle, mass_files: Mapping[str, str] | None = None) -> None:
    """Refuse mass tables that disagree with the loads and the jettisoned masses.

    * every table starts at 0 propellant; the stack's ends at ``first_stage.propellant_kg``,
      the upper configurations' at ``upper_stage.lox_kg + lh2_kg``;
    * stack mass at 0 propellant minus ``first_stage.jettison_mass_kg`` equals the
      upper_les mass at full propellant;
    * upper_les minus upper mass equals ``upper_stage.les_mass_kg`` at every propellant
      level (upper_les interpolated at upper's breakpoints; mass is linear in propellant).

    All within :data:`MASS_TOLERANCE_KG`.
    """
    files = dict(mass_files or {n: f"mass_{n}.csv" for n in CONFIG_NAMES})
    tol = MASS_TOLERANCE_KG
    stack, les, up = (v.configurations[n].mass for n in CONFIG_NAMES)
    us_prop = v.upper_stage.lox_kg + v.upper_stage.lh2_kg
    for name, table, full, key in (("stack", stack, v.first_stage.propellant_kg, "vehicle.first_stage.propellant_kg"),
                                   ("upper_les", les, us_prop, "vehicle.upper_stage.lox_kg + lh2_kg"),
                                   ("upper", up, us_prop, "vehicle.upper_stage.lox_kg + lh2_kg")):
        if table.propellant_kg[0] > tol:
            raise ConfigError(f"{files[name]}:propellant_remaining", float(table.propellant_kg[0]),
                              "the table must start at 0 propellant remaining")
        if abs(table.propellant_kg[-1] - full) > tol:
            raise ConfigError(key, full, f"must equal the largest propellant_remaining of {files[name]} "
                                         f"({table.propellant_kg[-1]:.1f} kg)")
    after_sep = stack.mass_kg[0] - v.first_stage.jettison_mass_kg
    if abs(after_sep - les.mass_kg[-1]) > tol:
        raise ConfigError("vehicle.first_stage.jettison_mass_kg", v.first_stage.jettison_mass_kg,
                          f"stack mass at burnout ({stack.mass_kg[0]:.1f} kg, {files['stack']}) minus the jettison "
                          f"mass must equal the upper_les mass at full propellant ({les.mass_kg[-1]:.1f} kg, "
                          f"{files['upper_les']}) within {tol:g} kg")
    diff = np.interp(up.propellant_kg, les.propellant_kg, les.mass_kg) - up.mass_kg
    worst = int(np.argmax(np.abs(diff - v.upper_stage.les_mass_kg)))
    if abs(diff[worst] - v.upper_stage.les_mass_kg) > tol:
        raise ConfigError("vehicle.upper_stage.les_mass_kg", v.upper_stage.les_mass_kg,
                          f"must equal upper_les mass minus upper mass at every propellant level within {tol:g} kg; "
                          f"at {up.propellant_kg[worst]:.1f} kg propellant the difference is {diff[worst]:.1f} kg")
