"""Strapdown inertial navigation with IMU errors (``navigation=inertial``).

The flight software's navigated state is the true state plus the navigation error, which
this model propagates from the IMU's own increments. Every IMU sample the truth gives the
increments an ideal strapdown IMU would output over the sample, the body-axis rotation
``Δθ`` (the rotation vector of ``q(t₁)* ⊗ q(t₂)``) and the sensed velocity change
``Δv = v(t₂) − v(t₁) − ½ (g₁ + g₂) Δt`` (ECI; the specific force's integral, gravity by
trapezoid). The instrument errors turn them into the error increments:

* gyro triad: ``δΔθ = b_g Δt + s_g ⊙ Δθ − ε_g × Δθ`` (bias, scale factor, and the triad's
  mounting misalignment as a small rotation ``ε_g`` from the body axes: a rotated triad
  reads ``R(ε)ᵀ ω ≈ ω − ε × ω``);
* accelerometer triad: ``δΔv_b = b_a Δt + s_a ⊙ Δv_b − ε_a × Δv_b`` with ``Δv_b`` the
  sensed velocity change in body axes.

Both are resolved in ECI at the sample's mid-attitude ``C_b2i(mid)`` (the attitude
halfway through ``Δθ``), which keeps the discretization second order in ``ω Δt``.

The navigation errors, all in ECI, integrate the standard strapdown error equations in
the inertial frame (Titterton & Weston, *Strapdown Inertial Navigation Technology*,
2nd ed., §12.3; Savage, *Strapdown Analytics*, §12): the attitude error ``φ`` (the
navigated body-to-ECI rotation is ``exp(φ) · C_b2i``), velocity error ``δv`` and position
error ``δr`` (navigated minus true)::

    φ  += C_b2i(mid) δΔθ
    δv += φ × Δv + C_b2i(mid) δΔv_b + (g(r + δr) − g(r)) Δt
    δr += ½ (δv_old + δv_new) Δt

The gravity term is evaluated exactly (the zonal model at the navigated and the true
position), so the gravity-gradient feedback (the Schuler oscillation horizontally, the
vertical-channel divergence) is in it; the navigation computer uses the same gravity model
as the plant (no gravity-model error). The initial alignment error is a small rotation
of the navigation frame about the body axes at the moment navigation starts (liftoff:
body x up, so its x component is the azimuth error and y, z the two tilts).

With ``navigation=perfect`` (the source paper's §III.H assumption) the errors stay zero
and the engine hands the true state to the flight software unchanged. With every error
zero the inertial model leaves them exactly zero too, so such a run is bit for bit the
perfect one (a test checks it).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks, gravity, quaternion as qt
from savant_cli.models.earth import P_RE

ARCSEC = np.pi / (180.0 * 3600.0)  # rad
DEG_PER_H = np.pi / 180.0 / 3600.0  # rad/s
MICRO_G = 9.80665e-6  # m/s² (standard gravity, ISO 80000-3)
PPM = 1e-6

_PARAMS = blocks.PARAMETERS.block("navigation")
P_ON = _PARAMS.scalar("on", "1", "1: inertial navigation with IMU errors, 0: perfect navigation")
P_GYRO_BIAS = _PARAMS.array("gyro_bias", 3, "rad/s", "gyro bias, body axes")
P_GYRO_SCALE = _PARAMS.array("gyro_scale_factor", 3, "1", "gyro scale-factor error, per axis")
P_GYRO_MISALIGN = _PARAMS.array("gyro_misalignment", 3, "rad", "gyro triad mounting: rotation vector body→triad")
P_ACCEL_BIAS = _PARAMS.array("accelerometer_bias", 3, "m/s^2", "accelerometer bias, body axes")
P_ACCEL_SCALE = _PARAMS.array("accelerometer_scale_factor", 3, "1", "accelerometer scale-factor error, per axis")
P_ACCEL_MISALIGN = _PARAMS.array("accelerometer_misalignment", 3, "rad",
                                 "accelerometer triad mounting: rotation vector body→triad")
P_ALIGNMENT = _PARAMS.array("alignment", 3, "rad",
                            "initial alignment error: rotation of the navigation frame about the body axes")

_DISCRETE = blocks.DISCRETE.block("navigation")
D_READY = _DISCRETE.scalar("ready", "1", "1 once navigation has its first IMU sample")
D_ATTITUDE = _DISCRETE.array("attitude_error", 3, "rad",
                             "navigated attitude error φ, ECI (navigated body→ECI = exp(φ) · true)")
D_POSITION = _DISCRETE.array("position_error", 3, "m", "navigated minus true position, ECI")
D_VELOCITY = _DISCRETE.array("velocity_error", 3, "m/s", "navigated minus true velocity, ECI")
D_T_LAST = _DISCRETE.scalar("last_sample_time", "s", "time of the previous IMU sample")
D_Q_LAST = _DISCRETE.array("last_attitude", 4, "1", "true q_b2i at the previous IMU sample")
D_V_LAST = _DISCRETE.array("last_velocity", 3, "m/s", "true ECI velocity at the previous IMU sample")
D_G_LAST = _DISCRETE.array("last_gravity", 3, "m/s^2", "gravity at the true position of the previous IMU sample, ECI")


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """IMU errors of ``navigation=inertial`` in SI (zero, and off, with ``perfect``)."""
    nav = inputs.cfg.navigation
    if nav.name != "inertial":
        p[P_ON] = 0.0
        return
    p[P_ON] = 1.0
    p[P_GYRO_BIAS:P_GYRO_BIAS + 3] = np.asarray(nav.gyro.bias_deg_per_h, float) * DEG_PER_H
    p[P_GYRO_SCALE:P_GYRO_SCALE + 3] = np.asarray(nav.gyro.scale_factor_ppm, float) * PPM
    p[P_GYRO_MISALIGN:P_GYRO_MISALIGN + 3] = np.asarray(nav.gyro.misalignment_arcsec, float) * ARCSEC
    p[P_ACCEL_BIAS:P_ACCEL_BIAS + 3] = np.asarray(nav.accelerometer.bias_micro_g, float) * MICRO_G
    p[P_ACCEL_SCALE:P_ACCEL_SCALE + 3] = np.asarray(nav.accelerometer.scale_factor_ppm, float) * PPM
    p[P_ACCEL_MISALIGN:P_ACCEL_MISALIGN + 3] = np.asarray(nav.accelerometer.misalignment_arcsec, float) * ARCSEC
    p[P_ALIGNMENT:P_ALIGNMENT + 3] = np.asarray(nav.alignment_arcsec, float) * ARCSEC


@njit(cache=True, error_model="numpy")
def instrument_error(p: np.ndarray, bias: int, scale: int, misalign: int, true_b: np.ndarray,
                     dt: float) -> np.ndarray:
    """Error of one triad's output over ``dt`` s for the true body-axis increment
    ``true_b`` (a rotation in rad or a velocity change in m/s): ``b dt + s ⊙ u − ε × u``."""
    e = np.empty(3)
    ex, ey, ez = p[misalign], p[misalign + 1], p[misalign + 2]
    ux, uy, uz = true_b[0], true_b[1], true_b[2]
    e[0] = p[bias] * dt + p[scale] * ux - (ey * uz - ez * uy)
    e[1] = p[bias + 1] * dt + p[scale + 1] * uy - (ez * ux - ex * uz)
    e[2] = p[bias + 2] * dt + p[scale + 2] * uz - (ex * uy - ey * ux)
    return e


@njit(cache=True, error_model="numpy")
def start(d: np.ndarray, t: float, r: np.ndarray, v: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
    """The first IMU sample: the alignment error (body axes, turned into ECI by the true
    attitude ``q``), the truth to difference the next sample against."""
    phi = qt.rotate(q, p[P_ALIGNMENT:P_ALIGNMENT + 3])
    d[D_ATTITUDE:D_ATTITUDE + 3] = phi
    d[D_POSITION:D_POSITION + 3] = 0.0
    d[D_VELOCITY:D_VELOCITY + 3] = 0.0
    _remember(d, t, r, v, q, p)
    d[D_READY] = 1.0


@njit(cache=True, error_model="numpy")
def _remember(d: np.ndarray, t: float, r: np.ndarray, v: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
    gx, gy, gz = gravity.gravity_at(r[0], r[1], r[2], p, p[P_RE])
    d[D_T_LAST] = t
    d[D_Q_LAST:D_Q_LAST + 4] = q
    d[D_V_LAST:D_V_LAST + 3] = v
    d[D_G_LAST] = gx
    d[D_G_LAST + 1] = gy
    d[D_G_LAST + 2] = gz


@njit(cache=True, error_model="numpy")
def imu_sample(d: np.ndarray, t: float, r: np.ndarray, v: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
    """Advance the navigation errors in ``d`` to the IMU sample at ``t`` (s) from the
    true ECI position ``r`` (m), velocity ``v`` (m/s) and attitude ``q`` (q_b2i) there.
    The first call starts navigation (:func:`start`)."""
    if d[D_READY] == 0.0:
        start(d, t, r, v, q, p)
        return
    dt = t - d[D_T_LAST]
    if dt <= 0.0:
        return
    re = p[P_RE]
    gx, gy, gz = gravity.gravity_at(r[0], r[1], r[2], p, re)
    dv_i = np.empty(3)  # sensed velocity change, ECI
    dv_i[0] = v[0] - d[D_V_LAST] - 0.5 * (gx + d[D_G_LAST]) * dt
    dv_i[1] = v[1] - d[D_V_LAST + 1] - 0.5 * (gy + d[D_G_LAST + 1]) * dt
    dv_i[2] = v[2] - d[D_V_LAST + 2] - 0.5 * (gz + d[D_G_LAST + 2]) * dt
    q_last = d[D_Q_LAST:D_Q_LAST + 4]
    dtheta_b = qt.to_rotation_vector(qt.qmul(qt.qconj(q_last), q))  # body rotation over the sample
    # the increments are resolved at the sample's mid-attitude (second order in ω Δt)
    q_mid = qt.qmul(q_last, qt.from_rotation_vector(0.5 * dtheta_b))
    dv_b = qt.rotate_inverse(q_mid, dv_i)
    gyro_err = qt.rotate(q_mid, instrument_error(p, P_GYRO_BIAS, P_GYRO_SCALE, P_GYRO_MISALIGN, dtheta_b, dt))
    accel_err = qt.rotate(q_mid, instrument_error(p, P_ACCEL_BIAS, P_ACCEL_SCALE, P_ACCEL_MISALIGN, dv_b, dt))
    phi = d[D_ATTITUDE:D_ATTITUDE + 3]
    dr = d[D_POSITION:D_POSITION + 3]
    dv = d[D_VELOCITY:D_VELOCITY + 3]
    hx, hy, hz = gravity.gravity_at(r[0] + dr[0], r[1] + dr[1], r[2] + dr[2], p, re)
    tilt = np.cross(phi, dv_i)  # the sensed velocity change resolved through the wrong attitude
    dv_new = np.empty(3)
    dv_new[0] = dv[0] + tilt[0] + accel_err[0] + (hx - gx) * dt
    dv_new[1] = dv[1] + tilt[1] + accel_err[1] + (hy - gy) * dt
    dv_new[2] = dv[2] + tilt[2] + accel_err[2] + (hz - gz) * dt
    for i in range(3):
        dr[i] += 0.5 * (dv[i] + dv_new[i]) * dt
        dv[i] = dv_new[i]
        phi[i] += gyro_err[i]
    _remember(d, t, r, v, q, p)


@njit(cache=True, error_model="numpy")
def navigated_state(d: np.ndarray, r: np.ndarray, v: np.ndarray, r_out: np.ndarray, v_out: np.ndarray) -> None:
    """The navigated ECI position and velocity: the true ``r``, ``v`` plus the errors."""
    for i in range(3):
        r_out[i] = r[i] + d[D_POSITION + i]
        v_out[i] = v[i] + d[D_VELOCITY + i]


@njit(cache=True, error_model="numpy")
def navigated_attitude(d: np.ndarray, q_b2i: np.ndarray, out: np.ndarray) -> None:
    """The navigated body-to-ECI attitude ``exp(φ) ⊗ q_b2i`` into ``out``."""
    qt.qmul_into(qt.from_rotation_vector(d[D_ATTITUDE:D_ATTITUDE + 3]), q_b2i, out)


@njit(cache=True, error_model="numpy")
def imu_gyro_rate(p: np.ndarray, wx: float, wy: float, wz: float) -> tuple[float, float, float]:
    """The IMU's rate output (body axes, rad/s) for the true rate: the same gyro bias,
    scale factor and triad misalignment that its attitude integrates."""
    w = np.empty(3)
    w[0], w[1], w[2] = wx, wy, wz
    e = instrument_error(p, P_GYRO_BIAS, P_GYRO_SCALE, P_GYRO_MISALIGN, w, 1.0)
    return wx + e[0], wy + e[1], wz + e[2]
