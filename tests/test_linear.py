"""Linearization and stability analysis against independent references: the nonlinear
plant's own small-step response, the tail-wags-dog zero pair, the slosh and flex model
frequencies, a closed-form rigid pitch-plane loop, and brute-force crossing counts."""

from __future__ import annotations

import warnings

import control as ct
import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.linear.loops import assemble
from savant_cli.linear.margins import Bands, loop_margins
from savant_cli.linear.plant import linearize_plant
from savant_cli.models import actuator, aero, atmosphere, layout, mass as mass_model, propulsion, rigid_body, slosh, twd
from savant_cli.sim.engine import rk4, work_array
from savant_cli.sim.plant import derivative
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare

DT_FCS = 0.02


def _point(overrides: list[str], t: float):
    cfg = validate(compose_config(overrides))
    model = prepare(cfg).model
    k = int(round(t / model.rates.dt))
    res = simulate(model, progress=False, snapshot_steps=(k,))
    return model, res.snapshots[k]


@pytest.fixture(scope="module")
def maxq():
    return _point([], 55.0)


def test_linear_plant_matches_nonlinear_small_step(maxq):
    """Frozen time: a 0.1° pitch-command step, 2 s, open loop (commands held)."""
    model, snap = maxq
    lin = linearize_plant(model, snap)
    step = np.radians(0.1)
    # nonlinear: frozen time t, the step added to the held command, no flight software
    x = snap.x.copy()
    u = snap.u.copy()
    x0 = snap.x.copy()
    dt = model.rates.dt
    tb = model.packed_tables
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)
    n = int(2.0 / dt)

    def run(u_in):
        xx = x0.copy()
        out = np.empty(n + 1)
        out[0] = xx[layout.W + 1]
        for k in range(n):
            rk4(snap.t, xx, u_in, dt, model.p, tb, aux, work)  # frozen time
            out[k + 1] = xx[layout.W + 1]
        return out

    up = u.copy()
    up[layout.U_DPC] += step
    q_nl = run(up) - run(u)  # the response to the step alone (the drift cancels)
    t = np.arange(n + 1) * dt
    sys = lin.sys
    i_q = sys.state_labels.index("q")
    resp = ct.forced_response(ct.ss(sys.A, sys.B[:, :1], np.eye(sys.nstates)[i_q:i_q + 1], 0.0), t, np.full(t.size, step))
    q_lin = resp.outputs.ravel()
    peak = np.abs(q_nl).max()
    assert peak > 1e-5
    assert np.abs(q_lin - q_nl).max() < 0.02 * peak  # measured 1.2 %


def test_tail_wags_dog_zero_pair():
    model, snap = _point(["twd=on"], 55.0)
    lin = linearize_plant(model, snap)
    sys = lin.sys
    # δ (actuator state) → pitch rate: the actuator's own poles aside, the zeros are the
    # moment's [T l_c + J s²]: take the plant from the nozzle angle itself (no actuator lag)
    i_dp = sys.state_labels.index("dp")
    keep = [i for i, n in enumerate(sys.state_labels) if n not in ("dp", "dp_dot", "dp_ddot")]
    a = sys.A[np.ix_(keep, keep)]
    # inputs: δ, δ̈ enter through the removed actuator states' columns
    i_ddp = sys.state_labels.index("dp_ddot")
    b_delta = sys.A[keep, i_dp]
    b_acc = sys.A[keep, i_ddp]
    i_q = [sys.state_labels[i] for i in keep].index("q")
    # transfer δ → q with δ̈ = s² δ: G(s) = C (sI − A)⁻¹ (b_δ + s² b_acc); its numerator at q
    # is a polynomial; find the zeros by evaluating on the imaginary axis
    aux = np.zeros(layout.N_AUX)
    derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, np.zeros(snap.x.size))
    thrust = aux[propulsion.A_THRUST]
    cg_x = aux[mass_model.A_CG]  # total CG (no slosh): the rigid CG
    l_c = model.p[propulsion.P_FS_GIMBAL] - cg_x
    engine = model.p[twd.P_FS_ENGINE:twd.P_FS_ENGINE + twd.ENGINE.size]
    jj = engine[twd.E_INERTIA] + engine[twd.E_MASS] * engine[twd.E_ARM] * l_c
    w_expected = np.sqrt(thrust * l_c / jj)
    w = np.linspace(0.5 * w_expected, 1.5 * w_expected, 4001)
    mag = []
    for wi in w:
        s = 1j * wi
        g = np.linalg.solve(s * np.eye(len(keep)) - a, b_delta + s * s * b_acc)
        mag.append(abs(g[i_q]))
    w_zero = w[int(np.argmin(mag))]
    assert w_zero == pytest.approx(w_expected, rel=0.01)


def test_slosh_and_flex_poles_at_their_model_frequencies():
    model, snap = _point(["flex=on", "flex.n_modes=2", "slosh=on"], 55.0)
    lin = linearize_plant(model, snap)
    poles = lin.sys.poles()
    wn = np.abs(poles[poles.imag > 0])
    aux = np.zeros(layout.N_AUX)
    derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, np.zeros(snap.x.size))
    for w_model in (*aux[slosh.A_FREQUENCY:slosh.A_FREQUENCY + 2], *model.tables.flex_freq[0, :2]):
        assert np.min(np.abs(wn - w_model) / w_model) < 0.03, (w_model, np.sort(wn))


def test_closed_form_rigid_pitch_loop_margins(maxq):
    """The numerical plant's pitch loop against the classical launch-vehicle rigid
    pitch-plane model with drift, built in closed form from the same q̄, S, CA, CN, Cm and
    their α and Mach slopes, moment arms, thrust, specific force and inertia:

        θ̈ = μα α + μc δ (+ the q̄ and Mach variation with speed),
        δv̇ = δf_b + θ × f_b0          (drift: inertial velocity in the frozen body axes),
        α = atan(w_b / u_b),  v_b = (I − [θ×]) v

    with the same third-order actuator, gyros and discrete flight control. Inertial drift
    coordinates, as in the classical launch-vehicle model, so the frozen-time terms are
    those of the numerical plant (body-axis velocity states would add the reference's
    acceleration and pitch rate as couplings). Margins agree within 2 % in gain and 1° in
    phase."""
    from scipy.interpolate import RegularGridInterpolator

    from savant_cli.linear.plant import EXTRA_OUTPUTS, INPUT_NAMES, SENSOR_NAMES, PlantLinearization

    model, snap = maxq
    aux = np.zeros(layout.N_AUX)
    derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, np.zeros(snap.x.size))
    tb = model.tables
    qbar, v, mass, thrust = aux[aero.A_QBAR], aux[aero.A_VREL], aux[mass_model.A_MASS], aux[propulsion.A_THRUST]
    cg, mach, a0, rho, sos = aux[mass_model.A_CG], aux[aero.A_MACH], aux[aero.A_ALPHA], aux[atmosphere.A_RHO], aux[atmosphere.A_SOS]
    f_bx0, f_bz0 = aux[rigid_body.A_ACCEL], aux[rigid_body.A_ACCEL + 2]  # specific force, body
    axes = (tb.aero_mach, tb.aero_alpha, tb.aero_beta)
    grid = [RegularGridInterpolator(axes, tb.aero_coef[0, k]) for k in range(tb.aero_coef.shape[1])]
    h = 1e-5  # the local slope of the tables' cell, as the plant's Jacobian sees it

    def coef(k, dm=0.0, da=0.0):
        return float(grid[k]([[mach + dm, a0 + da, 0.0]])[0])

    def d_alpha(k):
        return (coef(k, da=h) - coef(k, da=-h)) / (2 * h)

    def d_mach(k):
        return (coef(k, dm=h) - coef(k, dm=-h)) / (2 * h)

    s_ref, l_ref, x_mrp = tb.aero_ref[0, 0], tb.aero_ref[0, 2], tb.aero_ref[0, 4]
    n_tab = tb.mass_len[0]
    iyy = float(np.interp(snap.x[model.layout.tank("grain")], tb.mass_prop[0, :n_tab], tb.mass_data[0, :n_tab, 5]))
    dx = cg - x_mrp
    ca0, cn0, cm0 = coef(0), coef(2), coef(4)
    u0, w0 = v * np.cos(a0), v * np.sin(a0)
    # body-relative velocity (δu_b, δw_b) from the drift states (δu, δw, θ)
    vb = np.array([[1.0, 0.0, -w0], [0.0, 1.0, u0]])
    alpha_row = np.array([-w0, u0]) / v**2 @ vb  # δα
    mach_row = np.array([u0, w0]) / (v * sos) @ vb  # δM
    qbar_row = rho * np.array([u0, w0]) @ vb  # δq̄
    f_x = (-s_ref * ca0 * qbar_row - qbar * s_ref * (d_alpha(0) * alpha_row + d_mach(0) * mach_row)) / mass
    f_z = (-s_ref * cn0 * qbar_row - qbar * s_ref * (d_alpha(2) * alpha_row + d_mach(2) * mach_row)) / mass
    m_y = (s_ref * (l_ref * cm0 + dx * cn0) * qbar_row
           + qbar * s_ref * ((l_ref * d_alpha(4) + dx * d_alpha(2)) * alpha_row
                             + (l_ref * d_mach(4) + dx * d_mach(2)) * mach_row)) / iyy
    mu_c = thrust * (model.p[propulsion.P_FS_GIMBAL] - cg) / iyy
    third = model.p[actuator.P_FS_THIRD:actuator.P_FS_THIRD + actuator.THIRD.size]
    wa, wn, zeta = third[actuator.T3_LOOP_GAIN], third[actuator.T3_NATURAL_FREQUENCY], third[actuator.T3_DAMPING]
    # states δu, δw (inertial, frozen body axes), θ, q, δ, δ̇, δ̈
    a = np.zeros((7, 7))
    a[0, :3] = f_x + np.array([0.0, 0.0, f_bz0])  # δv̇ = δf_b + θ × f_b0
    a[1, :3] = f_z + np.array([0.0, 0.0, -f_bx0])
    a[1, 4] = thrust / mass
    a[2, 3] = 1.0
    a[3, :3] = m_y
    a[3, 4] = mu_c
    a[4, 5] = a[5, 6] = 1.0
    a[6, 4:] = [-wa * wn * wn, -wn * wn, -2 * zeta * wn]
    b = np.zeros((7, len(INPUT_NAMES)))
    b[6, 0] = wa * wn * wn
    outputs = list(SENSOR_NAMES) + list(EXTRA_OUTPUTS)
    c = np.zeros((len(outputs), 7))
    c[outputs.index("nav_pitch"), 2] = 1.0
    for g in ("upper", "imu", "first"):
        c[outputs.index(f"gyro_{g}_q"), 3] = 1.0
    c[outputs.index("gimbal_pitch"), 4] = 1.0
    c[outputs.index("alpha"), :3] = alpha_row
    closed_form = ct.ss(a, b, c, np.zeros((len(outputs), len(INPUT_NAMES))), inputs=list(INPUT_NAMES),
                        outputs=outputs, states=["du", "dw", "theta", "q", "dp", "dp_dot", "dp_ddot"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        numeric = assemble(model, snap, linearize_plant(model, snap), DT_FCS).loops["pitch"]
        textbook = assemble(model, snap, PlantLinearization(closed_form, np.ones(7), np.arange(7)),
                            DT_FCS).loops_open["pitch"]
    rows_n = loop_margins(numeric, snap.t, "pitch", Bands())
    rows_t = loop_margins(textbook, snap.t, "pitch", Bands())
    # the rigid-body crossings (below 2 Hz): aerodynamic and rigid gain margins, phase margin
    pick = lambda rows: [r for r in rows if r.frequency_hz < 2.0]  # noqa: E731
    rn, rt = pick(rows_n), pick(rows_t)
    assert [r.kind for r in rn] == [r.kind for r in rt] and len(rn) >= 3
    assert rn[0].kind == "gain" and rn[0].value < 0  # the aerodynamic gain margin is there
    for x, y in zip(rn, rt):
        if x.kind == "gain":
            assert 10 ** (x.value / 20) == pytest.approx(10 ** (y.value / 20), rel=0.02), (x, y)
        else:
            assert x.value == pytest.approx(y.value, abs=1.0), (x, y)
        assert x.frequency_hz == pytest.approx(y.frequency_hz, rel=0.02)


def test_every_crossing_of_a_flex_loop_is_listed():
    """A discrete loop with a lightly damped mode crossing 0 dB and −180° several times:
    the listed crossings equal a brute-force count of sign changes on a very fine grid."""
    s = ct.tf("s")
    rigid = 1.2 * (1.5 * s + 1.0) / (s * s - 0.4)  # PD on an unstable rigid plant
    mode = 1.0 + 0.2 * s * (2 * np.pi) / (s * s + 2 * 0.01 * (2 * np.pi) * s + (2 * np.pi) ** 2)  # peak ~10
    loop = ct.ss(ct.c2d(ct.ss(rigid * mode), DT_FCS, "zoh"))
    rows = loop_margins(loop, 0.0, "pitch", Bands(flex_from_hz=0.7))
    w = np.logspace(np.log10(2 * np.pi * 0.01), np.log10(np.pi / DT_FCS), 400000)[1:-1]
    h = loop.frequency_response(w).complex.ravel()
    mag = np.abs(h)
    ph = np.unwrap(np.angle(h))
    n_gain_cross = np.count_nonzero(np.diff(np.sign(mag - 1.0)))
    k = np.floor((ph + np.pi) / (2 * np.pi))  # index of the −180° + 360° k band
    n_phase_cross = np.count_nonzero(np.diff(k))
    assert sum(r.kind == "phase" for r in rows) == n_gain_cross
    assert sum(r.kind == "gain" for r in rows) == n_phase_cross
    assert n_gain_cross >= 3 and any(r.band == "flex" for r in rows)


def _closed_loop_gust_response(model, snap, gust: float, seconds: float) -> np.ndarray:
    """Pitch gimbal angle at every flight-control cycle of the time run (engine.advance,
    flight software in the loop) from ``snap`` with a constant body-z gust (m/s)."""
    from savant_cli.sim import engine, loop_perturbation
    from savant_cli.sim.run import log_columns

    x, d, u, ev = snap.x.copy(), snap.d.copy(), snap.u.copy(), snap.events.copy()
    u[layout.U_GUST + 2] = gust
    rt = model.rates
    log = np.empty((int(seconds / rt.dt) // rt.n_log + 4, log_columns(x.size)))
    kp = model.layout.channel(0)
    out, k, row = [x[kp]], snap.step, 0
    for _ in range(int(round(seconds / (rt.dt * rt.n_fcs)))):
        status, done, row, _ = engine.advance(x, d, u, ev, k, rt.n_fcs, rt, model.p, model.packed_tables, model.fcs,
                                              model.gyro, model.smoother, model.guidance, model.sched, log, row,
                                              loop_perturbation.NONE)
        assert status == engine.RUNNING and done == rt.n_fcs
        k += done
        out.append(x[kp])
    return np.asarray(out)


@pytest.mark.parametrize("overrides", [["flex=on", "flex.n_modes=4"], ["flex=on", "flex.n_modes=4",
                                                                   "controller.delay_s=0"]])
def test_closed_loop_matches_the_time_run_with_flight_software(overrides):
    """The linear closed loop (plant sampled as the flight software samples it: the rate
    gyros' own 200 Hz filters, the loop delay) against the time run itself: the pitch
    gimbal response to a 0.05 m/s body-z gust step at max-Q, flight software in the
    loop, as the difference of two nonlinear runs (the trajectory's drift cancels).

    Within 1 % of the peak over the first 0.5 s (measured 0.8 %; the issue-4 model, a
    continuous gyro and no delay, was off by 2.6 % with the 5 ms delay and 1.2 % without,
    7 % and 2.2 % over the first 0.25 s). Later the frozen-time model itself drifts from
    the flight: the airspeed grows by about 4 %/s at max-Q, and the gust's α with it
    (2 % at 1 s, 4 % at 2 s, for either model)."""
    model, snap = _point(overrides, 55.0)
    lin = linearize_plant(model, snap)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pt = assemble(model, snap, lin, DT_FCS)
    gust, seconds = 0.05, 0.5
    nonlinear = (_closed_loop_gust_response(model, snap, gust, seconds)
                 - _closed_loop_gust_response(model, snap, 0.0, seconds))
    t = np.arange(nonlinear.size) * DT_FCS
    sub = pt.closed[pt.closed.output_labels.index("pitch_gimbal"), pt.closed.input_labels.index("gust_z")]
    linear = ct.forced_response(sub, t, np.full(t.size, gust)).outputs.ravel()
    peak = np.abs(nonlinear).max()
    assert peak > 1e-6
    assert np.abs(linear - nonlinear).max() < 0.01 * peak
