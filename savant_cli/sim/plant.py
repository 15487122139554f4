"""The compiled continuous plant: rigid-body 6-DOF equations of motion in ECI with a
quaternion attitude, aerodynamics, gravity, gimbaled thrust, roll jets and actuators.

``derivative`` is the one function both the time simulation and (later) the
linearization call. It also fills ``aux`` with diagnostics (altitude, Mach, α …) so the
logger reports exactly what the dynamics used.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from savant_cli.models import earth, gravity, quaternion as qt
from savant_cli.models.atmosphere import atmosphere
from savant_cli.models.interp import locate, rows, trilinear
from savant_cli.sim.layout import (
    A_ACCEL, A_ALPHA, A_ALT, A_BETA, A_CG, A_DP, A_DY, A_FAERO, A_GRAV, A_LAT, A_LON,
    A_MACH, A_MAERO, A_MASS, A_MTHRUST, A_PRES, A_PROP, A_QBAR, A_RCS_TORQUE, A_RHO,
    A_SOS, A_TEMP, A_THRUST, A_VEARTH, A_VREL, A_WIND_D, A_WIND_E, A_WIND_N,
    ACT_P, ACT_Y, CONFIG_STACK, ENGINE_FIRST, ENGINE_UPPER, MFS, MLH2, MLOX, N_STATE,
    P_ACT_FS_RATE, P_ACT_FS_WA, P_ACT_FS_WN, P_ACT_FS_ZETA, P_ACT_US_RATE, P_ACT_US_WA,
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


@njit(cache=True)
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


@njit(cache=True)
def structure_to_body(v_s: np.ndarray) -> np.ndarray:
    """Direction transform structure → body: diag(-1, 1, -1)."""
    out = np.empty(3)
    out[0] = -v_s[0]
    out[1] = v_s[1]
    out[2] = -v_s[2]
    return out


@njit(cache=True)
def gimbal_direction(dp: float, dy: float) -> np.ndarray:
    """Thrust unit vector in body axes for pitch/yaw gimbal angles (rad)."""
    out = np.empty(3)
    out[0] = np.cos(dp) * np.cos(dy)
    out[1] = -np.sin(dy)
    out[2] = np.sin(dp) * np.cos(dy)
    return out


@njit(cache=True)
def first_stage_thrust_vac(t: float, p: np.ndarray, tb: PlantTables) -> float:
    """First-stage vacuum thrust (N) at mission time ``t`` (s)."""
    return p[P_FS_THRUST_SCALE] * np.interp(t, tb.fs_time, tb.fs_thrust)


@njit(cache=True)
def actuator_third_order(xa: np.ndarray, cmd: float, wa: float, wn: float, zeta: float,
                         rate_limit: float, out: np.ndarray, k: int) -> None:
    """Third-order TVC actuator: rate-limited position loop driving a 2nd-order load.

    States ``[δ, δ̇, δ̈]``; ``v = sat(ωa (δc − δ), ±rate_limit)`` is the commanded rate and
    ``δ⃛ = ωn² (v − δ̇) − 2 ζ ωn δ̈``. Unsaturated, δ/δc = ωa ωn² / (s(s² + 2ζωn s + ωn²) + ωa ωn²).
    """
    v = wa * (cmd - xa[0])
    if v > rate_limit:
        v = rate_limit
    elif v < -rate_limit:
        v = -rate_limit
    out[k] = xa[1]
    out[k + 1] = xa[2]
    out[k + 2] = wn * wn * (v - xa[1]) - 2.0 * zeta * wn * xa[2]


@njit(cache=True)
def clip(x: float, lim: float) -> float:
    if x > lim:
        return lim
    if x < -lim:
        return -lim
    return x


@njit(cache=True)
def jet_ramp(frac: float, on: bool, ramp_up_s: float, ramp_down_s: float) -> float:
    """Rate of the jet thrust fraction: linear ramp up to 1 when open, down to 0 when shut."""
    if on:
        return 1.0 / ramp_up_s if frac < 1.0 else 0.0
    return -1.0 / ramp_down_s if frac > 0.0 else 0.0


@njit(cache=True)
def derivative(t: float, x: np.ndarray, u: np.ndarray, p: np.ndarray, tb: PlantTables,
               aux: np.ndarray) -> np.ndarray:
    """Time derivative of the continuous state.

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
    tb : PlantTables
        Tabular data.
    aux : ndarray (N_AUX,)
        Filled with diagnostics of this evaluation.
    """
    xd = np.zeros(N_STATE)
    r = x[R:R + 3]
    v = x[V:V + 3]
    q = x[Q:Q + 4]
    w = x[W:W + 3]
    config = int(u[U_CONFIG])
    engine = int(u[U_ENGINE])
    omega_e = p[P_OMEGA_E]

    # ------------------------------------------------------------ environment
    c_i2e = earth.dcm_eci_to_ecef(t, omega_e)
    r_ecef = c_i2e @ r
    lat, lon, alt = earth.ecef_to_geodetic(r_ecef, p[P_RE], p[P_E2])
    temp, pres, rho, sos = atmosphere(alt, tb.atm_alt, tb.atm_lnp, tb.atm_lnrho)
    order = p[P_GRAVITY_ORDER]
    g = gravity.gravity_zonal(r, p[P_MU], p[P_RE], p[P_J2] if order >= 2 else 0.0,
                              p[P_J3] if order >= 3 else 0.0, p[P_J4] if order >= 4 else 0.0)
    v_earth = earth.velocity_relative_eci(r, v, omega_e)
    wind_n = np.zeros(3)
    wind_i = np.zeros(3)
    if p[P_WIND_SCALE] != 0.0:
        wind_n = earth.wind_ned(alt, tb.wind_alt, tb.wind_north, tb.wind_east, p[P_WIND_SCALE])
        c_e2n = earth.dcm_ecef_to_ned(lat, lon)
        wind_i = c_i2e.T @ (c_e2n.T @ wind_n)
    v_air_i = v_earth - wind_i
    c_b2i = qt.dcm(q)
    v_air_b = c_b2i.T @ v_air_i
    vair = np.sqrt(v_air_b[0] ** 2 + v_air_b[1] ** 2 + v_air_b[2] ** 2)
    alpha = np.arctan2(v_air_b[2], v_air_b[0])
    beta = np.arcsin(v_air_b[1] / vair) if vair > 1e-6 else 0.0
    mach = vair / sos
    qbar = 0.5 * rho * vair * vair

    # ------------------------------------------------------- mass properties
    if config == CONFIG_STACK:
        prop = x[MFS]
    else:
        prop = x[MLOX] + x[MLH2]
    mass, cg_s, inertia = mass_properties(tb, config, prop)

    # ---------------------------------------------------------- aerodynamics
    f_aero = np.zeros(3)
    m_aero = np.zeros(3)
    if p[P_AERO_ON] != 0.0 and qbar > 0.0:
        im, wm = locate(tb.aero_mach, tb.aero_mach.size, mach)
        ia, wa = locate(tb.aero_alpha, tb.aero_alpha.size, alpha)
        ib, wb = locate(tb.aero_beta, tb.aero_beta.size, beta)
        c = np.empty(6)
        for k in range(6):
            c[k] = trilinear(tb.aero_coef[config, k], im, wm, ia, wa, ib, wb)
        ref = tb.aero_ref[config]
        qs = qbar * ref[0]
        nb = tb.base_len[config]
        f_base = np.interp(t, tb.base_time[config, :nb], tb.base_force[config, :nb])
        f_aero[0] = -qs * c[0] + f_base
        f_aero[1] = qs * c[1]
        f_aero[2] = -qs * c[2]
        r_mrp = structure_to_body(ref[4:7] - cg_s)
        m_aero[0] = qs * ref[1] * c[3]
        m_aero[1] = qs * ref[2] * c[4]
        m_aero[2] = qs * ref[3] * c[5]
        m_aero += np.cross(r_mrp, f_aero)

    # ---------------------------------------------------------------- thrust
    thrust = 0.0
    mdot_fs = 0.0
    mdot_us = 0.0
    f_thr = np.zeros(3)
    m_thr = np.zeros(3)
    dp = 0.0
    dy = 0.0
    if engine == ENGINE_FIRST:
        f_vac = first_stage_thrust_vac(t, p, tb)
        if x[MFS] > 0.0 and f_vac > 0.0:
            mdot_fs = f_vac / (G0 * p[P_FS_ISP_VAC])
            thrust = max(f_vac - pres * p[P_FS_EXIT_AREA], 0.0)
        lim = p[P_FS_GIMBAL_LIMIT]
        gimbal_s = p[P_FS_GIMBAL_X:P_FS_GIMBAL_X + 3]
    else:
        if engine == ENGINE_UPPER and x[MLOX] > 0.0 and x[MLH2] > 0.0:
            frac = np.interp(t - u[U_T_IGN], tb.us_start_time, tb.us_start_frac)
            f_vac = frac * p[P_US_THRUST]
            mdot_us = f_vac / (G0 * p[P_US_ISP])
            thrust = max(f_vac - pres * p[P_US_EXIT_AREA], 0.0)
        lim = p[P_US_GIMBAL_LIMIT]
        gimbal_s = p[P_US_GIMBAL_X:P_US_GIMBAL_X + 3]
    if p[P_THRUST_ON] == 0.0:
        thrust = 0.0
    dp = clip(x[ACT_P], lim)
    dy = clip(x[ACT_Y], lim)
    if thrust > 0.0:
        f_thr = thrust * gimbal_direction(dp, dy)
        m_thr = np.cross(structure_to_body(gimbal_s - cg_s), f_thr)

    # ------------------------------------------------------------- roll jets
    altc = alt if alt > 0.0 else 0.0
    f_jet = np.interp(altc, tb.rcs_alt, tb.rcs_thrust) - pres * p[P_RCS_EXIT_AREA]
    if f_jet < 0.0:
        f_jet = 0.0
    rcs_torque = (x[RCS_POS] - x[RCS_NEG]) * p[P_RCS_N] * f_jet * p[P_RCS_ARM]

    # -------------------------------------------------------- rigid-body EOM
    f_body = f_aero + f_thr
    accel_b = f_body / mass
    xd[R:R + 3] = v
    xd[V:V + 3] = c_b2i @ accel_b + g
    xd[Q:Q + 4] = qt.derivative(q, w)
    moment = m_aero + m_thr
    moment[0] += rcs_torque
    xd[W:W + 3] = np.linalg.solve(inertia, moment - np.cross(w, inertia @ w))
    xd[MFS] = -mdot_fs
    xd[MLOX] = -mdot_us * p[P_US_MR] / (1.0 + p[P_US_MR])
    xd[MLH2] = -mdot_us / (1.0 + p[P_US_MR])

    # ------------------------------------------------------------- actuators
    if engine == ENGINE_FIRST:
        wa_, wn_, z_, rl_ = p[P_ACT_FS_WA], p[P_ACT_FS_WN], p[P_ACT_FS_ZETA], p[P_ACT_FS_RATE]
    else:
        wa_, wn_, z_, rl_ = p[P_ACT_US_WA], p[P_ACT_US_WN], p[P_ACT_US_ZETA], p[P_ACT_US_RATE]
    actuator_third_order(x[ACT_P:ACT_P + 3], clip(u[U_DPC], lim), wa_, wn_, z_, rl_, xd, ACT_P)
    actuator_third_order(x[ACT_Y:ACT_Y + 3], clip(u[U_DYC], lim), wa_, wn_, z_, rl_, xd, ACT_Y)

    # ------------------------------------------------------ jet thrust ramps
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
    aux[A_WIND_N] = wind_n[0]
    aux[A_WIND_E] = wind_n[1]
    aux[A_WIND_D] = wind_n[2]
    aux[A_GRAV:A_GRAV + 3] = g
    aux[A_THRUST] = thrust
    aux[A_MASS] = mass
    aux[A_FAERO:A_FAERO + 3] = f_aero
    aux[A_MAERO:A_MAERO + 3] = m_aero
    aux[A_MTHRUST:A_MTHRUST + 3] = m_thr
    aux[A_RCS_TORQUE] = rcs_torque
    aux[A_PROP] = prop
    aux[A_CG:A_CG + 3] = cg_s
    aux[A_DP] = dp
    aux[A_DY] = dy
    aux[A_VEARTH] = np.sqrt(v_earth[0] ** 2 + v_earth[1] ** 2 + v_earth[2] ** 2)
    aux[A_ACCEL:A_ACCEL + 3] = accel_b
    return xd
