"""Hamilton quaternion algebra, scalar first ``[w, x, y, z]``.

Convention (see docs/architecture.md): an attitude quaternion ``q_b2i`` rotates body
vectors into the inertial frame, ``v_i = q ⊗ v_b ⊗ q*``; its direction-cosine matrix
``dcm(q)`` is body→inertial, and the kinematics are ``q̇ = ½ q ⊗ [0, ω_body]``.
All functions are compiled with numba and allocate only their small results; the
``*_xyz`` kernels take and return scalars and allocate nothing (the flight software's
50-Hz cycle uses them). Each array function is a thin wrapper of its scalar kernel: one
copy of every formula.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def qmul_xyz(a0: float, a1: float, a2: float, a3: float, b0: float, b1: float, b2: float,
             b3: float) -> tuple[float, float, float, float]:
    """Hamilton product ``a ⊗ b`` on scalars (scalar parts first)."""
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


@njit(cache=True, error_model="numpy")
def qmul_into(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """Hamilton product ``a ⊗ b`` written into ``out`` (no allocation; ``out`` must not
    alias ``a`` or ``b``)."""
    p0, p1, p2, p3 = qmul_xyz(a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3])
    out[0] = p0  # one store per element: a tuple unpacked into array items compiles slower
    out[1] = p1
    out[2] = p2
    out[3] = p3


@njit(cache=True, error_model="numpy")
def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a ⊗ b``."""
    out = np.empty(4)
    qmul_into(a, b, out)
    return out


@njit(cache=True, error_model="numpy")
def qconj(q: np.ndarray) -> np.ndarray:
    """Conjugate (the inverse of a unit quaternion)."""
    out = np.empty(4)
    out[0] = q[0]
    out[1] = -q[1]
    out[2] = -q[2]
    out[3] = -q[3]
    return out


@njit(cache=True, error_model="numpy", inline="always")
def normalize_xyz(q0: float, q1: float, q2: float, q3: float) -> tuple[float, float, float, float]:
    """Unit quaternion in the same direction, with a non-negative scalar part (scalars)."""
    n = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    s = 1.0 / n if q0 >= 0.0 else -1.0 / n
    return q0 * s, q1 * s, q2 * s, q3 * s


@njit(cache=True, error_model="numpy")
def qnormalize(q: np.ndarray) -> np.ndarray:
    """Unit quaternion in the same direction, with a non-negative scalar part."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = normalize_xyz(q[0], q[1], q[2], q[3])
    return out


@njit(cache=True, error_model="numpy", inline="always")
def dcm_xyz(q0: float, q1: float, q2: float, q3: float):
    """Direction cosines of a unit quaternion (scalar first) as nine scalars, row by row:
    ``m_ij`` of the matrix that maps vectors of the rotated frame into the reference
    frame (body→ECI for q_b2i)."""
    return (1.0 - 2.0 * (q2 * q2 + q3 * q3), 2.0 * (q1 * q2 - q0 * q3), 2.0 * (q1 * q3 + q0 * q2),
            2.0 * (q1 * q2 + q0 * q3), 1.0 - 2.0 * (q1 * q1 + q3 * q3), 2.0 * (q2 * q3 - q0 * q1),
            2.0 * (q1 * q3 - q0 * q2), 2.0 * (q2 * q3 + q0 * q1), 1.0 - 2.0 * (q1 * q1 + q2 * q2))


@njit(cache=True, error_model="numpy")
def dcm(q: np.ndarray) -> np.ndarray:
    """Direction-cosine matrix of ``q``: ``v_i = dcm(q) @ v_b`` for ``q = q_b2i``."""
    m = np.empty((3, 3))
    (m[0, 0], m[0, 1], m[0, 2], m[1, 0], m[1, 1], m[1, 2],
     m[2, 0], m[2, 1], m[2, 2]) = dcm_xyz(q[0], q[1], q[2], q[3])
    return m


@njit(cache=True, error_model="numpy")
def from_dcm(m: np.ndarray) -> np.ndarray:
    """Quaternion of a body→inertial direction-cosine matrix (Shepperd's method)."""
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    q = np.empty(4)
    if tr > 0.0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q[0] = 0.25 * s
        q[1] = (m[2, 1] - m[1, 2]) / s
        q[2] = (m[0, 2] - m[2, 0]) / s
        q[3] = (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q[0] = (m[2, 1] - m[1, 2]) / s
        q[1] = 0.25 * s
        q[2] = (m[0, 1] + m[1, 0]) / s
        q[3] = (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q[0] = (m[0, 2] - m[2, 0]) / s
        q[1] = (m[0, 1] + m[1, 0]) / s
        q[2] = 0.25 * s
        q[3] = (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q[0] = (m[1, 0] - m[0, 1]) / s
        q[1] = (m[0, 2] + m[2, 0]) / s
        q[2] = (m[1, 2] + m[2, 1]) / s
        q[3] = 0.25 * s
    return qnormalize(q)


@njit(cache=True, error_model="numpy")
def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q ⊗ v ⊗ q*``: body components → inertial components for ``q = q_b2i``."""
    return dcm(q) @ v


@njit(cache=True, error_model="numpy", inline="always")
def rotate_inverse_xyz(q0: float, q1: float, q2: float, q3: float, v0: float, v1: float,
                       v2: float) -> tuple[float, float, float]:
    """``q* ⊗ v ⊗ q`` on scalars: inertial components → body components for ``q = q_b2i``
    (``dcm(q)ᵀ v``, each component summed in row order)."""
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = dcm_xyz(q0, q1, q2, q3)
    return (m00 * v0 + m10 * v1 + m20 * v2,
            m01 * v0 + m11 * v1 + m21 * v2,
            m02 * v0 + m12 * v1 + m22 * v2)


@njit(cache=True, error_model="numpy")
def rotate_inverse(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q* ⊗ v ⊗ q``: inertial components → body components for ``q = q_b2i``."""
    out = np.empty(3)
    out[0], out[1], out[2] = rotate_inverse_xyz(q[0], q[1], q[2], q[3], v[0], v[1], v[2])
    return out


@njit(cache=True, error_model="numpy", inline="always")
def from_rotation_vector_xyz(p0: float, p1: float, p2: float) -> tuple[float, float, float, float]:
    """Quaternion of a rotation by ``|φ|`` rad about ``φ/|φ|`` (exact exponential map),
    scalars."""
    ang = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if ang < 1e-12:
        # second-order series keeps the small-rotation limit exact to round-off
        return 1.0 - ang * ang / 8.0, 0.5 * p0, 0.5 * p1, 0.5 * p2
    s = np.sin(0.5 * ang) / ang
    return np.cos(0.5 * ang), p0 * s, p1 * s, p2 * s


@njit(cache=True, error_model="numpy")
def from_rotation_vector(phi: np.ndarray) -> np.ndarray:
    """Quaternion of a rotation by ``|phi|`` rad about ``phi/|phi|`` (exact exponential map)."""
    q = np.empty(4)
    q[0], q[1], q[2], q[3] = from_rotation_vector_xyz(phi[0], phi[1], phi[2])
    return q


@njit(cache=True, error_model="numpy")
def to_rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector (rad) of ``q``, the shortest rotation (angle ≤ π)."""
    w = q[0]
    v = q[1:4].copy()
    if w < 0.0:
        w = -w
        v = -v
    s = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if s < 1e-12:
        return 2.0 * v
    ang = 2.0 * np.arctan2(s, w)
    return v * (ang / s)


@njit(cache=True, error_model="numpy", inline="always")
def rate_xyz(q0: float, q1: float, q2: float, q3: float, wx: float, wy: float,
             wz: float) -> tuple[float, float, float, float]:
    """``q̇ = ½ q ⊗ [0, ω]`` on scalars: q scalar first, ω the body rate (rad/s, body
    axes). The one copy of the kinematics (the plant's attitude equation calls it)."""
    return (0.5 * (-q1 * wx - q2 * wy - q3 * wz),
            0.5 * (q0 * wx + q2 * wz - q3 * wy),
            0.5 * (q0 * wy - q1 * wz + q3 * wx),
            0.5 * (q0 * wz + q1 * wy - q2 * wx))


@njit(cache=True, error_model="numpy")
def derivative(q: np.ndarray, omega_body: np.ndarray) -> np.ndarray:
    """``q̇ = ½ q ⊗ [0, ω]`` with ω the body angular rate (rad/s, body axes)."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = rate_xyz(q[0], q[1], q[2], q[3], omega_body[0], omega_body[1],
                                              omega_body[2])
    return out


def dcm_array(q: np.ndarray) -> np.ndarray:
    """:func:`dcm` of many quaternions at once (numpy, for post-processing).

    Parameters
    ----------
    q : ndarray, shape (n, 4)

    Returns
    -------
    ndarray, shape (n, 3, 3)
    """
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=1)


def euler_321(m_b2ref: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (rad; 3-2-1 sequence) of body axes relative to a reference frame.

    Parameters
    ----------
    m_b2ref : ndarray, shape (n, 3, 3)
        Body→reference direction-cosine matrices.

    Returns
    -------
    ndarray, shape (n, 3)
        ``[roll, pitch, yaw]`` in rad (pitch in [-π/2, π/2]).
    """
    roll = np.arctan2(m_b2ref[:, 2, 1], m_b2ref[:, 2, 2])
    pitch = -np.arcsin(np.clip(m_b2ref[:, 2, 0], -1.0, 1.0))
    yaw = np.arctan2(m_b2ref[:, 1, 0], m_b2ref[:, 0, 0])
    return np.stack([roll, pitch, yaw], axis=1)
