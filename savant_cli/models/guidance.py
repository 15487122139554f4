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

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit

from savant_cli.models import blocks, quaternion as qt

if TYPE_CHECKING:  # pragma: no cover
    from savant_cli.config import SmootherConfig

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


class SmootherGains(NamedTuple):
    """The command smoother's gains (:func:`smoother_step`).

    Attributes
    ----------
    damping : float
        Damping ratio ζ (1).
    natural_frequency_rad_s : float
        Natural frequency ω, rad/s.
    """

    damping: float
    natural_frequency_rad_s: float


def smoother_gains(config: "SmootherConfig") -> SmootherGains:
    """The smoother's gains from ``guidance.smoother``."""
    return SmootherGains(float(config.damping), float(config.natural_frequency_rad_s))


@njit(cache=True, error_model="numpy")
def smoother_step(d: np.ndarray, t: float, dt: float, zeta: float, wn: float) -> None:
    """Advance the smoothed command (``d[D_QS]``, ``d[D_VS]``) from ``t`` by ``dt``.

    Scalar arithmetic throughout (no array is created: this runs at 50 Hz)."""
    vg0, vg1, vg2 = d[D_VG], d[D_VG + 1], d[D_VG + 2]
    h = t - d[D_TG]
    r0, r1, r2, r3 = qt.from_rotation_vector_xyz(vg0 * h, vg1 * h, vg2 * h)
    g0, g1, g2, g3 = qt.qmul_xyz(d[D_QG], d[D_QG + 1], d[D_QG + 2], d[D_QG + 3], r0, r1, r2, r3)  # target
    s0, s1, s2, s3 = d[D_QS], d[D_QS + 1], d[D_QS + 2], d[D_QS + 3]
    e0, e1, e2, e3 = qt.qmul_xyz(g0, -g1, -g2, -g3, s0, s1, s2, s3)  # target* ⊗ smoothed
    if e0 < 0.0:  # shortest way round
        e1, e2, e3 = -e1, -e2, -e3
    c_rate = -2.0 * zeta * wn
    c_att = 2.0 * wn * wn
    v0 = d[D_VS] + (c_rate * (d[D_VS] - vg0) - c_att * e1) * dt
    v1 = d[D_VS + 1] + (c_rate * (d[D_VS + 1] - vg1) - c_att * e2) * dt
    v2 = d[D_VS + 2] + (c_rate * (d[D_VS + 2] - vg2) - c_att * e3) * dt
    d[D_VS] = v0
    d[D_VS + 1] = v1
    d[D_VS + 2] = v2
    r0, r1, r2, r3 = qt.from_rotation_vector_xyz(v0 * dt, v1 * dt, v2 * dt)
    m0, m1, m2, m3 = qt.qmul_xyz(s0, s1, s2, s3, r0, r1, r2, r3)
    n0, n1, n2, n3 = qt.normalize_xyz(m0, m1, m2, m3)
    d[D_QS] = n0
    d[D_QS + 1] = n1
    d[D_QS + 2] = n2
    d[D_QS + 3] = n3
