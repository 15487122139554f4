"""Slosh alone: a non-rotating body under constant thrust acceleration with one slosh
mass per tank. The free oscillation's frequency and decay match ω_ref·√(a/a_ref) and ζ
(measured from zero crossings and the logarithmic decrement), and the vehicle's linear
momentum including the slosh masses is conserved laterally."""

from __future__ import annotations

import numpy as np
import pytest

import synthetic
from savant_cli.models import gravity, layout, propulsion, slosh
from savant_cli.sim.engine import rk4, work_array
from savant_cli.sim.plant import derivative, mass_state, pack_tables

A_REF = 9.80665


def _setup(w_ref: float, zeta: float, m_s: float, accel: float, inertia: float = 1e12):
    tables = synthetic.tables(mass=1.0e6, inertia=(inertia,) * 3 + (0.0, 0.0, 0.0), cg=(20.0, 0.0, 0.0))
    level = np.array([0.0, 20.0])
    row = [w_ref, zeta, m_s, 1.0]
    tables = tables._replace(slosh_level=np.tile(level, (2, 1)), slosh_data=np.tile(row, (2, 2, 1)))
    lay = synthetic.state_layout(slosh=True)
    p = synthetic.parameters(thrust=True, lay=lay)
    p[propulsion.P_US_THRUST] = accel * 1.0e6
    p[propulsion.P_US_ISP] = 1e12  # no mass flow: constant acceleration
    p[propulsion.P_US_GIMBAL:propulsion.P_US_GIMBAL + 3] = (40.0, 0.0, 0.0)
    for j in range(2):
        p[slosh.P_TANKS + slosh.N_TANK_FIELDS * j + slosh.K_AREF] = A_REF
    for j, bottom in enumerate((30.0, 15.0)):
        p[slosh.P_TANKS + slosh.N_TANK_FIELDS * j:slosh.P_TANKS + slosh.N_TANK_FIELDS * j + 3] = (2.75, bottom, 1000.0)
    u = synthetic.coast_inputs()
    u[layout.U_ENGINE] = layout.ENGINE_UPPER
    u[layout.U_T_IGN] = -100.0
    x = np.zeros(lay.n)
    x[layout.Q] = 1.0
    x[layout.R] = 7.0e6
    x[synthetic.LOX] = x[synthetic.LH2] = 5.0e4  # level 2.1 m, inside the table
    return pack_tables(tables), p, u, x, lay


@pytest.mark.parametrize("accel,zeta", [(2.0 * A_REF, 0.02), (0.5 * A_REF, 0.05)])
def test_free_slosh_frequency_and_decay(accel, zeta):
    w_ref, m_s = 2 * np.pi * 0.5, 200.0
    tb, p, u, x, lay = _setup(w_ref, zeta, m_s, accel)
    so = lay.slosh_offset
    x[so] = 0.05  # LOX mass displaced along body y
    x[so + 5] = 0.03  # LH2 mass along body z
    dt = 0.002
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)
    n = 20000
    hist = np.empty((n, 2))
    for k in range(n):
        rk4(k * dt, x, u, dt, p, tb, aux, work)
        hist[k] = x[so], x[so + 5]
    w_expected = w_ref * np.sqrt(accel / A_REF) * np.sqrt(1.0 + m_s / (1.0e6 - 2 * m_s))  # two-body coupling
    t = (np.arange(n) + 1) * dt
    for col in range(2):
        y = hist[:, col]
        up = np.nonzero((y[:-1] < 0) & (y[1:] >= 0))[0]
        tc = t[up] - y[up] * dt / (y[up + 1] - y[up])  # interpolated upward crossings
        wd = 2 * np.pi / np.mean(np.diff(tc))
        peaks = np.array([np.max(y[a:b]) for a, b in zip(up[:-1], up[1:])])
        delta = np.mean(np.log(peaks[:-1] / peaks[1:]))
        zeta_meas = delta / np.sqrt(4 * np.pi**2 + delta**2)
        wn_meas = wd / np.sqrt(1 - zeta_meas**2)
        assert wn_meas == pytest.approx(w_expected, rel=0.01)
        assert zeta_meas == pytest.approx(zeta, rel=0.01)


def test_slosh_force_is_the_reaction_on_the_vehicle():
    """Lateral momentum of rigid body plus slosh masses is conserved (no external lateral
    force; RK4 keeps linear invariants). The body is made practically non-rotating so the
    thrust keeps its direction."""
    tb, p, u, x, lay = _setup(2 * np.pi * 0.4, 0.01, 5.0e3, A_REF, inertia=1e20)
    p[gravity.P_MU] = 0.0  # no gravity gradient acting on the drifting rigid body
    so = lay.slosh_offset
    x[so] = 0.2
    m_r = 1.0e6 - 2 * 5.0e3
    dt = 0.002
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)

    def lateral_momentum():
        # body frame = inertial frame here (no rotation, identity attitude): ECI y
        return m_r * x[layout.V + 1] + 5.0e3 * (x[layout.V + 1] + x[so + 2]) + 5.0e3 * (x[layout.V + 1] + x[so + 6])

    p0 = lateral_momentum()
    for k in range(3000):
        rk4(k * dt, x, u, dt, p, tb, aux, work)
    assert abs(lateral_momentum() - p0) < 1e-9 * 5.0e3 * 0.2 * 2 * np.pi * 0.4
    assert np.max(np.abs(x[[so, so + 2]])) > 0.01  # it did oscillate


def test_a_jettisoned_tank_leaves_the_vehicle_and_holds_its_states():
    """Tank 1 aboard only in configurations below 2 (its stage gone in the upper stage's
    configuration 2, where the synthetic plant flies): its states' rates are zero, its
    level, frequency and force too, and the rigid part is the whole vehicle less tank 0's
    slosh mass only; tank 0 still oscillates at its closed-form coupled frequency."""
    w_ref, zeta, m_s, accel = 2 * np.pi * 0.5, 0.02, 200.0, 2.0 * A_REF
    tb, p, u, x, lay = _setup(w_ref, zeta, m_s, accel)
    p[slosh.P_TANKS + slosh.N_TANK_FIELDS + slosh.K_CONFIGS] = layout.CONFIG_UPPER  # gone in CONFIG_UPPER
    so = lay.slosh_offset
    x[so] = 0.05
    x[so + 4:so + 8] = (0.03, -0.02, 0.1, 0.2)  # the gone tank's mass, displaced and moving
    aux, xd = np.zeros(layout.N_AUX), np.zeros(x.size)
    derivative(0.0, x, u, p, tb, aux, xd)
    assert np.all(xd[so + 4:so + 8] == 0.0)
    assert aux[slosh.A_LEVEL + 1] == aux[slosh.A_FREQUENCY + 1] == 0.0
    assert np.all(aux[slosh.A_FORCE + 3:slosh.A_FORCE + 6] == 0.0)
    rigid = mass_state(x, p, tb, layout.CONFIG_UPPER, np.zeros(layout.N_AUX))[2]
    assert rigid[0] == 1.0e6 - m_s
    # the remaining tank: free oscillation at ω_ref √(a/a_ref) √(1 + m_s/m_r)
    dt, n = 0.002, 20000
    work = work_array(x.size)
    hist = np.empty(n)
    for k in range(n):
        rk4(k * dt, x, u, dt, p, tb, aux, work)
        hist[k] = x[so]
    np.testing.assert_array_equal(x[so + 4:so + 8], (0.03, -0.02, 0.1, 0.2))
    t = (np.arange(n) + 1) * dt
    up = np.nonzero((hist[:-1] < 0) & (hist[1:] >= 0))[0]
    tc = t[up] - hist[up] * dt / (hist[up + 1] - hist[up])
    w_expected = w_ref * np.sqrt(accel / A_REF) * np.sqrt(1.0 + m_s / (1.0e6 - m_s))
    assert 2 * np.pi / np.mean(np.diff(tc)) / np.sqrt(1 - zeta**2) == pytest.approx(w_expected, rel=0.01)
