"""The plant's wind kernels (models/winds.py) against hand interpolation and explicit
frame rotations (ECI → ECEF → NED matrices from models/earth.py)."""

from __future__ import annotations

import numpy as np
import pytest

import synthetic
from savant_cli import constants
from savant_cli.models import earth, winds
from savant_cli.sim.plant import pack_tables

W = constants.OMEGA_EARTH


def _packed(scale: float = 1.0):
    tb = synthetic.tables()._replace(wind_alt=np.array([0.0, 1000.0, 5000.0]), wind_north=np.array([0.0, 10.0, 30.0]),
                                     wind_east=np.array([5.0, -5.0, 15.0]))
    p = synthetic.parameters()
    p[winds.P_SCALE] = scale
    return pack_tables(tb), p


@pytest.mark.parametrize("alt, scale, expect", [(3000.0, 1.0, (20.0, 5.0)), (500.0, 2.0, (10.0, 0.0)),
                                                (-100.0, 1.0, (0.0, 5.0)), (9e4, 0.5, (15.0, 7.5))])
def test_wind_profile_interpolates_linearly_and_holds_its_ends(alt, scale, expect):
    tb, p = _packed(scale)
    np.testing.assert_allclose(winds.wind_ned(alt, tb, p), expect, rtol=1e-15)


def test_scale_zero_is_still_air():
    tb, p = _packed(0.0)
    assert winds.air_relative_velocity(10.0, 3000.0, 0.3, 0.9, 0.2, 0.8, 1.0, 0.0, 1.0, 2.0, 3.0, tb, p) == (
        1.0, 2.0, 3.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("lat_deg, lon_deg, t", [(0.0, 0.0, 0.0), (40.0, -100.0, 777.0), (-28.5, 80.6, 3.0)])
def test_air_velocity_subtracts_the_wind_rotated_into_eci(lat_deg, lon_deg, t):
    tb, p = _packed()
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    wind_ned = np.array([*winds.wind_ned(3000.0, tb, p), 0.0])
    expect_wind = earth.dcm_eci_to_ecef(t, W).T @ (earth.dcm_ecef_to_ned(lat, lon).T @ wind_ned)
    v_earth = np.array([100.0, -50.0, 20.0])
    got = winds.air_relative_velocity(t, 3000.0, np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon), np.cos(W * t),
                                      np.sin(W * t), *v_earth, tb, p)
    np.testing.assert_allclose(got[:3], v_earth - expect_wind, atol=1e-12)
    np.testing.assert_allclose(got[3:], wind_ned, rtol=1e-15)
    if lat_deg == 0.0 and lon_deg == 0.0 and t == 0.0:  # north is ECI +Z and east ECI +Y there
        np.testing.assert_allclose(expect_wind, [0.0, wind_ned[1], wind_ned[0]], atol=1e-15)
