"""The compiled loop's helpers against independent references: the fused multiply-add
against exact rational arithmetic, borrowed views against the arrays they view, and the
flight software's gain-schedule altitude against numpy's rotation and a closed form."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from numba import njit

from savant_cli import constants
from savant_cli.models import earth
from savant_cli.models.fused import fma
from savant_cli.sim.borrow import borrowed


@njit(cache=False)
def _fma(a, b, c):
    return fma(a, b, c)


def test_fma_rounds_once():
    rng = np.random.default_rng(7)
    a, b, c = rng.normal(size=(3, 2000)) * 10.0 ** rng.integers(-8, 8, size=(3, 2000))
    differs = 0
    for ai, bi, ci in zip(a, b, c):
        exact = Fraction(float(ai)) * Fraction(float(bi)) + Fraction(float(ci))
        got = _fma(ai, bi, ci)
        assert got == float(exact)  # float(Fraction) is the correctly rounded value
        differs += got != ai * bi + ci
    assert differs > 100  # and it is not the twice-rounded a*b + c
    # the textbook case: (1 + 2⁻²⁷)² − (1 + 2⁻²⁶) is 2⁻⁵⁴ exactly, lost by a*b + c
    x = 1.0 + 2.0 ** -27
    assert _fma(x, x, -(1.0 + 2.0 ** -26)) == 2.0 ** -54 and x * x - (1.0 + 2.0 ** -26) == 0.0


@njit(cache=False)
def _borrow_and_write(a, value):
    v = borrowed(a)
    v[1] = value
    return v.sum(), v.shape[0]


@njit(cache=False)
def _borrow_2d(a):
    v = borrowed(a)
    return v[1, 2], v.shape


def test_borrowed_views_the_same_buffer():
    a = np.arange(5.0)
    total, n = _borrow_and_write(a, 10.0)
    assert a[1] == 10.0 and total == a.sum() and n == 5
    m = np.arange(12.0).reshape(3, 4)
    assert _borrow_2d(m) == (m[1, 2], (3, 4))
    with pytest.raises(ValueError, match="C-contiguous"):
        _borrow_and_write(np.arange(10.0)[::2], 1.0)


@njit(cache=False)
def _height(t, r, omega, a, e2):
    return earth.height_of_eci(t, r[0], r[1], r[2], omega, a, e2)


def test_gain_schedule_height():
    """On the equator and over the pole the geodetic height is |r| − a and |z| − b; at any
    point and time it is the height of numpy's R3(ωt) r (to round-off)."""
    a, e2, w = constants.WGS84_A, constants.WGS84_E2, constants.OMEGA_EARTH
    b = a * np.sqrt(1.0 - e2)
    assert _height(123.0, np.array([a + 1000.0, 0.0, 0.0]), w, a, e2) == pytest.approx(1000.0, abs=1e-6)
    assert _height(0.0, np.array([0.0, 0.0, -(b + 5.0e4)]), w, a, e2) == pytest.approx(5.0e4, abs=1e-6)
    rng = np.random.default_rng(3)
    for _ in range(200):
        r = rng.normal(size=3)
        r *= (a + rng.uniform(-5e3, 4e5)) / np.linalg.norm(r)
        t = rng.uniform(0.0, 700.0)
        c, s = np.cos(w * t), np.sin(w * t)
        r_ecef = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]) @ r
        _, _, h = earth.ecef_to_geodetic(r_ecef, a, e2)
        assert _height(t, r, w, a, e2) == pytest.approx(h, abs=1e-6)
