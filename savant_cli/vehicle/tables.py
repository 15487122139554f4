"""Vehicle data tables: the one reader of every vehicle CSV table (units to SI, axes checked
in the order written, never sorted) and the aerodynamic and mass-properties tables of a
configuration.

Table format
------------
CSV, ``#`` comment lines allowed, one header row of column names, then numbers. A
column name's suffix after the last ``_`` is its unit when it is one of ``UNITS``
(:mod:`savant_cli.io.units`, shared with the modal data files)
(``thrust_vac_N``, ``alpha_deg``, ``cg_x_in``); the loader converts to SI and checks the
unit's dimension against the column's. Names without a unit suffix are dimensionless
(``mach``, ``CA``, ``thrust_fraction``).

Frames and conventions (``docs/vehicles.md``)
---------------------------------------------
* Locations (CG, moment reference point) are in the structure frame: x aft of the nose
  tip (a station), y = body y, z = -body z, metres.
* Inertias are about the CG in body axes; the columns ``ixy, ixz, iyz`` are products of
  inertia (``Ixy = integral of x y dm``), so the tensor's off-diagonal elements are their
  negatives.
* Aerodynamic coefficients are body-axis: force ``q S [-CA, CY, -CN]``, moment about the
  moment reference point ``q S [l_x Cl, l_y Cm, l_z Cn]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from savant_cli.config.checks import no_negative_entries, positive
from savant_cli.errors import ConfigError
from savant_cli.io.data_csv import read_numeric_csv
from savant_cli.io.table_order import require_grid_order, require_increasing, table_key
from savant_cli.io.units import UNITS, split_unit, units_of

#: The coefficient columns of an aero table (body axes, dimensionless), in the order of
#: the packed table's coefficient axis (models/aero.py).
AERO_COEFFICIENTS = ("CA", "CY", "CN", "Cl", "Cm", "Cn")

_INERTIA = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")

MASS_TOLERANCE_KG = 1.0   # consistency of the mass tables with the loads and the jettisoned masses

#: table kind -> required columns (base name, dimension); ``None`` = dimensionless
TABLE_COLUMNS: dict[str, tuple[tuple[str, str | None], ...]] = {
    "mass": (("propellant_remaining", "mass"), ("mass", "mass"), ("cg_x", "length"), ("cg_y", "length"),
             ("cg_z", "length")) + tuple((c, "inertia") for c in _INERTIA),
    "aero": (("mach", None), ("alpha", "angle"), ("beta", "angle")) + tuple((c, None) for c in AERO_COEFFICIENTS),
    "base_force": (("time", "time"), ("base_force", "force")),
    "first_stage_thrust": (("time", "time"), ("thrust_vac", "force")),
    "startup": (("time", "time"), ("thrust_fraction", None)),
    "throttle": (("time", "time"), ("throttle", None)),
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
    "first_stage_thrust": ("time",), "startup": ("time",), "throttle": ("time",), "rcs_thrust": ("altitude",),
    "slosh": ("level",),
}


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


def is_number(v: Any) -> bool:
    """A finite int or float (not a bool)."""
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and bool(np.isfinite(v))


def vec3(value: Any) -> np.ndarray:
    """A location or vector as a contiguous float64 array."""
    return np.ascontiguousarray(np.asarray(value, dtype=np.float64))


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
    key = table_key(path)
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


def read_aero(cfg: Mapping, vdir: Path, key_prefix: str) -> AeroTable:
    """The aerodynamic and base-force tables of one configuration node (``aero_table``,
    ``base_force_table``, reference area, lengths and moment reference point);
    ``key_prefix`` names the node in refusals (``vehicle.configurations.<name>``)."""
    path = vdir / cfg["aero_table"]
    key = table_key(path)
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
    p = key_prefix
    return AeroTable(
        mach=axes[0], alpha_rad=axes[1], beta_rad=axes[2],
        coeffs=np.ascontiguousarray(coeffs.reshape((6,) + shape)),
        base_time_s=b["time"], base_force_N=b["base_force"],
        area_m2=positive(f"{p}.reference_area_m2", cfg["reference_area_m2"]),
        lref_m=vec3([positive(f"{p}.reference_length_m", v) for v in cfg["reference_length_m"]]),
        mrp_m=vec3(cfg["moment_reference_m"]),
    )


def inertia_tensors(inertia: np.ndarray) -> np.ndarray:
    """``(n, 6)`` rows ``Ixx, Iyy, Izz, Ixy, Ixz, Iyz`` (moments and products of inertia,
    kg m²) → ``(n, 3, 3)`` tensors (off-diagonal elements the products' negatives)."""
    tensor = np.empty((inertia.shape[0], 3, 3))
    tensor[:, 0, 0], tensor[:, 1, 1], tensor[:, 2, 2] = inertia[:, 0], inertia[:, 1], inertia[:, 2]
    tensor[:, 0, 1] = tensor[:, 1, 0] = -inertia[:, 3]
    tensor[:, 0, 2] = tensor[:, 2, 0] = -inertia[:, 4]
    tensor[:, 1, 2] = tensor[:, 2, 1] = -inertia[:, 5]
    return tensor


def check_inertia(key: str, inertia: np.ndarray) -> None:
    """Refuse a row of ``(n, 6)`` inertia rows whose tensor is not positive definite or
    whose principal moments break the triangle inequality (I1 + I2 >= I3)."""
    ev = np.linalg.eigvalsh(inertia_tensors(inertia))  # ascending principal moments, per row
    scale = ev[:, 2]
    bad = np.nonzero((ev[:, 0] <= 1e-12 * scale) | (ev[:, 0] + ev[:, 1] < ev[:, 2] * (1.0 - 1e-9)))[0]
    if bad.size:
        i = int(bad[0])
        raise ConfigError(key, inertia[i].tolist(),
                          f"row {i + 1}: the inertia tensor must be positive definite and its principal moments "
                          f"must satisfy the triangle inequality (I1 + I2 >= I3); principal moments {ev[i].tolist()}")


def read_mass(cfg: Mapping, vdir: Path, length_m: float) -> MassTable:
    """The mass-properties table ``cfg["mass_table"]``, checked: positive mass and
    moments, mass at least the propellant, CG on the vehicle (``[0, length_m]``), a
    positive-definite inertia tensor obeying the triangle inequality."""
    path = vdir / cfg["mass_table"]
    key = table_key(path)
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
    check_inertia(f"{key}:{tn['ixx']}", inertia)
    return MassTable(propellant_kg=prop, mass_kg=t["mass"], cg_m=np.ascontiguousarray(cg),
                     inertia_kgm2=np.ascontiguousarray(inertia))
