"""Rigid-body equations of motion: translation of the CG in ECI, attitude quaternion and
Euler's rotational equation in body axes.

States (SI)::

    r   CG position, ECI, m                  ṙ = v
    v   CG inertial velocity, ECI, m/s       v̇ = C_b2i f_b / m + g(r)
    q   attitude q_b2i, scalar first         q̇ = ½ q ⊗ [0, ω]
    ω   body rate relative to ECI, body      I ω̇ = M − ω × (I ω)

``f_b`` is the non-gravitational force on the rigid part (aerodynamics, thrust, slosh
reactions), ``M`` the moment about its CG. The inertia tensor is frozen over a step: the
İω term of a variable-mass body is left out, as in the source paper (SAVANT §III; the
jet-damping and mass-flow terms are small for the rates of a controlled ascent). The
reference point is the CG of the current configuration (of its rigid part with slosh on,
``docs/models.md``); when that CG moves in the structure (separation, LES jettison, the
start with slosh on) :func:`move_reference` moves ``r`` and ``v`` with it, so every point
of the structure keeps its position and velocity.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks, quaternion as qt

_STATE = blocks.STATE.block("rigid_body")
R = _STATE.array("position", 3, "m", "CG position, ECI")
V = _STATE.array("velocity", 3, "m/s", "CG inertial velocity, ECI")
Q = _STATE.array("attitude", 4, "1", "attitude quaternion q_b2i (body→ECI, scalar first)")
W = _STATE.array("body_rate", 3, "rad/s", "body angular rate relative to ECI, body axes")
_AUX = blocks.DIAGNOSTICS.block("rigid_body")
A_ACCEL = _AUX.array("sensed_acceleration", 3, "m/s^2", "non-gravitational acceleration",  # of the rigid part
                     blocks.Logged("sensed_acceleration", ("x", "y", "z"), "body"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, ax: float, ay: float, az: float) -> None:
    """Write the rigid part's non-gravitational acceleration (m/s², body axes) into ``aux``."""
    aux[A_ACCEL] = ax
    aux[A_ACCEL + 1] = ay
    aux[A_ACCEL + 2] = az


STATE_NAMES = ("r_eci_x", "r_eci_y", "r_eci_z", "v_eci_x", "v_eci_y", "v_eci_z", "q_w", "q_x", "q_y", "q_z",
               "p", "q", "r")


@njit(cache=True, error_model="numpy", inline="always")
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


@njit(cache=True, error_model="numpy", inline="always")
def angular_acceleration(inertia_kgm2: tuple[float, float, float, float, float, float],
                         rate_rad_s: tuple[float, float, float],
                         moment_nm: tuple[float, float, float]) -> tuple[float, float, float]:
    """Euler's equation ``ω̇ = I⁻¹ (M − ω × I ω)``, body axes.

    Parameters
    ----------
    inertia_kgm2 : tuple of 6 float
        ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``: the inertia tensor about the CG, body axes,
        kg·m² (off-diagonal: tensor elements, the negative products of inertia).
    rate_rad_s : tuple of 3 float
        Body rate ω, rad/s.
    moment_nm : tuple of 3 float
        External moment about the CG, body axes, N·m.

    Returns
    -------
    tuple of float
        ω̇, rad/s².
    """
    ixx, iyy, izz, ixy, ixz, iyz = inertia_kgm2
    wx, wy, wz = rate_rad_s
    mx, my, mz = moment_nm
    hx = ixx * wx + ixy * wy + ixz * wz
    hy = ixy * wx + iyy * wy + iyz * wz
    hz = ixz * wx + iyz * wy + izz * wz
    return solve_sym3(ixx, iyy, izz, ixy, ixz, iyz, mx - (wy * hz - wz * hy), my - (wz * hx - wx * hz),
                      mz - (wx * hy - wy * hx))


@njit(cache=True, error_model="numpy", inline="always")
def inertial_acceleration(m00, m01, m02, m10, m11, m12, m20, m21, m22, abx, aby, abz, gx, gy, gz):
    """``v̇ = C_b2i a_b + g``: the body-axis specific force ``a_b`` (m/s²) turned into ECI
    by the direction cosines ``m_ij`` of q_b2i, plus gravity (ECI, m/s²)."""
    return (m00 * abx + m01 * aby + m02 * abz + gx,
            m10 * abx + m11 * aby + m12 * abz + gy,
            m20 * abx + m21 * aby + m22 * abz + gz)


@njit(cache=True, error_model="numpy")
def move_reference(x, dsx: float, dsy: float, dsz: float) -> None:
    """Move the state's reference point by ``(dsx, dsy, dsz)`` (m, structure axes: x aft,
    y, z as the vehicle data): ``r += C_b2i Δ`` and ``v += C_b2i (ω × Δ)`` with
    ``Δ = (−dsx, dsy, −dsz)`` in body axes, so the structure's points keep their
    positions and velocities (a rigid body's velocity field)."""
    dbx, dby, dbz = -dsx, dsy, -dsz
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = qt.dcm_xyz(x[Q], x[Q + 1], x[Q + 2], x[Q + 3])
    wx, wy, wz = x[W], x[W + 1], x[W + 2]
    ux, uy, uz = wy * dbz - wz * dby, wz * dbx - wx * dbz, wx * dby - wy * dbx  # ω × Δ
    x[R] += m00 * dbx + m01 * dby + m02 * dbz
    x[R + 1] += m10 * dbx + m11 * dby + m12 * dbz
    x[R + 2] += m20 * dbx + m21 * dby + m22 * dbz
    x[V] += m00 * ux + m01 * uy + m02 * uz
    x[V + 1] += m10 * ux + m11 * uy + m12 * uz
    x[V + 2] += m20 * ux + m21 * uy + m22 * uz
