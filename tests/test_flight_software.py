"""Flight-software kernels against independent references: the command smoother against
the closed-form second-order step response, the flex-filter recursion against
scipy.signal.lfilter, the gyro discretization against scipy's continuous step response,
the roll phase plane's regions and closed-loop limit cycle, and the upper-stage loop's
engagement at the J-2X start against its closed form."""

import numpy as np
import pytest
from scipy import signal

from savant_cli.models import quaternion as qt
from savant_cli.models.fcs import (
    FCS_COAST, FCS_STACK, FCS_UPPER, FcsTables, df2t, engagement, fcs_step, filter_pair, roll_phase_plane
)
from savant_cli.models.guidance import command_at, guidance_sample, smoother_step
from savant_cli.models.layout import D_CMD_P, D_GAINS, D_INT_ATT, D_QS, D_VS, N_DISC
from savant_cli.models.sensors import gyro_discrete, gyro_step


@pytest.mark.parametrize("zeta", [0.3, 0.5, 0.7])
def test_smoother_step_response_matches_second_order(zeta):
    wn, dt = 1.5, 0.02
    step = np.radians(10.0)
    q_target = qt.from_rotation_vector(np.array([0.0, step, 0.0]))
    times = np.array([0.0, 1000.0])
    quats = np.array([q_target, q_target])
    rates = np.zeros((2, 3))
    d = np.zeros(N_DISC)
    guidance_sample(d, 0.0, times, quats, rates, True)
    d[D_QS:D_QS + 4] = np.array([1.0, 0.0, 0.0, 0.0])  # smoothed command starts 10 deg away
    d[D_VS:D_VS + 3] = 0.0
    n = int(20.0 / dt)
    theta = np.empty(n)
    for k in range(n):
        smoother_step(d, k * dt, dt, zeta, wn)
        theta[k] = qt.to_rotation_vector(d[D_QS:D_QS + 4])[1]
    overshoot = theta.max() / step - 1.0
    expected = np.exp(-np.pi * zeta / np.sqrt(1.0 - zeta**2))
    assert overshoot == pytest.approx(expected, abs=0.02)
    t_peak = (np.argmax(theta) + 1) * dt
    assert t_peak == pytest.approx(np.pi / (wn * np.sqrt(1.0 - zeta**2)), rel=0.03)
    assert theta[-1] == pytest.approx(step, rel=1e-3)


def test_smoother_tracks_constant_rate_eigenaxis_maneuver():
    rate = np.array([0.0, np.radians(2.0), 0.0])
    times = np.arange(0.0, 60.0, 1.0)
    quats = np.array([qt.from_rotation_vector(rate * t) for t in times])
    rates = np.tile(rate, (times.size, 1))
    d = np.zeros(N_DISC)
    dt = 0.02
    for k in range(int(50.0 / dt)):
        t = k * dt
        if k % 50 == 0:
            guidance_sample(d, t, times, quats, rates, k == 0)
        smoother_step(d, t, dt, 0.8, 1.5)
    t_end = int(50.0 / dt) * dt
    err = qt.to_rotation_vector(qt.qmul(qt.qconj(qt.from_rotation_vector(rate * t_end)), d[D_QS:D_QS + 4]))
    assert np.degrees(np.linalg.norm(err)) < 0.01
    assert d[D_VS:D_VS + 3] == pytest.approx(rate, abs=1e-5)


def test_command_interpolation_is_slerp():
    q0 = qt.from_rotation_vector(np.array([0.0, 0.0, 0.0]))
    q1 = qt.from_rotation_vector(np.array([0.0, 0.0, np.radians(40.0)]))
    q, r = command_at(0.25, np.array([0.0, 1.0]), np.array([q0, q1]), np.zeros((2, 3)))
    assert np.degrees(qt.to_rotation_vector(q)[2]) == pytest.approx(10.0, rel=1e-12)


def test_flex_filter_recursion_matches_lfilter():
    rng = np.random.default_rng(1)
    b1, a1 = signal.butter(4, 8.0, fs=50.0)
    b2, a2 = signal.iirnotch(3.0, 1.5, fs=50.0)
    b2, a2 = np.convolve(b2, b2), np.convolve(a2, a2)
    coef = np.array([[b1, a1], [b2, a2]])
    x = rng.standard_normal(500)
    state = np.zeros(8)
    y = np.array([filter_pair(state, 0, coef, xi) for xi in x])
    ref = signal.lfilter(b2, a2, signal.lfilter(b1, a1, x))
    np.testing.assert_allclose(y, ref, rtol=1e-10, atol=1e-12)
    s = np.zeros(4)
    np.testing.assert_allclose([df2t(s, 0, b1, a1, xi) for xi in x], signal.lfilter(b1, a1, x), atol=1e-12)


def test_gyro_discretization_matches_continuous_step_at_samples():
    fn, zeta, dt = 25.0, 0.7, 0.005
    ad, bd, cd, dd = gyro_discrete(fn, zeta, dt)
    state = np.zeros(2)
    out = np.array([gyro_step(state, 0, 1.0, ad, bd, cd, dd) for _ in range(40)])
    wn = 2 * np.pi * fn
    t = np.arange(40) * dt
    _, y = signal.step(signal.TransferFunction([wn**2], [1, 2 * zeta * wn, wn**2]), T=t)
    np.testing.assert_allclose(out, y, atol=1e-9)  # ZOH is exact for a held input


def test_gyro_zoh_matches_scipy_cont2discrete():
    fn, zeta, dt = 25.0, 0.7, 0.005
    wn = 2 * np.pi * fn
    ad, bd, cd, dd = gyro_discrete(fn, zeta, dt)
    ref = signal.cont2discrete(signal.tf2ss([wn**2], [1, 2 * zeta * wn, wn**2]), dt, method="zoh")
    ref_tf = signal.ss2tf(*ref[:4])
    ours_tf = signal.ss2tf(ad, bd[:, None], cd[None, :], np.array([[dd]]))
    np.testing.assert_allclose(ours_tf[0], ref_tf[0], atol=1e-12)
    np.testing.assert_allclose(ours_tf[1], ref_tf[1], atol=1e-12)


def test_roll_phase_plane_regions():
    db, rdb, lead = np.radians(1.0), np.radians(0.5), 2.0
    # drift zone around the origin
    assert roll_phase_plane(0.0, 0.0, db, rdb, lead) == 0.0
    assert roll_phase_plane(0.9 * db, 0.0, db, rdb, lead) == 0.0
    # attitude beyond the deadband, at rest: torque back toward zero
    assert roll_phase_plane(1.5 * db, 0.0, db, rdb, lead) == -1.0
    assert roll_phase_plane(-1.5 * db, 0.0, db, rdb, lead) == 1.0
    # already returning fast enough: the lead term anticipates and drifts
    assert roll_phase_plane(1.5 * db, -0.8 * rdb, db, rdb, lead) == 0.0  # sigma = 0.7 db
    # rate beyond its deadband dominates, whatever the attitude
    assert roll_phase_plane(-5 * db, 1.2 * rdb, db, rdb, lead) == -1.0
    assert roll_phase_plane(5 * db, -1.2 * rdb, db, rdb, lead) == 1.0


def test_roll_phase_plane_closed_loop_settles_in_deadband():
    """A double integrator under the phase-plane law converges into a limit cycle within
    the attitude deadband with rates below the rate deadband."""
    db, rdb, lead = np.radians(1.0), np.radians(0.5), 2.0
    accel = np.radians(0.5)  # rad/s^2 of jet authority
    dt, th, w = 0.02, np.radians(20.0), 0.0
    hist = []
    for _ in range(int(300 / dt)):
        u = roll_phase_plane(th, w, db, rdb, lead)
        w += u * accel * dt
        th += w * dt
        hist.append((th, w))
    tail = np.array(hist[-int(60 / dt):])
    assert np.max(np.abs(tail[:, 0])) < 1.5 * db
    assert np.max(np.abs(tail[:, 1])) < rdb + accel * dt * 2


# ----------------------------------------------------------- engagement at J-2X ignition

FADE = np.array([0.3, 2.8])  # s after the ignition command


@pytest.mark.parametrize("tau, expected", [(0.0, 0.0), (0.29, 0.0), (0.3, 0.0), (0.8, 0.2), (1.55, 0.5),
                                           (2.3, 0.8), (2.8, 1.0), (10.0, 1.0)])
def test_engagement_rises_linearly_over_the_thrust_build_up(tau, expected):
    """φ = (τ − 0.3) / 2.5 between the fade's ends, 0 before, 1 after, in upper-stage
    flight; 0 throughout the coast, 1 on the stack."""
    assert engagement(FCS_UPPER, tau, FADE) == pytest.approx(expected, abs=1e-12)
    assert engagement(FCS_COAST, tau, FADE) == 0.0
    assert engagement(FCS_STACK, tau, FADE) == 1.0


def test_engagement_with_equal_ends_is_a_step():
    fade = np.array([1.0, 1.0])
    assert engagement(FCS_UPPER, 0.999, fade) == 0.0 and engagement(FCS_UPPER, 1.0, fade) == 1.0


def _tables(coast: tuple[float, float, float, float], upper: tuple[float, float, float, float]) -> FcsTables:
    """Pass-through filters (y = x), the upper-stage gyro alone, one gain set per phase
    held constant over its schedule (two breakpoints): stack (1, 1, 1, 1), the given
    coast and upper-stage sets (Kp, Ki, Kd, Kir), the same in pitch and yaw."""
    identity = np.array([[1.0, 0, 0, 0, 0], [1.0, 0, 0, 0, 0]])
    filters = np.broadcast_to(identity, (2, 2, 2, 2, 5)).copy()
    gain_data = np.array([[list((1.0, 1.0, 1.0, 1.0)) * 2] * 2, [list(coast) * 2] * 2, [list(upper) * 2] * 2])
    return FcsTables(filters=filters, roll_filters=np.broadcast_to(identity, (2, 2, 2, 5)).copy(),
                     blend=np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
                     gain_axis=np.array([[0.0, 1e5]] * 3), gain_data=gain_data, gain_len=np.array([2, 2, 2]),
                     roll=np.array([np.radians(1.0), np.radians(1.0), 1.0]), fade=FADE, roll_gimbal=np.zeros((3, 3)))


def _fly_cycles(ft: FcsTables, phase: int, n: int, pitch_error: float, dt: float = 0.02):
    """``n`` flight-control cycles after ignition (τ = 0.01 s + k dt) with the body held
    ``pitch_error`` (rad) past a fixed command, no rates: the gains, the attitude
    integrator and the pitch command of each cycle."""
    d = np.zeros(N_DISC)
    d[D_QS] = 1.0  # command: the identity attitude, no rate
    q_nav = np.array([np.cos(pitch_error / 2), 0.0, np.sin(pitch_error / 2), 0.0])
    out = []
    for k in range(n):
        tau = 0.01 + k * dt
        fcs_step(d, q_nav, phase, 3000.0, tau, dt, ft)
        out.append((tau, d[D_GAINS:D_GAINS + 4].copy(), d[D_INT_ATT], d[D_CMD_P]))
    return out


def test_gains_fade_from_the_coast_table_and_the_integrator_waits_for_thrust():
    """Through the J-2X start the applied gains are K_coast + φ (K_upper − K_coast) with
    φ = (τ − 0.3) / 2.5 (clipped to [0, 1]); the attitude integrator holds until the fade
    starts, then integrates e·dt; the pitch command is −(Kp e + Ki ∫e) (no rates)."""
    coast, upper = (0.2, 0.05, 0.4, 0.1), (0.8, 0.15, 2.0, 0.3)
    e = np.radians(2.0)
    err = 2.0 * np.sin(e / 2)  # the error angle of the error quaternion
    dt = 0.02
    integral = 0.0
    for tau, gains, i_att, cmd in _fly_cycles(_tables(coast, upper), FCS_UPPER, 200, e, dt):
        phi = min(max((tau - 0.3) / 2.5, 0.0), 1.0)
        np.testing.assert_allclose(gains, np.array(coast) + phi * (np.array(upper) - coast), rtol=1e-12)
        if phi > 0.0:
            integral += err * dt
        assert i_att == pytest.approx(integral, abs=1e-15)
        assert cmd == pytest.approx(-(gains[0] * err + gains[1] * integral), rel=1e-12)
    assert integral == pytest.approx(err * dt * (200 - 15))  # held for the 15 cycles before 0.3 s


def test_coast_commands_with_the_coast_table_and_holds_the_integrators():
    """In the coast (no thrust) the gains are the coast table's and nothing integrates:
    with the shipped zero coast table the nozzle is commanded to null."""
    e = np.radians(2.0)
    for _, gains, i_att, cmd in _fly_cycles(_tables((0.2, 0.05, 0.4, 0.1), (0.8, 0.15, 2.0, 0.3)), FCS_COAST, 50, e):
        np.testing.assert_allclose(gains, [0.2, 0.05, 0.4, 0.1], rtol=1e-12)
        assert i_att == 0.0 and cmd == pytest.approx(-0.2 * 2.0 * np.sin(e / 2), rel=1e-12)
    for _, gains, i_att, cmd in _fly_cycles(_tables((0.0, 0.0, 0.0, 0.0), (0.8, 0.15, 2.0, 0.3)), FCS_COAST, 50, e):
        assert i_att == 0.0 and cmd == 0.0
