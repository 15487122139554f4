"""Load a vehicle: its YAML config (``conf/vehicle/<name>.yaml``) and CSV tables, unit
conversion to SI once, and refusal of bad data before any computation.

CSV tables have one header row of column names whose suffix states the unit
(``thrust_vac_N``, ``alpha_deg``, ``cg_x_in``); ``#`` lines are comments. Recognized
suffixes and their SI factors are in :data:`UNITS`; a column without a unit suffix is
dimensionless (coefficients, fractions).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from savant_cli import constants as C
from savant_cli.errors import ConfigError

UNITS = {
    "m": 1.0, "ft": C.FT, "in": C.IN, "kg": 1.0, "lbm": C.LBM, "slug": C.SLUG, "N": 1.0, "lbf": C.LBF,
    "s": 1.0, "deg": C.DEG, "rad": 1.0, "kgm2": 1.0, "slugft2": C.SLUG * C.FT**2, "m2": 1.0, "ft2": C.FT**2,
    "Pa": 1.0, "psf": C.LBF / C.FT**2, "mps": 1.0, "fps": C.FT,
}
AERO_COEFFS = ("CA", "CY", "CN", "Cl", "Cm", "Cn")
CONFIG_NAMES = ("stack", "upper_les", "upper")


# ----------------------------------------------------------------------- data classes
@dataclass(frozen=True)
class AeroTable:
    """Aerodynamic coefficients of one configuration on a (Mach, α, β) grid."""

    mach: np.ndarray
    alpha_rad: np.ndarray
    beta_rad: np.ndarray
    coeffs: np.ndarray  # (6, n_mach, n_alpha, n_beta): CA CY CN Cl Cm Cn (body axes)
    base_time_s: np.ndarray
    base_force_N: np.ndarray  # along body X
    area_m2: float
    lref_m: np.ndarray  # (3,) roll, pitch, yaw reference lengths
    mrp_m: np.ndarray  # (3,) moment reference point, structure frame


@dataclass(frozen=True)
class MassTable:
    """Mass properties vs propellant remaining of the burning stage (ascending)."""

    propellant_kg: np.ndarray
    mass_kg: np.ndarray
    cg_m: np.ndarray  # (n, 3) structure frame
    inertia_kgm2: np.ndarray  # (n, 6) about the CG, body axes: Ixx Iyy Izz Ixy Ixz Iyz


@dataclass(frozen=True)
class Configuration:
    name: str
    aero: AeroTable
    mass: MassTable


@dataclass(frozen=True)
class Engine:
    """Moving engine/nozzle mass properties about its gimbal (for tail-wags-dog)."""

    mass_kg: float
    cg_from_gimbal_m: float
    inertia_about_gimbal_kgm2: float


@dataclass(frozen=True)
class FirstStage:
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
    thrust_vac_N: float
    isp_vac_s: float
    mixture_ratio: float
    nozzle_exit_area_m2: float
    lox_kg: float
    lh2_kg: float
    startup_time_s: np.ndarray
    startup_fraction: np.ndarray
    gimbal_m: np.ndarray
    gimbal_limit_rad: float
    les_mass_kg: float
    engine: Engine


@dataclass(frozen=True)
class Rcs:
    altitude_m: np.ndarray
    thrust_vac_N: np.ndarray  # per jet
    exit_area_m2: float
    jets_per_direction: int
    moment_arm_m: float
    ramp_up_s: float
    ramp_down_s: float
    location_m: np.ndarray


@dataclass(frozen=True)
class Sensors:
    imu_m: np.ndarray
    rate_gyro_upper_stage_m: np.ndarray
    rate_gyro_first_stage_m: np.ndarray


@dataclass(frozen=True)
class Events:
    separation_thrust_fraction: float
    ignition_delay_s: float
    les_jettison_delay_s: float


@dataclass(frozen=True)
class Vehicle:
    name: str
    description: str
    length_m: float
    configurations: dict[str, Configuration]
    first_stage: FirstStage
    upper_stage: UpperStage
    rcs: Rcs
    sensors: Sensors
    events: Events


# ------------------------------------------------------------------------- key schema
ENGINE_KEYS = {"mass_kg": float, "cg_from_gimbal_m": float, "inertia_about_gimbal_kgm2": float}
CONFIG_KEYS = {"aero_table": str, "base_force_table": str, "mass_table": str, "reference_area_m2": float,
               "reference_length_m": list, "moment_reference_m": list}
SCHEMA: dict[str, Any] = {
    "name": str, "description": str, "data_dir": str, "length_m": float,
    "configurations": {n: CONFIG_KEYS for n in CONFIG_NAMES},
    "first_stage": {"thrust_table": str, "isp_vac_s": float, "isp_sl_s": float, "nozzle_exit_area_m2": float,
                    "propellant_kg": float, "jettison_mass_kg": float, "gimbal_m": list, "gimbal_limit_deg": float,
                    "engine": ENGINE_KEYS},
    "upper_stage": {"thrust_vac_N": float, "isp_vac_s": float, "mixture_ratio": float, "nozzle_exit_area_m2": float,
                    "lox_kg": float, "lh2_kg": float, "startup_table": str, "gimbal_m": list,
                    "gimbal_limit_deg": float, "les_mass_kg": float, "engine": ENGINE_KEYS},
    "rcs": {"thrust_table": str, "exit_area_m2": float, "jets_per_direction": int, "moment_arm_m": float,
            "ramp_up_s": float, "ramp_down_s": float, "location_m": list},
    "sensors": {"imu_m": list, "rate_gyro_upper_stage_m": list, "rate_gyro_first_stage_m": list},
    "events": {"separation_thrust_fraction": float, "ignition_delay_s": float, "les_jettison_delay_s": float},
}


def _check_keys(node: Mapping, schema: Mapping, path: str) -> None:
    """Unknown, missing and mistyped keys of the vehicle YAML."""
    for key in node:
        if key not in schema:
            raise ConfigError(f"{path}.{key}", node[key], f"unknown key; allowed: {', '.join(schema)}")
    for key, kind in schema.items():
        full = f"{path}.{key}"
        if key not in node or node[key] is None:
            if key == "description":
                continue
            raise ConfigError(full, None, "missing")
        value = node[key]
        if isinstance(kind, Mapping):
            if not isinstance(value, Mapping):
                raise ConfigError(full, value, "must be a mapping of " + ", ".join(kind))
            _check_keys(value, kind, full)
        elif kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
                raise ConfigError(full, value, "must be a finite number")
        elif kind is int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise ConfigError(full, value, "must be an integer")
        elif kind is list:
            if not isinstance(value, (list, tuple)) or len(value) != 3 or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                raise ConfigError(full, value, "must be a list of 3 numbers (x, y, z)")
        elif kind is str and not isinstance(value, str):
            raise ConfigError(full, value, "must be a string")


def _positive(key: str, value: float, allow_zero: bool = False) -> float:
    ok = value >= 0.0 if allow_zero else value > 0.0
    if not ok:
        raise ConfigError(key, value, "must be zero or positive" if allow_zero else "must be positive")
    return float(value)


# ----------------------------------------------------------------------------- tables
def read_table(path: Path, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Read a CSV table and return SI columns by their base name (suffix stripped).

    ``columns`` are the required base names (``"thrust_vac"``; coefficients as is).
    """
    key = path.name
    if not path.is_file():
        raise ConfigError(key, str(path), "no such data file")
    try:
        with open(path) as f:
            lines = [ln.strip() for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    except OSError as exc:
        raise ConfigError(key, str(path), f"unreadable ({exc})") from None
    if len(lines) < 3:
        raise ConfigError(key, len(lines), "needs a header row and at least 2 data rows")
    header = [h.strip() for h in lines[0].split(",")]
    rows = []
    for i, ln in enumerate(lines[1:], start=2):
        cells = ln.split(",")
        if len(cells) != len(header):
            raise ConfigError(f"{key}:row {i}", ln, f"has {len(cells)} cells, the header has {len(header)}")
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            raise ConfigError(f"{key}:row {i}", ln, "cells must be numbers") from None
    data = np.array(rows)
    if not np.all(np.isfinite(data)):
        raise ConfigError(key, "non-finite", "all values must be finite")
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        base, _, unit = name.rpartition("_")
        if base and unit in UNITS:
            out[base] = data[:, j] * UNITS[unit]
        else:
            out[name] = data[:, j]
    for c in columns:
        if c not in out:
            raise ConfigError(f"{key}", header, f"missing column {c!r} (with a unit suffix such as _m, _kg, _N, _s, _deg)")
    return out


def _increasing(key: str, x: np.ndarray) -> None:
    if x.size < 2 or not np.all(np.diff(x) > 0):
        i = int(np.argmin(np.diff(x) > 0)) if x.size >= 2 else 0
        raise ConfigError(key, float(x[i + 1]) if x.size > i + 1 else x.tolist(),
                          "table axis must be strictly increasing")


def _aero(cfg: Mapping, vdir: Path, cname: str) -> AeroTable:
    t = read_table(vdir / cfg["aero_table"], ("mach", "alpha", "beta") + AERO_COEFFS)
    key = f"{cfg['aero_table']}"
    axes = [np.unique(t[a]) for a in ("mach", "alpha", "beta")]
    n = tuple(a.size for a in axes)
    if min(n) < 2:
        raise ConfigError(key, n, "needs at least 2 distinct values of mach, alpha and beta")
    if len(t["mach"]) != n[0] * n[1] * n[2]:
        raise ConfigError(key, len(t["mach"]), f"must be a full grid of {n[0]}x{n[1]}x{n[2]} = {np.prod(n)} rows")
    idx = [np.searchsorted(a, t[c]) for a, c in zip(axes, ("mach", "alpha", "beta"))]
    flat = np.ravel_multi_index(idx, n)
    if np.unique(flat).size != flat.size:
        raise ConfigError(key, "duplicate rows", "each (mach, alpha, beta) must appear exactly once")
    coeffs = np.empty((6,) + n)
    for k, c in enumerate(AERO_COEFFS):
        grid = np.empty(np.prod(n))
        grid[flat] = t[c]
        coeffs[k] = grid.reshape(n)
    if np.any(axes[0] < 0):
        raise ConfigError(f"{key}:mach", float(axes[0][0]), "Mach must be non-negative")
    b = read_table(vdir / cfg["base_force_table"], ("time", "base_force"))
    _increasing(f"{cfg['base_force_table']}:time_s", b["time"])
    p = f"vehicle.configurations.{cname}"
    return AeroTable(
        mach=axes[0], alpha_rad=axes[1], beta_rad=axes[2], coeffs=np.ascontiguousarray(coeffs),
        base_time_s=b["time"], base_force_N=b["base_force"],
        area_m2=_positive(f"{p}.reference_area_m2", cfg["reference_area_m2"]),
        lref_m=np.array([_positive(f"{p}.reference_length_m", v) for v in cfg["reference_length_m"]]),
        mrp_m=np.asarray(cfg["moment_reference_m"], float),
    )


def _mass(cfg: Mapping, vdir: Path) -> MassTable:
    name = cfg["mass_table"]
    cols = ("propellant_remaining", "mass", "cg_x", "cg_y", "cg_z", "ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    t = read_table(vdir / name, cols)
    _increasing(f"{name}:propellant_remaining", t["propellant_remaining"])
    for c in ("propellant_remaining", "mass", "ixx", "iyy", "izz"):
        bad = np.nonzero(t[c] < 0 if c == "propellant_remaining" else t[c] <= 0)[0]
        if bad.size:
            raise ConfigError(f"{name}:{c}", float(t[c][bad[0]]), "mass, propellant and principal inertias must be positive")
    inertia = np.column_stack([t[c] for c in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")])
    for i, row in enumerate(inertia):
        tensor = np.array([[row[0], -row[3], -row[4]], [-row[3], row[1], -row[5]], [-row[4], -row[5], row[2]]])
        ev = np.linalg.eigvalsh(tensor)
        if ev[0] <= 0 or ev[0] + ev[1] < ev[2] * (1 - 1e-9):
            raise ConfigError(f"{name}:row {i + 1}", row.tolist(),
                              "inertia tensor must be positive definite and satisfy the triangle inequality")
    return MassTable(propellant_kg=t["propellant_remaining"], mass_kg=t["mass"],
                     cg_m=np.column_stack([t["cg_x"], t["cg_y"], t["cg_z"]]),
                     inertia_kgm2=np.ascontiguousarray(inertia))


def _engine(node: Mapping, path: str) -> Engine:
    return Engine(**{k: _positive(f"{path}.{k}", node[k]) for k in ENGINE_KEYS})


def load_vehicle(vehicle_cfg: Mapping, data_dir: Path) -> Vehicle:
    """Load and check a vehicle.

    Parameters
    ----------
    vehicle_cfg : Mapping
        The ``vehicle`` config node (DictConfig or dict).
    data_dir : Path
        Resolved folder of the vehicle's CSV tables.

    Raises
    ------
    ConfigError
        For unknown or missing keys, missing or malformed files, non-monotonic axes,
        non-physical values and inconsistent mass tables.
    """
    try:
        from omegaconf import DictConfig, OmegaConf

        node = OmegaConf.to_container(vehicle_cfg, resolve=True) if isinstance(vehicle_cfg, DictConfig) else dict(vehicle_cfg)
    except ImportError:  # pragma: no cover
        node = dict(vehicle_cfg)
    _check_keys(node, SCHEMA, "vehicle")
    vdir = Path(data_dir)
    configs = {}
    for cname in CONFIG_NAMES:
        c = node["configurations"][cname]
        configs[cname] = Configuration(name=cname, aero=_aero(c, vdir, cname), mass=_mass(c, vdir))

    fs_node = node["first_stage"]
    ft = read_table(vdir / fs_node["thrust_table"], ("time", "thrust_vac"))
    _increasing(f"{fs_node['thrust_table']}:time_s", ft["time"])
    if np.any(ft["thrust_vac"] < 0):
        raise ConfigError(f"{fs_node['thrust_table']}:thrust_vac", float(ft["thrust_vac"].min()), "thrust must be non-negative")
    p = "vehicle.first_stage"
    fs = FirstStage(
        thrust_time_s=ft["time"], thrust_vac_N=ft["thrust_vac"],
        isp_vac_s=_positive(f"{p}.isp_vac_s", fs_node["isp_vac_s"]),
        isp_sl_s=_positive(f"{p}.isp_sl_s", fs_node["isp_sl_s"]),
        nozzle_exit_area_m2=_positive(f"{p}.nozzle_exit_area_m2", fs_node["nozzle_exit_area_m2"], True),
        propellant_kg=_positive(f"{p}.propellant_kg", fs_node["propellant_kg"]),
        jettison_mass_kg=_positive(f"{p}.jettison_mass_kg", fs_node["jettison_mass_kg"], True),
        gimbal_m=np.asarray(fs_node["gimbal_m"], float),
        gimbal_limit_rad=np.radians(_positive(f"{p}.gimbal_limit_deg", fs_node["gimbal_limit_deg"])),
        engine=_engine(fs_node["engine"], f"{p}.engine"),
    )
    us_node = node["upper_stage"]
    st = read_table(vdir / us_node["startup_table"], ("time", "thrust_fraction"))
    _increasing(f"{us_node['startup_table']}:time_s", st["time"])
    p = "vehicle.upper_stage"
    us = UpperStage(
        thrust_vac_N=_positive(f"{p}.thrust_vac_N", us_node["thrust_vac_N"]),
        isp_vac_s=_positive(f"{p}.isp_vac_s", us_node["isp_vac_s"]),
        mixture_ratio=_positive(f"{p}.mixture_ratio", us_node["mixture_ratio"]),
        nozzle_exit_area_m2=_positive(f"{p}.nozzle_exit_area_m2", us_node["nozzle_exit_area_m2"], True),
        lox_kg=_positive(f"{p}.lox_kg", us_node["lox_kg"]),
        lh2_kg=_positive(f"{p}.lh2_kg", us_node["lh2_kg"]),
        startup_time_s=st["time"], startup_fraction=st["thrust_fraction"],
        gimbal_m=np.asarray(us_node["gimbal_m"], float),
        gimbal_limit_rad=np.radians(_positive(f"{p}.gimbal_limit_deg", us_node["gimbal_limit_deg"])),
        les_mass_kg=_positive(f"{p}.les_mass_kg", us_node["les_mass_kg"], True),
        engine=_engine(us_node["engine"], f"{p}.engine"),
    )
    rn = node["rcs"]
    rt = read_table(vdir / rn["thrust_table"], ("altitude", "thrust_vac"))
    _increasing(f"{rn['thrust_table']}:altitude_m", rt["altitude"])
    if np.any(rt["thrust_vac"] < 0):
        raise ConfigError(f"{rn['thrust_table']}:thrust_vac", float(rt["thrust_vac"].min()), "thrust must be non-negative")
    p = "vehicle.rcs"
    rcs = Rcs(altitude_m=rt["altitude"], thrust_vac_N=rt["thrust_vac"],
              exit_area_m2=_positive(f"{p}.exit_area_m2", rn["exit_area_m2"], True),
              jets_per_direction=int(_positive(f"{p}.jets_per_direction", rn["jets_per_direction"])),
              moment_arm_m=_positive(f"{p}.moment_arm_m", rn["moment_arm_m"]),
              ramp_up_s=_positive(f"{p}.ramp_up_s", rn["ramp_up_s"]),
              ramp_down_s=_positive(f"{p}.ramp_down_s", rn["ramp_down_s"]),
              location_m=np.asarray(rn["location_m"], float))
    sn = node["sensors"]
    sensors = Sensors(**{k: np.asarray(sn[k], float) for k in SCHEMA["sensors"]})
    en = node["events"]
    frac = en["separation_thrust_fraction"]
    if not 0.0 < frac < 1.0:
        raise ConfigError("vehicle.events.separation_thrust_fraction", frac, "must be between 0 and 1")
    events = Events(separation_thrust_fraction=float(frac),
                    ignition_delay_s=_positive("vehicle.events.ignition_delay_s", en["ignition_delay_s"], True),
                    les_jettison_delay_s=_positive("vehicle.events.les_jettison_delay_s", en["les_jettison_delay_s"], True))
    vehicle = Vehicle(name=str(node["name"]), description=str(node.get("description") or ""),
                      length_m=_positive("vehicle.length_m", node["length_m"]), configurations=configs,
                      first_stage=fs, upper_stage=us, rcs=rcs, sensors=sensors, events=events)
    _check_consistency(vehicle)
    return vehicle


def _check_consistency(v: Vehicle) -> None:
    """Mass tables agree with the staging masses (within 0.5 % of the smaller mass)."""
    stack, les, up = (v.configurations[n].mass for n in CONFIG_NAMES)
    full_prop = stack.propellant_kg[-1]
    if abs(full_prop - v.first_stage.propellant_kg) > 1e-3 * v.first_stage.propellant_kg:
        raise ConfigError("vehicle.first_stage.propellant_kg", v.first_stage.propellant_kg,
                          f"must equal the stack mass table's largest propellant_remaining ({full_prop:.1f} kg)")
    us_prop = v.upper_stage.lox_kg + v.upper_stage.lh2_kg
    if abs(les.propellant_kg[-1] - us_prop) > 1e-3 * us_prop:
        raise ConfigError("vehicle.upper_stage.lox_kg", v.upper_stage.lox_kg,
                          f"LOX + LH2 must equal the upper-stage mass table's largest propellant_remaining ({les.propellant_kg[-1]:.1f} kg)")
    after_sep = stack.mass_kg[0] - v.first_stage.jettison_mass_kg
    if abs(after_sep - les.mass_kg[-1]) > 5e-3 * les.mass_kg[-1]:
        raise ConfigError("vehicle.first_stage.jettison_mass_kg", v.first_stage.jettison_mass_kg,
                          f"stack burnout mass {stack.mass_kg[0]:.0f} kg minus the jettison mass must equal the upper "
                          f"stage's full mass {les.mass_kg[-1]:.0f} kg")
    les_diff = np.interp(up.propellant_kg, les.propellant_kg, les.mass_kg) - up.mass_kg
    if np.max(np.abs(les_diff - v.upper_stage.les_mass_kg)) > 5e-3 * v.upper_stage.les_mass_kg + 1.0:
        raise ConfigError("vehicle.upper_stage.les_mass_kg", v.upper_stage.les_mass_kg,
                          "must equal the difference between the upper_les and upper mass tables")
