"""Rate gyros: a continuous second-order transfer function per axis, discretized
with a zero-order hold at the sensor rate; sensor mounting misalignment.

By default navigation is perfect (attitude, position and velocity sampled exactly), as in
the source paper (§III.H), apart from an optional mounting misalignment
(:func:`misalignment`) that the navigation unit shares with its own rate gyro;
``navigation=inertial`` adds the IMU's instrument errors (:mod:`savant_cli.models.navigation`).

The zero-order-hold discretization is the matrix exponential of the augmented system
``exp([[A, B], [0, 0]] T)`` (:func:`scipy.linalg.expm`), which is what
:func:`scipy.signal.cont2discrete` computes for ``method="zoh"``; we call ``expm``
directly because importing ``scipy.signal`` costs ~1.8 s per ``savant run``, and a test
checks the result against ``cont2discrete``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit
from scipy.linalg import expm

from savant_cli.models import blocks, quaternion as qt
from savant_cli.models.flex import PT_GYRO_FS, PT_GYRO_US, PT_IMU

if TYPE_CHECKING:  # pragma: no cover
    from savant_cli.config import RateGyroConfig

N_GYROS = 3  # in the flight software's order: upper-stage gyro, IMU, first-stage gyro
GYRO_POINTS = (PT_GYRO_US, PT_IMU, PT_GYRO_FS)  # their flex points, same order
IMU_GYRO = 1  # the IMU's rate output (navigation=inertial gives it the IMU's gyro errors)

_DISCRETE = blocks.DISCRETE.block("sensors")
D_GYRO_X = _DISCRETE.array("gyro_filters", 18, "rad/s", "rate-gyro filter states: [gyro][axis][2]")
D_GYRO_Y = _DISCRETE.array("gyro_outputs", 9, "rad/s", "gyro outputs, each in its own axes: [gyro][axis]")

_PARAMS = blocks.PARAMETERS.block("sensors")
P_IMU_MISALIGN = _PARAMS.array("imu_misalignment", 3, "rad",
                               "navigation-unit (and IMU gyro) mounting: rotation vector body→sensor")
P_GYRO_US_MISALIGN = _PARAMS.array("upper_stage_gyro_misalignment", 3, "rad", "upper-stage rate-gyro mounting")
P_GYRO_FS_MISALIGN = _PARAMS.array("first_stage_gyro_misalignment", 3, "rad", "first-stage rate-gyro mounting")
GYRO_MISALIGN = (P_GYRO_US_MISALIGN, P_IMU_MISALIGN, P_GYRO_FS_MISALIGN)  # in the gyro order


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """Mounting misalignments of the ``sensors`` group."""
    mis = inputs.cfg.sensors.misalignment_deg
    for base, eps in ((P_IMU_MISALIGN, mis.imu), (P_GYRO_US_MISALIGN, mis.rate_gyro_upper_stage),
                      (P_GYRO_FS_MISALIGN, mis.rate_gyro_first_stage)):
        p[base:base + 3] = np.radians(eps)


class GyroModel(NamedTuple):
    """One rate-gyro axis, discrete at the sensor sample time ``T``: the continuous
    ω_s² / (s² + 2ζω_s s + ω_s²) in controllable canonical form, held with a zero-order hold.

    With the filter state ``x = (x₁ rad, x₂ rad·s)``, the sensed rate ω rad/s in and
    the output rad/s: ``x⁺ = ad x + bd ω`` and ``y = cd · x + dd ω``.

    Attributes
    ----------
    ad : ndarray (2, 2)
        State transition over ``T`` (row 0: 1, 1/s; row 1: s, 1).
    bd : ndarray (2,)
        Input gain over ``T`` (s, s²).
    cd : ndarray (2,)
        Output gain (1/s, 1/s²): ``(0, ω_s²)``.
    dd : float
        Feedthrough (1): zero.
    """

    ad: np.ndarray
    bd: np.ndarray
    cd: np.ndarray
    dd: float


def gyro_discrete(natural_frequency_hz: float, damping: float, dt_s: float) -> GyroModel:
    """Discrete state-space of ω_s² / (s² + 2ζω_s s + ω_s²) sampled at ``dt_s`` (s), for
    one axis (natural frequency in Hz, damping ratio 1)."""
    wn = 2.0 * np.pi * natural_frequency_hz
    # controllable canonical form of ω² / (s² + 2ζω s + ω²)
    a = np.array([[-2.0 * damping * wn, -wn * wn], [1.0, 0.0]])
    b = np.array([1.0, 0.0])
    c = np.array([0.0, wn * wn])
    aug = np.zeros((3, 3))
    aug[:2, :2] = a * dt_s
    aug[:2, 2] = b * dt_s
    phi = expm(aug)
    return GyroModel(np.ascontiguousarray(phi[:2, :2]), np.ascontiguousarray(phi[:2, 2]), c, 0.0)


def build_gyro(config: "RateGyroConfig", sample_time_s: float) -> GyroModel:
    """The rate gyros' discrete model from ``sensors.rate_gyro``, sampled every
    ``sample_time_s`` (s; the sensor rate's period)."""
    return gyro_discrete(config.natural_frequency_hz, config.damping, sample_time_s)


@njit(cache=True, error_model="numpy", inline="always")
def gyro_step(state: np.ndarray, k: int, rate_in: float, ad: np.ndarray, bd: np.ndarray,
              cd: np.ndarray, dd: float) -> float:
    """One sample of one gyro axis with its two filter states at ``state[k:k+2]``: returns
    the output (rad/s) for the input rate ``rate_in`` (rad/s) and advances the states in
    place (no array view is made: this runs nine times per sensor sample)."""
    x0, x1 = state[k], state[k + 1]
    y = cd[0] * x0 + cd[1] * x1 + dd * rate_in
    s0 = ad[0, 0] * x0 + ad[0, 1] * x1 + bd[0] * rate_in
    s1 = ad[1, 0] * x0 + ad[1, 1] * x1 + bd[1] * rate_in
    state[k] = s0
    state[k + 1] = s1
    return y


def gyro_steady_state(ad: np.ndarray, bd: np.ndarray, rate_in: float) -> np.ndarray:
    """Filter state in equilibrium with a constant input (for a quiet start)."""
    return np.linalg.solve(np.eye(2) - ad, bd * rate_in)


@njit(cache=True, error_model="numpy")
def misalignment(eps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mounting of a sensor whose axes are the body axes turned by the rotation vector
    ``eps`` = ε (rad, body axes; right-hand rule, e.g. ε_y > 0 turns the sensor's x axis
    nose-up, toward −z_body).

    Returns ``(q_s2b, c_b2s)``: the quaternion of the rotation ε (exact exponential map;
    it maps sensor-axis vectors into body axes, ``q_s2b = [1, 0, 0, 0]`` exactly for
    ε = 0) and ``c_b2s = R(ε)ᵀ``, where ``R(ε) = dcm(q_s2b) ≈ I + [ε×]`` has the sensor
    axes as its columns. A rate gyro reads ``ω_s = R(ε)ᵀ ω ≈ ω − ε × ω``; the navigation
    unit reports the attitude of its own axes, ``q_s2i = q_b2i ⊗ q_s2b``, so the flight
    software's attitude error becomes ``e + ε`` to first order.
    """
    q = qt.from_rotation_vector(eps)
    return q, qt.dcm(q).T.copy()
