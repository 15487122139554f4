"""The compiled plant reads its tables from one flat array (``pack_tables``). These tests
check that what it reads there is what the named tables hold, using independent look-ups:
scipy's ``RegularGridInterpolator`` for the aerodynamic coefficients and ``np.interp``
for the one-dimensional tables."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.models import aero, atmosphere, earth, layout, mass, propulsion, quaternion as qt, winds
from savant_cli.sim.plant import derivative, pack_tables
from savant_cli.sim.setup import prepare


@pytest.fixture(scope="module")
def model():
    return prepare(validate(compose_config())).model


def test_pack_layout_round_trips_every_table(model):
    flat = pack_tables(model.tables)
    for f, arr in enumerate(model.tables):
        off, n = int(flat[2 * f]), int(flat[2 * f + 1])
        assert n == arr.size
        np.testing.assert_array_equal(flat[off:off + n], np.asarray(arr, float).ravel())
    last = len(model.tables) - 1
    assert int(flat[2 * last]) + int(flat[2 * last + 1]) == flat.size
    assert int(flat[2 * aero.T_COEF + 1]) == model.tables.aero_coef.size


def _state_in_flight(model, alt_m: float, speed_mps: float, alpha_deg: float, beta_deg: float, prop_kg: float):
    """A pad-based state lifted to ``alt_m`` (approximately, along the local radius) with
    the air-relative velocity set at the given angles in body axes."""
    x = model.x0.copy()
    r = x[layout.R:layout.R + 3]
    x[layout.R:layout.R + 3] = r * (1.0 + alt_m / np.linalg.norm(r))
    a, b = np.radians(alpha_deg), np.radians(beta_deg)
    v_body = speed_mps * np.array([np.cos(a) * np.cos(b), np.sin(b), np.sin(a) * np.cos(b)])
    c_b2i = qt.dcm(x[layout.Q:layout.Q + 4])
    omega = np.array([0.0, 0.0, model.p[earth.P_OMEGA_E]])
    x[layout.V:layout.V + 3] = c_b2i @ v_body + np.cross(omega, x[layout.R:layout.R + 3])  # no wind below
    x[model.layout.tank("grain")] = prop_kg  # ares_i's first-stage motor
    return x


@pytest.mark.parametrize("alt_m,speed,alpha,beta,prop_frac", [
    (3000.0, 250.0, 3.0, -2.0, 0.9),
    (11000.0, 480.0, -4.5, 1.3, 0.6),
    (30000.0, 1500.0, 7.0, 5.5, 0.25),
])
def test_plant_reads_aero_mass_and_thrust_tables_as_independent_lookups(model, alt_m, speed, alpha, beta, prop_frac):
    tb = model.tables
    p = model.p.copy()
    p[winds.P_SCALE] = 0.0
    u = model.u0.copy()
    prop = prop_frac * tb.mass_prop[layout.CONFIG_STACK, tb.mass_len[layout.CONFIG_STACK] - 1]
    x = _state_in_flight(model, alt_m, speed, alpha, beta, prop)
    aux = np.zeros(layout.N_AUX)
    t = 40.0
    derivative(t, x, u, p, model.packed_tables, aux, np.zeros(x.size))
    assert np.degrees(aux[aero.A_ALPHA]) == pytest.approx(alpha, abs=1e-6)
    assert np.degrees(aux[aero.A_BETA]) == pytest.approx(beta, abs=1e-6)

    c = layout.CONFIG_STACK
    n = tb.mass_len[c]
    data = tb.mass_data[c, :n]
    for col, key in ((0, mass.A_MASS), (1, mass.A_CG)):
        assert aux[key] == pytest.approx(np.interp(prop, tb.mass_prop[c, :n], data[:, col]), rel=1e-12)

    point = np.array([[aux[aero.A_MACH], aux[aero.A_ALPHA], aux[aero.A_BETA]]])
    axes = (tb.aero_mach, tb.aero_alpha, tb.aero_beta)
    ca, cy, cn = (RegularGridInterpolator(axes, tb.aero_coef[c, k])(point)[0] for k in range(3))
    nb = tb.base_len[c]
    f_base = np.interp(t, tb.base_time[c, :nb], tb.base_force[c, :nb])
    qs = aux[aero.A_QBAR] * tb.aero_ref[c, 0]
    np.testing.assert_allclose(aux[aero.A_FORCE:aero.A_FORCE + 3], [-qs * ca + f_base, qs * cy, -qs * cn],
                               rtol=1e-10, atol=1e-6)

    # the motor's mass flow is its load in the table's shape, its thrust that flow at its Isp
    mdot = p[propulsion.P_FS_PROP_FULL] * np.interp(t, tb.fs_time, tb.fs_thrust) / np.trapezoid(tb.fs_thrust, tb.fs_time)
    f_vac = 9.80665 * p[propulsion.P_FS_ISP] * mdot
    assert aux[propulsion.A_THRUST] == pytest.approx(f_vac - aux[atmosphere.A_PRES] * p[propulsion.P_FS_EXIT_AREA], rel=1e-12)
