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


# Packed layout: a header of two entries per PlantTables field (offset of the field's
# C-ordered data in the flat array, element count), then the data. T_* name the fields.
(T_AERO_MACH, T_AERO_ALPHA, T_AERO_BETA, T_AERO_COEF, T_AERO_REF, T_BASE_TIME, T_BASE_FORCE,
 T_BASE_LEN, T_MASS_PROP, T_MASS_DATA, T_MASS_LEN, T_FS_TIME, T_FS_THRUST, T_US_START_TIME,
 T_US_START_FRAC, T_RCS_ALT, T_RCS_THRUST, T_ATM_ALT, T_ATM_LNP, T_ATM_LNRHO, T_WIND_ALT,
 T_WIND_NORTH, T_WIND_EAST) = range(len(PlantTables._fields))
N_CONFIG = 3  # stack, upper stage with LES, upper stage
N_COEF = 6  # CA CY CN Cl Cm Cn
N_MASS_COLS = 10
N_AERO_REF = 7


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
    ub = m00 * ax_ + m10 * ay_ + m20 * az_
    vb = m01 * ax_ + m11 * ay_ + m21 * az_
    wb = m02 * ax_ + m12 * ay_ + m22 * az_
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
        lim = p[P_FS_GIMBAL_LIMIT]
        g0_ = P_FS_GIMBAL_X
    else:
        if engine == ENGINE_UPPER and x[MLOX] > 0.0 and x[MLH2] > 0.0:
            o_st, n_st = tab(tb, T_US_START_TIME)
            f_vac = interp1_at(tb, o_st, int(tb[2 * T_US_START_FRAC]), n_st, t - u[U_T_IGN]) * p[P_US_THRUST]
            mdot_us = f_vac / (G0 * p[P_US_ISP])
            thrust = max(f_vac - pres * p[P_US_EXIT_AREA], 0.0)
        lim = p[P_US_GIMBAL_LIMIT]
        g0_ = P_US_GIMBAL_X
    if p[P_THRUST_ON] == 0.0:
        thrust = 0.0
    dp = clip(x[ACT_P], lim)
    dy = clip(x[ACT_Y], lim)
    ftx = fty = ftz = 0.0
    mtx = mty = mtz = 0.0
    if thrust > 0.0:
        cdp, sdp = np.cos(dp), np.sin(dp)
        cdy, sdy = np.cos(dy), np.sin(dy)
        ftx = thrust * cdp * cdy
        fty = -thrust * sdy
        ftz = thrust * sdp * cdy
        rgx = -(p[g0_] - cgx)
        rgy = p[g0_ + 1] - cgy
        rgz = -(p[g0_ + 2] - cgz)
        mtx = rgy * ftz - rgz * fty
        mty = rgz * ftx - rgx * ftz
        mtz = rgx * fty - rgy * ftx

    # ------------------------------------------------------------- roll jets
    o_ra, n_ra = tab(tb, T_RCS_ALT)
    f_jet = interp1_at(tb, o_ra, int(tb[2 * T_RCS_THRUST]), n_ra, alt) - pres * p[P_RCS_EXIT_AREA]
    if f_jet < 0.0:
        f_jet = 0.0
    rcs_torque = (x[RCS_POS] - x[RCS_NEG]) * p[P_RCS_N] * f_jet * p[P_RCS_ARM]

    # -------------------------------------------------------- rigid-body EOM
    abx = (fax + ftx) / mass
    aby = (fay + fty) / mass
    abz = (faz + ftz) / mass
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
    mx = max_ + mtx + rcs_torque - (wy * hz - wz * hy)
    my = may + mty - (wz * hx - wx * hz)
    mz = maz + mtz - (wx * hy - wy * hx)
    xd[W], xd[W + 1], xd[W + 2] = solve_sym3(ixx, iyy, izz, ixy, ixz, iyz, mx, my, mz)
    xd[MFS] = -mdot_fs
    xd[MLOX] = -mdot_us * p[P_US_MR] / (1.0 + p[P_US_MR])
    xd[MLH2] = -mdot_us / (1.0 + p[P_US_MR])

    # ------------------------------------------------------------- actuators
    if engine == ENGINE_FIRST:
        wa_, wn_, z_, rl_ = p[P_ACT_FS_WA], p[P_ACT_FS_WN], p[P_ACT_FS_ZETA], p[P_ACT_FS_RATE]
    else:
        wa_, wn_, z_, rl_ = p[P_ACT_US_WA], p[P_ACT_US_WN], p[P_ACT_US_ZETA], p[P_ACT_US_RATE]
    actuator_third_order(x, ACT_P, clip(u[U_DPC], lim), wa_, wn_, z_, rl_, xd)
    actuator_third_order(x, ACT_Y, clip(u[U_DYC], lim), wa_, wn_, z_, rl_, xd)
    xd[RCS_POS] = jet_ramp(x[RCS_POS], u[U_RCS] > 0.5, p[P_RCS_RAMP_UP], p[P_RCS_RAMP_DOWN])
    xd[RCS_NEG] = jet_ramp(x[RCS_NEG], u[U_RCS] < -0.5, p[P_RCS_RAMP_UP], p[P_RCS_RAMP_DOWN])

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
    aux[A_MASS] = mass
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
    aux[A_CG] = cgx
    aux[A_CG + 1] = cgy
    aux[A_CG + 2] = cgz
    aux[A_DP] = dp
    aux[A_DY] = dy
    aux[A_VEARTH] = np.sqrt(ex * ex + ey * ey + ez * ez)
    aux[A_ACCEL] = abx
    aux[A_ACCEL + 1] = aby
    aux[A_ACCEL + 2] = abz
