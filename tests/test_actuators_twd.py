"""Simplex actuator against its closed-form transfer function (python-control), its
reduction to the third-order model, and the tail-wags-dog moment against
T·l_c·sin δ + (I_R + m_R l_R l_c)·δ̈ (the zero pair of [T l_c + J s²] δ)."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

import synthetic
from savant_cli.models import actuator, layout, propulsion, twd
from savant_cli.sim.plant import derivative, pack_tables

J_LOAD = 8125.0  # kg m²
WN = 2 * np.pi * 15.0
ZETA = 0.6
K_LOAD = J_LOAD * WN**2
C_LOAD = 2 * ZETA * np.sqrt(K_LOAD * J_LOAD)


def _simplex_params(wv: float, feedback: float, leak: float = 0.0) -> np.ndarray:
    p = np.zeros(actuator.SPX.size)
    p[[actuator.SX_LOOP_GAIN, actuator.SX_VALVE_FREQUENCY, actuator.SX_VALVE_DAMPING, actuator.SX_RATE_LIMIT,
       actuator.SX_STIFFNESS, actuator.SX_DAMPING, actuator.SX_LOAD_INERTIA, actuator.SX_LEAKAGE,
       actuator.SX_NOZZLE_FEEDBACK]] = (30.0, wv, 0.7, 10.0, K_LOAD, C_LOAD, J_LOAD, leak, feedback)
    return p  # large rate limit: linear


def _jacobian(fun, n: int, eps: float = 1e-7) -> tuple[np.ndarray, np.ndarray]:
    """A, B of a state function f(x, u) by central differences about 0."""
    a = np.zeros((n, n))
    b = np.zeros((n, 1))
    for i in range(n):
        e = np.zeros(n)
        e[i] = eps
        a[:, i] = (fun(e, 0.0) - fun(-e, 0.0)) / (2 * eps)
    b[:, 0] = (fun(np.zeros(n), eps) - fun(np.zeros(n), -eps)) / (2 * eps)
    return a, b


def _simplex_ss(wv: float, feedback: float) -> ct.StateSpace:
    sp = _simplex_params(wv, feedback)

    def f(x5, u):
        x = np.zeros(5)
        x[:] = x5
        out = np.zeros(5)
        actuator.simplex(x, 0, 3, u, sp, 0, 1.0, out)
        return out

    a, b = _jacobian(f, 5)
    return ct.ss(a, b, np.array([[1.0, 0, 0, 0, 0]]), 0.0)


def test_simplex_matches_its_closed_form_transfer_function():
    """Piston feedback: θ_p/δc = G_v K_a / (s + G_v K_a), δ/θ_p = K / (J s² + C s + K)."""
    wv = 2 * np.pi * 45.0
    sys = _simplex_ss(wv, feedback=0.0)
    s = ct.tf("s")
    gv = wv**2 / (s**2 + 2 * 0.7 * wv * s + wv**2)
    ka = 30.0
    ref = ct.minreal(gv * ka / (s + gv * ka) * K_LOAD / (J_LOAD * s**2 + C_LOAD * s + K_LOAD), verbose=False)
    w = np.logspace(-1, 3, 80)
    h = ct.frequency_response(sys, w).complex.ravel()
    h_ref = ct.frequency_response(ref, w).complex.ravel()
    np.testing.assert_allclose(h, h_ref, rtol=1e-5, atol=1e-8)


def test_simplex_reduces_to_third_order_with_fast_valve_and_nozzle_feedback():
    sys = _simplex_ss(wv=2 * np.pi * 2000.0, feedback=1.0)

    def f3(x3, u):
        x = np.array(x3, dtype=float)
        out = np.zeros(3)
        p3 = np.zeros(actuator.THIRD.size)
        p3[[actuator.T3_LOOP_GAIN, actuator.T3_NATURAL_FREQUENCY, actuator.T3_DAMPING, actuator.T3_RATE_LIMIT]] = 30.0, WN, ZETA, 10.0
        actuator.third_order(x, 0, u, p3, 0, 1.0, out)
        return out

    a3, b3 = _jacobian(f3, 3)
    third = ct.ss(a3, b3, np.array([[1.0, 0, 0]]), 0.0)
    s = ct.tf("s")
    closed_form = 30.0 * WN**2 / (s * (s**2 + 2 * ZETA * WN * s + WN**2) + 30.0 * WN**2)
    w = np.logspace(-1, 2.3, 60)
    h3 = ct.frequency_response(third, w).complex.ravel()
    np.testing.assert_allclose(h3, ct.frequency_response(closed_form, w).complex.ravel(), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(ct.frequency_response(sys, w).complex.ravel(), h3, rtol=2e-2, atol=2e-3)


def test_simplex_rate_saturates_at_the_valve_limit():
    """A large step: the spool sits on its stop and the ram moves at the flow limit."""
    sp = _simplex_params(2 * np.pi * 45.0, 0.0)
    sp[actuator.SX_RATE_LIMIT] = np.radians(5.0)
    x = np.zeros(5)
    dt = 1e-4
    for _ in range(int(0.2 / dt)):  # 0.2 s into a 0.1 rad step, still slewing
        k1 = np.zeros(5)
        actuator.simplex(x, 0, 3, 0.1, sp, 0, 1.0, k1)
        x += dt * k1
        if x[3] > sp[actuator.SX_RATE_LIMIT]:  # the stop (the engine's actuator.contain)
            x[3], x[4] = sp[actuator.SX_RATE_LIMIT], min(x[4], 0.0)
    out = np.zeros(5)
    actuator.simplex(x, 0, 3, 0.1, sp, 0, 1.0, out)
    assert x[3] == np.radians(5.0) and out[3] == 0.0 and out[4] == 0.0  # held on the stop
    assert out[2] == pytest.approx(np.radians(5.0), rel=1e-12)  # θ̇_p = r = rate limit


def _twd_setup(thrust: float):
    tb = pack_tables(synthetic.tables(mass=50000.0, inertia=(1e5, 4e6, 4e6, 0.0, 0.0, 0.0), cg=(5.0, 0.0, 0.0)))
    p = synthetic.parameters(thrust=True)
    p[propulsion.P_US_THRUST] = thrust
    p[actuator.P_US_GIMBAL + actuator.G_LIMIT] = 0.2
    p[propulsion.P_US_GIMBAL:propulsion.P_US_GIMBAL + 3] = (25.0, 0.0, 0.0)
    p[twd.P_US_ENGINE:twd.P_US_ENGINE + 3] = (2500.0, 1.5, 8125.0)
    p[twd.P_ON] = 1.0
    u = synthetic.coast_inputs()
    u[layout.U_ENGINE] = layout.ENGINE_UPPER
    u[layout.U_T_IGN] = -100.0  # long after the start transient
    return tb, p, u


def test_tail_wags_dog_moment_closed_form_and_zero_pair():
    """Prescribed δ(t) = A sin ωt: the pitch moment about the CG is T l_c sin δ + J δ̈ with
    J = I_R + m_R l_R l_c; at ω = √(T l_c / J) the two cancel (the TWD zero pair)."""
    thrust = 1.3e6
    tb, p, u = _twd_setup(thrust)
    l_c = 25.0 - 5.0
    jj = 8125.0 + 2500.0 * 1.5 * l_c
    w_twd = np.sqrt(thrust * l_c / jj)
    amp = 0.01
    aux = np.zeros(layout.N_AUX)
    x = np.zeros(synthetic.LAYOUT.n)
    x[layout.Q] = 1.0
    x[layout.R] = 7.0e6
    x[synthetic.LOX] = x[synthetic.LH2] = 1000.0
    for w in (0.3 * w_twd, w_twd, 2.0 * w_twd):
        for tt in np.linspace(0.1, 2.0, 7):
            d, dd, ddd = amp * np.sin(w * tt), amp * w * np.cos(w * tt), -amp * w * w * np.sin(w * tt)
            x[synthetic.ACT_P:synthetic.ACT_P + 3] = d, dd, ddd
            derivative(0.0, x, u, p, tb, aux, np.zeros(synthetic.LAYOUT.n))
            total = aux[propulsion.A_MOMENT + 1] + aux[twd.A_MOMENT + 1]
            expected = thrust * l_c * np.sin(d) + jj * ddd
            assert total == pytest.approx(expected, rel=1e-9, abs=1e-6 * thrust * l_c * amp)
            if w == w_twd:  # cancellation to small-angle accuracy
                assert abs(total) < 1e-4 * thrust * l_c * amp
    p[twd.P_ON] = 0.0
    derivative(0.0, x, u, p, tb, aux, np.zeros(synthetic.LAYOUT.n))
    assert aux[twd.A_MOMENT + 1] == 0.0
