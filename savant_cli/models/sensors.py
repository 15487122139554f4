"""Rate gyros: a continuous second-order transfer function per axis, discretized
(zero-order hold, :func:`scipy.signal.cont2discrete`) at the sensor rate.

The navigation unit is perfect (attitude, position and velocity sampled exactly), as in
the source paper (§III.H).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import signal


def gyro_discrete(natural_frequency_hz: float, damping: float, dt_s: float):
    """Discrete state-space of ω_s² / (s² + 2ζω_s s + ω_s²) sampled at ``dt_s``.

    Returns
    -------
    tuple of ndarray
        ``(Ad (2,2), Bd (2,), Cd (2,), Dd float)`` for one axis.
    """
    wn = 2.0 * np.pi * natural_frequency_hz
    sys = signal.TransferFunction([wn * wn], [1.0, 2.0 * damping * wn, wn * wn])
    ad, bd, cd, dd, _ = signal.cont2discrete(
        (*signal.tf2ss(sys.num, sys.den),), dt_s, method="zoh"
    )
    return (np.ascontiguousarray(ad), np.ascontiguousarray(bd[:, 0]),
            np.ascontiguousarray(cd[0]), float(dd[0, 0]))


@njit(cache=True)
def gyro_step(state: np.ndarray, rate_in: float, ad: np.ndarray, bd: np.ndarray,
              cd: np.ndarray, dd: float) -> float:
    """One sample of one gyro axis: returns the output, advances ``state`` in place."""
    y = cd[0] * state[0] + cd[1] * state[1] + dd * rate_in
    s0 = ad[0, 0] * state[0] + ad[0, 1] * state[1] + bd[0] * rate_in
    s1 = ad[1, 0] * state[0] + ad[1, 1] * state[1] + bd[1] * rate_in
    state[0] = s0
    state[1] = s1
    return y


def gyro_steady_state(ad: np.ndarray, bd: np.ndarray, rate_in: float) -> np.ndarray:
    """Filter state in equilibrium with a constant input (for a quiet start)."""
    return np.linalg.solve(np.eye(2) - ad, bd * rate_in)
