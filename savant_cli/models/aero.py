"""Aerodynamics: air data, tabular static coefficients and the base force.

Air data from the air-relative velocity ``(u, v, w)`` in body axes (m/s)::

    V = |(u, v, w)|,  α = atan2(w, u),  β = asin(v / V),  M = V / a,  q̄ = ½ ρ V²

Force and moment (body axes; coefficients from the vehicle's tables, interpolated
trilinearly in Mach, α and β and held beyond the table)::

    F = q̄ S (−C_A, C_Y, −C_N) + (F_base, 0, 0)
    M_cg = q̄ S (l_x C_l, l_y C_m, l_z C_n) + r_cg→mrp × F

The coefficients are about the moment reference point (MRP, structure frame); the
structure frame has x aft from the nose, z up, so ``r_cg→mrp = diag(−1, 1, −1)(mrp − cg)``
in body axes. The base force (N along body X) is a table against mission time per
configuration. The configurations' tables are resampled onto one common grid
(lossless for a multilinear interpolant; see :func:`common_grid`). Source: SAVANT §III,
"Aerodynamics"; the default tables are generated (``datagen/ares_i_tables.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import locate_at, tab, tab_offset, trilinear_at
from savant_cli.vehicle import AERO_COEFFICIENTS

C_CA, C_CY, C_CN, C_ROLL, C_PITCH, C_YAW = range(len(AERO_COEFFICIENTS))  # the coefficient axis
N_COEF = len(AERO_COEFFICIENTS)
REFERENCE = blocks.Record(
    "aerodynamic reference",
    ("area", "m^2", "reference area S"),
    ("length_x", "m", "roll reference length"),
    ("length_y", "m", "pitch reference length"),
    ("length_z", "m", "yaw reference length"),
    ("mrp_x", "m", "moment reference point, structure x"),
    ("mrp_y", "m", "moment reference point, structure y"),
    ("mrp_z", "m", "moment reference point, structure z"),
)
REF_AREA, REF_LX, REF_LY, REF_LZ, REF_MRP_X, REF_MRP_Y, REF_MRP_Z = REFERENCE.offsets
N_REF = REFERENCE.size

_PARAMS = blocks.PARAMETERS.block("aero")
P_ON = _PARAMS.scalar("on", "1", "1: aerodynamic force and moment applied (environment.aero)")
_TABLES = blocks.TABLES.block("aero")
T_MACH = _TABLES.table("aero_mach", "1", "(nM,) Mach breakpoints, common to the configurations")
T_ALPHA = _TABLES.table("aero_alpha", "rad", "(nA,) angle-of-attack breakpoints")
T_BETA = _TABLES.table("aero_beta", "rad", "(nB,) sideslip breakpoints")
T_COEF = _TABLES.table("aero_coef", "1", "(configurations, 6 COEFFICIENTS, nM, nA, nB) coefficients")
T_REF = _TABLES.table("aero_ref", "m^2, m", "(configurations, REFERENCE) reference area, lengths and MRP per "
                      "configuration")
T_BASE_TIME = _TABLES.table("base_time", "s", "(configurations, nb) base-force time axis per configuration (padded)")
T_BASE_FORCE = _TABLES.table("base_force", "N", "(configurations, nb) base force along body X")
T_BASE_LEN = _TABLES.table("base_len", "1", "(3,) valid rows of each base-force table")
_AUX = blocks.DIAGNOSTICS.block("aero")
A_MACH = _AUX.scalar("mach", "1", "Mach number", blocks.Logged("mach"))
A_QBAR = _AUX.scalar("dynamic_pressure", "Pa", "dynamic pressure", blocks.Logged("dynamic_pressure"))
A_ALPHA = _AUX.scalar("alpha", "rad", "angle of attack", blocks.Logged("alpha"))
A_BETA = _AUX.scalar("beta", "rad", "sideslip angle", blocks.Logged("beta"))
A_VREL = _AUX.scalar("air_speed", "m/s", "air-relative speed (Earth-relative minus wind)",
                     blocks.Logged("velocity_relative"))
A_FORCE = _AUX.array("force", 3, "N", "aerodynamic force incl. base force",
                     blocks.Logged("aero_force", ("x", "y", "z"), "body"))
A_MOMENT = _AUX.array("moment", 3, "N*m", "aerodynamic moment about the CG",
                      blocks.Logged("aero_moment", ("x", "y", "z"), "body"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, mach: float, qbar: float, alpha: float, beta: float, vair: float,
                      fx: float, fy: float, fz: float, mx: float, my: float, mz: float) -> None:
    """Write the air data (Mach, dynamic pressure Pa, α and β rad, air speed m/s) and the
    aerodynamic force (N) and moment about the CG (N·m), body axes, into ``aux``."""
    aux[A_MACH] = mach
    aux[A_QBAR] = qbar
    aux[A_ALPHA] = alpha
    aux[A_BETA] = beta
    aux[A_VREL] = vair
    aux[A_FORCE] = fx
    aux[A_FORCE + 1] = fy
    aux[A_FORCE + 2] = fz
    aux[A_MOMENT] = mx
    aux[A_MOMENT + 1] = my
    aux[A_MOMENT + 2] = mz


_GRID_CACHE: list[tuple[tuple, tuple]] = []  # (the aero objects, the resampled grid), newest last


def common_grid(vehicle) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The configurations' aero tables resampled onto the union of their axes.

    Multilinear interpolation of a multilinear interpolant at refined nodes reproduces it
    exactly, and clamping outside a table is the same before and after, so this is
    lossless; it lets the kernel hold one (configurations, 6, nM, nA, nB) array. The result is kept
    for the same (immutable) aero objects, so a batch of models of one vehicle resamples
    once; callers must not modify the returned arrays in place.

    Returns
    -------
    tuple of ndarray
        Mach, α (rad), β (rad), coefficients (configurations, 6, nM, nA, nB), reference (configurations, 7).
    """
    aeros = tuple(c.aero for c in vehicle.configurations.values())
    for key, grid in _GRID_CACHE:
        if all(a is b for a, b in zip(key, aeros)):
            return grid
    grid = _resample(aeros)
    for arr in grid:
        arr.setflags(write=False)  # shared between models: an in-place change would leak
    _GRID_CACHE.append((aeros, grid))
    del _GRID_CACHE[:-4]
    return grid


def _resample(aeros: tuple):
    from scipy.interpolate import RegularGridInterpolator

    mach = np.unique(np.concatenate([a.mach for a in aeros]))
    alpha = np.unique(np.concatenate([a.alpha_rad for a in aeros]))
    beta = np.unique(np.concatenate([a.beta_rad for a in aeros]))
    mg, ag, bg = np.meshgrid(mach, alpha, beta, indexing="ij")
    coef = np.empty((len(aeros), N_COEF, mach.size, alpha.size, beta.size))
    for c, a in enumerate(aeros):
        pts = np.stack([np.clip(mg, a.mach[0], a.mach[-1]),
                        np.clip(ag, a.alpha_rad[0], a.alpha_rad[-1]),
                        np.clip(bg, a.beta_rad[0], a.beta_rad[-1])], axis=-1)
        for k in range(N_COEF):
            f = RegularGridInterpolator((a.mach, a.alpha_rad, a.beta_rad), a.coeffs[k])
            coef[c, k] = f(pts)
    ref = np.array([[a.area_m2, *a.lref_m, *a.mrp_m] for a in aeros])
    return mach, alpha, beta, np.ascontiguousarray(coef), ref


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """Coefficients on the common grid, references and base forces; ``environment.aero``."""
    p[P_ON] = 1.0 if inputs.cfg.environment.aero else 0.0
    mach, alpha, beta, coef, ref = common_grid(inputs.vehicle)
    aeros = [c.aero for c in inputs.vehicle.configurations.values()]
    base_time, base_len = blocks.stack_padded([a.base_time_s for a in aeros])
    base_force, _ = blocks.stack_padded([a.base_force_N for a in aeros])
    tables.update(aero_mach=mach, aero_alpha=alpha, aero_beta=beta, aero_coef=coef, aero_ref=ref,
                  base_time=base_time, base_force=base_force, base_len=base_len)


def reference(tb: np.ndarray, config: int) -> np.ndarray:
    """The :data:`REFERENCE` record of a configuration from packed tables (Python)."""
    start = tab_offset(tb, T_REF) + config * N_REF
    return tb[start:start + N_REF]


@njit(cache=True, error_model="numpy", inline="always")
def air_data(ub: float, vb: float, wb: float, rho: float, sos: float):
    """``(V m/s, α rad, β rad, Mach, q̄ Pa)`` of the air-relative velocity (body axes, m/s)
    at density ``rho`` (kg/m³) and speed of sound ``sos`` (m/s)."""
    vair = np.sqrt(ub * ub + vb * vb + wb * wb)
    alpha = np.arctan2(wb, ub)
    beta = np.arcsin(vb / vair) if vair > 1e-6 else 0.0
    return vair, alpha, beta, vair / sos, 0.5 * rho * vair * vair


@njit(cache=True, error_model="numpy", inline="always")
def base_force(tb: np.ndarray, config: int, t: float) -> float:
    """Base force along body X (N) of a configuration at mission time ``t`` (s)."""
    o_bt, n_bt = tab(tb, T_BASE_TIME)
    nb = n_bt // tab(tb, T_BASE_LEN)[1]  # padded rows per configuration
    ib_, wb_ = locate_at(tb, o_bt + config * nb, int(tb[tab_offset(tb, T_BASE_LEN) + config]), t)
    o_bf = tab_offset(tb, T_BASE_FORCE) + config * nb + ib_
    return (1.0 - wb_) * tb[o_bf] + wb_ * tb[o_bf + 1]


@njit(cache=True, error_model="numpy", inline="always")
def coefficients(tb: np.ndarray, config: int, mach: float, alpha: float, beta: float):
    """``(C_A, C_Y, C_N, C_l, C_m, C_n)`` of a configuration at Mach, α (rad), β (rad):
    trilinear in the common grid, held beyond it."""
    o_m, n_m = tab(tb, T_MACH)
    o_a, n_a = tab(tb, T_ALPHA)
    o_b, n_b = tab(tb, T_BETA)
    im, wm = locate_at(tb, o_m, n_m, mach)
    ia, wa = locate_at(tb, o_a, n_a, alpha)
    ib, wb = locate_at(tb, o_b, n_b, beta)
    sj = n_b
    si = n_a * n_b
    blk = n_m * si  # one coefficient of one configuration
    base = tab_offset(tb, T_COEF) + config * N_COEF * blk
    return (trilinear_at(tb, base + C_CA * blk, si, sj, im, wm, ia, wa, ib, wb),
            trilinear_at(tb, base + C_CY * blk, si, sj, im, wm, ia, wa, ib, wb),
            trilinear_at(tb, base + C_CN * blk, si, sj, im, wm, ia, wa, ib, wb),
            trilinear_at(tb, base + C_ROLL * blk, si, sj, im, wm, ia, wa, ib, wb),
            trilinear_at(tb, base + C_PITCH * blk, si, sj, im, wm, ia, wa, ib, wb),
            trilinear_at(tb, base + C_YAW * blk, si, sj, im, wm, ia, wa, ib, wb))


@njit(cache=True, error_model="numpy")
def coefficients_at(tb: np.ndarray, config: int, mach: float, alpha: float, beta: float):
    """:func:`coefficients` for Python callers (the data generators)."""
    return coefficients(tb, config, mach, alpha, beta)


@njit(cache=True, error_model="numpy", inline="always")
def aero_loads(tb: np.ndarray, p: np.ndarray, config: int, t: float, mach: float, alpha: float, beta: float,
               qbar: float, cgx: float, cgy: float, cgz: float):
    """Aerodynamic force (N) and moment about the CG (N·m), body axes.

    ``cgx, cgy, cgz`` is the CG of the rigid part in the structure frame (m). Zero when
    aerodynamics are off or ``q̄ = 0``. Returns ``(Fx, Fy, Fz, Mx, My, Mz)``.
    """
    if p[P_ON] == 0.0 or not qbar > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ca, cy, cn, c_roll, cm, cnn = coefficients(tb, config, mach, alpha, beta)
    rf = tab_offset(tb, T_REF) + config * N_REF
    qs = qbar * tb[rf + REF_AREA]
    fax = -qs * ca + base_force(tb, config, t)
    fay = qs * cy
    faz = -qs * cn
    # r_cg→mrp in body axes: diag(−1, 1, −1)(mrp − cg)
    rmx = -(tb[rf + REF_MRP_X] - cgx)
    rmy = tb[rf + REF_MRP_Y] - cgy
    rmz = -(tb[rf + REF_MRP_Z] - cgz)
    return (fax, fay, faz,
            qs * tb[rf + REF_LX] * c_roll + rmy * faz - rmz * fay,
            qs * tb[rf + REF_LY] * cm + rmz * fax - rmx * faz,
            qs * tb[rf + REF_LZ] * cnn + rmx * fay - rmy * fax)
