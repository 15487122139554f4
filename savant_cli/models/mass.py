"""Mass properties: mass, CG and inertia of each configuration against propellant remaining.

Each configuration (stack, upper stage with LES, upper stage) has a table of the
vehicle's mass (kg), CG (structure frame, m) and inertia about the CG (body axes,
kg·m²: moments Ixx, Iyy, Izz and products Ixy, Ixz, Iyz, tensor off-diagonals being the
negative products) against the propellant remaining of the burning stage (kg,
ascending). Rows are interpolated linearly and held beyond the table. Source: SAVANT
§III, "Mass properties"; the default tables are generated (``datagen/ares_i_tables.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import locate_at, tab, tab_offset

COLUMNS = blocks.Record(
    "mass-properties row",
    ("mass", "kg", "vehicle mass"),
    ("cg_x", "m", "CG, structure x"),
    ("cg_y", "m", "CG, structure y"),
    ("cg_z", "m", "CG, structure z"),
    ("ixx", "kg*m^2", "moment of inertia about body X through the CG"),
    ("iyy", "kg*m^2", "moment of inertia about body Y"),
    ("izz", "kg*m^2", "moment of inertia about body Z"),
    ("ixy", "kg*m^2", "product of inertia Ixy (tensor element −Ixy)"),
    ("ixz", "kg*m^2", "product of inertia Ixz"),
    ("iyz", "kg*m^2", "product of inertia Iyz"),
)
M_MASS, M_CG_X, M_CG_Y, M_CG_Z, M_IXX, M_IYY, M_IZZ, M_IXY, M_IXZ, M_IYZ = COLUMNS.offsets
N_COLUMNS = COLUMNS.size

_TABLES = blocks.TABLES.block("mass")
T_PROP = _TABLES.table("mass_prop", "kg", "(configurations, n) propellant remaining, ascending (padded)")
T_DATA = _TABLES.table("mass_data", "kg, m, kg*m^2", "(configurations, n, COLUMNS) mass-properties rows")
T_LEN = _TABLES.table("mass_len", "1", "(configurations,) valid rows per configuration")
_AUX = blocks.DIAGNOSTICS.block("mass")
A_MASS = _AUX.scalar("mass", "kg", "vehicle mass", blocks.Logged("mass"))  # slosh masses included
A_CG = _AUX.array("cg", 3, "m", "CG location",  # slosh masses included
                  blocks.Logged("cg_structure", ("x", "y", "z"), "structure"))
A_PROP = _AUX.scalar("propellant", "kg", "propellant remaining of the burning configuration")


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, mass: float, propellant: float, cgx: float, cgy: float, cgz: float) -> None:
    """Write the whole vehicle's mass (kg), the burning configuration's propellant (kg) and
    the whole vehicle's CG (m, structure frame) into ``aux``."""
    aux[A_MASS] = mass
    aux[A_PROP] = propellant
    aux[A_CG] = cgx
    aux[A_CG + 1] = cgy
    aux[A_CG + 2] = cgz


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The vehicle's mass-properties tables, one per configuration in the order the
    sequence reaches them, stacked."""
    prop, data, n = stacked_tables([c.mass for c in inputs.vehicle.configurations.values()])
    tables.update(mass_prop=prop, mass_data=data, mass_len=n)


def stacked_tables(masses: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass tables (:class:`~savant_cli.vehicle.tables.MassTable`) stacked as
    :func:`stacked_row` reads them: propellant axes ``(k, n)`` (kg), rows ``(k, n,
    COLUMNS)`` and valid lengths ``(k,)`` (padded by repeating each last row)."""
    prop, n = blocks.stack_padded([m.propellant_kg for m in masses])
    data, _ = blocks.stack_padded([np.column_stack([m.mass_kg, m.cg_m, m.inertia_kgm2]) for m in masses])
    return prop, data, n


@njit(cache=True, error_model="numpy", inline="always")
def mass_properties(tb: np.ndarray, config: int, prop_kg: float):
    """Mass properties of ``config`` holding ``prop_kg`` of propellant.

    Returns
    -------
    tuple of float
        ``(m kg, cg_x, cg_y, cg_z m (structure), Ixx, Iyy, Izz, Ixy, Ixz, Iyz kg·m²)``,
        the last three as inertia-tensor elements (the negative products of inertia).
    """
    return stacked_row(tb, T_PROP, T_DATA, T_LEN, config, prop_kg)


@njit(cache=True, error_model="numpy", inline="always")
def stacked_row(tb: np.ndarray, t_prop: int, t_data: int, t_len: int, k: int, prop_kg: float):
    """The row of table ``k`` of a stack of mass-properties tables (propellant axis field
    ``t_prop``, rows ``t_data``, valid lengths ``t_len``, as :func:`build` packs them)
    at ``prop_kg``: linear between rows, held beyond the table; returned as
    :func:`mass_properties` returns it."""
    o_mp, n_mp = tab(tb, t_prop)
    nm = n_mp // tab(tb, t_len)[1]  # padded rows per table
    i0, w = locate_at(tb, o_mp + k * nm, int(tb[tab_offset(tb, t_len) + k]), prop_kg)
    r0 = tab_offset(tb, t_data) + (k * nm + i0) * N_COLUMNS
    r1 = r0 + N_COLUMNS
    a = 1.0 - w
    return (a * tb[r0 + M_MASS] + w * tb[r1 + M_MASS],
            a * tb[r0 + M_CG_X] + w * tb[r1 + M_CG_X],
            a * tb[r0 + M_CG_Y] + w * tb[r1 + M_CG_Y],
            a * tb[r0 + M_CG_Z] + w * tb[r1 + M_CG_Z],
            a * tb[r0 + M_IXX] + w * tb[r1 + M_IXX],
            a * tb[r0 + M_IYY] + w * tb[r1 + M_IYY],
            a * tb[r0 + M_IZZ] + w * tb[r1 + M_IZZ],
            -(a * tb[r0 + M_IXY] + w * tb[r1 + M_IXY]),
            -(a * tb[r0 + M_IXZ] + w * tb[r1 + M_IXZ]),
            -(a * tb[r0 + M_IYZ] + w * tb[r1 + M_IYZ]))


@njit(cache=True, error_model="numpy")
def inertia_tensor(tb: np.ndarray, config: int, prop_kg: float):
    """:func:`mass_properties` as arrays, for Python callers: mass (kg), CG (structure,
    m, shape (3,)) and the inertia tensor about the CG (body, kg·m², shape (3, 3))."""
    m, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz = mass_properties(tb, config, prop_kg)
    cg = np.empty(3)
    cg[0], cg[1], cg[2] = cx, cy, cz
    inertia = np.empty((3, 3))
    inertia[0, 0], inertia[1, 1], inertia[2, 2] = ixx, iyy, izz
    inertia[0, 1] = inertia[1, 0] = ixy
    inertia[0, 2] = inertia[2, 0] = ixz
    inertia[1, 2] = inertia[2, 1] = iyz
    return m, cg, inertia


@njit(cache=True, error_model="numpy", inline="always")
def minus_point_mass(ixx: float, iyy: float, izz: float, ixy: float, ixz: float, iyz: float,
                     m: float, dx: float, dy: float, dz: float):
    """Inertia tensor elements minus those of a point mass ``m`` (kg) at body offset ``d``
    (m): ``I − m (|d|² E − d dᵀ)`` (off-diagonal elements are tensor elements)."""
    return (ixx - m * (dy * dy + dz * dz), iyy - m * (dx * dx + dz * dz), izz - m * (dx * dx + dy * dy),
            ixy + m * dx * dy, ixz + m * dx * dz, iyz + m * dy * dz)
