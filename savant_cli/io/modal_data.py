"""Import of flexible-body modal data sets (frequencies and mode shapes at nodes).

A set is three CSV files in the vehicle's flex folder (``#`` comment lines, then a header):

* ``<set>_modes.csv`` — ``mode, frequency_hz, generalized_mass``;
* ``<set>_shapes.csv`` — ``mode, node, station_<len>, dx_<len>, dy_<len>, dz_<len>,
  rx_<ang>, ry_<ang>, rz_<ang>``: displacement and rotation per unit modal coordinate at
  each node, structure frame (x aft of the nose tip, y = body y, z = −body z). The
  suffixes are units of :data:`savant_cli.io.units.UNITS`: a displacement column in
  another length unit than the declared one is taken to the declared unit first, a
  rotation in ``deg`` to rad;
* ``<set>_nodes.csv`` (optional) — ``node, station_<len>, mass_<mass>,
  rotary_inertia_<inertia>``: the lumped masses and rotary inertias, each column in the
  unit its suffix names (``kg``, ``slug``, ``lbf_s2_per_in``, …; ``kgm2``, ``lbf_in_s2``,
  …), kept in SI for checks of the generalized mass.

Unit conversion follows the source paper (§III.K). With unit generalized mass in a
consistent (length, force, second) system, a change of units keeps the generalized mass
at 1 only if the modal coordinate changes with the square root of the energy unit: for
length factor ``c_L`` and force factor ``c_F`` to SI, displacements scale by
``c_L / √(c_F c_L)`` and rotations by ``1 / √(c_F c_L)``. For inches to feet with pounds
force (``c_F = 1``, ``c_L = 1/12``) that is the paper's ÷√12 and ×√12. Structure to body
is ``diag(−1, 1, −1)`` for displacements and rotations alike (a proper rotation).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from savant_cli import constants
from savant_cli.errors import ConfigError
from savant_cli.io.data_csv import read_numeric_csv
from savant_cli.io.table_order import require_increasing, row_text, table_key
from savant_cli.io.units import UNITS, units_of

LENGTH_TO_M = {"in": constants.IN, "ft": constants.FT, "m": 1.0}
FORCE_TO_N = {"lbf": constants.LBF, "N": 1.0}
STRUCTURE_TO_BODY = np.array([-1.0, 1.0, -1.0])


@dataclass(frozen=True)
class ModalSet:
    """One modal data set in SI, body frame, unit generalized mass (kg).

    Attributes
    ----------
    name : str
    frequency_rad_s : ndarray (n_modes,)
    nodes : ndarray (n_nodes,) int
    station_m : ndarray (n_nodes,)
        Structure-frame x of each node.
    shapes : ndarray (n_modes, n_nodes, 6)
        Displacement (m per √kg·m) and rotation (rad per √kg·m) per unit modal
        coordinate, body axes.
    node_mass_kg, node_inertia_kgm2 : ndarray (n_nodes,) or None
        Lumped masses when the set provides them.
    """

    name: str
    frequency_rad_s: np.ndarray
    nodes: np.ndarray
    station_m: np.ndarray
    shapes: np.ndarray
    node_mass_kg: np.ndarray | None = None
    node_inertia_kgm2: np.ndarray | None = None

    def at_nodes(self, node_ids: list[int], key: str) -> np.ndarray:
        """Mean shape over ``node_ids`` (an attach point may average nodes): (n_modes, 6)."""
        idx = []
        for nid in node_ids:
            hit = np.nonzero(self.nodes == int(nid))[0]
            if hit.size == 0:
                raise ConfigError(key, int(nid), f"node is not in modal set {self.name!r} "
                                  f"(its nodes run {int(self.nodes.min())}..{int(self.nodes.max())})")
            idx.append(int(hit[0]))
        return self.shapes[:, idx, :].mean(axis=1)


def conversion_factors(length_unit: str, force_unit: str) -> tuple[float, float]:
    """Factors (displacement, rotation) taking unit-generalized-mass shapes to SI."""
    c_l, c_f = LENGTH_TO_M[length_unit], FORCE_TO_N[force_unit]
    energy = c_l * c_f
    return c_l / np.sqrt(energy), 1.0 / np.sqrt(energy)


def convert_shapes(shapes: np.ndarray, from_units: tuple[str, str], to_units: tuple[str, str]) -> np.ndarray:
    """Re-normalize ``(..., 6)`` shapes (3 displacements, 3 rotations) between unit systems
    ``(length, force)``, keeping unit generalized mass (the paper's ÷√12, ×√12 for in→ft)."""
    d0, r0 = conversion_factors(*from_units)
    d1, r1 = conversion_factors(*to_units)
    out = np.array(shapes, dtype=float, copy=True)
    out[..., :3] *= d0 / d1
    out[..., 3:] *= r0 / r1
    return out


def _ckey(path: Path, header: list[str], prefix: str) -> str:
    """``<folder>/<file>.csv:<column>`` of the column named ``prefix`` or ``prefix_<unit>``."""
    name = next((h for h in header if h == prefix or h.startswith(prefix + "_")), prefix)
    return f"{table_key(path)}:{name}"


def _column(header: list[str], data: np.ndarray, prefix: str, path: Path, key: str) -> tuple[np.ndarray, str]:
    """Column whose name is ``prefix`` or ``prefix_<unit>``; returns values and unit."""
    for i, h in enumerate(header):
        if h == prefix or h.startswith(prefix + "_"):
            return data[:, i], h[len(prefix) + 1:]
    raise ConfigError(f"{table_key(path)}:{prefix}", header, f"missing column (modal set of {key})")


def _unit_factor(ckey: str, unit: str, dimension: str) -> float:
    """The factor to SI of a column's unit suffix (:data:`savant_cli.io.units.UNITS`), or a
    ConfigError at ``<folder>/<file>.csv:<column>`` naming the units of ``dimension``."""
    if unit not in UNITS or UNITS[unit][0] != dimension:
        raise ConfigError(ckey, unit, f"needs a {dimension} unit suffix: one of {', '.join(units_of(dimension))}")
    return UNITS[unit][1]


def read_modal_set(folder: Path, name: str, units: tuple[str, str], key: str) -> ModalSet:
    """Read one set and convert it to SI, body frame.

    Parameters
    ----------
    folder : Path
        The vehicle's flex folder.
    name : str
        Set name (file prefix).
    units : (str, str)
        Declared length unit (``in``, ``ft``, ``m``) and force unit (``lbf``, ``N``).
    key : str
        Config key named in errors.
    """
    length_unit, force_unit = units
    if length_unit not in LENGTH_TO_M:
        raise ConfigError(f"{key}.units.length", length_unit, f"must be one of {', '.join(LENGTH_TO_M)}")
    if force_unit not in FORCE_TO_N:
        raise ConfigError(f"{key}.units.force", force_unit, f"must be one of {', '.join(FORCE_TO_N)}")
    mpath = folder / f"{name}_modes.csv"
    mh, md, mlines = read_numeric_csv(mpath)
    modes = _column(mh, md, "mode", mpath, key)[0]
    freq_hz = _column(mh, md, "frequency", mpath, key)[0]
    gmass = _column(mh, md, "generalized_mass", mpath, key)[0]
    if np.any(freq_hz <= 0.0):
        i = int(np.argmax(freq_hz <= 0.0))
        raise ConfigError(_ckey(mpath, mh, "frequency"), float(freq_hz[i]),
                          f"{row_text(i, mlines)}: modal frequencies must be positive")
    if np.any(gmass <= 0.0):
        i = int(np.argmax(gmass <= 0.0))
        raise ConfigError(_ckey(mpath, mh, "generalized_mass"), float(gmass[i]), f"{row_text(i, mlines)}: must be positive")
    require_increasing(_ckey(mpath, mh, "mode"), modes, mlines, what="the mode number")
    numbered = modes == np.arange(1, modes.size + 1)
    if not np.all(numbered):
        i = int(np.argmax(~numbered))
        raise ConfigError(_ckey(mpath, mh, "mode"), float(modes[i]),
                          f"{row_text(i, mlines)}: modes must be numbered 1, 2, … in order (row {i + 1} must be mode {i + 1})")
    modes = modes.astype(int)
    require_increasing(_ckey(mpath, mh, "frequency"), freq_hz, mlines, strict=False,
                       what="the modal frequency (modes listed lowest first; equal frequencies allowed)")

    spath = folder / f"{name}_shapes.csv"
    sh, sd, slines = read_numeric_csv(spath)
    smode = _column(sh, sd, "mode", spath, key)[0]
    snode = _column(sh, sd, "node", spath, key)[0]
    # rows grouped by mode, modes in order (the table's axis): refused otherwise, never sorted
    require_increasing(_ckey(spath, sh, "mode"), smode, slines, strict=False,
                       what="the mode number (rows grouped by mode, modes in order)")
    smode, snode = smode.astype(int), snode.astype(int)
    station, st_unit = _column(sh, sd, "station", spath, key)
    cols = []
    for comp in ("dx", "dy", "dz"):  # any length unit, taken to the declared one of the modal system
        vals, unit = _column(sh, sd, comp, spath, key)
        factor = _unit_factor(_ckey(spath, sh, comp), unit, "length")
        cols.append(vals if unit == length_unit else vals * (factor / LENGTH_TO_M[length_unit]))
    for comp in ("rx", "ry", "rz"):  # any angle unit, taken to rad
        vals, unit = _column(sh, sd, comp, spath, key)
        factor = _unit_factor(_ckey(spath, sh, comp), unit, "angle")
        cols.append(vals if unit == "rad" else vals * factor)
    outside = (smode < 1) | (smode > modes.size)
    if np.any(outside):
        i = int(np.argmax(outside))
        raise ConfigError(_ckey(spath, sh, "mode"), int(smode[i]),
                          f"{row_text(i, slines)}: mode numbers must be within 1..{modes.size} ({mpath.name})")
    nodes = snode[smode == 1]  # node ids are names, not an axis: mode 1's order, kept
    n_m, n_n = modes.size, nodes.size
    if n_n == 0:
        raise ConfigError(_ckey(spath, sh, "mode"), int(smode[0]), f"{row_text(0, slines)}: the rows must start with mode 1")
    _, first_seen = np.unique(nodes, return_index=True)
    if first_seen.size != n_n:
        i = int(np.setdiff1d(np.arange(n_n), first_seen)[0])
        raise ConfigError(_ckey(spath, sh, "node"), int(nodes[i]),
                          f"{row_text(i, slines)}: mode 1 lists this node twice; one row per (mode, node)")
    expected = np.tile(nodes, n_m)
    if snode.size != expected.size or not np.array_equal(snode, expected) or \
            not np.array_equal(smode, np.repeat(modes, n_n)):
        k = min(snode.size, expected.size)
        differs = (snode[:k] != expected[:k]) | (smode[:k] != np.repeat(modes, n_n)[:k])
        i = int(np.argmax(differs)) if differs.any() else k
        want = f"mode {i // n_n + 1}, node {expected[i]}" if i < expected.size else "no further row"
        raise ConfigError(_ckey(spath, sh, "node"), int(snode[i]) if i < snode.size else f"{snode.size} rows",
                          f"{row_text(i, slines)}: needs every (mode, node) pair exactly once, each mode listing "
                          f"mode 1's {n_n} nodes in mode 1's order ({n_m} x {n_n} = {n_m * n_n} rows); this row "
                          f"should be {want}")
    shapes = np.column_stack(cols).reshape(n_m, n_n, 6)  # row i is (mode i // n_n, node i % n_n)
    stations = station[:n_n] * _unit_factor(_ckey(spath, sh, "station"), st_unit, "length")  # mode 1's rows
    shapes /= np.sqrt(gmass)[:, None, None]  # to unit generalized mass
    shapes = convert_shapes(shapes, (length_unit, force_unit), ("m", "N"))
    shapes[..., :3] *= STRUCTURE_TO_BODY
    shapes[..., 3:] *= STRUCTURE_TO_BODY

    node_mass = node_inertia = None
    npath = folder / f"{name}_nodes.csv"
    if npath.is_file():
        nh, nd, nlines = read_numeric_csv(npath)
        nn = _column(nh, nd, "node", npath, key)[0]
        nn = nn.astype(int)
        _, once = np.unique(nn, return_index=True)
        if once.size != nn.size:
            i = int(np.setdiff1d(np.arange(nn.size), once)[0])
            raise ConfigError(_ckey(npath, nh, "node"), int(nn[i]), f"{row_text(i, nlines)}: node listed twice")
        m, m_unit = _column(nh, nd, "mass", npath, key)
        j, j_unit = _column(nh, nd, "rotary_inertia", npath, key)
        to_kg = _unit_factor(_ckey(npath, nh, "mass"), m_unit, "mass")
        to_kgm2 = _unit_factor(_ckey(npath, nh, "rotary_inertia"), j_unit, "inertia")
        node_mass = np.zeros(n_n)
        node_inertia = np.zeros(n_n)
        unknown = ~np.isin(nn, nodes)
        if np.any(unknown):
            i = int(np.argmax(unknown))
            raise ConfigError(_ckey(npath, nh, "node"), int(nn[i]),
                              f"{row_text(i, nlines)}: node is not in the shapes file ({spath.name})")
        idx = np.array([int(np.nonzero(nodes == n)[0][0]) for n in nn], dtype=int)
        node_mass[idx] = m * to_kg
        node_inertia[idx] = j * to_kgm2
    return ModalSet(name=name, frequency_rad_s=2.0 * np.pi * freq_hz, nodes=nodes, station_m=stations,
                    shapes=shapes, node_mass_kg=node_mass, node_inertia_kgm2=node_inertia)
