"""Guidance command table and the command smoother of the source paper (§III.E).

Guidance delivers, at 1 Hz, an inertial attitude command ``q_c2i`` (commanded body →
ECI) and a commanded angular rate (commanded-body axes). The smoother assumes a
constant-rate eigenaxis maneuver between guidance samples and tracks it with a
second-order filter run at the flight-control rate:

    α = −2 ζ ω (v − v_eig) − 2 ω² q_err,      v ← v + α Δt,     q_s ← q_s ⊗ δq(v Δt)

where ``q_err`` is the vector part of the error quaternion from the eigenaxis target to
the smoothed command. Linearised, the smoothed attitude follows the target like
θ̈ + 2ζωθ̇ + ω²θ = 0, so ζ and ω are the configured damping and natural frequency.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import quaternion as qt
from savant_cli.models import blocks

_DISCRETE = blocks.DISCRETE.block("guidance")
D_QG = _DISCRETE.array("command_quaternion", 4, "1", "latest guidance quaternion q_c2i")
D_VG = _DISCRETE.array("command_rate", 3, "rad/s", "guidance (eigenaxis) rate, command frame")
D_TG = _DISCRETE.scalar("command_time", "s", "time of the latest guidance sample")
D_QS = _DISCRETE.array("smoothed_quaternion", 4, "1", "smoothed quaternion command")
D_VS = _DISCRETE.array("smoothed_rate", 3, "rad/s", "smoothed rate command, command frame")


@njit(cache=True, error_model="numpy")
def command_at(t: float, times: np.ndarray, quats: np.ndarray, rates: np.ndarray):
    """Guidance command at time ``t`` by interpolation in a command table.

    The quaternion is interpolated along the great circle (slerp) between the two
    bracketing samples, the rate linearly; outside the table the end sample is held.

    Returns
    -------
    q_c2i : ndarray (4,)
    rate : ndarray (3,) rad/s, commanded-body axes
    """
    n = times.size
    if t <= times[0]:
        return quats[0].copy(), rates[0].copy()
    if t >= times[n - 1]:
        return quats[n - 1].copy(), rates[n - 1].copy()
    i = np.searchsorted(times, t, side="right") - 1
    w = (t - times[i]) / (times[i + 1] - times[i])
    dq = qt.qmul(qt.qconj(quats[i]), quats[i + 1])
    q = qt.qmul(quats[i], qt.from_rotation_vector(w * qt.to_rotation_vector(dq)))
    return qt.qnormalize(q), (1.0 - w) * rates[i] + w * rates[i + 1]


@njit(cache=True, error_model="numpy")
def guidance_sample(d: np.ndarray, t: float, times: np.ndarray, quats: np.ndarray,
                    rates: np.ndarray, initialize: bool) -> None:
    """Low-rate block: take a new guidance command at time ``t`` into ``d``."""
    q, rate = command_at(t, times, quats, rates)
    d[D_QG:D_QG + 4] = q
    d[D_VG:D_VG + 3] = rate
    d[D_TG] = t
    if initialize:
        d[D_QS:D_QS + 4] = q
        d[D_VS:D_VS + 3] = rate


@njit(cache=True, error_model="numpy")
def smoother_step(d: np.ndarray, t: float, dt: float, zeta: float, wn: float) -> None:
    """Advance the smoothed command (``d[D_QS]``, ``d[D_VS]``) from ``t`` by ``dt``."""
    v_eig = d[D_VG:D_VG + 3]
    q_target = qt.qmul(d[D_QG:D_QG + 4], qt.from_rotation_vector(v_eig * (t - d[D_TG])))
    q_s = d[D_QS:D_QS + 4]
    q_err = qt.qmul(qt.qconj(q_target), q_s)
    if q_err[0] < 0.0:  # shortest way round
        q_err = -q_err
    v = d[D_VS:D_VS + 3]
    acc = -2.0 * zeta * wn * (v - v_eig) - 2.0 * wn * wn * q_err[1:4]
    v_new = v + acc * dt
    d[D_VS:D_VS + 3] = v_new
    d[D_QS:D_QS + 4] = qt.qnormalize(qt.qmul(q_s, qt.from_rotation_vector(v_new * dt)))
