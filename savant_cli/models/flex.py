"""Flexible body: retained bending modes in modal coordinates, blended between the modal
sets of a stage, loaded by the forces and moments at the plant's points.

Each mode ``i`` (unit generalized mass, SI: q in √kg·m) obeys::

    q̈_i + 2 ζ_i ω_i q̇_i + ω_i² q_i = Σ_points (φ_i(pt) · F(pt) + σ_i(pt) · M(pt))

with φ the translation and σ the rotation mode shape at a point (body axes). Loaded
points: the active gimbal (thrust plus the tail-wags-dog force, and the tail-wags-dog
torque), the roll jets (their torque) and every tank's slosh mass (its force). The
structure's rotation at a point is ``Σ σ_i(pt) q_i`` and its displacement
``Σ φ_i(pt) q_i``: at the gimbal the rotation turns the thrust line (follower thrust) and
the displacement moves the point the thrust and the tail-wags-dog force act at (their
moment arm about the CG is ``r_g + Σ φ_i(g) q_i``); at the navigation unit and the rate
gyros the rotation is what the sensors see on top of the rigid motion.

Each configuration flies its own modal sets (``flex_set_map``, from the vehicle's
``flex.sets``; by default the paper's four, two per stage: first-stage liftoff and
burnout, second-stage ignition and burnout, and with strap-on boosters two more for the
configuration that carries them, ``boosted_liftoff`` and ``boosted_burnout``, the latter
at the boosters' burnout), each set at a fraction of the burning stage's propellant
burned. With ``flex.switching: separation`` (the paper's assumption) a configuration
flies its first set throughout (by default the liftoff set until separation, the
boosted one while the boosters are attached, and the ignition set after separation);
with ``propellant`` the frequencies and shapes are blended linearly in the burned
fraction between the two sets around it (the boosters' own while they are attached).
Each booster's nozzle is a point of its own (after the sloshing tanks'): its thrust and
its moving nozzle's reaction load the modes there, and its thrust line turns with the
structure's rotation there (``models/boosters.py``). Source:
SAVANT §III, "Flexible body"; the default modal data come from a beam model
(``datagen/ares_i_flex.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from savant_cli.flex_slosh import FIRST_STAGE_KEYS, MAX_SETS_PER_CONFIGURATION, POINT_KEYS
from savant_cli.models import blocks, slosh
from savant_cli.models.interp import tab, tab_offset
from savant_cli.models.propulsion import (
    P_FS_CONFIGS, P_FS_PROP_FULL, P_US_PROP_FULL, first_stage_propellant, upper_stage_propellant
)

# Points where the plant and the sensors use mode shapes, and the vehicle YAML key
# (``flex.nodes.<key>``) of each; a point may average several nodes.
PT_IMU = 0  # navigation unit (its rotation enters the attitude errors) and IMU gyros
PT_GYRO_US = 1
PT_GYRO_FS = 2
PT_RCS = 3
PT_GIMBAL_FS = 4
PT_GIMBAL_US = 5
N_POINTS = 6  # the points every vehicle has; the sloshing tanks' follow, one each
PT_SLOSH = N_POINTS  # the first sloshing tank's point (tank j at PT_SLOSH + j)
# POINT_KEYS (the YAML key of each point, in PT_ order), FIRST_STAGE_KEYS and FLEX_SETS (the
# modal data sets, in this order in the packed tables) are vehicle-data names: they live
# with the reader (savant_cli/flex_slosh.py), which arranges the data in their order.
FIRST_STAGE_POINTS = (PT_GYRO_FS, PT_GIMBAL_FS)  # absent from the upper-stage modal sets
assert len(POINT_KEYS) == N_POINTS and tuple(POINT_KEYS[i] for i in FIRST_STAGE_POINTS) == FIRST_STAGE_KEYS
SHAPE = blocks.Record(
    "mode shape at a point",
    ("phi_x", "1/sqrt(kg)", "translation per unit modal coordinate, body X"),
    ("phi_y", "1/sqrt(kg)", "translation, body Y"),
    ("phi_z", "1/sqrt(kg)", "translation, body Z"),
    ("sigma_x", "rad/(sqrt(kg)*m)", "rotation per unit modal coordinate, body X"),
    ("sigma_y", "rad/(sqrt(kg)*m)", "rotation, body Y"),
    ("sigma_z", "rad/(sqrt(kg)*m)", "rotation, body Z"),
)
PHI_X, PHI_Y, PHI_Z, SIGMA_X, SIGMA_Y, SIGMA_Z = SHAPE.offsets
N_SHAPE = SHAPE.size

_PARAMS = blocks.PARAMETERS.block("flex")
P_OFFSET = _PARAMS.scalar("state_offset", "1", "offset of q₁…q_N, q̇₁…q̇_N in x (−1: flex off)")
P_N_MODES = _PARAMS.scalar("n_modes", "1", "retained modes")
P_SWITCH = _PARAMS.scalar("switching", "1", "0: liftoff set then ignition set; 1: blend by propellant")
P_BOOSTER_TANK = _PARAMS.scalar("booster_tank_state", "1", "index in x of the first booster's propellant (the "
                                "others follow it; read only with boosters)")
P_N_BOOSTERS = _PARAMS.scalar("boosters", "1", "boosters whose nozzles are flex points, whose boosted sets fly while "
                              "they are attached (0: none, or flex off)")
P_BOOSTER_FULL = _PARAMS.scalar("booster_propellant_full", "kg", "the boosters' propellant at liftoff, summed")
#: Boosters whose nozzles load the flexible body (flex on with more is refused).
MAX_BOOSTERS = 8
_TABLES = blocks.TABLES.block("flex")
T_FREQ = _TABLES.table("flex_freq", "rad/s", "(sets, n_modes) modal frequencies of the vehicle's sets (by default "
                       "FLEX_SETS, then the boosted pair)")
T_SET_MAP = _TABLES.table("flex_set_map", "1", "(configurations, 1 + 2 MAX_SETS_PER_CONFIGURATION) each "
                          "configuration's modal sets: their count, then (set, burned fraction) pairs, the fractions "
                          "increasing")
T_ZETA = _TABLES.table("flex_zeta", "1", "(n_modes,) modal damping ratios")
T_SHAPE = _TABLES.table("flex_shape", "SI", "(sets, n_modes, n_points, SHAPE) mode shapes at the points (N_POINTS, "
                         "then one per sloshing tank, then one per booster nozzle), body axes")
_AUX = blocks.DIAGNOSTICS.block("flex")
A_GIMBAL_ROTATION = _AUX.array("gimbal_rotation", 3, "rad", "flex rotation at the active gimbal (turns the thrust)",
                               blocks.Logged("flex_gimbal_rotation", ("roll", "pitch", "yaw"), "body",
                                             lambda model: model.layout.n_modes > 0))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, rx: float, ry: float, rz: float) -> None:
    """Write the flex rotation at the active gimbal (rad, body axes) into ``aux``."""
    aux[A_GIMBAL_ROTATION] = rx
    aux[A_GIMBAL_ROTATION + 1] = ry
    aux[A_GIMBAL_ROTATION + 2] = rz


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The ``flex`` group and the vehicle's modal sets, loaded once per run by the
    vehicle-data layer and handed in as ``inputs.flex`` (placeholders when off)."""
    f = inputs.cfg.flex
    p[P_OFFSET] = inputs.layout.flex
    p[P_N_MODES] = inputs.layout.n_modes
    p[P_SWITCH] = 1.0 if f.enabled and f.switching == "propellant" else 0.0
    b = inputs.vehicle.boosters
    if f.enabled and b is not None:
        p[P_BOOSTER_TANK] = inputs.layout.tank(b.tanks[0])
        p[P_N_BOOSTERS] = b.count
        p[P_BOOSTER_FULL] = b.count * b.propellant_kg
    if f.enabled:
        fx = inputs.flex
        tables.update(flex_freq=fx.frequency_rad_s, flex_zeta=fx.damping, flex_shape=fx.shapes, flex_set_map=fx.set_map)
    else:
        tables.update(flex_freq=np.zeros((4, 1)), flex_zeta=np.zeros(1), flex_shape=np.zeros((4, 1, N_POINTS, N_SHAPE)),
                      flex_set_map=np.zeros((1, 1 + 2 * MAX_SETS_PER_CONFIGURATION)))


@njit(cache=True, error_model="numpy", inline="always")
def flex_sets(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray) -> tuple[int, int, float]:
    """The two modal sets of configuration ``config`` the structure is between, and the
    blend weight toward the second.

    A configuration's sets (``flex_set_map``; by default its stage's liftoff or ignition
    set at 0 and burnout set at 1, the boosted pair while the boosters are attached)
    each hold at a fraction of the burning stage's propellant burned (the boosters' own
    while they are attached). With ``switching: separation`` (the source paper's assumption)
    the configuration's first set flies throughout (weight 0); with ``propellant`` the
    shapes and frequencies are linear in the burned fraction between the two sets around
    it (held at the first set before its fraction and at the last after its own).
    """
    if config == 0 and p[P_N_BOOSTERS] > 0.0:
        tank = int(p[P_BOOSTER_TANK])
        left = 0.0
        for i in range(tank, tank + int(p[P_N_BOOSTERS])):
            left += x[i]
        frac = left / p[P_BOOSTER_FULL]
    elif config < p[P_FS_CONFIGS]:
        frac = first_stage_propellant(x, p) / p[P_FS_PROP_FULL]
    else:
        lox, lh2 = upper_stage_propellant(x, p)
        frac = (lox + lh2) / p[P_US_PROP_FULL]
    row = tab_offset(tb, T_SET_MAP) + config * (1 + 2 * MAX_SETS_PER_CONFIGURATION)
    count = int(tb[row])
    first = int(tb[row + 1])
    if p[P_SWITCH] == 0.0 or count == 1:
        return first, int(tb[row + 1 + 2 * min(1, count - 1)]), 0.0
    burned = 1.0 - min(max(frac, 0.0), 1.0)
    k = 0  # the segment [k, k + 1] the burned fraction is in (the first or the last beyond the ends)
    while k < count - 2 and burned > tb[row + 2 + 2 * (k + 1)]:
        k += 1
    f_a, f_b = tb[row + 2 + 2 * k], tb[row + 4 + 2 * k]
    w = min(max((burned - f_a) / (f_b - f_a), 0.0), 1.0)
    return int(tb[row + 1 + 2 * k]), int(tb[row + 3 + 2 * k]), w


@njit(cache=True, error_model="numpy", inline="always")
def point_count(tb: np.ndarray) -> int:
    """The points of the shape table: :data:`N_POINTS`, one per sloshing tank, one per
    booster nozzle (with the boosted sets)."""
    return tab(tb, T_SHAPE)[1] // (tab(tb, T_FREQ)[1] * N_SHAPE)


@njit(cache=True, error_model="numpy", inline="always")
def booster_point(p: np.ndarray, tb: np.ndarray, i: int) -> int:
    """Booster ``i``'s nozzle point (after the sloshing tanks')."""
    return point_count(tb) - int(p[P_N_BOOSTERS]) + i


@njit(cache=True, error_model="numpy", inline="always")
def _shape_sum(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray, pt: int, rate: bool,
               component: int) -> tuple[float, float, float]:
    """``Σ_i s_i(pt) q_i`` (or ``q̇_i``) for the three shape entries from ``component``
    (``PHI_X``: translation, ``SIGMA_X``: rotation) at point ``pt``, blended between the
    stage's two modal sets; zero when flex is off."""
    rx = ry = rz = 0.0
    fo = int(p[P_OFFSET])
    if fo < 0:
        return rx, ry, rz
    nm = int(p[P_N_MODES])
    sa, sb, w = flex_sets(x, config, p, tb)
    o_sh = tab_offset(tb, T_SHAPE)
    nd = tab(tb, T_ZETA)[1]  # modes in the data
    npt = point_count(tb)
    for i in range(nm):
        qi = x[fo + nm + i] if rate else x[fo + i]
        ia = o_sh + ((sa * nd + i) * npt + pt) * N_SHAPE + component
        ib = o_sh + ((sb * nd + i) * npt + pt) * N_SHAPE + component
        rx += ((1.0 - w) * tb[ia] + w * tb[ib]) * qi
        ry += ((1.0 - w) * tb[ia + 1] + w * tb[ib + 1]) * qi
        rz += ((1.0 - w) * tb[ia + 2] + w * tb[ib + 2]) * qi
    return rx, ry, rz


@njit(cache=True, error_model="numpy", inline="always")
def rotation_at(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray, pt: int,
                rate: bool) -> tuple[float, float, float]:
    """Flex rotation (``rate`` False, rad) or rotation rate (True, rad/s) at point ``pt``,
    body axes: ``Σ_i σ_i(pt) q_i`` (or ``q̇_i``). Zero when flex is off."""
    return _shape_sum(x, config, p, tb, pt, rate, SIGMA_X)


@njit(cache=True, error_model="numpy", inline="always")
def displacement_at(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray,
                    pt: int) -> tuple[float, float, float]:
    """Flex displacement at point ``pt`` (m, body axes): ``Σ_i φ_i(pt) q_i``. Zero when
    flex is off."""
    return _shape_sum(x, config, p, tb, pt, False, PHI_X)


@njit(cache=True, error_model="numpy")
def flex_point(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray, pt: int, rate: bool,
               out: np.ndarray) -> None:
    """:func:`rotation_at` into ``out[0:3]`` (the sensors' call)."""
    out[0], out[1], out[2] = rotation_at(x, config, p, tb, pt, rate)


@njit(cache=True, error_model="numpy", inline="always")
def point_work(tb: np.ndarray, base_a: int, base_b: int, w: float, pt: int, f0: float, f1: float, f2: float,
               m0: float, m1: float, m2: float) -> float:
    """``φ·F + σ·M`` of one mode at point ``pt``, blended between two sets (``base_*``: the
    mode's first shape entry in each set)."""
    ia = base_a + pt * N_SHAPE
    ib = base_b + pt * N_SHAPE
    return (((1.0 - w) * tb[ia + PHI_X] + w * tb[ib + PHI_X]) * f0
            + ((1.0 - w) * tb[ia + PHI_Y] + w * tb[ib + PHI_Y]) * f1
            + ((1.0 - w) * tb[ia + PHI_Z] + w * tb[ib + PHI_Z]) * f2
            + ((1.0 - w) * tb[ia + SIGMA_X] + w * tb[ib + SIGMA_X]) * m0
            + ((1.0 - w) * tb[ia + SIGMA_Y] + w * tb[ib + SIGMA_Y]) * m1
            + ((1.0 - w) * tb[ia + SIGMA_Z] + w * tb[ib + SIGMA_Z]) * m2)


class StructuralLoads(NamedTuple):
    """The loads the structure carries at the flex points (body axes).

    Attributes
    ----------
    gimbal_force_n : tuple of 3 float
        Thrust and engine-inertia reaction force at the active gimbal, N.
    gimbal_torque_nm : tuple of 2 float
        The engine-inertia reaction torque about body y and z at the gimbal, N·m.
    rcs_torque_nm : float
        Roll-jet torque about body x at the jets, N·m.
    rcs_force_n : tuple of 2 float
        The pitch and yaw jets' force along body y and z at the jets, N.
    gimbal_couple_nm : tuple of 3 float
        A cluster's couple about its stage's gimbal point, ``Σ Δ_i × F_i`` of its
        engines' forces at their own gimbals, N·m (zero for one engine:
        ``cluster.cluster_loads``).

    The slosh masses' forces on the structure are the slosh model's diagnostics
    (``slosh.A_FORCE``, one per sloshing tank), the boosters' nozzle loads the boosters'
    (``boosters.A_NOZZLE_LOADS``, written by ``boosters.loads``).
    """

    gimbal_force_n: tuple[float, float, float]
    gimbal_torque_nm: tuple[float, float]
    rcs_torque_nm: float
    rcs_force_n: tuple[float, float]
    gimbal_couple_nm: tuple[float, float, float]


@njit(cache=True, error_model="numpy", inline="always")
def modal_rates(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray, gimbal_pt: int,
                loads: StructuralLoads, aux: np.ndarray, nozzle_loads: int, xd: np.ndarray) -> None:
    """Modal equations into ``xd`` under the ``loads`` at the flex points (the active
    gimbal point ``gimbal_pt``, with a cluster's couple, the jets), the slosh masses'
    forces and, in the boosted sets, the boosters' nozzle loads (both in ``aux``; the
    latter five per booster from ``aux[nozzle_loads]``: force x, y, z, torque y, z).
    Nothing when flex is off."""
    fo = int(p[P_OFFSET])
    if fo < 0:
        return
    fgx, fgy, fgz = loads.gimbal_force_n
    tgy, tgz = loads.gimbal_torque_nm
    rcs_torque = loads.rcs_torque_nm
    jet_fy, jet_fz = loads.rcs_force_n
    cpx, cpy, cpz = loads.gimbal_couple_nm
    couple = cpx != 0.0 or cpy != 0.0 or cpz != 0.0  # a cluster's (none for one engine: its sums kept as they were)
    nmod = int(p[P_N_MODES])
    sa, sb, w = flex_sets(x, config, p, tb)
    o_sh = tab_offset(tb, T_SHAPE)
    o_fz = tab_offset(tb, T_ZETA)
    o_ff = tab_offset(tb, T_FREQ)
    nd = tab(tb, T_ZETA)[1]  # modes in the data
    npt = point_count(tb)
    n_slosh = slosh.tank_count(p)
    for i in range(nmod):
        wi = (1.0 - w) * tb[o_ff + sa * nd + i] + w * tb[o_ff + sb * nd + i]
        base_a = o_sh + (sa * nd + i) * npt * N_SHAPE
        base_b = o_sh + (sb * nd + i) * npt * N_SHAPE
        # generalized force over the loaded points, in point order (jets, gimbal, slosh masses)
        gen = 0.0
        gen += point_work(tb, base_a, base_b, w, PT_RCS, 0.0, jet_fy, jet_fz, rcs_torque, 0.0, 0.0)
        gen += point_work(tb, base_a, base_b, w, gimbal_pt, fgx, fgy, fgz, 0.0, tgy, tgz)
        if couple:
            gen += point_work(tb, base_a, base_b, w, gimbal_pt, 0.0, 0.0, 0.0, cpx, cpy, cpz)
        for j in range(n_slosh):
            k = slosh.A_FORCE + 3 * j
            gen += point_work(tb, base_a, base_b, w, PT_SLOSH + j, aux[k], aux[k + 1], aux[k + 2], 0.0, 0.0, 0.0)
        if config == 0 and p[P_N_BOOSTERS] > 0.0:  # the boosters' nozzles, while they are attached
            for j in range(int(p[P_N_BOOSTERS])):
                k = nozzle_loads + 5 * j
                gen += point_work(tb, base_a, base_b, w, npt - int(p[P_N_BOOSTERS]) + j, aux[k], aux[k + 1],
                                  aux[k + 2], 0.0, aux[k + 3], aux[k + 4])
        qi = x[fo + i]
        qdi = x[fo + nmod + i]
        xd[fo + i] = qdi
        xd[fo + nmod + i] = gen - 2.0 * tb[o_fz + i] * wi * qdi - wi * wi * qi
