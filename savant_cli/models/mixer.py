"""Control mixer: the flight control's roll, pitch and yaw commands allocated to the
gimbal channels of every engine that burns.

The flight control computes its pitch and yaw commands as the gimbal angles of one
*equivalent engine* (rad, the angle every gimbaled engine of the stage would take if
they all moved together, which is what its gains were designed for) and its roll command
as a roll moment (N·m). The mixer turns them into the moment they ask for and gives each
gimbal channel its share.

Moment effectiveness. An engine ``i`` of thrust ``T_i`` (N) at the arm ``r_i`` (m, from
the CG to its gimbal, body axes) turns its thrust line by its gimbal angles plus its
fixed cant, ``n(δp, δy) = (cos δp cos δy, −sin δy, sin δp cos δy)`` (the plant's thrust
direction, ``models/propulsion.py::thrust_loads``). A small move ``dδ_j`` of channel ``j``
(the engine's pitch or yaw gimbal) adds the moment ``b_j dδ_j`` about the CG::

    b_j = r_i × (T_i ∂n/∂δ_j)                       (N·m/rad, body axes)

evaluated at the engine's cant: ``∂n/∂δp = (−sin cp cos cy, 0, cos cp cos cy)``,
``∂n/∂δy = (−cos cp sin cy, −cos cy, −sin cp sin cy)``. ``B = [b_1 … b_m]`` (3 × m).

Allocation. The requested moment is ``M = D v`` with ``v = (L, δp, δy)`` the commands and
``D = diag(1, d_p, d_y)``: ``d_p`` (``d_y``) is the pitch (yaw) moment of all pitch (yaw)
channels moved together by one radian, the row sum of ``B`` over those channels, so the
equivalent engine's angle gives the moment the gains expect. Each channel then gets
the smallest deflection, measured against its own gimbal limit, that produces ``M``::

    δ = W^(−1/2) (B W^(−1/2))⁺ M = K v,     K = W^(−1/2) (B W^(−1/2))⁺ D,     W = diag(1/limit_j²)

(``⁺`` the Moore-Penrose pseudo-inverse, ``numpy.linalg.pinv``). Where ``B`` has rank 3
every commanded moment is produced exactly; where it does not (one engine on the axis
cannot roll), ``K v`` gives the moment closest to ``M`` in least squares, and the part it
cannot give (roll, for one engine) is left to the other effectors. An engine that does
not burn has ``T_i = 0``: its columns vanish and its channels get exactly no command
(they are left out of the pseudo-inverse), so the allocation follows every engine start,
stop, failure and throttle setting when ``K`` is recomputed with the engines' thrusts.
This is the pseudo-inverse allocation of SLS's ascent flight control (Orr, Wall,
VanZwieten and Hall, AAS 14-038), weighted by the gimbal ranges.

A vehicle may give its own mixing matrix instead; :func:`check_mixing_matrix` tests that
one against ``B``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: The commands' order: roll moment (N·m), pitch and yaw equivalent gimbal angles (rad).
ROLL, PITCH, YAW = 0, 1, 2
#: A channel's axis on its engine's gimbal.
AXIS_PITCH, AXIS_YAW = 0, 1


@njit(cache=True, error_model="numpy")
def channel_direction(cant_pitch: float, cant_yaw: float, axis: int) -> tuple[float, float, float]:
    """``∂n/∂δ`` of a gimbal channel (1/rad, body axes): how the unit thrust direction
    moves per radian of the channel ``axis`` (:data:`AXIS_PITCH` or :data:`AXIS_YAW`) of a
    nozzle canted by ``cant_pitch``, ``cant_yaw`` (rad) at null."""
    cp, sp = np.cos(cant_pitch), np.sin(cant_pitch)
    cy, sy = np.cos(cant_yaw), np.sin(cant_yaw)
    if axis == AXIS_PITCH:
        return -sp * cy, 0.0, cp * cy
    return -cp * sy, -cy, -sp * sy


@njit(cache=True, error_model="numpy")
def moment_effectiveness(arms: np.ndarray, cants: np.ndarray, thrust: np.ndarray, engine: np.ndarray,
                         axis: np.ndarray) -> np.ndarray:
    """The moment effectiveness ``B`` (3 × m, N·m/rad, body axes) of m gimbal channels.

    Parameters
    ----------
    arms : ndarray (n_engines, 3)
        Arm from the CG to each engine's gimbal, body axes, m.
    cants : ndarray (n_engines, 2)
        Each nozzle's cant at null, pitch and yaw, rad.
    thrust : ndarray (n_engines,)
        Each engine's thrust, N (0: not burning; its channels get no moment).
    engine, axis : ndarray (m,) of int
        Each channel's engine (row of ``arms``) and axis (:data:`AXIS_PITCH`, :data:`AXIS_YAW`).
    """
    m = engine.size
    b = np.zeros((3, m))
    for j in range(m):
        i = engine[j]
        dx, dy, dz = channel_direction(cants[i, 0], cants[i, 1], axis[j])
        t = thrust[i]
        fx, fy, fz = t * dx, t * dy, t * dz
        rx, ry, rz = arms[i, 0], arms[i, 1], arms[i, 2]
        b[0, j] = ry * fz - rz * fy
        b[1, j] = rz * fx - rx * fz
        b[2, j] = rx * fy - ry * fx
    return b


@njit(cache=True, error_model="numpy")
def equivalent_scales(b: np.ndarray, axis: np.ndarray) -> tuple[float, float]:
    """``d_p``, ``d_y`` (N·m/rad): the pitch moment of every pitch channel moved together by
    one radian, and the yaw moment of every yaw channel likewise (the equivalent
    engine's effectiveness)."""
    d_p = 0.0
    d_y = 0.0
    for j in range(axis.size):
        if axis[j] == AXIS_PITCH:
            d_p += b[1, j]
        else:
            d_y += b[2, j]
    return d_p, d_y


@njit(cache=True, error_model="numpy")
def mixing_matrix(b: np.ndarray, limits: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The allocation ``K`` (m × 3): channel commands ``δ = K v`` (rad) for the commands
    ``v = (L N·m, δp rad, δy rad)``, the limit-weighted minimum-norm solution of
    ``B δ = diag(1, d_p, d_y) v`` (module notes).

    Parameters
    ----------
    b : ndarray (3, m)
        :func:`moment_effectiveness`.
    limits : ndarray (m,)
        Each channel's gimbal limit, rad (> 0).
    axis : ndarray (m,) of int
        Each channel's axis.
    """
    m = limits.size
    active = np.zeros(m, dtype=np.int64)  # channels with any effect (an engine not burning has none)
    n_active = 0
    for j in range(m):
        if b[0, j] != 0.0 or b[1, j] != 0.0 or b[2, j] != 0.0:
            active[n_active] = j
            n_active += 1
    k = np.zeros((m, 3))
    if n_active == 0:
        return k
    scaled = np.empty((3, n_active))
    for a in range(n_active):
        for r in range(3):
            scaled[r, a] = b[r, active[a]] * limits[active[a]]
    k_active = np.linalg.pinv(scaled)  # (n_active, 3)
    d_p, d_y = equivalent_scales(b, axis)
    for a in range(n_active):
        j = active[a]
        k[j, ROLL] = k_active[a, ROLL] * limits[j]
        k[j, PITCH] = k_active[a, PITCH] * d_p * limits[j]
        k[j, YAW] = k_active[a, YAW] * d_y * limits[j]
    return k


def check_mixing_matrix(k: np.ndarray, b: np.ndarray, limits: np.ndarray, axis: np.ndarray,
                        rtol: float = 1e-6) -> list[str]:
    """What a given mixing matrix ``K`` (m × 3) fails to do with the effectiveness ``B``:
    each command must produce the moment the mixer's own allocation produces (the
    requested moment wherever ``B`` can give it), within ``rtol`` of that command's largest
    requested moment component (at least 1 N·m per unit command). An empty list: it
    allocates moments as the mixer's own would.

    Parameters
    ----------
    k : array_like (m, 3)
        The given matrix.
    b, limits, axis
        As :func:`mixing_matrix`.
    """
    b = np.ascontiguousarray(b, dtype=float)
    axis = np.asarray(axis, np.int64)
    k = np.asarray(k, float)
    if k.shape != (b.shape[1], 3):
        return [f"has shape {list(k.shape)}, not [{b.shape[1]}, 3] (one row per gimbal channel)"]
    want = b @ mixing_matrix(b, np.asarray(limits, float), axis)
    got = b @ k
    names = ("roll", "pitch", "yaw")
    return [f"the {names[c]} command gives the moment {got[:, c].tolist()} N·m instead of {want[:, c].tolist()}"
            for c in range(3)
            if np.max(np.abs(got[:, c] - want[:, c])) > rtol * max(float(np.max(np.abs(want[:, c]))), 1.0)]
