"""US Standard Atmosphere 1976 against the standard's published tables.

Reference values are the printed tables of *U.S. Standard Atmosphere, 1976*
(NOAA-S/T 76-1562): Table 4 (layer-base pressures and molecular-scale temperatures),
Table I (geometric-altitude T, p, rho) and the speed-of-sound column; above 86 km the
printed values are given to 4-5 significant digits.
"""

from __future__ import annotations

import numpy as np
import pytest

from savant_cli.models.atmosphere import atmosphere, upper_atmosphere_table, us76, us76_profile, us76_upper

R0 = 6356766.0  # m, the standard's effective Earth radius for geopotential


@pytest.fixture(scope="module")
def table():
    return upper_atmosphere_table()


def _geometric(h_geopotential_m: float) -> float:
    """Geometric altitude of a geopotential altitude (the standard's eq. 18 inverted)."""
    return R0 * h_geopotential_m / (R0 - h_geopotential_m)


# Table 4 layer bases: H (m'), T_M (K), P (Pa); rho (kg/m3) from Table I at the same H.
LAYER_BASES = [
    (0.0, 288.150, 101325.0, 1.2250),
    (11000.0, 216.650, 22632.06, 0.36392),
    (20000.0, 216.650, 5474.889, 0.088035),
    (32000.0, 228.650, 868.0187, 0.013225),
    (47000.0, 270.650, 110.9063, 1.4275e-3),
    (51000.0, 270.650, 66.93887, 8.6160e-4),
    (71000.0, 214.650, 3.956420, 6.4211e-5),
]


@pytest.mark.parametrize("h, t_ref, p_ref, rho_ref", LAYER_BASES)
def test_layer_bases(h, t_ref, p_ref, rho_ref, table):
    t, p, rho, _ = atmosphere(_geometric(h), *table)
    assert t == pytest.approx(t_ref, rel=1e-5)
    assert p == pytest.approx(p_ref, rel=1e-5)
    assert rho == pytest.approx(rho_ref, rel=1e-4)


def test_top_of_lower_model_84852_geopotential(table):
    # H = 84.852 km' is Z = 86 km: T = 186.87 K (T_M = 186.946 K), p = 0.3733836 Pa
    z = _geometric(84852.0)
    assert z == pytest.approx(86000.0, abs=1.0)
    t, p, rho, a = us76(z)
    assert t == pytest.approx(186.87, rel=1e-4)
    assert p == pytest.approx(0.3733836, rel=1e-5)
    assert rho == pytest.approx(6.958e-6, rel=1e-4)
    assert a == pytest.approx(274.10, rel=1e-4)


# Table I (geometric altitude): z (km), T (K), p (Pa), rho (kg/m3), speed of sound (m/s)
INTERMEDIATE = [
    (5.0, 255.676, 54048.0, 0.73643, 320.545),
    (10.0, 223.252, 26500.0, 0.41351, 299.532),
    (15.0, 216.650, 12111.0, 0.19476, 295.070),
    (25.0, 221.552, 2549.2, 0.040084, 298.389),
    (40.0, 250.350, 287.14, 3.9957e-3, 317.189),
    (50.0, 270.650, 79.779, 1.0269e-3, 329.799),
    (60.0, 247.021, 21.958, 3.0968e-4, 315.07),
    (80.0, 198.639, 1.0524, 1.8458e-5, 282.54),
]


@pytest.mark.parametrize("z_km, t_ref, p_ref, rho_ref, a_ref", INTERMEDIATE)
def test_intermediate_altitudes(z_km, t_ref, p_ref, rho_ref, a_ref, table):
    t, p, rho, a = atmosphere(z_km * 1e3, *table)
    assert t == pytest.approx(t_ref, rel=1e-4)
    assert p == pytest.approx(p_ref, rel=1e-4)
    assert rho == pytest.approx(rho_ref, rel=1e-4)
    assert a == pytest.approx(a_ref, rel=1e-4)


def test_sea_level_and_below(table):
    t, p, rho, a = atmosphere(0.0, *table)
    assert (t, p) == (288.15, 101325.0)
    assert rho == pytest.approx(1.2250, rel=1e-4)
    assert a == pytest.approx(340.294, rel=1e-5)
    # -5 km, the bottom of the standard's tables: T = 320.676 K, p/p0 = 1.7543
    t, p, _, _ = atmosphere(-5000.0, *table)
    assert t == pytest.approx(320.676, rel=1e-5)
    assert p / 101325.0 == pytest.approx(1.7543, rel=1e-4)
    # clamped below -5 km
    assert atmosphere(-8000.0, *table) == atmosphere(-5000.0, *table)


# Above 86 km, Table I: z (km), T (K), p (Pa), rho (kg/m3)
UPPER = [
    (90.0, 186.87, 1.8359e-1, 3.416e-6),
    (100.0, 195.08, 3.2011e-2, 5.604e-7),
    (110.0, 240.00, 7.1042e-3, 9.708e-8),
    (120.0, 360.00, 2.5382e-3, 2.222e-8),
    (150.0, 634.39, 4.5422e-4, 2.076e-9),
    (200.0, 854.56, 8.4736e-5, 2.541e-10),
    (300.0, 976.01, 8.7704e-6, 1.916e-11),
    (500.0, 999.24, 3.0236e-7, 5.215e-13),
    (1000.0, 1000.00, 7.5138e-9, 3.561e-15),
]


@pytest.mark.parametrize("z_km, t_ref, p_ref, rho_ref", UPPER)
def test_upper_atmosphere(z_km, t_ref, p_ref, rho_ref, table):
    t, p, rho, a = atmosphere(z_km * 1e3, *table)
    assert t == pytest.approx(t_ref, rel=1e-4)
    # required 1 %; the integrated model achieves better than 0.04 %
    assert p == pytest.approx(p_ref, rel=1e-3)
    assert rho == pytest.approx(rho_ref, rel=1e-3)
    assert a == pytest.approx(np.sqrt(1.4 * p / rho), rel=1e-12)


def test_continuity_at_86_km(table):
    below = np.array(atmosphere(86000.0 - 1e-6, *table))
    above = np.array(atmosphere(86000.0, *table))
    np.testing.assert_allclose(above, below, rtol=1e-6)
    np.testing.assert_allclose(us76_upper(86000.0, *table), us76(86000.0), rtol=1e-6)


def test_monotone_to_1000_km_and_clamped_above():
    z = np.arange(-5000.0, 1000001.0, 250.0)
    prof = us76_profile(z)
    assert np.all(np.diff(prof["p_Pa"]) < 0.0)
    assert np.all(np.diff(prof["rho_kgm3"]) < 0.0)
    for key in ("T_K", "a_mps"):
        assert np.all(np.isfinite(prof[key])) and np.all(prof[key] > 0.0)
    top = us76_profile(np.array([1.0e6, 1.5e6]))
    assert top["p_Pa"][1] == top["p_Pa"][0] and top["rho_kgm3"][1] == top["rho_kgm3"][0]


def test_table_layout(table):
    alt, lnp, lnrho = table
    assert alt[0] == 86000.0 and alt[-1] == 1.0e6
    for arr in table:
        assert arr.dtype == np.float64 and arr.flags.c_contiguous and arr.shape == alt.shape
    assert np.all(np.diff(alt) > 0.0)


def test_profile_matches_scalar_kernel(table):
    z = np.array([[1000.0, 30000.0], [95000.0, 400000.0]])
    prof = us76_profile(z)
    assert prof["T_K"].shape == z.shape
    for idx in np.ndindex(z.shape):
        t, p, rho, a = atmosphere(z[idx], *table)
        assert (prof["T_K"][idx], prof["p_Pa"][idx], prof["rho_kgm3"][idx],
                prof["a_mps"][idx]) == (t, p, rho, a)
