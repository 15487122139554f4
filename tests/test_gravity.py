"""Zonal gravity against independent evaluations.

References: the potential written here from the Legendre polynomials (numpy's
``legval``), differentiated by central finite differences; and the textbook closed-form
values on the equator and at the poles.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import legendre

from savant_cli import constants
from savant_cli.models.gravity import gravity_potential, gravity_zonal

MU, RE = constants.MU_EARTH, constants.WGS84_A
J = {2: constants.EGM2008_J2, 3: constants.EGM2008_J3, 4: constants.EGM2008_J4}

rng = np.random.default_rng(1976)
POINTS = [np.array(p) for p in (
    [RE + 200e3, 0.0, 0.0],
    [0.0, 0.0, RE + 300e3],
    [0.0, 0.0, -(RE + 50e3)],
    [4.1e6, -3.3e6, 3.9e6],
    [-2.0e6, 5.5e6, -4.4e6],
    [1.0e3, -2.0e3, 7.0e6],         # near the pole
)] + [v / np.linalg.norm(v) * rng.uniform(RE, 4 * RE) for v in rng.normal(size=(6, 3))]


def term_potential(r: np.ndarray, n: int, jn: float) -> float:
    """−μ/r Jn (R/r)^n Pn(z/r): the degree-n zonal term of the potential."""
    rn = np.linalg.norm(r)
    coef = np.zeros(n + 1)
    coef[n] = 1.0
    return -MU / rn * jn * (RE / rn) ** n * legendre.legval(r[2] / rn, coef)


def fd_gradient(f, r: np.ndarray, h: float = 20.0) -> np.ndarray:
    """Fourth-order central-difference gradient."""
    g = np.zeros(3)
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        g[i] = (-f(r + 2 * e) + 8 * f(r + e) - 8 * f(r - e) + f(r - 2 * e)) / (12 * h)
    return g


def only(n: int) -> tuple[float, float, float]:
    return tuple(J[k] if k == n else 0.0 for k in (2, 3, 4))


@pytest.mark.parametrize("r", POINTS)
def test_point_mass_limit(r):
    a = gravity_zonal(r, MU, RE, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(a, -MU * r / np.linalg.norm(r) ** 3, rtol=1e-14)


@pytest.mark.parametrize("n", [2, 3, 4])
@pytest.mark.parametrize("r", POINTS)
def test_each_term_is_gradient_of_its_potential(n, r):
    a_term = gravity_zonal(r, MU, RE, *only(n)) - gravity_zonal(r, MU, RE, 0.0, 0.0, 0.0)
    a_fd = fd_gradient(lambda q: term_potential(q, n, J[n]), r)
    scale = abs(J[n]) * MU / np.linalg.norm(r) ** 2 * (RE / np.linalg.norm(r)) ** n
    np.testing.assert_allclose(a_term, a_fd, rtol=0.0, atol=1e-6 * scale)


@pytest.mark.parametrize("r", POINTS)
def test_potential_matches_legendre_expansion(r):
    u_ref = MU / np.linalg.norm(r) + sum(term_potential(r, n, J[n]) for n in (2, 3, 4))
    assert gravity_potential(r, MU, RE, J[2], J[3], J[4]) == pytest.approx(u_ref, rel=1e-14)


@pytest.mark.parametrize("r", POINTS)
def test_full_field_is_gradient_of_gravity_potential(r):
    a = gravity_zonal(r, MU, RE, J[2], J[3], J[4])
    a_fd = fd_gradient(lambda q: gravity_potential(q, MU, RE, J[2], J[3], J[4]), r)
    np.testing.assert_allclose(a, a_fd, rtol=0.0, atol=1e-9 * np.linalg.norm(a))


def test_textbook_surface_values():
    g0 = MU / RE**2
    # J2: equator g = μ/R² (1 + 3/2 J2) inward; pole g = μ/R² (1 − 3 J2)
    a = gravity_zonal(np.array([RE, 0.0, 0.0]), MU, RE, *only(2))
    np.testing.assert_allclose(a, [-g0 * (1.0 + 1.5 * J[2]), 0.0, 0.0], rtol=1e-14, atol=0.0)
    a = gravity_zonal(np.array([0.0, 0.0, RE]), MU, RE, *only(2))
    np.testing.assert_allclose(a, [0.0, 0.0, -g0 * (1.0 - 3.0 * J[2])], rtol=1e-14, atol=0.0)
    # J3 (odd): at either pole a_z(J3) = +4 J3 μ/R²; on the equator a_z(J3) = 3/2 J3 μ/R²
    for zs in (1.0, -1.0):
        a = gravity_zonal(np.array([0.0, 0.0, zs * RE]), MU, RE, *only(3))
        assert a[2] - (-zs * g0) == pytest.approx(4.0 * J[3] * g0, rel=1e-9)
    a = gravity_zonal(np.array([RE, 0.0, 0.0]), MU, RE, *only(3))
    assert a[2] == pytest.approx(1.5 * J[3] * g0, rel=1e-12)
    assert a[0] == pytest.approx(-g0, rel=1e-15)
    # J4: radial 5 J4 μ/R² at the poles, 15/8 J4 μ/R² on the equator (outward positive)
    a = gravity_zonal(np.array([0.0, 0.0, RE]), MU, RE, *only(4))
    assert a[2] + g0 == pytest.approx(5.0 * J[4] * g0, rel=1e-9)
    a = gravity_zonal(np.array([RE, 0.0, 0.0]), MU, RE, *only(4))
    assert a[0] + g0 == pytest.approx(1.875 * J[4] * g0, rel=1e-9)


@pytest.mark.parametrize("r", POINTS)
def test_symmetries(r):
    mirror = np.array([r[0], r[1], -r[2]])
    # even terms: mirror-symmetric about the equator
    for n in (2, 4):
        a, b = gravity_zonal(r, MU, RE, *only(n)), gravity_zonal(mirror, MU, RE, *only(n))
        np.testing.assert_allclose(b, [a[0], a[1], -a[2]], rtol=1e-13, atol=1e-20)
    # odd J3 term: antisymmetric
    base = gravity_zonal(r, MU, RE, 0.0, 0.0, 0.0)
    base_m = gravity_zonal(mirror, MU, RE, 0.0, 0.0, 0.0)
    d = gravity_zonal(r, MU, RE, *only(3)) - base
    dm = gravity_zonal(mirror, MU, RE, *only(3)) - base_m
    np.testing.assert_allclose(dm, [-d[0], -d[1], d[2]], rtol=1e-7, atol=1e-15)
    # axial symmetry: rotating the point about Z rotates the acceleration
    ang = 0.7
    rot = np.array([[np.cos(ang), -np.sin(ang), 0.0], [np.sin(ang), np.cos(ang), 0.0],
                    [0.0, 0.0, 1.0]])
    a_full = gravity_zonal(r, MU, RE, J[2], J[3], J[4])
    np.testing.assert_allclose(gravity_zonal(rot @ r, MU, RE, J[2], J[3], J[4]),
                               rot @ a_full, rtol=0.0, atol=1e-14 * np.linalg.norm(a_full))
