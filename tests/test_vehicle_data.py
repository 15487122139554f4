"""The default vehicle's data against the PUBLIC figures of
``shared/data/ares_i_public_data.md`` (not against copies of the generator's output),
aerodynamic sign conventions of ``docs/architecture.md``, and the loader's refusals."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf
from scipy.integrate import trapezoid

from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir
from savant_cli.vehicle import CONFIG_NAMES, Vehicle, load_vehicle

G0 = 9.80665
CONF = shipped_config_dir()
VEHICLE_YAML = CONF / "vehicle" / "ares_i.yaml"
DATA_DIR = CONF / "vehicle" / "ares_i"
BODY_FROM_STRUCTURE = np.diag([-1.0, 1.0, -1.0])

# ---------------------------------------------------------------- public figures
LIFTOFF_T, FS_BURNOUT_T, US_IGNITION_T, US_BURNOUT_T = 920.0, 272.0, 181.0, 35.6      # [D]
LIFTOFF_CG_ABOVE_EXIT_M, FS_BURNOUT_CG_ABOVE_EXIT_M = 33.9, 54.9                      # [D]
LIFTOFF_IYY, FS_BURNOUT_IYY, US_IGNITION_IYY, US_BURNOUT_IYY = 4.2e8, 1.4e8, 2.1e7, 3.7e6  # [D]
FS_PROPELLANT_KG, FS_INERT_KG, INTERSTAGE_KG = 647600.0, 85500.0, 5900.0               # [E]
LOX_KG, LH2_KG, LES_KG = 112900.0, 22200.0, 7060.0                                    # [P]
FS_TOTAL_IMPULSE_NS = 1.689e9                                                         # [D]
J2X_THRUST_N, J2X_ISP_S, J2X_MDOT_KGS = 1307500.0, 448.0, 297.6                       # [P], [P], [D]
LENGTH_M = 94.0                                                                       # [P]
ATLAS_CA = {0.0: .373, 0.5: .345, 0.9: .481, 1.0: .725, 1.1: .773, 1.5: .622, 2.0: .459, 4.5: .273,
            10.0: .289}                                                               # [P]
# Tolerances: the data file's mass-property figures are 2-3 significant-figure
# estimates from a uniform-segment layout, and its four masses disagree among
# themselves by ~1.5 % (920 - 647.6 = 272.4; 272 - 91.4 = 180.6): masses and CGs 2 %,
# pitch inertias (stated to 2 significant figures, layout [E]) 5 %.
MASS_TOL, CG_TOL, INERTIA_TOL = 0.02, 0.02, 0.05


def _cfg() -> dict:
    return OmegaConf.to_container(OmegaConf.load(VEHICLE_YAML).vehicle, resolve=True)  # a `_global_` preset


# the sections of ares_i.yaml the refusal tests edit (paths below `vehicle`)
FIRST = "stages.first_stage"
MOTOR = f"{FIRST}.engines.five_segment_motor"
UPPER = "stages.upper_stage"
J2X = f"{UPPER}.engines.j2x"
GRAIN, LOX, LH2 = f"{FIRST}.tanks.grain", f"{UPPER}.tanks.lox", f"{UPPER}.tanks.lh2"
ROLL_JETS, LES = f"{UPPER}.roll_jets", "items.les"


def _section(cfg: dict, path: str) -> dict:
    """The section of the vehicle node at a dotted path."""
    for part in path.split("."):
        cfg = cfg[part]
    return cfg


@pytest.fixture(scope="module")
def vehicle() -> Vehicle:
    return load_vehicle(OmegaConf.load(VEHICLE_YAML).vehicle, DATA_DIR)


def _state(v: Vehicle, config: str, full: bool):
    m = v.configurations[config].mass
    i = -1 if full else 0
    return m.mass_kg[i], m.cg_m[i], m.inertia_kgm2[i]


# ======================================================================= mass properties
@pytest.mark.parametrize("config, full, mass_t, cg_above_exit_m, iyy", [
    ("stack", True, LIFTOFF_T, LIFTOFF_CG_ABOVE_EXIT_M, LIFTOFF_IYY),
    ("stack", False, FS_BURNOUT_T, FS_BURNOUT_CG_ABOVE_EXIT_M, FS_BURNOUT_IYY),
    ("upper_les", True, US_IGNITION_T, None, US_IGNITION_IYY),
    ("upper", False, US_BURNOUT_T, None, US_BURNOUT_IYY),
])
def test_mass_properties_match_public_figures(vehicle, config, full, mass_t, cg_above_exit_m, iyy):
    mass, cg, inertia = _state(vehicle, config, full)
    assert mass / 1e3 == pytest.approx(mass_t, rel=MASS_TOL)
    if cg_above_exit_m is not None:
        assert LENGTH_M - cg[0] == pytest.approx(cg_above_exit_m, rel=CG_TOL)
    assert inertia[1] == pytest.approx(iyy, rel=INERTIA_TOL)
    assert inertia[2] == pytest.approx(iyy, rel=INERTIA_TOL)       # axisymmetric: yaw = pitch
    assert 0.0 < inertia[0] < 0.05 * inertia[1]                    # slender: small roll inertia


def test_mass_tables_span_the_public_loads(vehicle):
    stack = vehicle.configurations["stack"].mass
    assert stack.propellant_kg[0] == 0.0
    assert stack.propellant_kg[-1] == pytest.approx(FS_PROPELLANT_KG, abs=1.0)
    for name in ("upper_les", "upper"):
        m = vehicle.configurations[name].mass
        assert m.propellant_kg[0] == 0.0
        assert m.propellant_kg[-1] == pytest.approx(LOX_KG + LH2_KG, abs=1.0)
        assert 20 <= m.propellant_kg.size <= 40
        assert np.all(np.diff(m.propellant_kg) > 0)
    assert 20 <= stack.propellant_kg.size <= 40


def test_mass_tables_consistent_across_configurations(vehicle):
    stack, les, up = (vehicle.configurations[n].mass for n in CONFIG_NAMES)
    # separation drops the first-stage inert mass and the interstage
    assert stack.mass_kg[0] - (FS_INERT_KG + INTERSTAGE_KG) == pytest.approx(les.mass_kg[-1], abs=1.0)
    # LES jettison drops 7.06 t at every propellant level
    np.testing.assert_allclose(np.interp(up.propellant_kg, les.propellant_kg, les.mass_kg) - up.mass_kg,
                               LES_KG, atol=1.0)
    # propellant is the only thing burning: dm = dprop in every table
    for m in (stack, les, up):
        np.testing.assert_allclose(np.diff(m.mass_kg), np.diff(m.propellant_kg), atol=1e-6)
    # axisymmetric layout: CG on the axis, no products of inertia; CG on the vehicle
    for m in (stack, les, up):
        np.testing.assert_array_equal(m.cg_m[:, 1:], 0.0)
        np.testing.assert_array_equal(m.inertia_kgm2[:, 3:], 0.0)
        assert np.all((m.cg_m[:, 0] > 0.0) & (m.cg_m[:, 0] < LENGTH_M))
    assert vehicle.first_stage.jettison_mass_kg == pytest.approx(FS_INERT_KG + INTERSTAGE_KG)
    assert vehicle.upper_stage.les_mass_kg == pytest.approx(LES_KG)


# ============================================================================ propulsion
def test_first_stage_total_vacuum_impulse(vehicle):
    fs = vehicle.first_stage
    impulse = trapezoid(fs.thrust_vac_N, fs.thrust_time_s)
    assert impulse == pytest.approx(FS_TOTAL_IMPULSE_NS, rel=0.01)
    # at constant Isp the impulse burns the public propellant load
    assert impulse / (G0 * fs.isp_vac_s) == pytest.approx(FS_PROPELLANT_KG, rel=0.01)
    assert fs.thrust_vac_N.max() == pytest.approx(16.0e6, rel=0.02)       # "up to 3.6 Mlbf" [P]


def test_first_stage_exit_area_matches_isp_ratio(vehicle):
    fs = vehicle.first_stage
    f_peak = fs.thrust_vac_N.max()
    assert fs.nozzle_exit_area_m2 * 101325.0 == pytest.approx(f_peak * (1 - 242.0 / 266.0), rel=0.01)


def test_j2x_mass_flow(vehicle):
    us = vehicle.upper_stage
    assert us.thrust_vac_N == pytest.approx(J2X_THRUST_N)
    assert us.isp_vac_s == pytest.approx(J2X_ISP_S)
    assert us.thrust_vac_N / (G0 * us.isp_vac_s) == pytest.approx(J2X_MDOT_KGS, rel=1e-3)
    burn_s = (us.lox_kg + us.lh2_kg) / J2X_MDOT_KGS
    assert 440.0 < burn_s < 465.0                                          # "burn ≈ 455-465 s" [D]


def test_j2x_startup_transient(vehicle):
    us = vehicle.upper_stage
    t, f = us.startup_time_s, us.startup_fraction
    assert f[0] == 0.0 and f[-1] == pytest.approx(1.0)
    assert np.all(np.diff(f) >= 0.0)
    t_full = t[np.argmax(f >= 0.999)]
    assert 2.0 <= t_full <= 3.5


def test_rcs_and_gimbals(vehicle):
    assert vehicle.rcs.thrust_vac_N == pytest.approx(3100.0, rel=0.1)
    assert vehicle.rcs.moment_arm_m == pytest.approx(5.5 / 2)
    assert vehicle.first_stage.gimbal_limit_rad == pytest.approx(np.radians(8.0))
    assert vehicle.upper_stage.gimbal_limit_rad == pytest.approx(np.radians(5.0))
    # engines are aft of every CG they push
    stack = vehicle.configurations["stack"].mass
    assert vehicle.first_stage.gimbal_m[0] > stack.cg_m[:, 0].max()
    for name in ("upper_les", "upper"):
        assert vehicle.upper_stage.gimbal_m[0] > vehicle.configurations[name].mass.cg_m[:, 0].max()


# ====================================================================== aerodynamics
def _coeffs(aero, mach, alpha_deg, beta_deg):
    """Coefficients at grid nodes (exact match required)."""
    i = int(np.flatnonzero(np.isclose(aero.mach, mach))[0])
    j = int(np.flatnonzero(np.isclose(aero.alpha_rad, np.radians(alpha_deg)))[0])
    k = int(np.flatnonzero(np.isclose(aero.beta_rad, np.radians(beta_deg)))[0])
    return aero.coeffs[:, i, j, k]


def test_aero_grid_axes(vehicle):
    for name in CONFIG_NAMES:
        a = vehicle.configurations[name].aero
        assert a.mach[0] == 0.0 and a.mach[-1] == pytest.approx(10.0) and 18 <= a.mach.size <= 30
        for mach in (0.9, 0.93, 0.95, 1.0, 1.05, 1.1):                    # transonic detail
            assert np.any(np.isclose(a.mach, mach))
        for ax in (a.alpha_rad, a.beta_rad):
            assert ax[0] <= np.radians(-10.0) + 1e-12 and ax[-1] >= np.radians(10.0) - 1e-12
        assert a.coeffs.shape == (6, a.mach.size, a.alpha_rad.size, a.beta_rad.size)
        assert a.area_m2 == pytest.approx(np.pi * 5.5**2 / 4, rel=1e-3)


def test_axial_force_is_the_atlas_table(vehicle):
    a = vehicle.configurations["stack"].aero
    for mach, ca in ATLAS_CA.items():
        assert _coeffs(a, mach, 0.0, 0.0)[0] == pytest.approx(ca)


@pytest.mark.parametrize("mach, slope", [(0.5, 3.2), (1.0, 4.3), (4.5, 4.6), (6.0, 4.6)])
def test_normal_force_slope(vehicle, mach, slope):
    a = vehicle.configurations["stack"].aero
    cn = _coeffs(a, mach, 2.0, 0.0)[2]
    assert cn / np.radians(2.0) == pytest.approx(slope, rel=0.03)


@pytest.mark.parametrize("name", CONFIG_NAMES)
def test_aero_signs(vehicle, name):
    a = vehicle.configurations[name].aero
    for mach in (0.5, 1.0, 2.0, 4.5):
        ca, cy, cn, cl, cm, cn_yaw = _coeffs(a, mach, 4.0, 0.0)
        assert cn > 0.0 and cy == pytest.approx(0.0, abs=1e-12)             # CN > 0 for alpha > 0
        assert cm < 0.0                                                      # CP aft of the nose MRP
        ca, cy, cn, cl, cm, cn_yaw = _coeffs(a, mach, 0.0, 4.0)
        assert cy < 0.0 and cn == pytest.approx(0.0, abs=1e-12)             # CY < 0 for beta > 0
        assert cn_yaw > 0.0                                                  # CP aft of the nose MRP
        ca0, cy0, cn0, cl0, cm0, cnz0 = _coeffs(a, mach, 0.0, 0.0)
        assert cy0 == cn0 == cm0 == cnz0 == 0.0 and ca0 > 0.0
    np.testing.assert_array_equal(a.coeffs[3], 0.0)                          # no roll aero


@pytest.mark.parametrize("name", CONFIG_NAMES)
def test_moments_are_r_cross_f_from_one_centre_of_pressure(vehicle, name):
    """Cm, Cn about the MRP equal r x F with F = qS[-CA, CY, -CN] applied at a centre of
    pressure on the axis (the same point for the pitch and yaw planes)."""
    a = vehicle.configurations[name].aero
    lref = a.lref_m
    for i in range(a.mach.size):
        ca, cy, cn, _, cm, cnz = a.coeffs[:, i]
        sel = np.abs(cn) > 1e-3
        # x_cp from the pitch plane, then the yaw moment predicted by r x F must match
        x_cp = a.mrp_m[0] - (cm[sel] * lref[1] / cn[sel])
        assert np.ptp(x_cp) < 1e-5
        r = BODY_FROM_STRUCTURE @ np.array([x_cp[0] - a.mrp_m[0], 0.0, 0.0])
        f = np.stack([-ca, cy, -cn], axis=-1)
        m = np.cross(r, f)
        np.testing.assert_allclose(m[..., 1] / lref[1], cm, atol=1e-7)
        np.testing.assert_allclose(m[..., 2] / lref[2], cnz, atol=1e-7)
        np.testing.assert_allclose(m[..., 0], 0.0, atol=1e-12)


@pytest.mark.parametrize("name", CONFIG_NAMES)
def test_total_angle_of_attack_symmetry(vehicle, name):
    """Body of revolution: the crossflow force depends on the total angle of attack only,
    and (alpha, beta) and (beta, alpha) have the same total angle."""
    a = vehicle.configurations[name].aero
    np.testing.assert_array_equal(a.alpha_rad, a.beta_rad)
    mag = np.hypot(a.coeffs[1], a.coeffs[2])
    np.testing.assert_allclose(mag, np.swapaxes(mag, 1, 2), atol=1e-7)
    alpha_t = np.arccos(np.cos(a.alpha_rad)[:, None] * np.cos(a.beta_rad)[None, :])
    # CN odd in alpha, CY odd in beta, CA even in both
    np.testing.assert_allclose(a.coeffs[2], -a.coeffs[2][:, ::-1, :], atol=1e-12)
    np.testing.assert_allclose(a.coeffs[1], -a.coeffs[1][:, :, ::-1], atol=1e-12)
    np.testing.assert_allclose(a.coeffs[0], a.coeffs[0][:, ::-1, ::-1], atol=1e-12)
    # magnitude grows with the total angle at fixed Mach
    for i in range(a.mach.size):
        order = np.argsort(alpha_t.ravel(), kind="stable")
        assert np.all(np.diff(mag[i].ravel()[order]) > -1e-7)


def test_stack_aerodynamically_unstable_in_first_stage_flight(vehicle):
    """Centre of pressure ahead of the CG at Mach 0.5-4 at every propellant level, so the
    moment about the CG (M_cg = M_mrp + r_cg->mrp x F) drives the angles away from zero:
    a positive alpha (nose above the air-relative velocity) gives a nose-up (positive)
    pitching moment; a positive beta (air-relative velocity toward +Y) gives a negative
    yawing moment, turning the nose further from the velocity (stable would be Cn_beta > 0)."""
    cfg = vehicle.configurations["stack"]
    a, m = cfg.aero, cfg.mass
    for mach in a.mach[(a.mach >= 0.5) & (a.mach <= 4.0)]:
        for alpha_deg, beta_deg, axis, unstable_sign in ((4.0, 0.0, 1, 1.0), (0.0, 4.0, 2, -1.0)):
            c = _coeffs(a, mach, alpha_deg, beta_deg)
            f = np.array([-c[0], c[1], -c[2]])
            m_mrp = a.lref_m * c[3:]
            x_cp = a.mrp_m[0] - (c[4] * a.lref_m[1] / c[2] if axis == 1 else c[5] * a.lref_m[2] / c[1])
            assert 0.1 * LENGTH_M <= x_cp <= 0.3 * LENGTH_M                  # CP at 0.1-0.3 L
            for cg in m.cg_m:
                m_cg = m_mrp + np.cross(BODY_FROM_STRUCTURE @ (a.mrp_m - cg), f)
                assert unstable_sign * m_cg[axis] > 0.0, (mach, cg)
                assert x_cp < cg[0]


# ======================================================================== base force
def test_base_force_tables(vehicle):
    peak_thrust = vehicle.first_stage.thrust_vac_N.max()
    for name in CONFIG_NAMES:
        a = vehicle.configurations[name].aero
        assert np.all(np.diff(a.base_time_s) > 0.0)
        assert np.all(a.base_force_N <= 0.0)                                  # drag
        assert np.abs(a.base_force_N).max() < 0.01 * peak_thrust
    stack = vehicle.configurations["stack"].aero
    assert np.abs(stack.base_force_N).max() > 1e4                           # felt around max-Q
    t_peak = stack.base_time_s[np.argmax(np.abs(stack.base_force_N))]
    assert 45.0 < t_peak < 75.0


# ============================================================================ winds
def test_wind_profiles():
    ksc = OmegaConf.load(CONF / "winds" / "ksc_mean_annual.yaml")
    none = OmegaConf.load(CONF / "winds" / "none.yaml")
    assert set(ksc.keys()) == set(none.keys()) >= {"enabled", "scale", "profile"}
    assert ksc.enabled is True and none.enabled is False
    alt = np.asarray(ksc.profile.altitude_m, float)
    east = np.asarray(ksc.profile.east_mps, float)
    assert np.all(np.diff(alt) > 0) and len(ksc.profile.north_mps) == alt.size == east.size
    assert np.all(east >= 0.0)                                               # westerly: toward the east
    jet = east[(alt >= 11000) & (alt <= 13000)]
    assert np.all((jet >= 20.0) & (jet <= 30.0))
    assert east[0] < 8.0 and np.interp(30000.0, alt, east) < 10.0


def test_composed_config_loads(compose_cfg):
    cfg = compose_cfg(["winds=none"])
    assert cfg.winds.enabled is False
    v = load_vehicle(cfg.vehicle, DATA_DIR)
    assert v.name == "ares_i" and v.length_m == LENGTH_M


# =========================================================================== loader
def test_arrays_are_si_float64_contiguous(vehicle):
    def check(x):
        assert isinstance(x, np.ndarray) and x.dtype == np.float64 and x.flags.c_contiguous

    for c in vehicle.configurations.values():
        for x in (c.aero.mach, c.aero.alpha_rad, c.aero.beta_rad, c.aero.coeffs, c.aero.base_time_s,
                  c.aero.base_force_N, c.aero.lref_m, c.aero.mrp_m, c.mass.propellant_kg, c.mass.mass_kg,
                  c.mass.cg_m, c.mass.inertia_kgm2):
            check(x)
    for x in (vehicle.first_stage.thrust_time_s, vehicle.first_stage.thrust_vac_N, vehicle.first_stage.gimbal_m,
              vehicle.upper_stage.startup_time_s, vehicle.upper_stage.gimbal_m, vehicle.rcs.altitude_m,
              vehicle.rcs.location_m, vehicle.sensors.imu_m):
        check(x)
    assert vehicle.configurations["stack"].aero.alpha_rad.max() == pytest.approx(np.radians(10.0))


@pytest.fixture
def copy(tmp_path) -> Path:
    d = tmp_path / "ares_i"
    shutil.copytree(DATA_DIR, d)
    return d


def _edit(path: Path, fn) -> None:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(fn(lines)) + "\n")


def _header_index(lines: list[str]) -> int:
    return next(i for i, ln in enumerate(lines) if ln and not ln.startswith("#"))


def _set_cell(path: Path, row: int, column: str, value: str) -> None:
    """Replace one cell (data row index from 0) of a CSV."""
    def fn(lines):
        h = _header_index(lines)
        j = lines[h].split(",").index(column)
        cells = lines[h + 1 + row].split(",")
        cells[j] = value
        lines[h + 1 + row] = ",".join(cells)
        return lines
    _edit(path, fn)


def test_converts_units_from_header_suffixes(copy):
    """The same table in lbm / ft / slug ft^2 loads to the same SI arrays."""
    path = copy / "mass_stack.csv"
    lines = path.read_text().splitlines()
    h = _header_index(lines)
    data = np.loadtxt(lines[h + 1:], delimiter=",")
    lbm, ft = 0.45359237, 0.3048
    slug = lbm * 9.80665 / ft  # 1 lbf·s²/ft, exactly (NIST SP 811)
    factors = np.array([lbm, lbm, ft, ft, ft] + [slug * ft**2] * 6)
    header = ("propellant_remaining_lbm,mass_lbm,cg_x_ft,cg_y_ft,cg_z_ft,ixx_slugft2,iyy_slugft2,izz_slugft2,"
              "ixy_slugft2,ixz_slugft2,iyz_slugft2")
    rows = [",".join(repr(float(x)) for x in r) for r in data / factors]
    path.write_text("\n".join(["# converted", header] + rows) + "\n")
    v = load_vehicle(_cfg(), copy)
    ref = load_vehicle(_cfg(), DATA_DIR)
    for a, b in ((v.configurations["stack"].mass.mass_kg, ref.configurations["stack"].mass.mass_kg),
                 (v.configurations["stack"].mass.cg_m, ref.configurations["stack"].mass.cg_m),
                 (v.configurations["stack"].mass.inertia_kgm2, ref.configurations["stack"].mass.inertia_kgm2)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)


def _refused(cfg, data_dir, key_part: str) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        load_vehicle(cfg, data_dir)
    assert key_part in info.value.key, info.value
    return info.value


def test_refuses_missing_file(copy):
    (copy / "mass_upper.csv").unlink()
    _refused(_cfg(), copy, "mass_upper.csv")


@pytest.mark.parametrize("old, new, key", [
    ("mass_kg", "mass_m", "mass_stack.csv:mass_m"),                 # wrong unit dimension
    ("mass_kg", "masss_kg", "mass_stack.csv:masss_kg"),             # unknown column
    (",iyz_kgm2", "", "mass_stack.csv:iyz"),                        # missing column (ragged rows too)
])
def test_refuses_bad_headers(copy, old, new, key):
    path = copy / "mass_stack.csv"
    _edit(path, lambda lines: [ln.replace(old, new, 1) if i == _header_index(lines) else ln
                               for i, ln in enumerate(lines)])
    _refused(_cfg(), copy, key)


def test_refuses_non_numeric_cell(copy):
    _set_cell(copy / "first_stage_thrust.csv", 3, "thrust_vac_N", "lots")
    _refused(_cfg(), copy, "first_stage_thrust.csv")


def test_refuses_ragged_row(copy):
    _edit(copy / "rcs_thrust.csv", lambda lines: lines[:-1] + [lines[-1] + ",7"])
    _refused(_cfg(), copy, "rcs_thrust.csv")


def test_refuses_non_monotonic_axis(copy):
    path = copy / "first_stage_thrust.csv"

    def swap(lines):
        h = _header_index(lines)
        lines[h + 3], lines[h + 4] = lines[h + 4], lines[h + 3]
        return lines
    _edit(path, swap)
    _refused(_cfg(), copy, "first_stage_thrust.csv:time_s")


def test_refuses_non_monotonic_mass_table(copy):
    _set_cell(copy / "mass_upper.csv", 5, "propellant_remaining_kg", "1.0")
    _refused(_cfg(), copy, "mass_upper.csv:propellant_remaining_kg")


def test_refuses_incomplete_aero_grid(copy):
    _edit(copy / "aero_stack.csv", lambda lines: lines[:-1])
    _refused(_cfg(), copy, "aero_stack.csv")


def test_refuses_duplicated_aero_row(copy):
    def dup(lines):
        h = _header_index(lines)
        lines[-1] = lines[h + 1]
        return lines
    _edit(copy / "aero_upper.csv", dup)
    _refused(_cfg(), copy, "aero_upper.csv")


@pytest.mark.parametrize("file, column, value", [
    ("mass_stack.csv", "mass_kg", "-5"),
    ("mass_upper_les.csv", "iyy_kgm2", "-1e7"),
    ("first_stage_thrust.csv", "thrust_vac_N", "-1e6"),
    ("rcs_thrust.csv", "thrust_vac_N", "-3100"),
])
def test_refuses_negative_table_values(copy, file, column, value):
    _set_cell(copy / file, 2, column, value)
    _refused(_cfg(), copy, f"{file}:{column}")


@pytest.mark.parametrize("section, key", [
    (MOTOR, "isp_vac_s"), (MOTOR, "isp_sl_s"), (J2X, "isp_vac_s"), (J2X, "thrust_vac_N"), (LOX, "propellant_kg"),
    (GRAIN, "propellant_kg"), (FIRST, "inert_mass_kg"), (LES, "mass_kg"),
])
def test_refuses_negative_config_values(copy, section, key):
    cfg = _cfg()
    _section(cfg, section)[key] = -abs(_section(cfg, section)[key])
    _refused(cfg, copy, f"vehicle.{section}.{key}")


def test_refuses_negative_engine_mass(copy):
    cfg = _cfg()
    _section(cfg, MOTOR)["moving_mass"]["mass_kg"] = -7000.0
    _refused(cfg, copy, f"vehicle.{MOTOR}.moving_mass.mass_kg")


def test_refuses_inertia_not_positive_definite(copy):
    _set_cell(copy / "mass_upper.csv", 4, "ixy_kgm2", "5e7")      # |Ixy| > sqrt(Ixx Iyy)
    _refused(_cfg(), copy, "mass_upper.csv:ixx_kgm2")


def test_refuses_inertia_violating_triangle_inequality(copy):
    _set_cell(copy / "mass_upper_les.csv", 0, "ixx_kgm2", "1e9")   # Ixx > Iyy + Izz
    _refused(_cfg(), copy, "mass_upper_les.csv:ixx_kgm2")


@pytest.mark.parametrize("section, key, value", [
    (MOTOR, "gimbal_m", [90.5, 0.0]),
    ("sensors", "imu_m", [10.0, 0.0, 0.0, 0.0]),
    (ROLL_JETS, "location_m", "35.6"),
])
def test_refuses_wrong_location_length(copy, section, key, value):
    cfg = _cfg()
    _section(cfg, section)[key] = value
    _refused(cfg, copy, f"vehicle.{section}.{key}")


def test_refuses_wrong_reference_vector(copy):
    cfg = _cfg()
    cfg["configurations"]["stack"]["moment_reference_m"] = [0.0, 0.0]
    _refused(cfg, copy, "vehicle.configurations.stack.moment_reference_m")


@pytest.mark.parametrize("section, key, delta", [
    (FIRST, "inert_mass_kg", 500.0),
    (LES, "mass_kg", 100.0),
    (GRAIN, "propellant_kg", 1000.0),
    (LH2, "propellant_kg", -200.0),
])
def test_refuses_mass_tables_inconsistent_with_jettisoned_masses(copy, section, key, delta):
    cfg = _cfg()
    _section(cfg, section)[key] += delta
    _refused(cfg, copy, f"vehicle.{section if section != LH2 else LOX}.")


def test_refuses_mass_table_not_matching_staging(copy):
    """Adding mass to one upper_les row breaks the LES-mass difference."""
    path = copy / "mass_upper_les.csv"
    lines = path.read_text().splitlines()
    h = _header_index(lines)
    cells = lines[h + 6].split(",")
    cells[1] = repr(float(cells[1]) + 50.0)
    lines[h + 6] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    _refused(_cfg(), copy, f"vehicle.{LES}.mass_kg")


def test_refuses_unknown_and_missing_keys(copy):
    cfg = _cfg()
    _section(cfg, MOTOR)["isp_vacuum_s"] = 266.0
    _refused(cfg, copy, f"vehicle.{MOTOR}.isp_vacuum_s")
    cfg = _cfg()
    del _section(cfg, J2X)["mixture_ratio"]
    _refused(cfg, copy, f"vehicle.{J2X}.mixture_ratio")
    cfg = _cfg()
    del cfg["configurations"]["upper"]
    _refused(cfg, copy, "vehicle.events.les_jettison.jettison")  # the parts left after it have no configuration


# ===================================================================== reproducibility
def test_generator_reproduces_shipped_tables(tmp_path):
    """The shipped CSVs are exactly what the generators write: the vehicle's and the
    strap-on booster example's (the slosh tables have their own generator and test)."""
    from savant_cli.datagen import ares_i_tables as gen, strap_on_boosters

    gen.write_all(tmp_path)
    strap_on_boosters.write_all(tmp_path)
    shipped = sorted(p.name for p in DATA_DIR.glob("*.csv") if not p.name.startswith("slosh_"))
    assert shipped == sorted(p.name for p in tmp_path.glob("*.csv"))
    for name in shipped:
        a = [ln for ln in (DATA_DIR / name).read_text().splitlines() if ln and not ln.startswith("#")]
        b = [ln for ln in (tmp_path / name).read_text().splitlines() if ln and not ln.startswith("#")]
        assert a[0] == b[0] and len(a) == len(b), name
        np.testing.assert_allclose(np.loadtxt(a[1:], delimiter=","), np.loadtxt(b[1:], delimiter=","),
                                   rtol=1e-9, atol=1e-9, err_msg=name)


def test_yaml_derived_scalars_match_the_generator_layout():
    """The [D] scalars of ares_i.yaml follow the generator's segment layout."""
    from savant_cli.datagen import ares_i_tables as gen

    cfg = _cfg()
    d = gen.derived_figures()
    motor, j2x = _section(cfg, MOTOR), _section(cfg, J2X)
    assert motor["nozzle_exit_area_m2"] == pytest.approx(d["first_stage.nozzle_exit_area_m2"], abs=0.01)
    assert _section(cfg, FIRST)["inert_mass_kg"] == pytest.approx(d["first_stage.jettison_mass_kg"])
    assert motor["gimbal_m"][0] == pytest.approx(d["first_stage.gimbal_x_m"])
    assert j2x["gimbal_m"][0] == pytest.approx(d["upper_stage.gimbal_x_m"])
    for k in ("mass_kg", "cg_from_gimbal_m", "inertia_about_gimbal_kgm2"):
        assert j2x["moving_mass"][k] == pytest.approx(d[f"upper_stage.engine.{k}"])
    assert _section(cfg, ROLL_JETS)["location_m"][0] == pytest.approx(d["rcs.location_x_m"])
    les = _section(cfg, LES)
    assert les["cg_m"][0] == pytest.approx(d["items.les.cg_x_m"])
    assert les["inertia_kgm2"][:2] == pytest.approx([d["items.les.ixx_kgm2"], d["items.les.iyy_kgm2"]], rel=1e-7)
    assert cfg["sensors"]["imu_m"][0] == pytest.approx(d["sensors.imu_x_m"])
    assert cfg["sensors"]["rate_gyro_first_stage_m"][0] == pytest.approx(d["sensors.rate_gyro_first_stage_x_m"])
    assert cfg["configurations"]["upper"]["moment_reference_m"][0] == pytest.approx(
        d["configurations.upper.moment_reference_x_m"])
    assert cfg["configurations"]["stack"]["reference_area_m2"] == pytest.approx(gen.REF_AREA_M2, abs=0.01)
