"""Mass properties of a configuration composed from its parts (the parallel-axis theorem).

Each part brings its mass ``m_i``, CG ``c_i`` (structure frame, m) and inertia about its
own CG ``I_i`` (body axes; moments Ixx, Iyy, Izz and products Ixy, Ixz, Iyz, the tensor's
off-diagonal elements being the products' negatives, as in every mass table). The
whole::

    M = Σ m_i,    C = Σ m_i c_i / M,
    I = Σ [ I_i + m_i (|d_i|² E − d_i d_iᵀ) ],    d_i = S (c_i − C),  S = diag(−1, 1, −1)

(``S`` turns a structure-frame offset into body axes), so a moment gains
``m (d_b² + d_c²)`` and a product ``m d_a d_b``. A configuration's table is composed at
the rows of the part that burns in it (against that part's own propellant), the other
stages and boosters at their full load and the items as they are
(``tests/test_mass_composition.py`` checks it against hand-computed stacks and against
the generator's own whole-configuration sums for ares_i).
"""

from __future__ import annotations

import numpy as np

from savant_cli.vehicle.tables import MassTable

#: structure → body axes
STRUCTURE_TO_BODY = np.array([-1.0, 1.0, -1.0])


def combine(masses: np.ndarray, cgs: np.ndarray, inertias: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The whole of rigid bodies: mass (kg), CG (structure frame, m, (3,)) and inertia about
    that CG (body axes, ``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` kg m², (6,)).

    Parameters
    ----------
    masses : numpy.ndarray
        ``(n,)`` kg.
    cgs : numpy.ndarray
        ``(n, 3)`` each body's CG, structure frame, m.
    inertias : numpy.ndarray
        ``(n, 6)`` each about its own CG, body axes, kg m².
    """
    masses = np.asarray(masses, float)
    total = float(masses.sum())
    cg = masses @ np.asarray(cgs, float) / total
    d = (np.asarray(cgs, float) - cg) * STRUCTURE_TO_BODY  # offsets from the whole's CG, body axes
    dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
    shift = np.column_stack([dy * dy + dz * dz, dx * dx + dz * dz, dx * dx + dy * dy, dx * dy, dx * dz, dy * dz])
    inertia = np.asarray(inertias, float).sum(axis=0) + masses @ shift
    return total, cg, inertia


def full_row(table: MassTable) -> tuple[float, np.ndarray, np.ndarray]:
    """A part's mass properties at its full load (the table's last row)."""
    return float(table.mass_kg[-1]), table.cg_m[-1], table.inertia_kgm2[-1]


def composed_table(burning: MassTable, fixed: list[tuple[float, np.ndarray, np.ndarray]]) -> MassTable:
    """The configuration's table at the rows of its burning part, against that part's
    propellant: each row combined with the ``fixed`` parts ``(mass kg, CG m, inertia)``."""
    n = burning.propellant_kg.size
    mass, cg, inertia = np.empty(n), np.empty((n, 3)), np.empty((n, 6))
    for j in range(n):
        ms = np.array([burning.mass_kg[j], *(f[0] for f in fixed)])
        cgs = np.array([burning.cg_m[j], *(f[1] for f in fixed)])
        ins = np.array([burning.inertia_kgm2[j], *(f[2] for f in fixed)])
        mass[j], cg[j], inertia[j] = combine(ms, cgs, ins)
    return MassTable(propellant_kg=burning.propellant_kg.copy(), mass_kg=mass, cg_m=np.ascontiguousarray(cg),
                     inertia_kgm2=np.ascontiguousarray(inertia))
