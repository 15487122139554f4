"""Flexible body on the synthetic plant, against closed-form references.

* Free-free, undamped, unloaded modes conserve their modal energy ½(q̇² + ω² q²) (unit
  generalized mass) and follow q₀ cos ωt + (q̇₀/ω) sin ωt.
* A damped mode's frequency (zero crossings) and logarithmic decrement give ω and ζ.
* The sensors: ``flex_point`` returns Σ σ_i(pt) q̇_i (rate) and Σ σ_i(pt) q_i (rotation)
  from the tables built here, with the modal sets selected and blended as documented; a
  run of the engine feeds each gyro ω + Σ σ_i(gyro point) q̇_i (read at DC steady state)
  and stores Σ σ_i(IMU) q_i as the navigation unit's flex rotation.
* Generalized force: Q_i = φ_i(gimbal)·F_thrust + σ_i(gimbal)·M with the thrust turned by
  the flex rotation at the active gimbal, the engine-inertia reaction (m_R l_R δ̈ force,
  I_R δ̈ torque) at the same point, and the roll-jet torque at the RCS point.
"""

from __future__ import annotations

import numpy as np
import pytest

import synthetic
from savant_cli.models import flex, layout, mass as mass_model, propulsion, rcs, rigid_body, twd as twd_model
from savant_cli.models.flex import flex_point
from savant_cli.sim.engine import rk4, work_array
from savant_cli.sim.plant import derivative, pack_tables

N_SETS = len(layout.FLEX_SETS)


def _flex_tables(freq: np.ndarray, zeta: np.ndarray, shapes: np.ndarray, **kw):
    """Synthetic plant tables with the given modal data (freq (4, n), zeta (n,),
    shapes (4, n, N_POINTS, 6))."""
    tb = synthetic.tables(**kw)
    return tb._replace(flex_freq=np.ascontiguousarray(freq, dtype=float),
                       flex_zeta=np.ascontiguousarray(zeta, dtype=float),
                       flex_shape=np.ascontiguousarray(shapes, dtype=float))


def _flex_params(n_modes: int, switch: int = 0, **kw) -> tuple[np.ndarray, layout.StateLayout]:
    lay = synthetic.state_layout(n_modes=n_modes)
    p = synthetic.parameters(lay=lay, **kw)
    p[flex.P_N_MODES] = n_modes
    p[flex.P_SWITCH] = switch
    return p, lay


def _orbit_state(lay: layout.StateLayout) -> np.ndarray:
    x = np.zeros(lay.n)
    x[layout.R] = 7.0e6  # far above the atmosphere (no pressure loss, no divergence on altitude)
    x[layout.Q] = 1.0
    x[synthetic.FS] = x[synthetic.LOX] = x[synthetic.LH2] = 1.0
    return x


def _random_shapes(rng, n_modes: int, scale_d: float = 1e-3, scale_r: float = 1e-4) -> np.ndarray:
    s = np.empty((N_SETS, n_modes, layout.N_POINTS, 6))
    s[..., :3] = scale_d * rng.standard_normal((N_SETS, n_modes, layout.N_POINTS, 3))
    s[..., 3:] = scale_r * rng.standard_normal((N_SETS, n_modes, layout.N_POINTS, 3))
    return s


def test_a_clusters_couple_loads_the_modes_through_the_rotation_at_its_node():
    """q = q̇ = 0 and a couple C about the upper stage's gimbal point alone (a cluster's
    ``Σ Δ_i × F_i``, no net force): q̈_i = σ_i(gimbal) · C, the set flown by the upper
    configuration (set 2 at weight 0); and no couple: no load."""
    from savant_cli.models.flex import PT_GIMBAL_US, StructuralLoads, modal_rates

    rng = np.random.default_rng(7)
    shapes = _random_shapes(rng, 2)
    tb = pack_tables(_flex_tables(np.ones((N_SETS, 2)), np.zeros(2), shapes))
    p, lay = _flex_params(2)
    x = _orbit_state(lay)
    couple = np.array([3.0e4, -2.0e5, 1.5e5])
    for c, expected in ((couple, shapes[2, :, PT_GIMBAL_US, 3:] @ couple), (np.zeros(3), np.zeros(2))):
        xd = np.zeros(lay.n)
        loads = StructuralLoads((0.0, 0.0, 0.0), (0.0, 0.0), 0.0, (0.0, 0.0), tuple(c))
        modal_rates(x, layout.CONFIG_UPPER, p, tb, PT_GIMBAL_US, loads, np.zeros(layout.N_AUX), 0, xd)
        np.testing.assert_allclose(xd[lay.flex + 2:lay.flex + 4], expected, rtol=1e-14, atol=0.0)


# ----------------------------------------------------------------- free vibration


def test_undamped_free_modes_conserve_modal_energy():
    """No thrust, aero or jets: the modes are unloaded. Two modes, ζ = 0, ω = 2π·1.3 and
    2π·3.1 rad/s, dt = 0.5 ms (ω dt < 0.01, RK4 energy error (ω dt)⁶/72 per step) for
    10 s (13 and 31 periods)."""
    rng = np.random.default_rng(1)
    w = np.array([2 * np.pi * 1.3, 2 * np.pi * 3.1])
    freq = np.tile(w, (N_SETS, 1))
    freq[:2] *= 3.0  # stack sets: must not be used on the upper-stage configuration
    tb = pack_tables(_flex_tables(freq, np.zeros(2), _random_shapes(rng, 2)))
    p, lay = _flex_params(2, gravity_order=0)
    u = synthetic.coast_inputs()  # upper stage: sets 2 (weight 1) and 3 (weight 0)
    x = _orbit_state(lay)
    fo = lay.flex
    q0, qd0 = np.array([0.7, -0.2]), np.array([1.5, 4.0])
    x[fo:fo + 2] = q0
    x[fo + 2:fo + 4] = qd0

    def energy(x):
        return 0.5 * (x[fo + 2:fo + 4] ** 2 + w**2 * x[fo:fo + 2] ** 2)

    e0 = energy(x)
    dt, n = 5e-4, 20000
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)
    max_err = np.zeros(2)
    for k in range(n):
        rk4(k * dt, x, u, dt, p, tb, aux, work)
        if k % 97 == 0:
            max_err = np.maximum(max_err, np.abs(energy(x) / e0 - 1.0))
    max_err = np.maximum(max_err, np.abs(energy(x) / e0 - 1.0))
    assert np.all(max_err < 1e-8), max_err
    t = n * dt
    q_exact = q0 * np.cos(w * t) + qd0 / w * np.sin(w * t)
    amp = np.sqrt(q0**2 + (qd0 / w) ** 2)
    np.testing.assert_allclose(x[fo:fo + 2], q_exact, rtol=0, atol=1e-7 * amp.max())
    # free-free: the unloaded modes do not move the rigid body
    np.testing.assert_array_equal(x[layout.W:layout.W + 3], 0.0)


@pytest.mark.parametrize("zeta", [0.01, 0.05])
def test_damped_mode_frequency_and_log_decrement(zeta):
    rng = np.random.default_rng(2)
    wn = 2 * np.pi * 2.0
    tb = pack_tables(_flex_tables(np.full((N_SETS, 1), wn), np.array([zeta]), _random_shapes(rng, 1)))
    p, lay = _flex_params(1)
    u = synthetic.coast_inputs()
    x = _orbit_state(lay)
    fo = lay.flex
    x[fo] = 0.3
    dt, n = 1e-3, 8000
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)
    y = np.empty(n)
    for k in range(n):
        rk4(k * dt, x, u, dt, p, tb, aux, work)
        y[k] = x[fo]
    t = (np.arange(n) + 1) * dt
    up = np.nonzero((y[:-1] < 0) & (y[1:] >= 0))[0]
    tc = t[up] - y[up] * dt / (y[up + 1] - y[up])  # interpolated upward zero crossings
    wd = 2 * np.pi / np.mean(np.diff(tc))
    peaks = np.array([np.max(y[a:b]) for a, b in zip(up[:-1], up[1:])])
    delta = np.mean(np.log(peaks[:-1] / peaks[1:]))
    zeta_meas = delta / np.sqrt(4 * np.pi**2 + delta**2)
    wn_meas = wd / np.sqrt(1 - zeta_meas**2)
    assert len(peaks) >= 10
    assert wn_meas == pytest.approx(wn, rel=0.01)
    assert zeta_meas == pytest.approx(zeta, rel=0.01)


# ------------------------------------------------------------------------ sensors


@pytest.mark.parametrize("n_used", [3, 2])  # 2: fewer retained modes than the tables hold
@pytest.mark.parametrize("config,switch,sets,weight", [
    (layout.CONFIG_STACK, 0, (0, 1), 0.0),
    (layout.CONFIG_UPPER, 0, (2, 3), 0.0),
    (layout.CONFIG_UPPER_LES, 0, (2, 3), 0.0),
    (layout.CONFIG_STACK, 1, (0, 1), 0.25),  # by propellant: 75 % of the stage remains
    (layout.CONFIG_UPPER, 1, (2, 3), 0.6),  # 40 % remains
])
def test_flex_point_rotation_and_rate_at_every_point(config, switch, sets, weight, n_used):
    """``flex_point`` = Σ_i [(1−w) σ_i^a(pt) + w σ_i^b(pt)] q_i (or q̇_i), with w the
    fraction of the stage's propellant burned (0 with the separation switch)."""
    rng = np.random.default_rng(3)
    nd = 3
    shapes = _random_shapes(rng, nd)
    tb = pack_tables(_flex_tables(np.full((N_SETS, nd), 10.0), np.zeros(nd), shapes))
    nm = n_used
    p, lay = _flex_params(nm, switch=switch)
    p[propulsion.P_FS_PROP_FULL] = 4.0e5
    p[propulsion.P_US_PROP_FULL] = 1.0e5
    x = _orbit_state(lay)
    x[synthetic.FS] = 0.75 * 4.0e5
    x[synthetic.LOX], x[synthetic.LH2] = 0.4 * 1.0e5 * 5 / 6, 0.4 * 1.0e5 / 6
    x[layout.W:layout.W + 3] = (0.01, -0.02, 0.03)
    fo = lay.flex
    q = rng.standard_normal(nm)
    qd = rng.standard_normal(nm)
    x[fo:fo + nm] = q
    x[fo + nm:fo + 2 * nm] = qd
    sa, sb = sets
    sig = (1.0 - weight) * shapes[sa, :, :, 3:] + weight * shapes[sb, :, :, 3:]  # (nd, N_POINTS, 3)
    out = np.zeros(3)
    for pt in range(layout.N_POINTS):
        expected_rate = sum(sig[i, pt] * qd[i] for i in range(nm))
        expected_rot = sum(sig[i, pt] * q[i] for i in range(nm))
        flex_point(x, config, p, tb, pt, True, out)
        np.testing.assert_allclose(out, expected_rate, rtol=1e-12, atol=1e-18)
        flex_point(x, config, p, tb, pt, False, out)
        np.testing.assert_allclose(out, expected_rot, rtol=1e-12, atol=1e-18)
    # flex off: zero
    p[flex.P_OFFSET] = -1
    flex_point(x, config, p, tb, layout.PT_IMU, True, out)
    np.testing.assert_array_equal(out, 0.0)


@pytest.mark.parametrize("config", [layout.CONFIG_STACK, layout.CONFIG_UPPER])
def test_engine_feeds_gyros_rigid_plus_flex_rate_and_nav_unit_flex_rotation(config):
    """Spherical inertia and no loads: the body rate ω is constant; modes with ω_i = 0 and
    ζ = 0 drift at constant q̇ (q = q₀ + q̇ t, integrated exactly by RK4). The gyro filter
    ω_s²/(s² + 2ζω_s s + ω_s²) has unit DC gain, so after 2 s each gyro outputs exactly
    ω + Σ σ_i(its point) q̇_i; the navigation unit's flex rotation at the last flight-control
    cycle t_c is Σ σ_i(IMU) (q₀ᵢ + q̇ᵢ t_c)."""
    from conftest import compose_config
    from savant_cli.config import validate
    from savant_cli.models.fcs import fcs_tables
    from savant_cli.models.guidance import SmootherGains
    from savant_cli.models.sensors import gyro_discrete
    from savant_cli.sim import engine, loop_perturbation
    from savant_cli.sim.run import log_columns

    rng = np.random.default_rng(4)
    nm = 2
    shapes = _random_shapes(rng, nm, scale_r=1e-2)
    tables = _flex_tables(np.zeros((N_SETS, nm)), np.zeros(nm), shapes,
                          inertia=(500.0, 500.0, 500.0, 0.0, 0.0, 0.0))
    tb = pack_tables(tables)
    p, lay = _flex_params(nm)
    u = synthetic.coast_inputs()
    u[layout.U_CONFIG] = config
    x = _orbit_state(lay)
    w_body = np.array([0.02, -0.05, 0.03])
    x[layout.W:layout.W + 3] = w_body
    fo = lay.flex
    q0 = np.array([0.5, -1.0])
    qd = np.array([2.0, 0.7])
    x[fo:fo + nm] = q0
    x[fo + nm:fo + 2 * nm] = qd

    dt = 0.005
    rates = engine.Rates(dt=dt, n_sensor=1, n_fcs=4, n_guid=200, n_log=4)
    gyro = gyro_discrete(25.0, 0.7, dt)
    smoother = SmootherGains(damping=0.8, natural_frequency_rad_s=1.0)
    gt = engine.GuidanceTable(time=np.array([0.0, 1.0e4]), quat=np.tile([1.0, 0.0, 0.0, 0.0], (2, 1)),
                              rate=np.zeros((2, 3)), speed=np.zeros(0))
    ft = fcs_tables(validate(compose_config()).controller)
    never = engine.EventRule(after=-1, delay_s=np.inf, when=engine.WHEN_NONE, of=-1, above=False, threshold=0.0)
    sched = engine.EventSchedule(rules=(never,) * len(engine.EVENT_NAMES), cutoff_energy_j_kg=1.0e12, max_time_s=1.0e9,
                                 stop_at_separation=False, max_body_rate_rad_s=10.0, command_delay_steps=0, profile_schedule=0)
    d = np.zeros(layout.N_DISC)
    events = np.full(len(engine.EVENT_NAMES), np.nan)
    n = 400
    log = np.empty((n // rates.n_log + 2, log_columns(lay.n)))
    status, done, _, detail = engine.advance(x, d, u, events, 0, n, rates, p, tb, ft, gyro, smoother, gt, sched,
                                             log, 0, loop_perturbation.NONE)
    assert status == engine.RUNNING and done == n, detail

    np.testing.assert_allclose(x[layout.W:layout.W + 3], w_body, rtol=1e-12)  # torque-free sphere
    np.testing.assert_allclose(x[fo + nm:fo + 2 * nm], qd, rtol=1e-12)
    sets = (0, 1) if config == layout.CONFIG_STACK else (2, 3)
    sig = shapes[sets[0], :, :, 3:]  # separation switch: the first set of the stage
    for g, pt in enumerate((layout.PT_GYRO_US, layout.PT_IMU, layout.PT_GYRO_FS)):  # FCS gyro order
        expected = w_body + sig[0, pt] * qd[0] + sig[1, pt] * qd[1]
        np.testing.assert_allclose(d[layout.D_GYRO_Y + 3 * g:layout.D_GYRO_Y + 3 * g + 3], expected, rtol=1e-9, atol=1e-13)
    t_c = ((n - 1) // rates.n_fcs) * rates.n_fcs * dt
    q_c = q0 + qd * t_c
    expected_nav = sig[0, layout.PT_IMU] * q_c[0] + sig[1, layout.PT_IMU] * q_c[1]
    np.testing.assert_allclose(d[layout.D_FLEX_NAV:layout.D_FLEX_NAV + 3], expected_nav, rtol=1e-10, atol=1e-15)
    assert np.linalg.norm(expected_nav) > 1e-3  # a non-trivial check


# ------------------------------------------------------------- generalized force


def _thrust_setup(engine: int, rng, nm: int = 2, twd: bool = False):
    shapes = _random_shapes(rng, nm, scale_d=2e-3, scale_r=3e-4)
    w = np.array([2 * np.pi * 1.1, 2 * np.pi * 2.7])[:nm]
    zeta = np.array([0.02, 0.03])[:nm]
    tables = _flex_tables(np.tile(w, (N_SETS, 1)), zeta, shapes)
    thrust = 2.0e6
    tables = tables._replace(fs_time=np.array([0.0, 1.0e3]), fs_thrust=np.array([thrust, thrust]))
    p, lay = _flex_params(nm, thrust=True)
    p[propulsion.P_US_THRUST] = thrust
    if twd:
        p[twd_model.P_ON] = 1.0
        p[twd_model.P_FS_ENGINE:twd_model.P_FS_ENGINE + 3] = (7000.0, 2.0, 35000.0)  # mass, arm, inertia
        p[twd_model.P_US_ENGINE:twd_model.P_US_ENGINE + 3] = (2500.0, 1.5, 8125.0)
    u = synthetic.coast_inputs()
    if engine == layout.ENGINE_FIRST:
        u[layout.U_CONFIG], u[layout.U_ENGINE] = layout.CONFIG_STACK, layout.ENGINE_FIRST
    else:
        u[layout.U_CONFIG], u[layout.U_ENGINE] = layout.CONFIG_UPPER, layout.ENGINE_UPPER
        u[layout.U_T_IGN] = -10.0
    x = _orbit_state(lay)
    return tables, shapes, w, zeta, thrust, p, lay, u, x


def _rotation_matrix(theta: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``theta`` (Rodrigues)."""
    a = np.linalg.norm(theta)
    if a == 0.0:
        return np.eye(3)
    k = theta / a
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(a) * kx + (1 - np.cos(a)) * kx @ kx


@pytest.mark.parametrize("engine", [layout.ENGINE_FIRST, layout.ENGINE_UPPER])
@pytest.mark.parametrize("plane", ["pitch", "yaw", "both"])
def test_modal_acceleration_is_thrust_at_the_gimbal_turned_by_flex(engine, plane):
    """q̈_i = φ_i(gimbal)·F − 2ζ_i ω_i q̇_i − ω_i² q_i with F = T R(θ_g) t̂(δ_p, δ_y),
    θ_g = Σ σ_i(gimbal) q_i. In one plane the exact rotation composes with the gimbal
    angle (δ − θ), in both planes the two agree to second order (|θ|·|δ|)."""
    rng = np.random.default_rng(5 + engine)
    tables, shapes, w, zeta, thrust, p, lay, u, x = _thrust_setup(engine, rng)
    nm = 2
    pg, other = ((layout.PT_GIMBAL_FS, layout.PT_GIMBAL_US) if engine == layout.ENGINE_FIRST
                 else (layout.PT_GIMBAL_US, layout.PT_GIMBAL_FS))
    if plane == "pitch":  # pitch-plane modes (dz, ry) and a pitch gimbal angle only
        shapes[..., [0, 1, 3, 5]] = 0.0
        dp, dy = 0.05, 0.0
    elif plane == "yaw":
        shapes[..., [0, 2, 3, 4]] = 0.0
        dp, dy = 0.0, -0.04
    else:
        dp, dy = 0.05, -0.04
    tb = pack_tables(tables._replace(flex_shape=shapes))
    fo = lay.flex
    q = np.array([0.8, -0.5])
    qd = np.array([0.3, 1.2])
    x[fo:fo + nm] = q
    x[fo + nm:fo + 2 * nm] = qd
    x[synthetic.ACT_P], x[synthetic.ACT_Y] = dp, dy
    sa = 0 if engine == layout.ENGINE_FIRST else 2
    phi = shapes[sa, :, pg, :3]
    sig = shapes[sa, :, pg, 3:]
    theta = sig.T @ q
    t_hat = np.array([np.cos(dp) * np.cos(dy), -np.sin(dy), np.sin(dp) * np.cos(dy)])
    force = thrust * _rotation_matrix(theta) @ t_hat
    expected = phi @ force - 2 * zeta * w * qd - w**2 * q

    aux, xd = np.zeros(layout.N_AUX), np.zeros(lay.n)
    derivative(0.0, x, u, p, tb, aux, xd)
    assert aux[propulsion.A_THRUST] == pytest.approx(thrust, rel=1e-12)
    np.testing.assert_allclose(xd[fo:fo + nm], qd, rtol=1e-15)
    gen_scale = np.abs(phi).max() * thrust
    tol = 1e-12 if plane != "both" else 2.0 * np.abs(theta).max() * (abs(dp) + abs(dy) + np.abs(theta).max())
    np.testing.assert_allclose(xd[fo + nm:fo + 2 * nm], expected, rtol=0, atol=tol * gen_scale)
    np.testing.assert_allclose(aux[flex.A_GIMBAL_ROTATION:flex.A_GIMBAL_ROTATION + 3], theta, rtol=1e-12, atol=1e-18)
    # the rigid body feels the same turned thrust (force along body axes / mass)
    np.testing.assert_allclose(aux[rigid_body.A_ACCEL:rigid_body.A_ACCEL + 3], force / 1000.0, rtol=0,
                               atol=tol * thrust / 1000.0)
    # the other stage's gimbal carries no load: moving its shapes changes nothing
    sh2 = shapes.copy()
    sh2[:, :, other, :] += 1.0
    xd2 = np.zeros(lay.n)
    derivative(0.0, x, u, p, pack_tables(tables._replace(flex_shape=sh2)), aux, xd2)
    np.testing.assert_array_equal(xd2[fo:], xd[fo:])


@pytest.mark.parametrize("engine", [layout.ENGINE_FIRST, layout.ENGINE_UPPER])
def test_engine_inertia_reaction_loads_the_modes_at_the_gimbal(engine):
    """Tail-wags-dog on, no thrust (P_THRUST_ON = 0), third-order actuator with nozzle
    angular accelerations δ̈_p, δ̈_y: the nozzle (mass m_R, CG l_R aft of the gimbal, inertia
    I_R about it) pushes the structure at the gimbal with F = m_R l_R (0, −δ̈_y, δ̈_p) and
    M = I_R (0, δ̈_p, δ̈_y), so q̈_i = φ_i(g)·F + σ_i(g)·M − 2ζωq̇ − ω²q."""
    rng = np.random.default_rng(11 + engine)
    tables, shapes, w, zeta, thrust, p, lay, u, x = _thrust_setup(engine, rng, twd=True)
    p[propulsion.P_ON] = 0.0
    tb = pack_tables(tables)
    nm = 2
    fo = lay.flex
    q = np.array([0.2, 0.1])
    x[fo:fo + nm] = q
    x[synthetic.ACT_P], x[synthetic.ACT_P + 2] = 0.01, 4.0
    x[synthetic.ACT_Y], x[synthetic.ACT_Y + 2] = -0.02, -2.5
    if engine == layout.ENGINE_FIRST:
        pg, (m_r, l_r, i_r), sa = layout.PT_GIMBAL_FS, (7000.0, 2.0, 35000.0), 0
    else:
        pg, (m_r, l_r, i_r), sa = layout.PT_GIMBAL_US, (2500.0, 1.5, 8125.0), 2
    force = m_r * l_r * np.array([0.0, 2.5, 4.0])
    moment = i_r * np.array([0.0, 4.0, -2.5])
    expected = shapes[sa, :, pg, :3] @ force + shapes[sa, :, pg, 3:] @ moment - w**2 * q
    aux, xd = np.zeros(layout.N_AUX), np.zeros(lay.n)
    derivative(0.0, x, u, p, tb, aux, xd)
    assert aux[propulsion.A_THRUST] == 0.0
    np.testing.assert_allclose(xd[fo + nm:fo + 2 * nm], expected, rtol=1e-12)


def test_roll_jet_torque_loads_the_modes_at_the_rcs_point():
    """Positive-roll jets fully on: torque T_x = n F_jet arm about body x at the RCS point,
    Q_i = σ_x,i(RCS)·T_x."""
    rng = np.random.default_rng(13)
    tables, shapes, w, zeta, thrust, p, lay, u, x = _thrust_setup(layout.ENGINE_UPPER, rng)
    p[propulsion.P_ON] = 0.0
    f_jet = 3100.0
    tables = tables._replace(rcs_alt=np.array([0.0, 1.0e7]), rcs_thrust=np.array([f_jet, f_jet]))
    p[rcs.P_N], p[rcs.P_ARM] = 2.0, 2.75
    tb = pack_tables(tables)
    x[synthetic.RCS_POS] = 1.0
    fo = lay.flex
    torque = 2.0 * f_jet * 2.75
    expected = shapes[2, :, layout.PT_RCS, 3] * torque
    aux, xd = np.zeros(layout.N_AUX), np.zeros(lay.n)
    derivative(0.0, x, u, p, tb, aux, xd)
    assert aux[rcs.A_TORQUE] == pytest.approx(torque, rel=1e-12)
    np.testing.assert_allclose(xd[fo + 2:fo + 4], expected, rtol=1e-12)


@pytest.mark.parametrize("engine", [layout.ENGINE_FIRST, layout.ENGINE_UPPER])
def test_thrust_and_engine_reaction_act_at_the_displaced_gimbal(engine):
    """One pitch-plane mode (φ_x, φ_z, σ_y at the gimbal), nozzle at null: the thrust
    T R(σ_y q) x̂ acts at r_g + φ q, so the modal-to-rigid pitch moment per unit q is,
    by hand, ∂M_y/∂q = T (φ_z + r_gx σ_y) (the turned thrust on the arm, plus the axial
    thrust on the displacement; the old plant had only T r_gx σ_y). The tail-wags-dog force
    F = m_R l_R (0, 0, δ̈_p) at the same point adds ∂M_y/∂q = −φ_x m_R l_R δ̈_p."""
    rng = np.random.default_rng(21 + engine)
    tables, shapes, w, zeta, thrust, p, lay, u, x = _thrust_setup(engine, rng, nm=1, twd=True)
    pg = layout.PT_GIMBAL_FS if engine == layout.ENGINE_FIRST else layout.PT_GIMBAL_US
    shapes[...] = 0.0
    phi_x, phi_z, sigma_y = 4.0e-4, 2.5e-3, -3.0e-4
    shapes[:, 0, pg, flex.PHI_X], shapes[:, 0, pg, flex.PHI_Z], shapes[:, 0, pg, flex.SIGMA_Y] = phi_x, phi_z, sigma_y
    tb = pack_tables(tables._replace(flex_shape=shapes))
    fo = lay.flex
    acc_p = 3.0  # rad/s², the third-order nozzle acceleration state
    x[synthetic.ACT_P:synthetic.ACT_P + 3] = 0.0, 0.0, acc_p
    x[synthetic.ACT_Y:synthetic.ACT_Y + 3] = 0.0

    def moments(q: float) -> tuple[float, float]:
        xs = x.copy()
        xs[fo] = q
        aux, xd = np.zeros(layout.N_AUX), np.zeros(lay.n)
        derivative(0.0, xs, u, p, tb, aux, xd)
        return aux[propulsion.A_MOMENT + 1], aux[twd_model.A_MOMENT + 1]

    # the arm at q = 0 from the plant's own CG (aux) and the vehicle's gimbal station
    aux0, xd0 = np.zeros(layout.N_AUX), np.zeros(lay.n)
    derivative(0.0, x, u, p, tb, aux0, xd0)
    cg = aux0[mass_model.A_CG:mass_model.A_CG + 3]
    r_gx = propulsion.gimbal_arm(p, int(u[layout.U_ENGINE]), *cg)[0]
    assert r_gx < -1.0  # the gimbal is aft of the CG
    h = 1e-3
    (mp, wp), (mm, wm) = moments(h), moments(-h)
    e = twd_model.P_FS_ENGINE if engine == layout.ENGINE_FIRST else twd_model.P_US_ENGINE
    m_l = p[e + twd_model.E_MASS] * p[e + twd_model.E_ARM]
    assert (mp - mm) / (2 * h) == pytest.approx(thrust * (phi_z + r_gx * sigma_y), rel=1e-6)
    assert (wp - wm) / (2 * h) == pytest.approx(-phi_x * m_l * acc_p, rel=1e-6)
