"""Flight control system of the source paper (§III.F), run at 50 Hz.

Pitch and yaw (same architecture, uncoupled):

    δ_c = −[ Kp·e + Ki·∫e dt + Kd·F₂F₁(ω_blend − ω_c) + Kir·F₂F₁(∫(ω_gyro − ω_c) dt) ]

* ``e`` is the attitude error angle from the error quaternion between the smoothed
  command and the sensed attitude (positive when the body is rotated positively past the
  command);
* ``ω_blend`` blends the rate gyros (upper-stage gyro, IMU, first-stage gyro) with
  configured weights summing to 1;
* ``F₁``, ``F₂`` are the two fourth-order discrete flex filters in series (coefficients
  switch at separation);
* ``∫(ω_gyro − ω_c)`` is the integrated sensed rate of the stage's own gyro (first stage
  on the stack, upper stage after separation), its own flex-filtered path added to the
  PID output;
* gains come from tables whose independent variable is altitude on the integrated stack
  and Earth-relative speed in coast and upper-stage flight.

Engagement at upper-stage ignition (:func:`engagement`): through the coast the J-2X gives
no thrust, so the pitch/yaw loop runs on the coast table (the shipped controllers': zero,
the nozzle held at null where separation leaves it) with its integrators held. From the
ignition command the gains fade from the coast table to the upper-stage table as the
engine builds thrust, ``K = K_coast + φ(τ)(K_upper − K_coast)`` with φ rising linearly
from 0 at ``controller.ignition_fade.start_s`` after the command to 1 at ``end_s``; the
integrators stay held while φ = 0. The flex filters run on the upper-stage set from
separation on and are not restarted at ignition, so the command is continuous there.

Roll uses a phase plane of the flex-filtered roll error and rate error with attitude and
rate deadbands, commanding +1 / 0 / −1 jet torque.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit

from savant_cli.models import blocks, quaternion as qt
from savant_cli.models.guidance import D_QS, D_VS
from savant_cli.models.interp import locate
from savant_cli.models.sensors import D_GYRO_Y

if TYPE_CHECKING:  # pragma: no cover
    from savant_cli.config import ControllerConfig

_DISCRETE = blocks.DISCRETE.block("fcs")
D_ERR = _DISCRETE.array("attitude_error", 3, "rad", "attitude error roll, pitch, yaw")
D_RATE_ERR = _DISCRETE.array("rate_error", 3, "rad/s", "blended rate error")
D_INT_ATT = _DISCRETE.array("attitude_integral", 2, "rad*s", "integral of pitch, yaw attitude error")
D_INT_RATE = _DISCRETE.array("rate_integral", 2, "rad", "integrated (gyro − command) rate, pitch, yaw")
D_FILT = _DISCRETE.array("flex_filters", 32, "rad/s, rad", "flex filter states: 2 axes x 2 paths x 2 sections x 4")
D_ROLL_FILT = _DISCRETE.array("roll_filter", 8, "rad/s", "roll rate-error filter: 2 sections x 4")
D_GAINS = _DISCRETE.array("gains", 8, "1, 1/s, s, 1", "scheduled Kp, Ki, Kd, Kir, pitch then yaw")
D_CMD_P = _DISCRETE.scalar("pitch_command", "rad", "pitch gimbal command")
D_CMD_Y = _DISCRETE.scalar("yaw_command", "rad", "yaw gimbal command")
D_CMD_RCS = _DISCRETE.scalar("roll_jet_command", "1", "roll jet command +1, 0, −1")
D_RATE_CMD_B = _DISCRETE.array("rate_command_body", 3, "rad/s", "rate command in body axes")
D_FLEX_NAV = _DISCRETE.array("flex_nav", 3, "rad", "flex rotation at the navigation unit, added to the errors")
D_CMD_PY = _DISCRETE.array("pitch_yaw_jet_command", 2, "1", "pitch and yaw jet commands +1, 0, −1 (the coasts only)")

# flight-control phases (also the gain-table index)
FCS_STACK = 0
FCS_COAST = 1
FCS_UPPER = 2

# gyro order in blending vectors and in d[D_GYRO_Y]
GYRO_UPPER = 0
GYRO_IMU = 1
GYRO_FIRST = 2


class FcsTables(NamedTuple):
    """Numeric flight-control data, SI.

    ``filters[s, path, section, 0|1, :]`` holds ``b`` / ``a`` (a₀ = 1) of the fourth-order
    section ``section`` of path ``path`` (0 rate, 1 integrated rate) of filter set ``s``
    (0 integrated stack, 1 upper stage). ``roll_filters[s, section, 0|1, :]`` likewise.
    ``gain_axis[phase, :gain_len[phase]]`` is altitude (m, stack) or relative speed (m/s);
    ``gain_data[phase, i, :]`` = Kp, Ki, Kd, Kir for pitch then for yaw. ``fade`` is the
    ignition fade (:func:`engagement`). ``roll_gimbal[phase]`` = Kp (rad/rad), Ki (1/s),
    Kd (s) of roll by the engines' gimbals (``models/roll_gimbal.py``).
    """

    filters: np.ndarray  # (2, 2, 2, 2, 5)
    roll_filters: np.ndarray  # (2, 2, 2, 5)
    blend: np.ndarray  # (2, 3) weights (upper gyro, IMU, first gyro) per filter set
    gain_axis: np.ndarray  # (3, n)
    gain_data: np.ndarray  # (3, n, 8)
    gain_len: np.ndarray  # (3,) int64
    roll: np.ndarray  # (3,): attitude deadband rad, rate deadband rad/s, lead time s
    fade: np.ndarray  # (2,): ignition fade start, end, s after the upper-stage ignition command
    roll_gimbal: np.ndarray  # (3, 3): roll-by-gimbal Kp, Ki, Kd per phase (coast: zeros)


def fcs_tables(c: "ControllerConfig") -> FcsTables:
    """The builder of the flight control: the ``controller`` group's filters, blending,
    gain schedules, ignition fade and roll phase plane as :class:`FcsTables` (SI)."""
    filters = np.zeros((2, 2, 2, 2, 5))
    roll_filters = np.zeros((2, 2, 2, 5))
    blend = np.zeros((2, 3))
    for s, name in enumerate(("stack", "upper")):
        fs = getattr(c.flex_filters, name)
        for path, sections in enumerate((fs.rate, fs.integrated_rate)):
            for i, sec in enumerate(sections):
                a0 = sec.a[0]
                filters[s, path, i, 0] = np.asarray(sec.b) / a0
                filters[s, path, i, 1] = np.asarray(sec.a) / a0
        for i, sec in enumerate(fs.roll):
            roll_filters[s, i, 0] = np.asarray(sec.b) / sec.a[0]
            roll_filters[s, i, 1] = np.asarray(sec.a) / sec.a[0]
        blend[s] = getattr(c.blending, name)
    axes, data = [], []
    for name in ("stack", "coast", "upper"):
        t = getattr(c.gains, name)
        axes.append(np.asarray(t.breakpoints, float))
        cols = []
        for axis in ("pitch", "yaw"):
            g = getattr(t, axis)
            cols += [g.kp, g.ki, g.kd, g.kir]
        data.append(np.asarray(cols, float).T)
    gain_axis, gain_len = blocks.stack_padded(axes)
    gain_data, _ = blocks.stack_padded(data)
    roll = np.array([np.radians(c.roll.attitude_deadband_deg), np.radians(c.roll.rate_deadband_deg_s),
                     c.roll.lead_time_s])
    fade = np.array([c.ignition_fade.start_s, c.ignition_fade.end_s], float)
    roll_gimbal = np.zeros((3, 3))
    for phase, name in ((FCS_STACK, "stack"), (FCS_UPPER, "upper")):
        g = getattr(c.roll.gimbal, name)
        roll_gimbal[phase] = g.kp, g.ki, g.kd
    return FcsTables(filters=filters, roll_filters=roll_filters, blend=blend, gain_axis=gain_axis,
                     gain_data=gain_data, gain_len=gain_len, roll=roll, fade=fade, roll_gimbal=roll_gimbal)


@njit(cache=True, error_model="numpy")
def df2t(state: np.ndarray, k: int, b: np.ndarray, a: np.ndarray, x: float) -> float:
    """One sample of a 4th-order IIR section (direct form II transposed, a₀ = 1).

    ``state[k:k+4]`` holds the delay line; evaluated as :func:`scipy.signal.lfilter` does.
    """
    y = b[0] * x + state[k]
    state[k] = b[1] * x - a[1] * y + state[k + 1]
    state[k + 1] = b[2] * x - a[2] * y + state[k + 2]
    state[k + 2] = b[3] * x - a[3] * y + state[k + 3]
    state[k + 3] = b[4] * x - a[4] * y
    return y


@njit(cache=True, error_model="numpy")
def filter_pair(state: np.ndarray, k: int, coef: np.ndarray, x: float) -> float:
    """Two fourth-order sections in series; ``coef`` is (2, 2, 5)."""
    y = df2t(state, k, coef[0, 0], coef[0, 1], x)
    return df2t(state, k + 4, coef[1, 0], coef[1, 1], y)


@njit(cache=True, error_model="numpy")
def roll_phase_plane(err: float, rate_err: float, att_db: float, rate_db: float,
                     lead_s: float) -> float:
    """Jet command from the roll phase plane.

    Rate limits dominate: ``rate_err > rate_db`` → −1, ``< −rate_db`` → +1. Otherwise the
    switching function ``σ = err + lead_s·rate_err`` is compared with the attitude
    deadband: ``σ > att_db`` → −1, ``σ < −att_db`` → +1, else 0 (drift).
    """
    if rate_err > rate_db:
        return -1.0
    if rate_err < -rate_db:
        return 1.0
    sigma = err + lead_s * rate_err
    if sigma > att_db:
        return -1.0
    if sigma < -att_db:
        return 1.0
    return 0.0


@njit(cache=True, error_model="numpy")
def fcs_step(d: np.ndarray, q_nav: np.ndarray, phase: int, schedule_var: float,
             since_ignition: float, dt: float, ft: FcsTables) -> tuple[float, float]:
    """One 50 Hz flight-control cycle; reads sensors and smoother from ``d`` and writes
    the gimbal and jet commands back into ``d``; returns the flex-filtered roll-rate error
    (rad/s) and the loop's engagement φ (1, :func:`engagement`), for the roll law by the
    engines' gimbals (``models/roll_gimbal.py``).

    Parameters
    ----------
    d : ndarray
        Discrete state (see :mod:`savant_cli.models.layout`).
    q_nav : ndarray (4,)
        Sensed attitude q_b2i from the navigation unit.
    phase : int
        FCS_STACK, FCS_COAST or FCS_UPPER.
    schedule_var : float
        Altitude (m) on the stack, Earth-relative speed (m/s) afterwards.
    since_ignition : float
        Time since the upper-stage ignition command, s (read in ``FCS_UPPER`` only).
    dt : float
        Control period, s.
    ft : FcsTables
        The flight control's data.

    Notes
    -----
    Scalar arithmetic, the intermediate results kept in ``d`` itself: no array is
    created (this runs at 50 Hz).
    """
    fset = 0 if phase == FCS_STACK else 1
    # error quaternion: rotation from the smoothed command to the body, qs* ⊗ q_nav
    e0, e1, e2, e3 = qt.qmul_xyz(d[D_QS], -d[D_QS + 1], -d[D_QS + 2], -d[D_QS + 3],
                                 q_nav[0], q_nav[1], q_nav[2], q_nav[3])
    if e0 < 0.0:
        e0, e1, e2, e3 = -e0, -e1, -e2, -e3
    d[D_ERR] = 2.0 * e1 + d[D_FLEX_NAV]  # the flex rotation at the nav unit adds
    d[D_ERR + 1] = 2.0 * e2 + d[D_FLEX_NAV + 1]
    d[D_ERR + 2] = 2.0 * e3 + d[D_FLEX_NAV + 2]
    # rate command expressed in body axes
    rc0, rc1, rc2 = qt.rotate_inverse_xyz(e0, e1, e2, e3, d[D_VS], d[D_VS + 1], d[D_VS + 2])
    d[D_RATE_CMD_B] = rc0
    d[D_RATE_CMD_B + 1] = rc1
    d[D_RATE_CMD_B + 2] = rc2
    b0 = b1 = b2 = 0.0  # blended gyro rate
    for g in range(3):
        wgt = ft.blend[fset, g]
        b0 += wgt * d[D_GYRO_Y + 3 * g]
        b1 += wgt * d[D_GYRO_Y + 3 * g + 1]
        b2 += wgt * d[D_GYRO_Y + 3 * g + 2]
    d[D_RATE_ERR] = b0 - rc0
    d[D_RATE_ERR + 1] = b1 - rc1
    d[D_RATE_ERR + 2] = b2 - rc2
    own = GYRO_FIRST if phase == FCS_STACK else GYRO_UPPER

    phi = flight_gains(ft, phase, schedule_var, since_ignition, d, D_GAINS)
    integrate = phi > 0.0

    for c in range(2):  # 0 pitch (body y), 1 yaw (body z)
        ax = c + 1
        if integrate:  # held while the engine has no authority
            d[D_INT_ATT + c] += d[D_ERR + ax] * dt
            d[D_INT_RATE + c] += (d[D_GYRO_Y + 3 * own + ax] - d[D_RATE_CMD_B + ax]) * dt
        base = D_FILT + c * 16
        rate_f = filter_pair(d, base, ft.filters[fset, 0], d[D_RATE_ERR + ax])
        irate_f = filter_pair(d, base + 8, ft.filters[fset, 1], d[D_INT_RATE + c])
        g = D_GAINS + 4 * c
        cmd = -(d[g] * d[D_ERR + ax] + d[g + 1] * d[D_INT_ATT + c] + d[g + 2] * rate_f + d[g + 3] * irate_f)
        if c == 0:
            d[D_CMD_P] = cmd
        else:
            d[D_CMD_Y] = cmd

    roll_rate_f = filter_pair(d, D_ROLL_FILT, ft.roll_filters[fset], d[D_RATE_ERR])
    d[D_CMD_RCS] = roll_phase_plane(d[D_ERR], roll_rate_f, ft.roll[0], ft.roll[1], ft.roll[2])
    return roll_rate_f, phi


@njit(cache=True, error_model="numpy")
def scheduled_gains(gain_axis: np.ndarray, gain_len: np.ndarray, gain_data: np.ndarray, phase: int,
                    schedule_var: float, out: np.ndarray, k0: int) -> None:
    """Kp, Ki, Kd, Kir of pitch then yaw at ``schedule_var`` (altitude m or speed m/s;
    :class:`FcsTables` ``gain_*``), linear between breakpoints, held beyond them, into
    ``out[k0:k0 + 8]``."""
    i, w = locate(gain_axis[phase], gain_len[phase], schedule_var)
    for k in range(8):
        out[k0 + k] = (1.0 - w) * gain_data[phase, i, k] + w * gain_data[phase, i + 1, k]


@njit(cache=True, error_model="numpy")
def engagement(phase: int, since_ignition: float, fade: np.ndarray) -> float:
    """The upper-stage loop's engagement φ (1) at the J-2X start.

    0 in the coast (no thrust); in upper-stage flight φ rises linearly from 0 at
    ``fade[0]`` to 1 at ``fade[1]`` seconds after the ignition command (a step at
    ``fade[0]`` when the two are equal); 1 on the stack.

    Parameters
    ----------
    phase : int
        Flight-control phase (FCS_STACK, FCS_COAST, FCS_UPPER).
    since_ignition : float
        Time since the upper-stage ignition command, s.
    fade : ndarray (2,)
        Fade start and end, s after the ignition command (:class:`FcsTables` ``fade``).
    """
    if phase == FCS_STACK:
        return 1.0
    if phase == FCS_COAST or since_ignition < fade[0]:
        return 0.0
    if since_ignition >= fade[1]:
        return 1.0
    return (since_ignition - fade[0]) / (fade[1] - fade[0])


@njit(cache=True, error_model="numpy")
def flight_gains(ft: FcsTables, phase: int, schedule_var: float, since_ignition: float,
                 out: np.ndarray, k0: int) -> float:
    """The gains the flight control applies, Kp, Ki, Kd, Kir of pitch then yaw, into
    ``out[k0:k0 + 8]``; returns the engagement φ (:func:`engagement`).

    The phase's scheduled gains (:func:`scheduled_gains`); in upper-stage flight faded
    in from the coast table's, ``K_coast + φ (K_upper − K_coast)``.

    Parameters
    ----------
    ft : FcsTables
        The flight control's data.
    phase : int
        Flight-control phase.
    schedule_var : float
        Altitude (m) on the stack, Earth-relative speed (m/s) afterwards.
    since_ignition : float
        Time since the upper-stage ignition command, s (read in ``FCS_UPPER`` only).
    out : ndarray
        Receives the 8 gains at ``k0``.
    k0 : int
        First index written.
    """
    scheduled_gains(ft.gain_axis, ft.gain_len, ft.gain_data, phase, schedule_var, out, k0)
    phi = engagement(phase, since_ignition, ft.fade)
    if phase == FCS_UPPER and phi < 1.0:
        i, w = locate(ft.gain_axis[FCS_COAST], ft.gain_len[FCS_COAST], schedule_var)
        for k in range(8):
            coast = (1.0 - w) * ft.gain_data[FCS_COAST, i, k] + w * ft.gain_data[FCS_COAST, i + 1, k]
            out[k0 + k] = coast + phi * (out[k0 + k] - coast)
    return phi


@njit(cache=True, error_model="numpy")
def pitch_yaw_jets_step(d: np.ndarray, phase: int, ft: FcsTables) -> None:
    """The pitch and yaw jets' commands into ``d`` after a flight-control cycle
    (:func:`fcs_step`'s errors): in the coast phase each axis by the roll channel's phase
    plane (:func:`roll_phase_plane`, its deadbands and lead time) on that axis's attitude
    and blended rate errors; off in powered flight, where the gimbals steer."""
    for c in range(2):
        ax = c + 1
        d[D_CMD_PY + c] = roll_phase_plane(d[D_ERR + ax], d[D_RATE_ERR + ax], ft.roll[0], ft.roll[1],
                                           ft.roll[2]) if phase == FCS_COAST else 0.0


@njit(cache=True, error_model="numpy")
def reset_phase(d: np.ndarray) -> None:
    """Clear integrators and filter memories at separation (the filter set and the
    integrated-rate gyro change; :func:`engagement` holds the integrators through the
    coast, so the J-2X ignition needs no reset); the gimbal commands restart at null, as
    the upper-stage nozzle does."""
    d[D_CMD_P] = 0.0
    d[D_CMD_Y] = 0.0
    d[D_INT_ATT:D_INT_ATT + 2] = 0.0
    d[D_INT_RATE:D_INT_RATE + 2] = 0.0
    d[D_FILT:D_FILT + 32] = 0.0
    d[D_ROLL_FILT:D_ROLL_FILT + 8] = 0.0
