"""The compiled continuous plant: rigid-body 6-DOF equations of motion in ECI with a
quaternion attitude, aerodynamics, gravity, gimbaled thrust, roll jets and actuators.

``derivative`` is the one function both the time simulation and (later) the
linearization call. It also fills ``aux`` with diagnostics (altitude, Mach, α …) so the
logger reports exactly what the dynamics used.

Tables are built as a :class:`PlantTables` (named arrays, for Python code) and handed to
the compiled code packed into one flat array by :func:`pack_tables`: numba increments and
decrements a reference count for every array argument of every call, and two dozen
arrays made those atomic operations a quarter of the whole run time.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from savant_cli.models import earth, gravity
from savant_cli.models.atmosphere import atmosphere_at
from savant_cli.models.interp import interp1_at, locate, locate_at, rows, trilinear_at
from savant_cli.sim import layout as L
from savant_cli.sim.layout import (
    A_ACCEL, A_ALPHA, A_ALT, A_BETA, A_CG, A_DP, A_DY, A_FAERO, A_GRAV, A_LAT, A_LON,
    A_MACH, A_MAERO, A_MASS, A_MTHRUST, A_PRES, A_PROP, A_QBAR, A_RCS_TORQUE, A_RHO,
    A_SOS, A_TEMP, A_THRUST, A_VEARTH, A_VREL, A_WIND_D, A_WIND_E, A_WIND_N,
    ACT_P, ACT_Y, CONFIG_STACK, ENGINE_FIRST, ENGINE_UPPER, MFS, MLH2, MLOX, P_ACT_FS_RATE, P_ACT_FS_WA, P_ACT_FS_WN, P_ACT_FS_ZETA, P_ACT_US_RATE, P_ACT_US_WA,
    P_ACT_US_WN, P_ACT_US_ZETA, P_AERO_ON, P_E2, P_FS_EXIT_AREA, P_FS_GIMBAL_LIMIT,
    P_FS_GIMBAL_X, P_FS_ISP_VAC, P_FS_THRUST_SCALE, P_GRAVITY_ORDER, P_J2, P_J3, P_J4,
    P_MU, P_OMEGA_E, P_RCS_ARM, P_RCS_EXIT_AREA, P_RCS_N, P_RCS_RAMP_DOWN,
    P_RCS_RAMP_UP, P_RE, P_THRUST_ON, P_US_EXIT_AREA, P_US_GIMBAL_LIMIT, P_US_GIMBAL_X,
    P_US_ISP, P_US_MR, P_US_THRUST, P_WIND_SCALE, Q, R, RCS_NEG, RCS_POS, U_CONFIG,
    U_DPC, U_DYC, U_ENGINE, U_RCS, U_T_IGN, V, W,
)

G0 = 9.80665


class PlantTables(NamedTuple):
    """Tabular data of the plant, SI, as contiguous float64 arrays.

    Aerodynamic and mass tables are stacked over the three configurations (stack,
    upper stage with LES, upper stage); shorter tables are padded and their valid
    lengths stored in ``*_len``.
    """

    aero_mach: np.ndarray  # (nM,)
    aero_alpha: np.ndarray  # (nA,) rad
    aero_beta: np.ndarray  # (nB,) rad
    aero_coef: np.ndarray  # (3, 6, nM, nA, nB): CA CY CN Cl Cm Cn
    aero_ref: np.ndarray  # (3, 7): S m2, lx, ly, lz m, MRP x, y, z (structure) m
    base_time: np.ndarray  # (3, nb) s
    base_force: np.ndarray  # (3, nb) N along body X
    base_len: np.ndarray  # (3,) int64
    mass_prop: np.ndarray  # (3, nm) kg, ascending
    mass_data: np.ndarray  # (3, nm, 10): mass, cg xyz (structure), Ixx Iyy Izz Ixy Ixz Iyz (body)
    mass_len: np.ndarray  # (3,) int64
    fs_time: np.ndarray  # first-stage thrust table time, s
    fs_thrust: np.ndarray  # first-stage vacuum thrust, N
    us_start_time: np.ndarray  # J-2X start transient time since ignition, s
    us_start_frac: np.ndarray  # thrust fraction
    rcs_alt: np.ndarray  # m
    rcs_thrust: np.ndarray  # vacuum thrust per jet, N
    atm_alt: np.ndarray  # upper-atmosphere table, m
    atm_lnp: np.ndarray
    atm_lnrho: np.ndarray
    wind_alt: np.ndarray  # m
    wind_north: np.ndarray  # m/s
    wind_east: np.ndarray  # m/s
    flex_freq: np.ndarray  # (4 sets, n_modes) rad/s (layout.FLEX_SETS order)
    flex_zeta: np.ndarray  # (n_modes,) damping ratio per mode
    flex_shape: np.ndarray  # (4, n_modes, N_POINTS, 6) body-frame shapes at the points, SI
    slosh_level: np.ndarray  # (2 tanks, n) liquid level, m (padded)
    slosh_data: np.ndarray  # (2, n, 4): ω at the reference acceleration rad/s, ζ, mass kg, height m
    slosh_len: np.ndarray  # (2,) valid rows


# Packed layout: a header of two entries per PlantTables field (offset of the field's
# C-ordered data in the flat array, element count), then the data. T_* name the fields.
(T_AERO_MACH, T_AERO_ALPHA, T_AERO_BETA, T_AERO_COEF, T_AERO_REF, T_BASE_TIME, T_BASE_FORCE,
 T_BASE_LEN, T_MASS_PROP, T_MASS_DATA, T_MASS_LEN, T_FS_TIME, T_FS_THRUST, T_US_START_TIME,
 T_US_START_FRAC, T_RCS_ALT, T_RCS_THRUST, T_ATM_ALT, T_ATM_LNP, T_ATM_LNRHO, T_WIND_ALT,
 T_WIND_NORTH, T_WIND_EAST, T_FLEX_FREQ, T_FLEX_ZETA, T_FLEX_SHAPE, T_SLOSH_LEVEL, T_SLOSH_DATA,
 T_SLOSH_LEN) = range(len(PlantTables._fields))
N_CONFIG = 3  # stack, upper stage with LES, upper stage
N_COEF = 6  # CA CY CN Cl Cm Cn
N_MASS_COLS = 10
N_AERO_REF = 7
N_SLOSH_COLS = 4


def pack_tables(tb: PlantTables) -> np.ndarray:
    """One flat float64 array holding every table of ``tb`` (see the ``T_*`` layout)."""
    parts = [np.ascontiguousarray(a, dtype=np.float64).ravel() for a in tb]
    n_header = 2 * len(parts)
    out = np.empty(n_header + sum(a.size for a in parts))
    pos = n_header
    for f, a in enumerate(parts):
        out[2 * f] = pos
        out[2 * f + 1] = a.size
        out[pos:pos + a.size] = a
        pos += a.size
    return out


@njit(cache=True, error_model="numpy")
def tab(tb: np.ndarray, field: int) -> tuple[int, int]:
    """Offset and element count of a packed field."""
    return int(tb[2 * field]), int(tb[2 * field + 1])


@njit(cache=True, error_model="numpy")
def mass_properties(tb: PlantTables, config: int, prop_kg: float):
    """Mass (kg), CG (structure, m) and inertia tensor about the CG (body, kg·m²)."""
    n = tb.mass_len[config]
    i, w = locate(tb.mass_prop[config], n, prop_kg)
    row = rows(tb.mass_data[config], i, w)
    inertia = np.empty((3, 3))
    inertia[0, 0] = row[4]
    inertia[1, 1] = row[5]
    inertia[2, 2] = row[6]
    inertia[0, 1] = inertia[1, 0] = -row[7]
    inertia[0, 2] = inertia[2, 0] = -row[8]
    inertia[1, 2] = inertia[2, 1] = -row[9]
    return row[0], row[1:4].copy(), inertia


@njit(cache=True, error_model="numpy")
def solve_sym3(a00, a11, a22, a01, a02, a12, b0, b1, b2):
    """Solve ``A x = b`` for a symmetric positive-definite 3×3 ``A`` by cofactors (the
    inertia equation of the hot path; a LAPACK call costs more than the whole plant)."""
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    return ((c00 * b0 + c01 * b1 + c02 * b2) / det,
            (c01 * b0 + c11 * b1 + c12 * b2) / det,
            (c02 * b0 + c12 * b1 + c22 * b2) / det)


@njit(cache=True, error_model="numpy")
def actuator_third_order(x: np.ndarray, k: int, cmd: float, wa: float, wn: float, zeta: float,
                         rate_limit: float, out: np.ndarray) -> None:
    """Third-order TVC actuator: rate-limited position loop driving a 2nd-order load.

    States ``x[k:k+3] = [δ, δ̇, δ̈]``, derivatives into ``out[k:k+3]``; ``v = sat(ωa (δc − δ), ±rate_limit)`` is the commanded rate and
    ``δ⃛ = ωn² (v − δ̇) − 2 ζ ωn δ̈``. Unsaturated, δ/δc = ωa ωn² / (s(s² + 2ζωn s + ωn²) + ωa ωn²).
    """
    v = wa * (cmd - x[k])
    if v > rate_limit:
        v = rate_limit
    elif v < -rate_limit:
        v = -rate_limit
    out[k] = x[k + 1]
    out[k + 1] = x[k + 2]
    out[k + 2] = wn * wn * (v - x[k + 1]) - 2.0 * zeta * wn * x[k + 2]


@njit(cache=True, error_model="numpy")
def actuator_simplex(x: np.ndarray, k: int, kv: int, cmd: float, p: np.ndarray, sp: int,
                     out: np.ndarray) -> float:
    """Simplex TVC actuator: position loop, power valve, hydraulic ram and compliant load.

    States ``x[k:k+3] = [δ, δ̇, θ_p]`` (nozzle angle and rate, ram position as an
    equivalent gimbal angle) and ``x[kv:kv+2] = [r, ṙ]`` (valve flow expressed as the
    no-load ram rate). Parameters ``p[sp:sp+N_SPX]``: loop gain K_a (1/s), valve natural
    frequency ω_v (rad/s) and damping ζ_v, flow saturation (rate limit, rad/s), load
    stiffness K (N m/rad), load damping C (N m s/rad), load inertia J (kg m², the nozzle
    about its gimbal), leakage c_l (rad/s per N m), feedback (0 ram LVDT, 1 nozzle angle)::

        v   = sat(K_a (δ_c − δ_fb), ±rate_limit)            position loop, valve stops
        r̈   = ω_v² (v − r) − 2 ζ_v ω_v ṙ                    power valve
        θ̇_p = r − c_l K (θ_p − δ)                           ram: flow minus leakage
        J δ̈ = K (θ_p − δ) − C δ̇                             nozzle on a compliant mount

    With ω_v → ∞, c_l = 0 and nozzle feedback this is exactly the third-order model with
    ω_a = K_a, ω_n² = K/J, 2ζω_n = C/J. Returns δ̈ (rad/s²).
    """
    ka, wv, zv, rl = p[sp], p[sp + 1], p[sp + 2], p[sp + 3]
    kk, cc, jj, leak = p[sp + 4], p[sp + 5], p[sp + 6], p[sp + 7]
    d, dd, th = x[k], x[k + 1], x[k + 2]
    fb = d if p[sp + 8] > 0.5 else th
    v = ka * (cmd - fb)
    if v > rl:
        v = rl
    elif v < -rl:
        v = -rl
    torque = kk * (th - d)
    ddd = (torque - cc * dd) / jj
    out[k] = dd
    out[k + 1] = ddd
    out[k + 2] = x[kv] - leak * torque
    out[kv] = x[kv + 1]
    out[kv + 1] = wv * wv * (v - x[kv]) - 2.0 * zv * wv * x[kv + 1]
    return ddd


@njit(cache=True, error_model="numpy")
def minus_point_mass(ixx: float, iyy: float, izz: float, ixy: float, ixz: float, iyz: float,
                     m: float, dx: float, dy: float, dz: float):
    """Inertia tensor elements minus those of a point mass ``m`` at body offset ``d``:
    ``I − m (|d|² E − d dᵀ)`` (off-diagonal elements are tensor elements, −products)."""
    return (ixx - m * (dy * dy + dz * dz), iyy - m * (dx * dx + dz * dz), izz - m * (dx * dx + dy * dy),
            ixy + m * dx * dy, ixz + m * dx * dz, iyz + m * dy * dz)


@njit(cache=True, error_model="numpy")
def slosh_tank(tb: np.ndarray, p: np.ndarray, j: int, liquid_kg: float):
    """Level (m), slosh ω at the reference acceleration (rad/s), ζ, slosh mass (kg) and
    slosh-mass station (structure x, m) of tank ``j`` holding ``liquid_kg``.

    The level is the flat-bottom cylinder height ``m / (ρ π R²)``; tables are read at it.
    """
    radius, bottom, density = p[L.P_TANK + 3 * j], p[L.P_TANK + 3 * j + 1], p[L.P_TANK + 3 * j + 2]
    level = max(liquid_kg, 0.0) / (density * np.pi * radius * radius)
    o_l, n_l = tab(tb, T_SLOSH_LEVEL)
    ns = n_l // L.N_TANKS
    i, w = locate_at(tb, o_l + j * ns, int(tb[int(tb[2 * T_SLOSH_LEN]) + j]), level)
    r0 = int(tb[2 * T_SLOSH_DATA]) + (j * ns + i) * N_SLOSH_COLS
    r1 = r0 + N_SLOSH_COLS
    a = 1.0 - w
    w_ref = (a * tb[r0] + w * tb[r1]) * p[L.P_SLOSH_FREQ_SCALE]
    zeta = (a * tb[r0 + 1] + w * tb[r1 + 1]) * p[L.P_SLOSH_ZETA_SCALE]
    mass = a * tb[r0 + 2] + w * tb[r1 + 2]
    height = a * tb[r0 + 3] + w * tb[r1 + 3]
    return level, w_ref, zeta, mass, bottom - height


@njit(cache=True, error_model="numpy")
def flex_sets(x: np.ndarray, config: int, p: np.ndarray) -> tuple[int, int, float]:
    """The two modal sets of the current stage and the blend weight toward the second.

    Stack: first-stage liftoff → burnout; upper stage: ignition → burnout. With
    ``P_FLEX_SWITCH = 0`` (the source paper's assumption) the weight is 0: the liftoff
    set until separation, the ignition set after. With 1 the weight is the fraction of
    the stage's propellant burned.
    """
    if config == CONFIG_STACK:
        a, frac = 0, x[MFS] / p[L.P_FS_PROP_FULL]
    else:
        a, frac = 2, (x[MLOX] + x[MLH2]) / p[L.P_US_PROP_FULL]
    if p[L.P_FLEX_SWITCH] == 0.0:
        return a, a + 1, 0.0
    return a, a + 1, 1.0 - min(max(frac, 0.0), 1.0)


@njit(cache=True, error_model="numpy")
def flex_point(x: np.ndarray, config: int, p: np.ndarray, tb: np.ndarray, pt: int, rate: bool,
               out: np.ndarray) -> None:
    """Flex rotation (``rate`` False, rad) or rotation rate (True, rad/s) at point ``pt``,
    body axes: ``out[0:3] = Σ_i σ_i(pt) q_i`` (or ``q̇_i``). Zero when flex is off."""
    out[0] = out[1] = out[2] = 0.0
    fo = int(p[L.P_FLEX_OFF])
    if fo < 0:
        return
    nm = int(p[L.P_N_MODES])
    sa, sb, w = flex_sets(x, config, p)
    o_sh = int(tb[2 * T_FLEX_SHAPE])
    nd = int(tb[2 * T_FLEX_ZETA + 1])  # modes in the data
    for i in range(nm):
        qi = x[fo + nm + i] if rate else x[fo + i]
        ia = o_sh + ((sa * nd + i) * L.N_POINTS + pt) * 6 + 3
        ib = o_sh + ((sb * nd + i) * L.N_POINTS + pt) * 6 + 3
        for c in range(3):
            out[c] += ((1.0 - w) * tb[ia + c] + w * tb[ib + c]) * qi


@njit(cache=True, error_model="numpy")
def clip(x: float, lim: float) -> float:
    if x > lim:
        return lim
    if x < -lim:
        return -lim
    return x


@njit(cache=True, error_model="numpy")
def jet_ramp(frac: float, on: bool, ramp_up_s: float, ramp_down_s: float) -> float:
    """Rate of the jet thrust fraction: linear ramp up to 1 when open, down to 0 when shut."""
    if on:
        return 1.0 / ramp_up_s if frac < 1.0 else 0.0
    return -1.0 / ramp_down_s if frac > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def derivative(t: float, x: np.ndarray, u: np.ndarray, p: np.ndarray, tb: np.ndarray,
               aux: np.ndarray, xd: np.ndarray) -> None:
    """Time derivative of the continuous state, written into ``xd``.

    Parameters
    ----------
    t : float
        Mission time, s (0 at liftoff).
    x : ndarray (N_STATE,)
        Continuous state (see :mod:`savant_cli.sim.layout`).
    u : ndarray (N_INPUT,)
        Held inputs from the discrete flight software and the event logic.
    p : ndarray (N_PARAM,)
        Scalar parameters.
    tb : ndarray
        Tabular data packed by :func:`pack_tables`.
    aux : ndarray (N_AUX,)
        Filled with diagnostics of this evaluation.
    xd : ndarray (N_STATE,)
        Output: the state derivative.

    Notes
    -----
    Written with scalars rather than small temporary arrays: this function runs four
    times per plant step, and heap temporaries would dominate its cost.
    """
    config = int(u[U_CONFIG])
    engine = int(u[U_ENGINE])
    omega_e = p[P_OMEGA_E]
    rx, ry, rz = x[R], x[R + 1], x[R + 2]
    vx, vy, vz = x[V], x[V + 1], x[V + 2]
    q0, q1, q2, q3 = x[Q], x[Q + 1], x[Q + 2], x[Q + 3]
    wx, wy, wz = x[W], x[W + 1], x[W + 2]

    # body→ECI direction cosines
    m00 = 1.0 - 2.0 * (q2 * q2 + q3 * q3)
    m01 = 2.0 * (q1 * q2 - q0 * q3)
    m02 = 2.0 * (q1 * q3 + q0 * q2)
    m10 = 2.0 * (q1 * q2 + q0 * q3)
    m11 = 1.0 - 2.0 * (q1 * q1 + q3 * q3)
    m12 = 2.0 * (q2 * q3 - q0 * q1)
    m20 = 2.0 * (q1 * q3 - q0 * q2)
    m21 = 2.0 * (q2 * q3 + q0 * q1)
    m22 = 1.0 - 2.0 * (q1 * q1 + q2 * q2)

    # ------------------------------------------------------------ environment
    th = omega_e * t
    ct, st = np.cos(th), np.sin(th)
    lat, lon, alt, sl, cl, so, co = earth.geodetic_xyz_sc(ct * rx + st * ry, -st * rx + ct * ry, rz,
                                                         p[P_RE], p[P_E2])
    o_atm, n_atm = tab(tb, T_ATM_ALT)
    temp, pres, rho, sos = atmosphere_at(alt, tb, o_atm, int(tb[2 * T_ATM_LNP]), int(tb[2 * T_ATM_LNRHO]), n_atm)
    order = p[P_GRAVITY_ORDER]
    gx, gy, gz = gravity.gravity_zonal_xyz(rx, ry, rz, p[P_MU], p[P_RE], p[P_J2] if order >= 2 else 0.0,
                                           p[P_J3] if order >= 3 else 0.0, p[P_J4] if order >= 4 else 0.0)
    # Earth-relative velocity v − ω_E ẑ × r, ECI axes
    ex = vx + omega_e * ry
    ey = vy - omega_e * rx
    ez = vz
    wn_n = wn_e = 0.0
    ax_ = ex
    ay_ = ey
    az_ = ez
    if p[P_WIND_SCALE] != 0.0:
        sc = p[P_WIND_SCALE]
        o_w, n_w = tab(tb, T_WIND_ALT)
        iw, ww = locate_at(tb, o_w, n_w, alt)
        o_n = int(tb[2 * T_WIND_NORTH]) + iw
        o_e = int(tb[2 * T_WIND_EAST]) + iw
        wn_n = sc * ((1.0 - ww) * tb[o_n] + ww * tb[o_n + 1])
        wn_e = sc * ((1.0 - ww) * tb[o_e] + ww * tb[o_e + 1])
        # NED → ECEF (north = (−sl·co, −sl·so, cl), east = (−so, co, 0)), then ECEF → ECI
        we_x = -sl * co * wn_n - so * wn_e
        we_y = -sl * so * wn_n + co * wn_e
        we_z = cl * wn_n
        ax_ -= ct * we_x - st * we_y
        ay_ -= st * we_x + ct * we_y
        az_ -= we_z
    # air-relative velocity in body axes (R^T v)
    ub = m00 * ax_ + m10 * ay_ + m20 * az_ - u[L.U_GUST]
    vb = m01 * ax_ + m11 * ay_ + m21 * az_ - u[L.U_GUST + 1]
    wb = m02 * ax_ + m12 * ay_ + m22 * az_ - u[L.U_GUST + 2]
    vair = np.sqrt(ub * ub + vb * vb + wb * wb)
    alpha = np.arctan2(wb, ub)
    beta = np.arcsin(vb / vair) if vair > 1e-6 else 0.0
    mach = vair / sos
    qbar = 0.5 * rho * vair * vair

    # ------------------------------------------------------- mass properties
    prop = x[MFS] if config == CONFIG_STACK else x[MLOX] + x[MLH2]
    o_mp, n_mp = tab(tb, T_MASS_PROP)
    nm = n_mp // N_CONFIG  # padded rows per configuration
    i0, wm_ = locate_at(tb, o_mp + config * nm, int(tb[int(tb[2 * T_MASS_LEN]) + config]), prop)
    r0 = int(tb[2 * T_MASS_DATA]) + (config * nm + i0) * N_MASS_COLS
    r1 = r0 + N_MASS_COLS
    a_ = 1.0 - wm_
    mass = a_ * tb[r0] + wm_ * tb[r1]
    cgx = a_ * tb[r0 + 1] + wm_ * tb[r1 + 1]
    cgy = a_ * tb[r0 + 2] + wm_ * tb[r1 + 2]
    cgz = a_ * tb[r0 + 3] + wm_ * tb[r1 + 3]
    ixx = a_ * tb[r0 + 4] + wm_ * tb[r1 + 4]
    iyy = a_ * tb[r0 + 5] + wm_ * tb[r1 + 5]
    izz = a_ * tb[r0 + 6] + wm_ * tb[r1 + 6]
    ixy = -(a_ * tb[r0 + 7] + wm_ * tb[r1 + 7])  # tensor element = −product of inertia
    ixz = -(a_ * tb[r0 + 8] + wm_ * tb[r1 + 8])
    iyz = -(a_ * tb[r0 + 9] + wm_ * tb[r1 + 9])
    mass_total = mass
    cgx_t, cgy_t, cgz_t = cgx, cgy, cgz

    # ------------------------------------------------- slosh masses (LOX, LH2)
    so = int(p[L.P_SLOSH_OFF])
    lvl0 = lvl1 = ws0 = ws1 = zs0 = zs1 = ms0 = ms1 = xs0 = xs1 = 0.0
    if so >= 0:
        lvl0, ws0, zs0, ms0, xs0 = slosh_tank(tb, p, 0, x[MLOX])
        lvl1, ws1, zs1, ms1, xs1 = slosh_tank(tb, p, 1, x[MLH2])
        # the rigid part leaves the slosh masses out (they sit on the tank centerlines)
        m_r = mass - ms0 - ms1
        cgx_r = (mass * cgx - ms0 * xs0 - ms1 * xs1) / m_r
        cgy_r = mass * cgy / m_r
        cgz_r = mass * cgz / m_r
        # remove each slosh mass (offset from the total CG), then move to the rigid CG
        for mj, dx, dy_, dz in ((ms0, -(xs0 - cgx), -cgy, cgz), (ms1, -(xs1 - cgx), -cgy, cgz),
                                (m_r, -(cgx_r - cgx), cgy_r - cgy, -(cgz_r - cgz))):
            ixx, iyy, izz, ixy, ixz, iyz = minus_point_mass(ixx, iyy, izz, ixy, ixz, iyz, mj, dx, dy_, dz)
        mass, cgx, cgy, cgz = m_r, cgx_r, cgy_r, cgz_r

    # ---------------------------------------------------------- aerodynamics
    fax = fay = faz = 0.0
    max_ = may = maz = 0.0
    if p[P_AERO_ON] != 0.0 and qbar > 0.0:
        o_m, n_m = tab(tb, T_AERO_MACH)
        o_a, n_a = tab(tb, T_AERO_ALPHA)
        o_b, n_b = tab(tb, T_AERO_BETA)
        im, wm = locate_at(tb, o_m, n_m, mach)
        ia, wa = locate_at(tb, o_a, n_a, alpha)
        ib, wb2 = locate_at(tb, o_b, n_b, beta)
        sj = n_b
        si = n_a * n_b
        blk = n_m * si  # one coefficient of one configuration
        base = int(tb[2 * T_AERO_COEF]) + config * N_COEF * blk
        ca = trilinear_at(tb, base, si, sj, im, wm, ia, wa, ib, wb2)
        cy = trilinear_at(tb, base + blk, si, sj, im, wm, ia, wa, ib, wb2)
        cn = trilinear_at(tb, base + 2 * blk, si, sj, im, wm, ia, wa, ib, wb2)
        c_roll = trilinear_at(tb, base + 3 * blk, si, sj, im, wm, ia, wa, ib, wb2)
        cm = trilinear_at(tb, base + 4 * blk, si, sj, im, wm, ia, wa, ib, wb2)
        cnn = trilinear_at(tb, base + 5 * blk, si, sj, im, wm, ia, wa, ib, wb2)
        rf = int(tb[2 * T_AERO_REF]) + config * N_AERO_REF  # S, lx, ly, lz, MRP xyz
        qs = qbar * tb[rf]
        o_bt, n_bt = tab(tb, T_BASE_TIME)
        nb = n_bt // N_CONFIG
        ib_, wb_ = locate_at(tb, o_bt + config * nb, int(tb[int(tb[2 * T_BASE_LEN]) + config]), t)
        o_bf = int(tb[2 * T_BASE_FORCE]) + config * nb + ib_
        f_base = (1.0 - wb_) * tb[o_bf] + wb_ * tb[o_bf + 1]
        fax = -qs * ca + f_base
        fay = qs * cy
        faz = -qs * cn
        # r_cg→mrp in body axes: diag(−1, 1, −1)(mrp − cg)
        rmx = -(tb[rf + 4] - cgx)
        rmy = tb[rf + 5] - cgy
        rmz = -(tb[rf + 6] - cgz)
        max_ = qs * tb[rf + 1] * c_roll + rmy * faz - rmz * fay
        may = qs * tb[rf + 2] * cm + rmz * fax - rmx * faz
        maz = qs * tb[rf + 3] * cnn + rmx * fay - rmy * fax

    # ------------------------------------------------------------- actuators
    if engine == ENGINE_FIRST:
        lim = p[P_FS_GIMBAL_LIMIT]
        g0_ = P_FS_GIMBAL_X
        e0_ = L.P_FS_ENG_M
        sp = L.P_SPX_FS
        wa_, wn_, z_, rl_ = p[P_ACT_FS_WA], p[P_ACT_FS_WN], p[P_ACT_FS_ZETA], p[P_ACT_FS_RATE]
        pg = L.PT_GIMBAL_FS
        gb_ = L.P_FS_GIMBAL_BIAS
    else:
        lim = p[P_US_GIMBAL_LIMIT]
        g0_ = P_US_GIMBAL_X
        e0_ = L.P_US_ENG_M
        sp = L.P_SPX_US
        wa_, wn_, z_, rl_ = p[P_ACT_US_WA], p[P_ACT_US_WN], p[P_ACT_US_ZETA], p[P_ACT_US_RATE]
        pg = L.PT_GIMBAL_US
        gb_ = L.P_US_GIMBAL_BIAS
    if int(p[L.P_ACT_KIND]) == L.ACT_SIMPLEX:
        vo = int(p[L.P_VALVE_OFF])
        ddp = actuator_simplex(x, ACT_P, vo, clip(u[U_DPC], lim), p, sp, xd)
        ddy = actuator_simplex(x, ACT_Y, vo + 2, clip(u[U_DYC], lim), p, sp, xd)
    else:
        actuator_third_order(x, ACT_P, clip(u[U_DPC], lim), wa_, wn_, z_, rl_, xd)
        actuator_third_order(x, ACT_Y, clip(u[U_DYC], lim), wa_, wn_, z_, rl_, xd)
        ddp, ddy = x[ACT_P + 2], x[ACT_Y + 2]
    if abs(x[ACT_P]) >= lim:  # held at the stop: no nozzle acceleration
        ddp = 0.0
    if abs(x[ACT_Y]) >= lim:
        ddy = 0.0
    xd[RCS_POS] = jet_ramp(x[RCS_POS], u[U_RCS] > 0.5, p[P_RCS_RAMP_UP], p[P_RCS_RAMP_DOWN])
    xd[RCS_NEG] = jet_ramp(x[RCS_NEG], u[U_RCS] < -0.5, p[P_RCS_RAMP_UP], p[P_RCS_RAMP_DOWN])

    # ------------------------------------------- flex rotation at the active gimbal
    fo = int(p[L.P_FLEX_OFF])
    nmod = int(p[L.P_N_MODES])
    sa = sb = 0
    wset = 0.0
    o_sh = nd = 0
    tgx = tgy = tgz = 0.0
    if fo >= 0:
        sa, sb, wset = flex_sets(x, config, p)
        o_sh = int(tb[2 * T_FLEX_SHAPE])
        nd = int(tb[2 * T_FLEX_ZETA + 1])
        for i in range(nmod):
            ia = o_sh + ((sa * nd + i) * L.N_POINTS + pg) * 6 + 3
            ib = o_sh + ((sb * nd + i) * L.N_POINTS + pg) * 6 + 3
            qi = x[fo + i]
            tgx += ((1.0 - wset) * tb[ia] + wset * tb[ib]) * qi
            tgy += ((1.0 - wset) * tb[ia + 1] + wset * tb[ib + 1]) * qi
            tgz += ((1.0 - wset) * tb[ia + 2] + wset * tb[ib + 2]) * qi

    # ---------------------------------------------------------------- thrust
    thrust = 0.0
    mdot_fs = 0.0
    mdot_us = 0.0
    if engine == ENGINE_FIRST:
        o_ft, n_ft = tab(tb, T_FS_TIME)
        f_vac = p[P_FS_THRUST_SCALE] * interp1_at(tb, o_ft, int(tb[2 * T_FS_THRUST]), n_ft, t)
        if x[MFS] > 0.0 and f_vac > 0.0:
            mdot_fs = f_vac / (G0 * p[P_FS_ISP_VAC])
            thrust = max(f_vac - pres * p[P_FS_EXIT_AREA], 0.0)
    elif engine == ENGINE_UPPER and x[MLOX] > 0.0 and x[MLH2] > 0.0:
        o_st, n_st = tab(tb, T_US_START_TIME)
        f_vac = interp1_at(tb, o_st, int(tb[2 * T_US_START_FRAC]), n_st, t - u[U_T_IGN]) * p[P_US_THRUST]
        mdot_us = f_vac / (G0 * p[P_US_ISP])
        thrust = max(f_vac - pres * p[P_US_EXIT_AREA], 0.0)
    if p[P_THRUST_ON] == 0.0:
        thrust = 0.0
    dp = clip(x[ACT_P], lim)
    dy = clip(x[ACT_Y], lim)
    # r_cg→gimbal, body axes
    rgx = -(p[g0_] - cgx)
    rgy = p[g0_ + 1] - cgy
    rgz = -(p[g0_ + 2] - cgz)
    ftx = fty = ftz = 0.0
    mtx = mty = mtz = 0.0
    if thrust > 0.0:
        # the thrust line is the actuator angle plus the nozzle's null bias (misalignment),
        # and turns with the structure's flex rotation at the gimbal (follower thrust)
        dpe, dye = dp + p[gb_] - tgy, dy + p[gb_ + 1] - tgz
        cdp, sdp = np.cos(dpe), np.sin(dpe)
        cdy, sdy = np.cos(dye), np.sin(dye)
        ftx = thrust * cdp * cdy
        fty = -thrust * sdy
        ftz = thrust * sdp * cdy
        mtx = rgy * ftz - rgz * fty
        mty = rgz * ftx - rgx * ftz
        mtz = rgx * fty - rgy * ftx

    # ------------------------------------------------ tail-wags-dog (engine inertia)
    # Reaction of the nozzle's angular acceleration on the vehicle at the gimbal: force
    # m_R l_R δ̈ and torque I_R δ̈ (source paper's assumptions: small angles, only the
    # angular-acceleration terms). About the CG: (I_R + m_R l_R l_c) δ̈ for an on-axis
    # gimbal. The translational effect of the force is neglected, as in the paper.
    fwx = fwy = fwz = 0.0
    twy = twz = 0.0
    mwx = mwy = mwz = 0.0
    if p[L.P_TWD_ON] != 0.0:
        m_l = p[e0_] * p[e0_ + 1]
        fwy = -m_l * ddy
        fwz = m_l * ddp
        twy = p[e0_ + 2] * ddp
        twz = p[e0_ + 2] * ddy
        mwx = rgy * fwz - rgz * fwy
        mwy = rgz * fwx - rgx * fwz + twy
        mwz = rgx * fwy - rgy * fwx + twz

    # ------------------------------------------------------------- roll jets
    o_ra, n_ra = tab(tb, T_RCS_ALT)
    f_jet = interp1_at(tb, o_ra, int(tb[2 * T_RCS_THRUST]), n_ra, alt) - pres * p[P_RCS_EXIT_AREA]
    if f_jet < 0.0:
        f_jet = 0.0
    rcs_torque = (x[RCS_POS] - x[RCS_NEG]) * p[P_RCS_N] * f_jet * p[P_RCS_ARM]

    # ------------------------------------------------------------ slosh forces
    fex, fey, fez = fax + ftx, fay + fty, faz + ftz  # external, non-gravitational
    fsx0 = fsy0 = fsz0 = fsx1 = fsy1 = fsz1 = 0.0
    msx = msy = msz = 0.0
    w_s0 = w_s1 = 0.0
    if so >= 0:
        f_mag = np.sqrt(fex * fex + fey * fey + fez * fez) / mass_total
        a_ratio = np.sqrt(f_mag / p[L.P_SLOSH_AREF])  # ω ∝ √a
        w_s0 = ws0 * a_ratio
        w_s1 = ws1 * a_ratio
        fx_spec = fex / mass_total  # axial specific force; the masses ride axially with the tank
        for j in range(2):
            k = so + 4 * j
            mj, wj, zj, xj = (ms0, w_s0, zs0, xs0) if j == 0 else (ms1, w_s1, zs1, xs1)
            # force of the slosh mass on the tank: spring and damper laterally, its axial inertia
            fy_ = mj * (wj * wj * x[k] + 2.0 * zj * wj * x[k + 2])
            fz_ = mj * (wj * wj * x[k + 1] + 2.0 * zj * wj * x[k + 3])
            fx_ = -mj * fx_spec
            rx_, ry_, rz_ = -(xj - cgx), x[k] - cgy, x[k + 1] + cgz  # rigid CG → slosh mass, body
            msx += ry_ * fz_ - rz_ * fy_
            msy += rz_ * fx_ - rx_ * fz_
            msz += rx_ * fy_ - ry_ * fx_
            if j == 0:
                fsx0, fsy0, fsz0 = fx_, fy_, fz_
            else:
                fsx1, fsy1, fsz1 = fx_, fy_, fz_

    # -------------------------------------------------------- rigid-body EOM
    fbx = fex + fsx0 + fsx1
    fby = fey + fsy0 + fsy1
    fbz = fez + fsz0 + fsz1
    abx = fbx / mass
    aby = fby / mass
    abz = fbz / mass
    xd[R] = vx
    xd[R + 1] = vy
    xd[R + 2] = vz
    xd[V] = m00 * abx + m01 * aby + m02 * abz + gx
    xd[V + 1] = m10 * abx + m11 * aby + m12 * abz + gy
    xd[V + 2] = m20 * abx + m21 * aby + m22 * abz + gz
    xd[Q] = 0.5 * (-q1 * wx - q2 * wy - q3 * wz)
    xd[Q + 1] = 0.5 * (q0 * wx + q2 * wz - q3 * wy)
    xd[Q + 2] = 0.5 * (q0 * wy - q1 * wz + q3 * wx)
    xd[Q + 3] = 0.5 * (q0 * wz + q1 * wy - q2 * wx)
    # H = I ω; ω̇ = I⁻¹ (M − ω × H)
    hx = ixx * wx + ixy * wy + ixz * wz
    hy = ixy * wx + iyy * wy + iyz * wz
    hz = ixz * wx + iyz * wy + izz * wz
    mx = max_ + mtx + mwx + msx + rcs_torque - (wy * hz - wz * hy)
    my = may + mty + mwy + msy - (wz * hx - wx * hz)
    mz = maz + mtz + mwz + msz - (wx * hy - wy * hx)
    alx, aly, alz = solve_sym3(ixx, iyy, izz, ixy, ixz, iyz, mx, my, mz)
    xd[W], xd[W + 1], xd[W + 2] = alx, aly, alz
    xd[MFS] = -mdot_fs
    xd[MLOX] = -mdot_us * p[P_US_MR] / (1.0 + p[P_US_MR])
    xd[MLH2] = -mdot_us / (1.0 + p[P_US_MR])

    # ------------------------------------------------- slosh-mass accelerations
    if so >= 0:
        for j in range(2):
            k = so + 4 * j
            wj, zj, xj = (w_s0, zs0, xs0) if j == 0 else (w_s1, zs1, xs1)
            rx_, ry_, rz_ = -(xj - cgx), x[k] - cgy, x[k + 1] + cgz
            vy_, vz_ = x[k + 2], x[k + 3]
            # specific force of the point of the rigid body where the mass sits, plus Coriolis:
            # f + α × r + ω × (ω × r) + 2 ω × v_rel   (lateral components)
            wdr = wx * rx_ + wy * ry_ + wz * rz_
            w2 = wx * wx + wy * wy + wz * wz
            ay_ = aby + (alz * rx_ - alx * rz_) + (wy * wdr - w2 * ry_) + 2.0 * (-wx * vz_)
            az_ = abz + (alx * ry_ - aly * rx_) + (wz * wdr - w2 * rz_) + 2.0 * (wx * vy_)
            xd[k] = vy_
            xd[k + 1] = vz_
            xd[k + 2] = -2.0 * zj * wj * vy_ - wj * wj * x[k] - ay_
            xd[k + 3] = -2.0 * zj * wj * vz_ - wj * wj * x[k + 1] - az_

    # ------------------------------------------------------ modal equations
    if fo >= 0:
        o_fz = int(tb[2 * T_FLEX_ZETA])
        o_ff = int(tb[2 * T_FLEX_FREQ])
        for i in range(nmod):
            wi = (1.0 - wset) * tb[o_ff + sa * nd + i] + wset * tb[o_ff + sb * nd + i]
            base_a = o_sh + (sa * nd + i) * L.N_POINTS * 6
            base_b = o_sh + (sb * nd + i) * L.N_POINTS * 6
            # generalized force Σ φ·F + σ·M over the loaded points
            gen = 0.0
            for pt in range(L.N_POINTS):
                if pt == pg:
                    f0, f1, f2 = ftx + fwx, fty + fwy, ftz + fwz
                    m0, m1, m2 = 0.0, twy, twz
                elif pt == L.PT_RCS:
                    f0 = f1 = f2 = 0.0
                    m0, m1, m2 = rcs_torque, 0.0, 0.0
                elif pt == L.PT_SLOSH_LOX:
                    f0, f1, f2 = fsx0, fsy0, fsz0
                    m0 = m1 = m2 = 0.0
                elif pt == L.PT_SLOSH_LH2:
                    f0, f1, f2 = fsx1, fsy1, fsz1
                    m0 = m1 = m2 = 0.0
                else:
                    continue
                ia = base_a + pt * 6
                ib = base_b + pt * 6
                gen += (((1.0 - wset) * tb[ia] + wset * tb[ib]) * f0
                        + ((1.0 - wset) * tb[ia + 1] + wset * tb[ib + 1]) * f1
                        + ((1.0 - wset) * tb[ia + 2] + wset * tb[ib + 2]) * f2
                        + ((1.0 - wset) * tb[ia + 3] + wset * tb[ib + 3]) * m0
                        + ((1.0 - wset) * tb[ia + 4] + wset * tb[ib + 4]) * m1
                        + ((1.0 - wset) * tb[ia + 5] + wset * tb[ib + 5]) * m2)
            qi = x[fo + i]
            qdi = x[fo + nmod + i]
            xd[fo + i] = qdi
            xd[fo + nmod + i] = gen - 2.0 * tb[o_fz + i] * wi * qdi - wi * wi * qi

    # ------------------------------------------------------------ diagnostics
    aux[A_ALT] = alt
    aux[A_LAT] = lat
    aux[A_LON] = lon
    aux[A_RHO] = rho
    aux[A_PRES] = pres
    aux[A_TEMP] = temp
    aux[A_SOS] = sos
    aux[A_MACH] = mach
    aux[A_QBAR] = qbar
    aux[A_ALPHA] = alpha
    aux[A_BETA] = beta
    aux[A_VREL] = vair
    aux[A_WIND_N] = wn_n
    aux[A_WIND_E] = wn_e
    aux[A_WIND_D] = 0.0
    aux[A_GRAV] = gx
    aux[A_GRAV + 1] = gy
    aux[A_GRAV + 2] = gz
    aux[A_THRUST] = thrust
    aux[A_MASS] = mass_total
    aux[A_FAERO] = fax
    aux[A_FAERO + 1] = fay
    aux[A_FAERO + 2] = faz
    aux[A_MAERO] = max_
    aux[A_MAERO + 1] = may
    aux[A_MAERO + 2] = maz
    aux[A_MTHRUST] = mtx
    aux[A_MTHRUST + 1] = mty
    aux[A_MTHRUST + 2] = mtz
    aux[A_RCS_TORQUE] = rcs_torque
    aux[A_PROP] = prop
    aux[A_CG] = cgx_t
    aux[A_CG + 1] = cgy_t
    aux[A_CG + 2] = cgz_t
    aux[A_DP] = dp
    aux[A_DY] = dy
    aux[A_VEARTH] = np.sqrt(ex * ex + ey * ey + ez * ez)
    aux[A_ACCEL] = abx
    aux[A_ACCEL + 1] = aby
    aux[A_ACCEL + 2] = abz
    aux[L.A_TWD] = mwx
    aux[L.A_TWD + 1] = mwy
    aux[L.A_TWD + 2] = mwz
    aux[L.A_DDP] = ddp
    aux[L.A_DDP + 1] = ddy
    aux[L.A_SLOSH_W] = w_s0
    aux[L.A_SLOSH_W + 1] = w_s1
    aux[L.A_LEVEL] = lvl0
    aux[L.A_LEVEL + 1] = lvl1
    aux[L.A_SLOSH_F] = fsx0
    aux[L.A_SLOSH_F + 1] = fsy0
    aux[L.A_SLOSH_F + 2] = fsz0
    aux[L.A_SLOSH_F + 3] = fsx1
    aux[L.A_SLOSH_F + 4] = fsy1
    aux[L.A_SLOSH_F + 5] = fsz1
    aux[L.A_FLEX_GIMBAL] = tgx
    aux[L.A_FLEX_GIMBAL + 1] = tgy
    aux[L.A_FLEX_GIMBAL + 2] = tgz
