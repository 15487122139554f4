"""Upper-stage slosh tables (``conf/vehicle/ares_i/slosh_*.csv``) against the public check
values of ``shared/data/ares_i_public_data.md``, independent restatements of the SP-106
formulas, a numerical moment-equivalence check of the spring-mass height, and a fresh
generation (``savant_cli.datagen.ares_i_slosh``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import j1, jnp_zeros

from savant_cli.datagen import ares_i_slosh as gen
from savant_cli.paths import shipped_config_dir

G0 = 9.80665
XI = 1.8412
DATA_DIR = shipped_config_dir() / "vehicle" / "ares_i"
HEADER = ["level_m", "frequency_hz", "damping", "slosh_mass_kg", "slosh_height_m"]

# ---------------------------------------------------------------- public figures / estimates
R_M = 2.75                                                    # [P] 5.5 m diameter
TANKS = {  # name: (load kg [D]: the public 135.1 t at MR 5.5, density kg/m^3 [E], kinematic viscosity m^2/s [E])
    "lox": (135100.0 * 5.5 / 6.5, 1141.0, 1.7e-7),
    "lh2": (135100.0 / 6.5, 70.85, 1.9e-7),
}
HEADROOM = 1.01  # the tables reach 1 % above the nominal fill (dispersed loads, ±0.3 % at 3σ)
# Data file: R = 2.75 m, h/R = 2 -> f1 = 0.34 / 0.50 / 0.76 Hz at 0.7 / 1.5 / 3.5 g, m1/mF = 0.227
CHECK_FREQ = [(0.7, 0.34), (1.5, 0.50), (3.5, 0.76)]
CHECK_MASS_RATIO = 0.227


# ----------------------------------------------------------- independent restatements (SP-106)
def ref_frequency_hz(h, a=G0):
    return np.sqrt(XI * a / R_M * np.tanh(XI * h / R_M)) / (2.0 * np.pi)


def ref_mass_kg(h, rho):
    h = np.asarray(h, dtype=float)
    m_f = rho * np.pi * R_M**2 * h
    with np.errstate(invalid="ignore", divide="ignore"):
        m1 = m_f * 2.0 * R_M / (XI * (XI**2 - 1.0) * h) * np.tanh(XI * h / R_M)
    return np.where(h > 0.0, m1, 0.0)


def ref_height_m(h):
    return h - (2.0 * R_M / XI) * np.tanh(XI * h / (2.0 * R_M))


def ref_smooth_wall_damping(h, nu, a=G0):
    q = np.maximum(np.asarray(h, dtype=float) / R_M, 0.1)
    return (4.98 * nu**0.5 * R_M**-0.75 * a**-0.25
            * (1.0 + 0.318 / np.sinh(1.84 * q) * (1.0 + (1.0 - q) / np.cosh(1.84 * q))) / (2.0 * np.pi))


# [E] ring baffles of slosh_README.md: width 0.1 R every 1.1 m from 0.55 m up to the last
# ring below the full level, damping judged at a wave of 0.01 R (Miles 1958, SP-106 ch. 4)
RING_WIDTH, RING_SPACING, RING_LOWEST, RING_AMPLITUDE = 0.1, 1.1, 0.55, 0.01


def ref_damping(h, nu, h_full):
    """Smooth wall plus Miles' ring damping, one term per submerged ring."""
    alpha = 1.0 - (1.0 - RING_WIDTH) ** 2  # blocked area fraction
    total = ref_smooth_wall_damping(h, nu)
    for level, zeta in np.nditer([np.asarray(h, float), total], op_flags=[["readonly"], ["readwrite"]]):
        for ring in np.arange(RING_LOWEST, h_full, RING_SPACING):
            if ring <= level:
                d = max(level - ring, 0.1 * R_M)
                zeta += 2.83 * np.exp(-4.6 * d / R_M) * alpha**1.5 * RING_AMPLITUDE**0.5
    return total


def read_table(path: Path) -> tuple[list[str], list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    comments = [ln[2:] for ln in lines if ln.startswith("# ")]
    body = [ln for ln in lines if not ln.startswith("#")]
    header = body[0].split(",")
    rows = np.array([[float(v) for v in ln.split(",")] for ln in body[1:] if ln.strip()])
    return comments, header, rows


@pytest.fixture(scope="module", params=sorted(TANKS))
def shipped(request):
    name = request.param
    comments, header, rows = read_table(DATA_DIR / f"slosh_{name}.csv")
    return name, comments, header, rows


# ======================================================================= public check values
@pytest.mark.parametrize("g_level, f_hz", CHECK_FREQ)
def test_public_frequency_check_values(g_level, f_hz):
    f = gen.slosh_frequency_hz(R_M, 2.0 * R_M, g_level * G0)
    assert f == pytest.approx(f_hz, rel=0.01)
    assert gen.slosh_frequency_rad_s(R_M, 2.0 * R_M, g_level * G0) == pytest.approx(2.0 * np.pi * f, rel=1e-12)


def test_public_mass_ratio_check_value():
    h = 2.0 * R_M
    assert gen.slosh_mass_ratio(R_M, h) == pytest.approx(CHECK_MASS_RATIO, rel=0.01)
    rho = 1000.0
    m_f = rho * np.pi * R_M**2 * h
    assert gen.slosh_mass_kg(R_M, h, rho) / m_f == pytest.approx(CHECK_MASS_RATIO, rel=0.01)


def test_frequency_scales_with_sqrt_acceleration():
    h = np.array([0.05, 1.0, 4.0, 13.0])
    f_ref = gen.slosh_frequency_rad_s(R_M, h, G0)
    for a in (0.1, 0.7 * G0, 1.5 * G0, 3.5 * G0, 50.0):
        np.testing.assert_allclose(gen.slosh_frequency_rad_s(R_M, h, a), f_ref * np.sqrt(a / G0), rtol=1e-12)
    assert gen.slosh_frequency_rad_s(R_M, 4.0, 0.0) == 0.0


# ======================================================================= the formulas
def test_functions_match_independent_formulas():
    h = np.linspace(0.01, 15.0, 200)
    np.testing.assert_allclose(gen.slosh_frequency_hz(R_M, h), ref_frequency_hz(h), rtol=1e-12)
    np.testing.assert_allclose(gen.slosh_mass_kg(R_M, h, 1141.0), ref_mass_kg(h, 1141.0), rtol=1e-12)
    np.testing.assert_allclose(gen.slosh_mass_height_m(R_M, h), ref_height_m(h), rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(gen.slosh_damping(R_M, h, 1.7e-7), ref_smooth_wall_damping(h, 1.7e-7), rtol=1e-12)


def test_empty_tank_limits_are_finite():
    assert gen.slosh_frequency_rad_s(R_M, 0.0) == 0.0
    assert gen.slosh_mass_kg(R_M, 0.0, 1141.0) == 0.0
    assert gen.slosh_mass_height_m(R_M, 0.0) == 0.0
    assert gen.slosh_mass_ratio(R_M, 0.0) == pytest.approx(2.0 / (XI**2 - 1.0), rel=1e-12)
    zeta0 = gen.slosh_damping(R_M, 0.0, 1.7e-7)
    assert np.isfinite(zeta0) and zeta0 > 0.0
    # below h/R = 0.1 the damping's depth factor is frozen (continuous at the clamp)
    assert zeta0 == pytest.approx(gen.slosh_damping(R_M, 0.1 * R_M, 1.7e-7), rel=1e-12)
    assert gen.slosh_damping(R_M, 0.1 * R_M * (1 + 1e-9), 1.7e-7) == pytest.approx(zeta0, rel=1e-6)
    # either side of the switch between the small-depth series and the closed form
    # (y = k h / 2 = 1e-3), the height matches y - tanh(y) = y^3/3 - 2y^5/15 + 17y^7/315 - ...
    k = XI / R_M
    for y in (0.999e-3, 1.001e-3):
        series = y**3 / 3 - 2 * y**5 / 15 + 17 * y**7 / 315 - 62 * y**9 / 2835
        assert gen.slosh_mass_height_m(R_M, 2.0 * y / k) == pytest.approx((2.0 / k) * series, rel=1e-6)


def test_rejects_bad_inputs():
    with pytest.raises(ValueError):
        gen.slosh_frequency_rad_s(R_M, -0.1)
    with pytest.raises(ValueError):
        gen.slosh_mass_height_m(0.0, 1.0)
    with pytest.raises(ValueError):
        gen.slosh_damping(R_M, 1.0, 0.0)


def test_spring_mass_height_by_moment_equivalence():
    """Numerical mode-1 pressure on wall and bottom: resultant height M/F, minus the
    weight-moment arm a/omega^2 of the displaced spring mass, is the spring-mass height.
    Uses the exact root of J1' (the bottom moment relies on J2(xi) = J1(xi)/xi there)."""
    xi = jnp_zeros(1, 1)[0]                       # 1.841183781...
    k = xi / R_M
    for h in (0.3, 1.0, 2.75, 4.16, 13.2):
        # p ~ J1(k r) cos(theta) cosh(k z); the common factors (J1(xi) pi R, pi) cancel per term
        force = j1(xi) * np.pi * R_M * quad(lambda z: np.cosh(k * z), 0.0, h)[0]
        m_wall = j1(xi) * np.pi * R_M * quad(lambda z: z * np.cosh(k * z), 0.0, h)[0]
        m_bottom = np.pi * quad(lambda r: j1(k * r) * r * r, 0.0, R_M)[0]
        omega2 = G0 * k * np.tanh(k * h)
        z1 = (m_wall + m_bottom) / force - G0 / omega2
        assert h - (2.0 / k) * np.tanh(k * h / 2.0) == pytest.approx(z1, rel=1e-8, abs=1e-12)
        # the generator's xi = 1.8412 (SP-106's rounding) moves z1 by < 1e-4 relative
        assert gen.slosh_mass_height_m(R_M, h) == pytest.approx(z1, rel=1e-4)


def test_spring_mass_height_bounds_and_deep_limit():
    h = np.linspace(0.0, 40.0, 801)
    z = gen.slosh_mass_height_m(R_M, h)
    assert np.all(z >= 0.0) and np.all(z <= h)
    assert np.all(np.diff(z) > 0.0)
    # never more than 2R/xi below the free surface; approaches that as h/R grows
    assert np.all(h - z <= 2.0 * R_M / XI + 1e-12)
    assert 40.0 - z[-1] == pytest.approx(2.0 * R_M / XI, rel=1e-9)
    # above the liquid CG once h/2 > (2R/xi) tanh(xi h/(2R)), i.e. h/R > 2.080; below it
    # for shallower fills
    above, below = h > 2.1 * R_M, (h > 0.0) & (h < 2.05 * R_M)
    assert np.all(z[above] > h[above] / 2.0)
    assert np.all(z[below] < h[below] / 2.0)


# ======================================================================= shipped tables
def test_shipped_header_and_comments(shipped):
    name, comments, header, _ = shipped
    assert header == HEADER
    text = "\n".join(comments)
    _, rho, nu = TANKS[name]
    assert name.upper() in text
    assert "python -m savant_cli.datagen.ares_i_slosh" in text
    assert f"R = {R_M:g} m" in text
    assert f"density rho = {rho:g} kg/m3" in text
    assert f"kinematic viscosity nu = {nu:g} m2/s" in text
    assert "a_ref = 9.80665 m/s2" in text
    assert "above the flat tank bottom" in text
    assert "spring mass above the tank bottom" in text
    for formula in ("tanh(xi h/R)", "(2R/xi) tanh(xi h/(2R))", "4.98 nu^0.5 R^-0.75 a^-0.25"):
        assert formula in text


def test_shipped_level_axis_covers_empty_to_full(shipped):
    name, _, _, rows = shipped
    load, rho, _ = TANKS[name]
    level = rows[:, 0]
    h_full = load / (rho * np.pi * R_M**2)
    assert len(rows) == 41
    assert level[0] == 0.0
    assert level[-1] == pytest.approx(HEADROOM * h_full, rel=1e-6)
    assert level[-1] >= 1.003 * h_full     # the importer's coverage test (flex_slosh) at a +3σ load
    assert np.all(np.diff(level) > 0.0)


def test_shipped_rows_reproduce_formulas(shipped):
    name, _, _, rows = shipped
    _, rho, nu = TANKS[name]
    level, freq, zeta, mass, height = rows.T
    np.testing.assert_allclose(freq, ref_frequency_hz(level), rtol=1e-8, atol=1e-12)
    h_full = TANKS[name][0] / (rho * np.pi * R_M**2)  # rings up to the nominal fill
    np.testing.assert_allclose(zeta, ref_damping(level, nu, h_full), rtol=1e-8)
    np.testing.assert_allclose(mass, ref_mass_kg(level, rho), rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(height, ref_height_m(level), rtol=1e-8, atol=1e-12)


def test_shipped_physical_bounds(shipped):
    name, _, _, rows = shipped
    _, rho, _ = TANKS[name]
    assert np.all(np.isfinite(rows))
    level, freq, zeta, mass, height = rows.T
    m_f = rho * np.pi * R_M**2 * level
    assert np.all(mass >= 0.0) and np.all(mass <= m_f * (1 + 1e-9))
    assert np.all(height >= 0.0) and np.all(height <= level)
    assert np.all(zeta > 0.0)
    # baffled: wherever a ring is submerged, at least 0.3 % and of the 0.001-0.01 order of
    # the data file (not the smooth wall's 1e-4)
    wet = level >= RING_LOWEST
    assert np.all(zeta[wet] >= 0.003) and np.all(zeta[wet] <= 0.02)
    assert np.all(zeta[~wet] < 1e-3)
    assert np.all(freq >= 0.0) and np.all(np.diff(freq) > 0.0)
    assert freq[0] == 0.0 and mass[0] == 0.0 and height[0] == 0.0


def test_shipped_tables_equal_fresh_generation(tmp_path):
    written = gen.write_all(tmp_path)
    assert sorted(p.name for p in written) == ["slosh_lh2.csv", "slosh_lox.csv"]
    for p in written:
        assert (DATA_DIR / p.name).read_text() == p.read_text(), f"{p.name}: regenerate with " \
            "`python -m savant_cli.datagen.ares_i_slosh`"


def test_command_line_writes_to_out(tmp_path, capsys):
    gen.main(["--out", str(tmp_path / "x")])
    assert (tmp_path / "x" / "slosh_lox.csv").is_file() and (tmp_path / "x" / "slosh_lh2.csv").is_file()
    assert "lox full" in capsys.readouterr().out


def test_generator_constants_are_the_public_figures():
    for tank in gen.TANKS:
        load, rho, nu = TANKS[tank.name]
        assert (tank.radius_m, tank.density_kg_m3, tank.kinematic_viscosity_m2_s) == (R_M, rho, nu)
        assert tank.load_kg == pytest.approx(load, abs=0.01)  # the generator rounds the split to the gram
    assert gen.A_REF_MPS2 == G0
