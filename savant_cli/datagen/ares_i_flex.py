"""Reproducible generator of the default vehicle's flexible-body modal data
(``conf/vehicle/ares_i/flex/``).

Run ``python -m savant_cli.datagen.ares_i_flex [--out DIR]``. No public Ares I modal data
exist, so the modes come from a free-free Euler–Bernoulli beam of the vehicle centerline
(``conf/vehicle/ares_i/flex/README.md`` lists every assumption with its mark [E]/[D]):

* **mass** [D]: the segments of :mod:`savant_cli.datagen.ares_i_tables`
  (:func:`~savant_cli.datagen.ares_i_tables.configuration_segments`), each spread uniformly
  over its span and lumped at the beam nodes by exact overlap with each node's tributary
  length (half an element on each side); a node's rotary (pitch) inertia is the sum over
  its slices of ``m (r_out² + r_in²)/4 + m Δx²/12``;
* **stiffness** [E]: one thin-shell ``EI = E π R³ t`` per structural region
  (:func:`stiffness_regions`), all scaled by ONE factor so that the first bending frequency
  of ``first_stage_liftoff`` is :data:`TARGET_F1_HZ`; the same scaled distribution serves
  the four sets; propellant adds mass only;
* **solver**: Hermite-cubic beam elements (lateral displacement and slope per node), the
  lumped diagonal mass matrix, ``scipy.linalg.eigh`` of the free-free (inertia-relief)
  flexibility, which excludes the two rigid-body modes.

Files per set: ``<set>_modes.csv``, ``_shapes.csv``, ``_nodes.csv`` in inch, lbf, s,
structure frame (x aft of the nose tip, y = body y, z = −body z). Each bending mode is
written in the x–z plane (dz, ry = −d(dz)/dx), then in the x–y plane (dy, rz = +d(dy)/dx),
forward node's displacement positive, unit generalized mass in lbf·in·s².
"""

from __future__ import annotations

import argparse
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.linalg import cho_factor, cho_solve, eigh

from savant_cli.constants import IN, LBF
from savant_cli.datagen.ares_i_tables import (
    J2X_LENGTH_M, LAYOUT, LENGTH_M, M_FS_PROP, M_LH2, M_LOX, Layout, Segment, configuration_segments, derived_figures,
    stations
)

MASS_UNIT_KG = LBF / IN            # 1 lbf s^2/in = 175.126835 kg
INERTIA_UNIT_KGM2 = LBF * IN       # 1 lbf in s^2 = 0.112984829 kg m^2

# modal data sets: (configuration, propellant of its burning stage remaining, kg)
SETS = {
    "first_stage_liftoff": ("stack", M_FS_PROP),
    "first_stage_burnout": ("stack", 0.0),
    "second_stage_ignition": ("upper_les", M_LOX + M_LH2),
    "second_stage_burnout": ("upper", 0.0),
}
BENDING_MODES = 6                  # per plane; 12 modes per set
TARGET_F1_HZ = 1.0                 # [E] "~1 Hz at liftoff" (public estimate)
NODE_SPACING_M = 1.0               # largest element length
FIRST_GENERIC_NODE = 1001
HEADERS = {
    "modes": ["mode", "frequency_hz", "generalized_mass"],
    "shapes": ["mode", "node", "station_in", "dx_in", "dy_in", "dz_in", "rx_rad", "ry_rad", "rz_rad"],
    "nodes": ["node", "station_in", "mass_lbf_s2_per_in", "rotary_inertia_lbf_in_s2"],
}
COMMAND = "python -m savant_cli.datagen.ares_i_flex"


@dataclass(frozen=True)
class StiffnessRegion:
    """A thin-shell bending stiffness ``EI = E π R³ t`` (N m², before scaling) over
    ``[x_fwd, x_aft]`` (m, structure x)."""

    name: str
    x_fwd_m: float
    x_aft_m: float
    e_pa: float
    r_m: float
    t_m: float
    configs: tuple[str, ...] = ("stack", "upper_les", "upper")   # where the region exists

    @property
    def ei_nm2(self) -> float:
        return self.e_pa * math.pi * self.r_m**3 * self.t_m


def stiffness_regions(lay: Layout = LAYOUT) -> list[StiffnessRegion]:
    """Structural regions from the nose aft, all [E]; they do not overlap within a
    configuration. The J-2X, inside the interstage on the stack, is a beam stub aft of the
    upper stage's aft skirt once the first stage is gone."""
    s = stations(lay)
    stack, upper = ("stack",), ("upper_les", "upper")
    return [
        StiffnessRegion("les_tower_motor", 0.0, s["cm_fwd"], 70e9, 0.8, 0.010, ("stack", "upper_les")),
        StiffnessRegion("crew_module", s["cm_fwd"], s["sm_fwd"], 70e9, 2.0, 0.006),
        StiffnessRegion("service_module", s["sm_fwd"], s["sa_fwd"], 70e9, 2.5, 0.006),
        StiffnessRegion("spacecraft_adapter", s["sa_fwd"], s["us_fwd"], 70e9, 2.75, 0.006),
        StiffnessRegion("upper_stage_skirts_tanks", s["us_fwd"], s["us_aft"], 76e9, 2.75, 0.008),
        StiffnessRegion("interstage", s["us_aft"], s["fs_fwd"], 70e9, 2.3375, 0.008, stack),
        StiffnessRegion("first_stage_case", s["fs_fwd"], LENGTH_M, 200e9, 1.855, 0.0127, stack),
        StiffnessRegion("j2x_stub", s["us_aft"], s["j2x_gimbal"] + J2X_LENGTH_M, 200e9, 1.0, 0.005, upper),
    ]


def named_nodes(lay: Layout = LAYOUT) -> dict[int, float]:
    """Named node ids and their stations (m). At a shared station the first id listed
    carries the beam node; later ids are alias rows (same shape, zero mass)."""
    s, d = stations(lay), derived_figures(lay)
    return {
        4021: d["sensors.imu_x_m"],                  # navigation unit + upper-stage rate gyro
        6030: d["sensors.rate_gyro_first_stage_x_m"],
        718: d["first_stage.gimbal_x_m"],
        6023: d["rcs.location_x_m"],                 # upper-stage roll RCS
        6226: d["upper_stage.gimbal_x_m"],           # J-2X gimbal
        6003: s["lh2_fwd"], 6004: s["lox_fwd"],      # LH2 tank ends (common bulkhead aft)
        6021: s["lox_fwd"], 6022: s["lox_aft"],      # LOX tank ends
    }


def _extent(segs: list[Segment]) -> tuple[float, float]:
    return min(g.x_fwd_m for g in segs), max(g.x_aft_m for g in segs)


def _key(x: float) -> float:
    return round(float(x), 9)        # merges stations equal up to summation round-off


def global_mesh(lay: Layout = LAYOUT) -> tuple[np.ndarray, np.ndarray]:
    """Beam nodes of all sets: stations (m) and ids of the primary node at each.

    Breakpoints are every stiffness-region end, every named station and every set's
    extent; each interval is split into equal elements no longer than
    :data:`NODE_SPACING_M`. Generic ids run 1001, 1002, … from the nose aft over the whole
    stack, so an id means the same station in every set.
    """
    named = named_nodes(lay)
    pts = {_key(v) for r in stiffness_regions(lay) for v in (r.x_fwd_m, r.x_aft_m)}
    pts |= {_key(v) for v in named.values()}
    for config, prop in SETS.values():
        pts |= {_key(v) for v in _extent(configuration_segments(config, prop, lay))}
    brk = np.array(sorted(pts))
    x = [brk[0]]
    for a, b in itertools.pairwise(brk):
        n = math.ceil((b - a) / NODE_SPACING_M - 1e-9)
        x.extend(a + (b - a) * np.arange(1, n + 1) / n)
    x = np.array(x)
    ids = np.zeros(len(x), dtype=int)
    primary = {}
    for nid, xs in named.items():
        primary.setdefault(_key(xs), nid)
    nxt = FIRST_GENERIC_NODE
    for i, xi in enumerate(x):
        if _key(xi) in primary:
            ids[i] = primary[_key(xi)]
        else:
            ids[i], nxt = nxt, nxt + 1
    return x, ids


def lumped_mass(x_m: np.ndarray, segs: list[Segment]) -> tuple[np.ndarray, np.ndarray]:
    """Node masses (kg) and pitch rotary inertias (kg m²) of uniform segments.

    Each node owns the tributary span between the midpoints to its neighbours (the
    extent's ends for the end nodes); a segment's slice of length Δx and mass m in that
    span adds m to the node's mass and ``m ((r_out² + r_in²)/4 + Δx²/12)`` to its inertia.
    """
    edges = np.concatenate([[x_m[0]], 0.5 * (x_m[1:] + x_m[:-1]), [x_m[-1]]])
    mass, inertia = np.zeros(len(x_m)), np.zeros(len(x_m))
    for g in segs:
        dl = np.clip(np.minimum(edges[1:], g.x_aft_m) - np.maximum(edges[:-1], g.x_fwd_m), 0.0, None)
        ms = g.mass_kg * dl / (g.x_aft_m - g.x_fwd_m)
        mass += ms
        inertia += ms * ((g.r_out_m**2 + g.r_in_m**2) / 4.0 + dl**2 / 12.0)
    return mass, inertia


def element_ei(x_m: np.ndarray, config: str, scale: float = 1.0, lay: Layout = LAYOUT) -> np.ndarray:
    """Bending stiffness (N m²) of each element ``[x_m[i], x_m[i+1]]`` of ``config``
    (stack, upper_les, upper), times ``scale``."""
    mid = 0.5 * (x_m[1:] + x_m[:-1])
    hits = np.zeros(len(mid), dtype=int)
    ei = np.zeros(len(mid))
    for r in stiffness_regions(lay):
        inside = (mid > r.x_fwd_m) & (mid < r.x_aft_m) & (config in r.configs)
        ei[inside], hits = r.ei_nm2, hits + inside
    if np.any(hits != 1):
        raise ValueError(f"{config}: every element needs exactly one stiffness region")
    return scale * ei


def free_free_bending_modes(x_m: np.ndarray, ei_nm2: np.ndarray, node_mass_kg: np.ndarray,
                            node_rotary_inertia_kgm2: np.ndarray, n_modes: int
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bending modes of a free-free Euler–Bernoulli beam in one plane.

    Hermite-cubic elements (lateral displacement ``w`` and slope ``dw/dx`` per node) with
    a lumped diagonal mass matrix ``M``; stiffness ``K``. The elastic modes (``K φ = ω² M φ``,
    ``Rᵀ M φ = 0`` for the rigid-body modes ``R``) are found from the inertia-relief
    flexibility ``G = P K_c⁻¹ Pᵀ`` (``K_c``: ``K`` with the first node's two DOFs held,
    ``P = I − R (Rᵀ M R)⁻¹ Rᵀ M``), whose symmetric form ``M½ G M½`` has the eigenvalues
    ``1/ω²`` (``scipy.linalg.eigh``) and zero for the rigid-body modes: the low modes
    come to ~1e-10 relative, where ``eigh(K, M)`` errs by ε·ω²_max (~1e-7 here).

    Parameters
    ----------
    x_m : numpy.ndarray, shape (n,)
        Node stations along the beam axis, strictly increasing, m.
    ei_nm2 : numpy.ndarray, shape (n-1,)
        Bending stiffness of each element ``[x_m[i], x_m[i+1]]``, N m².
    node_mass_kg : numpy.ndarray, shape (n,)
        Lumped mass on each node's lateral displacement, kg (> 0).
    node_rotary_inertia_kgm2 : numpy.ndarray, shape (n,)
        Lumped rotary inertia on each node's slope, kg m² (> 0).
    n_modes : int
        Number of elastic modes returned (``1 ≤ n_modes ≤ 2n − 2``).

    Returns
    -------
    freq_hz : numpy.ndarray, shape (n_modes,)
        Natural frequencies, Hz, ascending.
    w : numpy.ndarray, shape (n_modes, n)
        Lateral displacement shapes, m per unit modal coordinate; unit generalized mass
        in SI (``Σ m w² + J θ² = 1`` kg m²); ``w[:, 0] > 0`` (first node positive).
    theta : numpy.ndarray, shape (n_modes, n)
        Slopes ``dw/dx`` of the same shapes, rad per unit modal coordinate.
    """
    x = np.asarray(x_m, float)
    n = len(x)
    k = np.zeros((2 * n, 2 * n))
    for e, (h, ei) in enumerate(zip(np.diff(x), ei_nm2)):
        ke = ei / h**3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                                   [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
        k[2 * e:2 * e + 4, 2 * e:2 * e + 4] += ke
    m = np.empty(2 * n)
    m[0::2], m[1::2] = node_mass_kg, node_rotary_inertia_kgm2
    rigid = np.zeros((2 * n, 2))                      # translation; rotation about x = 0
    rigid[0::2, 0], rigid[0::2, 1], rigid[1::2, 1] = 1.0, x, 1.0
    p = np.eye(2 * n) - rigid @ np.linalg.solve(rigid.T @ (m[:, None] * rigid), (m[:, None] * rigid).T)
    flex = np.zeros_like(k)
    flex[2:, 2:] = cho_solve(cho_factor(k[2:, 2:]), np.eye(2 * n - 2))
    s = np.sqrt(m)[:, None] * (p @ flex @ p.T) * np.sqrt(m)[None, :]
    mu, u = eigh(0.5 * (s + s.T), subset_by_index=[2 * n - n_modes, 2 * n - 1])
    vec = u[:, ::-1] / np.sqrt(m)[:, None]            # M-orthonormal, lowest mode first
    vec *= np.sign(vec[0])                            # first node's displacement > 0
    return np.sqrt(1.0 / mu[::-1]) / (2.0 * np.pi), vec[0::2].T, vec[1::2].T


@dataclass(frozen=True)
class ModalSet:
    """One set in file units (in, lbf, s), structure frame; rows by station, an alias row
    right after the node it shares a station with."""

    name: str
    scale: float                # EI factor used
    node_ids: np.ndarray        # (r,)
    station_in: np.ndarray      # (r,)
    mass: np.ndarray            # (r,) lbf s^2/in, zero on alias rows
    inertia: np.ndarray         # (r,) lbf in s^2, zero on alias rows
    freq_hz: np.ndarray         # (12,)
    shapes: np.ndarray          # (12, r, 6): dx dy dz (in), rx ry rz (rad)


def _beam(name: str, scale: float, lay: Layout = LAYOUT) -> tuple[np.ndarray, ...]:
    """Stations (m), primary ids, node masses (kg) and inertias (kg m²), then the
    frequencies (Hz), displacements (m) and slopes of one set's beam (SI, one plane)."""
    config, prop = SETS[name]
    segs = configuration_segments(config, prop, lay)
    x0, x1 = _extent(segs)
    xg, ids = global_mesh(lay)
    keep = (xg >= x0 - 1e-9) & (xg <= x1 + 1e-9)
    x, ids = xg[keep], ids[keep]
    mass, inertia = lumped_mass(x, segs)
    ei = element_ei(x, config, scale, lay)
    return (x, ids, mass, inertia, *free_free_bending_modes(x, ei, mass, inertia, BENDING_MODES))


def ei_scale(lay: Layout = LAYOUT) -> float:
    """The global EI factor giving ``first_stage_liftoff`` its :data:`TARGET_F1_HZ`
    (frequencies scale with its square root)."""
    return (TARGET_F1_HZ / _beam("first_stage_liftoff", 1.0, lay)[4][0]) ** 2


def modal_set(name: str, scale: float, lay: Layout = LAYOUT) -> ModalSet:
    """One set in file units with the stiffness scaled by ``scale``."""
    x, ids, mass, inertia, f, w, th = _beam(name, scale, lay)
    at = {nid: _key(xs) for nid, xs in named_nodes(lay).items()}
    rows = []                                         # (beam node index, row id, alias?)
    for i, nid in enumerate(ids):
        twins = [n for n in at if nid in at and n != nid and at[n] == at[nid]]
        rows += [(i, nid, False)] + [(i, n, True) for n in twins]
    node, row_id, alias = (np.array(c) for c in zip(*rows))
    shapes = np.zeros((2 * BENDING_MODES, len(node), 6))
    shapes[0::2, :, 2] = w[:, node] / IN              # x-z plane: dz, ry = -d(dz)/dx
    shapes[0::2, :, 4] = -th[:, node]
    shapes[1::2, :, 1] = w[:, node] / IN              # x-y plane: dy, rz = +d(dy)/dx
    shapes[1::2, :, 5] = th[:, node]
    m_u = np.where(alias, 0.0, mass[node] / MASS_UNIT_KG)
    j_u = np.where(alias, 0.0, inertia[node] / INERTIA_UNIT_KGM2)
    gm = m_u @ (shapes[:, :, :3] ** 2).sum(2).T + j_u @ (shapes[:, :, 3:] ** 2).sum(2).T
    return ModalSet(name, scale, row_id, x[node] / IN, m_u, j_u, np.repeat(f, 2),
                    shapes / np.sqrt(gm)[:, None, None])


def _write(path: Path, header: list[str], rows: list[list], comments: list[str], fmt: list[str]) -> None:
    from savant_cli.io.atomic import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w") as f:
        f.writelines(f"# {c}\n" for c in comments)
        f.write(",".join(header) + "\n")
        np.savetxt(f, np.array(rows, dtype=float), delimiter=",", fmt=fmt)


def write_set(out: Path, ms: ModalSet) -> None:
    """Write the three CSVs of one set into ``out``."""
    config, prop = SETS[ms.name]
    common = [
        f"set: {ms.name} (configuration {config}, {prop:.0f} kg propellant of the burning stage) [E] beam model",
        "units: length=in force=lbf (mass lbf*s^2/in, rotary inertia lbf*in*s^2, time s, angles rad)",
        "frame: structure, origin at the stack's nose tip; x = station aft, y = body y, z = -body z; "
        "rotations right-handed about the structure axes: ry = -d(dz)/dx, rz = +d(dy)/dx",
        "normalization: unit generalized mass, sum over nodes of m (dx^2+dy^2+dz^2) + J (rx^2+ry^2+rz^2) "
        "= 1 lbf*in*s^2 with m, J of the nodes file; lateral displacement at the most forward node > 0",
        f"modes: 2k-1 = k-th bending in the x-z (pitch) plane, 2k = the same in the x-y (yaw) plane; "
        f"free-free Euler-Bernoulli beam, EI scale {ms.scale:.6g} so that first_stage_liftoff f1 = {TARGET_F1_HZ:g} Hz",
        f"generated by `{COMMAND}`; assumptions and marks in README.md",
    ]
    n_rows = len(ms.node_ids)
    _write(out / f"{ms.name}_modes.csv", HEADERS["modes"],
           [[i + 1, f, 1.0] for i, f in enumerate(ms.freq_hz)], common, ["%d", "%.10g", "%.10g"])
    shape_rows = [[i + 1, ms.node_ids[r], ms.station_in[r], *ms.shapes[i, r]]
                  for i in range(len(ms.freq_hz)) for r in range(n_rows)]
    _write(out / f"{ms.name}_shapes.csv", HEADERS["shapes"], shape_rows, common,
           ["%d", "%d"] + ["%.10g"] * 7)
    node_rows = [[ms.node_ids[r], ms.station_in[r], ms.mass[r], ms.inertia[r]] for r in range(n_rows)]
    _write(out / f"{ms.name}_nodes.csv", HEADERS["nodes"], node_rows,
           common + ["lumped mass and pitch rotary inertia per node; an alias row (a named node at the "
                     "station of the row above) has the same shape and zero mass"], ["%d"] + ["%.10g"] * 3)


def write_all(out: Path, lay: Layout = LAYOUT) -> dict[str, ModalSet]:
    """Compute the EI scale, then write every set into ``out``; returns the sets."""
    out.mkdir(parents=True, exist_ok=True)
    scale = ei_scale(lay)
    sets = {name: modal_set(name, scale, lay) for name in SETS}
    for ms in sets.values():
        write_set(out, ms)
    return sets


def main(argv: list[str] | None = None) -> None:
    """Command line: write the modal data and print each set's frequencies."""
    ap = argparse.ArgumentParser(description="Generate the ares_i free-free beam modal data.")
    ap.add_argument("--out", type=Path, default=None,
                    help="output folder (default: the shipped conf/vehicle/ares_i/flex)")
    args = ap.parse_args(argv)
    from savant_cli.paths import shipped_config_dir

    out = args.out or shipped_config_dir() / "vehicle" / "ares_i" / "flex"
    sets = write_all(out)
    scale = sets["first_stage_liftoff"].scale
    print(f"EI scale factor {scale:.6g} (first_stage_liftoff f1 = {TARGET_F1_HZ:g} Hz)")
    for r in stiffness_regions():
        print(f"  {r.name:26s} {r.x_fwd_m:6.2f}-{r.x_aft_m:6.2f} m  EI {r.ei_nm2:.3e} -> {scale * r.ei_nm2:.3e} N m^2")
    for name, ms in sets.items():
        print(f"{name:22s} {len(np.unique(ms.station_in)):3d} nodes  bending Hz: "
              + " ".join(f"{f:.3f}" for f in ms.freq_hz[0::2]))
    print(f"wrote {out}")


__all__ = ["SETS", "ModalSet", "StiffnessRegion", "stiffness_regions", "named_nodes", "global_mesh",
           "lumped_mass", "element_ei", "free_free_bending_modes", "ei_scale", "modal_set", "write_set",
           "write_all", "main"]

if __name__ == "__main__":
    main()
