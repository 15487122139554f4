"""Frames: rotation, geodetic/ECEF, NED, Earth-relative velocity and winds.

Independent references: the ellipse's parametric form for surface points, the
geocentric-radius formula of an ellipse, finite differences, and exact rotations.
"""

from __future__ import annotations

import numpy as np
import pytest

from savant_cli import constants
from savant_cli.models import earth

A, E2, B, W = constants.WGS84_A, constants.WGS84_E2, constants.WGS84_B, constants.OMEGA_EARTH
LATS = np.radians([-90.0, -89.9999, -60.0, -28.627, -1e-7, 0.0, 1e-7, 15.0, 45.0, 75.0,
                   89.99, 89.9999999, 90.0])
LONS = np.radians([-180.0, -80.621, 0.0, 33.3, 90.0, 179.0])
HEIGHTS = [-5000.0, 0.0, 1.0, 3000.0, 86000.0, 400e3, 1000e3]


def reference_ecef(lat: float, lon: float, h: float) -> np.ndarray:
    """Surface point from the parametric latitude (tan β = (b/a) tan φ) plus h along the normal."""
    beta = np.arctan2(B * np.sin(lat), A * np.cos(lat))
    normal = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    surface = np.array([A * np.cos(beta) * np.cos(lon), A * np.cos(beta) * np.sin(lon),
                        B * np.sin(beta)])
    return surface + h * normal


def test_geodetic_round_trip_grid():
    for lat in LATS:
        for lon in LONS:
            for h in HEIGHTS:
                r = earth.geodetic_to_ecef(lat, lon, h, A, E2)
                np.testing.assert_allclose(r, reference_ecef(lat, lon, h), rtol=0.0, atol=1e-6)
                la, lo, hh = earth.ecef_to_geodetic(r, A, E2)
                assert abs(la - lat) < 1e-9
                assert abs(hh - h) < 1e-3
                if abs(lat) < np.radians(89.9999):   # longitude undefined at the pole
                    dlon = (lo - lon + np.pi) % (2 * np.pi) - np.pi
                    assert abs(dlon) < 1e-12


def test_ecef_to_geodetic_random_points():
    rng = np.random.default_rng(84)
    for _ in range(2000):
        lat = np.arcsin(rng.uniform(-1.0, 1.0))
        lon = rng.uniform(-np.pi, np.pi)
        h = rng.uniform(-5e3, 1e6)
        la, lo, hh = earth.ecef_to_geodetic(reference_ecef(lat, lon, h), A, E2)
        assert abs(la - lat) < 1e-9 and abs(hh - h) < 1e-3


def test_known_points():
    np.testing.assert_allclose(earth.geodetic_to_ecef(0.0, 0.0, 0.0, A, E2), [A, 0.0, 0.0],
                               rtol=0.0, atol=1e-9)
    for lon in (0.0, 1.234):
        np.testing.assert_allclose(earth.geodetic_to_ecef(np.pi / 2, lon, 0.0, A, E2),
                                   [0.0, 0.0, B], rtol=0.0, atol=1e-6)
        np.testing.assert_allclose(earth.geodetic_to_ecef(-np.pi / 2, lon, 0.0, A, E2),
                                   [0.0, 0.0, -B], rtol=0.0, atol=1e-6)
    assert B == pytest.approx(6356752.314245, abs=1e-6)     # WGS84 semi-minor axis
    lat, lon, h = earth.ecef_to_geodetic(np.array([0.0, 0.0, B + 100.0]), A, E2)
    assert lat == np.pi / 2 and h == pytest.approx(100.0, abs=1e-6)
    lat, lon, h = earth.ecef_to_geodetic(np.array([0.0, -(A + 10.0), 0.0]), A, E2)
    assert (lat, lon) == (0.0, -np.pi / 2) and h == pytest.approx(10.0, abs=1e-9)


def test_lc39b_geocentric_radius():
    lat, lon = np.radians(28.627), np.radians(-80.621)
    r = earth.geodetic_to_ecef(lat, lon, 0.0, A, E2)
    # radius of the meridian ellipse at geodetic latitude φ:
    # r² = ((a² cos φ)² + (b² sin φ)²) / ((a cos φ)² + (b sin φ)²)
    c, s = np.cos(lat), np.sin(lat)
    r_ref = np.sqrt(((A * A * c) ** 2 + (B * B * s) ** 2) / ((A * c) ** 2 + (B * s) ** 2))
    assert np.linalg.norm(r) == pytest.approx(r_ref, rel=1e-13)
    assert r_ref == pytest.approx(6373.3e3, abs=0.2e3)
    # geocentric latitude: tan ψ = (b/a)² tan φ
    psi = np.arctan2(r[2], np.hypot(r[0], r[1]))
    assert np.tan(psi) == pytest.approx((B / A) ** 2 * np.tan(lat), rel=1e-13)
    assert np.arctan2(r[1], r[0]) == pytest.approx(lon, abs=1e-15)


@pytest.mark.parametrize("lat", LATS)
@pytest.mark.parametrize("lon", LONS[:3])
def test_ned_dcm(lat, lon):
    c = earth.dcm_ecef_to_ned(lat, lon)
    np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(c) == pytest.approx(1.0, abs=1e-14)
    normal = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    np.testing.assert_allclose(c[2], -normal, atol=1e-15)
    # north and east are the directions of increasing latitude and longitude
    d = 1e-7
    dn = earth.geodetic_to_ecef(lat + d, lon, 0.0, A, E2) - earth.geodetic_to_ecef(lat - d, lon, 0.0, A, E2)
    np.testing.assert_allclose(c[0], dn / np.linalg.norm(dn), atol=1e-7)
    if abs(lat) < np.radians(89.0):
        de = earth.geodetic_to_ecef(lat, lon + d, 0.0, A, E2) - earth.geodetic_to_ecef(lat, lon - d, 0.0, A, E2)
        np.testing.assert_allclose(c[1], de / np.linalg.norm(de), atol=1e-7)


def test_eci_ecef_rotation():
    t = 1234.5
    c = earth.dcm_eci_to_ecef(t, W)
    np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-15)
    v = np.array([1.0e6, -2.0e6, 3.0e6])
    np.testing.assert_allclose(earth.eci_to_ecef(v, t, W), c @ v, rtol=1e-15)
    np.testing.assert_allclose(earth.ecef_to_eci(earth.eci_to_ecef(v, t, W), t, W), v, rtol=1e-15)
    np.testing.assert_allclose(earth.dcm_eci_to_ecef(0.0, W), np.eye(3))
    # after a quarter turn the inertial X axis is seen along ECEF −Y
    quarter = 0.5 * np.pi / W
    np.testing.assert_allclose(earth.eci_to_ecef(np.array([1.0, 0.0, 0.0]), quarter, W),
                               [0.0, -1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(earth.dcm_eci_to_ecef(2 * np.pi / W, W), np.eye(3), atol=1e-14)


def test_relative_velocity_of_earth_fixed_point_is_zero():
    r_ecef = earth.geodetic_to_ecef(np.radians(28.627), np.radians(-80.621), 50.0, A, E2)
    t, dt = 300.0, 1e-3
    r_eci = earth.ecef_to_eci(r_ecef, t, W)
    v_eci = (earth.ecef_to_eci(r_ecef, t + dt, W) - earth.ecef_to_eci(r_ecef, t - dt, W)) / (2 * dt)
    assert np.linalg.norm(v_eci) == pytest.approx(W * np.hypot(r_ecef[0], r_ecef[1]), rel=1e-9)
    np.testing.assert_allclose(earth.velocity_relative_eci(r_eci, v_eci, W), 0.0, atol=1e-6)
    # and an inertially fixed point moves at −ω ẑ × r relative to the Earth
    np.testing.assert_allclose(earth.velocity_relative_eci(r_eci, np.zeros(3), W), -v_eci, rtol=1e-8)
