"""The compiled plant against conservation laws and closed-form rigid-body motion."""

import numpy as np
import pytest

import synthetic
from savant_cli import constants
from savant_cli.models import layout, propulsion
from savant_cli.sim.engine import rk4, work_array
from savant_cli.sim.plant import derivative, pack_tables


def _orbit_state(alt_m=400e3, inc_deg=51.6):
    r = constants.WGS84_A + alt_m
    v = np.sqrt(constants.MU_EARTH / r) * 1.01  # slightly elliptic
    i = np.radians(inc_deg)
    x = np.zeros(synthetic.LAYOUT.n)
    x[layout.R:layout.R + 3] = [r, 0.0, 0.0]
    x[layout.V:layout.V + 3] = [0.0, v * np.cos(i), v * np.sin(i)]
    x[layout.Q] = 1.0
    x[synthetic.LOX] = x[synthetic.LH2] = 1.0
    return x


@pytest.mark.parametrize("order", [0, 4])
def test_vacuum_coast_conserves_energy_and_angular_momentum(order):
    """Thrust and aero off: specific energy (with the zonal potential when J2–J4 are on)
    is conserved; with point-mass gravity the full angular momentum vector is, and with
    zonal harmonics its polar component is (the zonal field is axisymmetric)."""
    from savant_cli.models.gravity import gravity_potential

    tb, p, u = pack_tables(synthetic.tables()), synthetic.parameters(gravity_order=order), synthetic.coast_inputs()
    x = _orbit_state()
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)
    j2, j3, j4 = (constants.EGM2008_J2, constants.EGM2008_J3, constants.EGM2008_J4) if order else (0.0, 0.0, 0.0)

    def invariants(x):
        r, v = x[layout.R:layout.R + 3], x[layout.V:layout.V + 3]
        energy = 0.5 * v @ v - gravity_potential(r, constants.MU_EARTH, constants.WGS84_A, j2, j3, j4)
        return energy, np.cross(r, v)

    e0, h0 = invariants(x)
    dt = 1.0
    for k in range(5600):  # about one orbit
        rk4(k * dt, x, u, dt, p, tb, aux, work)
        x[layout.Q:layout.Q + 4] /= np.linalg.norm(x[layout.Q:layout.Q + 4])
    e1, h1 = invariants(x)
    assert abs(e1 - e0) / abs(e0) < 1e-9
    if order == 0:
        np.testing.assert_allclose(h1, h0, rtol=0, atol=1e-9 * np.linalg.norm(h0))
    else:
        assert h1[2] == pytest.approx(h0[2], rel=1e-9)


def test_torque_free_axisymmetric_body_precesses_at_theory_rate():
    """Euler's equations for Ix ≠ It = Iy = Iz: the transverse rate rotates in body axes at
    λ = Ω (It − Ix)/It and the spin Ω and transverse magnitude are constant."""
    ix, it = 100.0, 400.0
    tb = pack_tables(synthetic.tables(inertia=(ix, it, it, 0.0, 0.0, 0.0)))
    p, u = synthetic.parameters(), synthetic.coast_inputs()
    x = _orbit_state()
    spin, trans = 2.0, 0.3
    x[layout.W:layout.W + 3] = [spin, trans, 0.0]
    aux, work = np.zeros(layout.N_AUX), work_array(x.size)
    dt, n = 0.001, 4000
    phase = []
    for k in range(n):
        rk4(k * dt, x, u, dt, p, tb, aux, work)
        phase.append(np.arctan2(x[layout.W + 2], x[layout.W + 1]))
    lam = np.polyfit(np.arange(1, n + 1) * dt, np.unwrap(phase), 1)[0]
    # Euler: d(ωy + iωz)/dt = −iλ(ωy + iωz): the transverse rate turns negatively in body axes
    assert lam == pytest.approx(-spin * (it - ix) / it, rel=1e-6)
    assert x[layout.W] == pytest.approx(spin, rel=1e-12)
    assert np.hypot(x[layout.W + 1], x[layout.W + 2]) == pytest.approx(trans, rel=1e-9)
    # kinetic energy and |H| conserved
    w = x[layout.W:layout.W + 3]
    assert 0.5 * (ix * w[0] ** 2 + it * w[1] ** 2 + it * w[2] ** 2) == pytest.approx(
        0.5 * (ix * spin**2 + it * trans**2), rel=1e-9)


def test_gimbal_moment_sign_and_magnitude():
    """δp > 0 gives a nose-up (positive) pitching moment T·l·sin δ for an engine aft of
    the CG; δy > 0 a positive yawing moment (docs/architecture.md)."""
    tb, u = pack_tables(synthetic.tables(cg=(5.0, 0.0, 0.0))), synthetic.coast_inputs()
    p = synthetic.parameters(thrust=True)
    p[propulsion.P_US_THRUST] = 1000.0
    u[layout.U_ENGINE] = layout.ENGINE_UPPER
    x = _orbit_state()
    aux = np.zeros(layout.N_AUX)
    delta = 0.05
    x[synthetic.ACT_P] = delta
    derivative(0.0, x, u, p, tb, aux, np.zeros(synthetic.LAYOUT.n))
    arm = 10.0 - 5.0  # gimbal station minus CG station
    assert aux[propulsion.A_MOMENT + 1] == pytest.approx(1000.0 * arm * np.sin(delta), rel=1e-9)
    x[synthetic.ACT_P], x[synthetic.ACT_Y] = 0.0, delta
    derivative(0.0, x, u, p, tb, aux, np.zeros(synthetic.LAYOUT.n))
    assert aux[propulsion.A_MOMENT + 2] == pytest.approx(1000.0 * arm * np.sin(delta), rel=1e-9)
