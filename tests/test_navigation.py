"""Inertial navigation with IMU errors (issue 26 item 9, ``models/navigation.py``).

The error kernel is checked against closed-form solutions of the strapdown error
equations on synthetic trajectories (Titterton & Weston, *Strapdown Inertial Navigation
Technology*, §12): a gyro bias integrates to a linear attitude drift; a horizontal
accelerometer bias of a vehicle held at constant radius gives the Schuler oscillation
``δy = b/ω_s² (1 − cos ω_s t)``, a vertical one the divergence ``δx = b/(2ω_s²)(cosh(√2
ω_s t) − 1)``; a gyro-triad misalignment seen by a body spinning about x traces a circle;
an alignment tilt under a constant specific force grows a velocity error ``φ × f t``.
In flight: all-zero errors fly bit for bit the perfect navigation; a gyro bias's logged
attitude error is the integral of the bias through the logged attitude; the errors reach
the flight software (PEG cuts off on the navigated state); the config refuses values
outside the model's range, and the dispersion set's navigation items are inactive with
``navigation=perfect``.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.bitwise import WALL_CLOCK_KEYS
from savant_cli.models import earth, gravity, navigation as nav, quaternion as qt
from savant_cli.models.layout import N_DISC, N_PARAM
from savant_cli.models.peg import insertion_target
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import orbit_elements, summarize

MU = constants.MU_EARTH
R0 = 6_500_000.0  # m, radius of the synthetic trajectories
OMEGA_S = np.sqrt(MU / R0 ** 3)  # rad/s, Schuler frequency at R0 (point-mass gravity)
SPECIFIC_FORCE = MU / R0 ** 2  # m/s², what an IMU held at R0 senses (upward)


def _params(**errors) -> np.ndarray:
    """Plant parameters with point-mass gravity and the given IMU errors (SI)."""
    p = np.zeros(N_PARAM)
    p[gravity.P_MU] = MU
    p[gravity.P_ORDER] = 0.0
    p[earth.P_RE] = constants.WGS84_A
    p[nav.P_ON] = 1.0
    fields = {"gyro_bias": nav.P_GYRO_BIAS, "gyro_scale": nav.P_GYRO_SCALE, "gyro_misalign": nav.P_GYRO_MISALIGN,
              "accel_bias": nav.P_ACCEL_BIAS, "accel_scale": nav.P_ACCEL_SCALE,
              "accel_misalign": nav.P_ACCEL_MISALIGN, "alignment": nav.P_ALIGNMENT}
    for name, value in errors.items():
        p[fields[name]:fields[name] + 3] = value
    return p


def _hold(p: np.ndarray, t_end: float, dt: float, attitude=lambda t: np.array([1.0, 0.0, 0.0, 0.0])) -> np.ndarray:
    """Run the kernel over a vehicle held at rest at ``R0 e_x`` (sensing 1 g up) with the
    given body attitude history; returns ``d``."""
    d = np.zeros(N_DISC)
    r = np.array([R0, 0.0, 0.0])
    v = np.zeros(3)
    for k in range(int(round(t_end / dt)) + 1):
        nav.imu_sample(d, k * dt, r, v, attitude(k * dt), p)
    return d


def _errors(d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return (d[nav.D_ATTITUDE:nav.D_ATTITUDE + 3], d[nav.D_POSITION:nav.D_POSITION + 3],
            d[nav.D_VELOCITY:nav.D_VELOCITY + 3])


def test_gyro_bias_integrates_to_a_linear_attitude_drift():
    b = np.array([1e-6, -2e-6, 3e-6])  # rad/s
    d = _hold(_params(gyro_bias=b), 100.0, 0.005)
    phi, _, _ = _errors(d)
    np.testing.assert_allclose(phi, b * 100.0, rtol=1e-9)


def test_horizontal_accelerometer_bias_gives_the_schuler_oscillation():
    b = 1e-4  # m/s² (≈ 10 µg) along body y, horizontal at R0 e_x
    t = np.pi / OMEGA_S  # half a Schuler period (≈ 42 min): the largest excursion
    d = _hold(_params(accel_bias=[0.0, b, 0.0]), t, 0.5)
    _, dr, dv = _errors(d)
    expected = b / OMEGA_S ** 2 * (1.0 - np.cos(OMEGA_S * t))  # 2b/ω_s² ≈ 130 m
    assert dr[1] == pytest.approx(expected, rel=1e-3)
    assert abs(dv[1]) < 1e-3 * b / OMEGA_S  # the velocity error is back through zero
    assert abs(dr[0]) < 1e-3 * expected and abs(dr[2]) < 1e-9


def test_vertical_accelerometer_bias_diverges_at_the_vertical_channel_rate():
    b = 1e-4  # m/s² along body x (up)
    t = 1500.0
    d = _hold(_params(accel_bias=[b, 0.0, 0.0]), t, 0.5)
    _, dr, _ = _errors(d)
    expected = b / (2.0 * OMEGA_S ** 2) * (np.cosh(np.sqrt(2.0) * OMEGA_S * t) - 1.0)
    assert dr[0] == pytest.approx(expected, rel=2e-3)
    assert dr[0] > 1.2 * 0.5 * b * t ** 2  # the gravity feedback, not just the double integral


def test_accelerometer_scale_factor_scales_the_sensed_velocity_change():
    s = 200e-6
    t = 20.0
    d = _hold(_params(accel_scale=[s, 0.0, 0.0]), t, 0.01)
    _, _, dv = _errors(d)
    # δv̇ = s f + (the vertical gravity gradient's share over 20 s: (ω_s t)²/3 ≈ 2e-4)
    assert dv[0] == pytest.approx(s * SPECIFIC_FORCE * t, rel=5e-4)


def test_gyro_triad_misalignment_seen_by_a_spinning_body_traces_a_circle():
    w = 0.3  # rad/s about body x (= ECI x at t = 0)
    eps_y = 1e-4  # rad: the gyro triad turned about body y
    t_end = 7.0

    def spin(t):
        return qt.from_rotation_vector(np.array([w * t, 0.0, 0.0]))

    d = _hold(_params(gyro_misalign=[0.0, eps_y, 0.0]), t_end, 0.005, spin)
    phi, _, _ = _errors(d)
    # δω = −ε × ω = ε_y ω e_z(body); e_z(body) in ECI = (0, −sin ωt, cos ωt)
    expected = eps_y * np.array([0.0, np.cos(w * t_end) - 1.0, np.sin(w * t_end)])
    np.testing.assert_allclose(phi, expected, atol=1e-5 * eps_y)


def test_alignment_tilt_turns_the_sensed_force_into_a_velocity_error():
    tilt = 50e-6  # rad about body z
    t = 10.0
    d = _hold(_params(alignment=[0.0, 0.0, tilt]), t, 0.01)
    phi, _, dv = _errors(d)
    np.testing.assert_allclose(phi, [0.0, 0.0, tilt], rtol=1e-12)
    f = np.array([SPECIFIC_FORCE, 0.0, 0.0])  # sensed, ECI
    np.testing.assert_allclose(dv, np.cross(phi, f) * t, rtol=1e-4, atol=1e-12)


def test_zero_errors_stay_exactly_zero():
    d = _hold(_params(), 50.0, 0.005, lambda t: qt.from_rotation_vector(np.array([0.1 * t, 0.02 * t, -0.03 * t])))
    for e in _errors(d):
        assert np.all(e == 0.0)


# ------------------------------------------------------------------ config


def test_config_refuses_values_outside_the_error_model(compose_cfg):
    validate(compose_cfg(["navigation=inertial", "navigation.gyro.bias_deg_per_h=[10,0,0]"]))
    for key, value, allowed in (("navigation.gyro.bias_deg_per_h", "[10.01,0,0]", "10 deg/h"),
                                ("navigation.accelerometer.bias_micro_g", "[0,0,nan]", "10000 µg"),
                                ("navigation.alignment_arcsec", "[0,3601,0]", "3600 arcsec")):
        with pytest.raises(ConfigError) as e:
            validate(compose_cfg(["navigation=inertial", f"{key}={value}"]))
        assert key in str(e.value) and allowed in str(e.value)
    with pytest.raises(ConfigError, match="must list 3 values"):
        validate(compose_cfg(["navigation=inertial", "navigation.gyro.scale_factor_ppm=[1,2]"]))


def test_perfect_navigation_has_no_error_keys():
    from savant_cli.hydra_compose import variant_key_hint

    hint = variant_key_hint(["navigation.gyro.bias_deg_per_h=[1,0,0]"], {"navigation": "perfect"})
    assert "not a key of navigation=perfect; it belongs to navigation=inertial" in hint


def test_dispersion_items_are_inactive_with_perfect_navigation():
    from savant_cli.montecarlo.spec import parse

    for navigation, kind in (("perfect", "inactive"), ("inertial", "config")):
        cfg = validate(compose_config([f"navigation={navigation}"]))
        dset = parse(cfg.dispersions, 1, cfg, prepare(cfg, hydra_search_dirs()).vehicle, hydra_search_dirs())
        kinds = {d.name: d.target.kind for d in dset.items if d.name.startswith("nav_")}
        assert len(kinds) == 21 and set(kinds.values()) == {kind}


# ------------------------------------------------------------------ flight

FLIGHT = ["sim.progress=false"]


def _fly(overrides):
    cfg = validate(compose_config([*FLIGHT, *overrides]))
    prep = prepare(cfg, hydra_search_dirs())
    res = simulate(prep.model, progress=False)
    sig = signals(res, prep.model)
    return res, sig, summarize(res, sig, target=insertion_target(cfg.guidance), p=prep.model.p)


@pytest.mark.slow
def test_zero_errors_fly_the_perfect_navigation_bit_for_bit():
    _, sig_p, sum_p = _fly(["navigation=perfect"])
    _, sig_i, sum_i = _fly(["navigation=inertial"])
    for name, s in sig_p.items():  # every history of the perfect run, identical
        assert np.array_equal(s.data, sig_i[name].data, equal_nan=True), name
    for name in ("navigation_position_error", "navigation_velocity_error", "navigation_attitude_error"):
        assert name not in sig_p and np.all(sig_i[name].data == 0.0)
    for k, v in sum_p.items():
        if "wall" not in k and k not in WALL_CLOCK_KEYS:
            assert sum_i[k] == v or (v != v and sum_i[k] != sum_i[k]), k


@pytest.mark.slow
def test_gyro_bias_in_flight_is_its_integral_through_the_flown_attitude():
    b_deg_h = np.array([0.0, 2.0, -1.0])  # deg/h: pitch and yaw gyro bias
    res, sig, summ = _fly(["navigation=inertial", f"navigation.gyro.bias_deg_per_h=[{','.join(map(str, b_deg_h))}]"])
    t = sig["time"].data
    q = sig["quaternion"].data
    b = np.radians(b_deg_h) / 3600.0
    integrand = np.einsum("nij,j->ni", qt.dcm_array(q), b)  # C_b2i b, ECI
    expected = np.concatenate([[np.zeros(3)], np.cumsum(0.5 * (integrand[1:] + integrand[:-1])
                                                        * np.diff(t)[:, None], axis=0)])
    phi = sig["navigation_attitude_error"].data
    # the logged φ is the kernel's at its latest IMU sample (≤ 5 ms before the log row)
    np.testing.assert_allclose(phi[-1], expected[-1], rtol=2e-3, atol=1e-3 * np.linalg.norm(b) * t[-1])
    assert summ["navigation_attitude_error_deg"] == pytest.approx(np.degrees(np.linalg.norm(expected[-1])), rel=2e-3)
    assert summ["status"] == "complete"  # 2 deg/h over 9 min: ≈ 0.3° of attitude, flown through


@pytest.mark.slow
def test_guidance_cuts_off_on_the_navigated_state():
    """A 2000 µg axial accelerometer bias (tactical grade): PEG flies the navigated state
    to its target, so the navigated orbit is on target and the true one is off by the
    navigation error."""
    _, _, nominal = _fly(["navigation=perfect"])
    res, sig, summ = _fly(["navigation=inertial", "navigation.accelerometer.bias_micro_g=[2000,0,0]"])
    assert summ["navigation_velocity_error_mps"] > 5.0
    # what the flight software believed is on the nominal's orbit to guidance accuracy ...
    for key in ("perigee_altitude_km", "apogee_altitude_km"):
        assert summ[f"navigated_{key}"] == pytest.approx(nominal[key], abs=1.0)
    # ... and the true orbit differs by the orbit of the navigation error
    r = sig["position_eci"].data[-1]
    v = sig["velocity_eci"].data[-1]
    true_orbit = orbit_elements(r, v)
    assert summ["perigee_altitude_km"] == pytest.approx(true_orbit["perigee_altitude_km"], abs=1e-9)
    assert abs(summ["apogee_altitude_km"] - nominal["apogee_altitude_km"]) > 5.0


# ------------------------------------------------------------------ Monte Carlo


def test_batch_statistics_add_the_navigation_errors_of_an_inertial_batch():
    from savant_cli.montecarlo.insertion import insertion_statistics

    keys = ["insertion_perigee_error_km", "navigation_position_error_m", "navigation_velocity_error_mps",
            "navigation_attitude_error_deg", "usable_propellant_remaining_kg"]
    rng = np.random.default_rng(3)
    summary = np.column_stack([rng.normal(size=50), np.abs(rng.normal(500.0, 100.0, 50)),
                               np.abs(rng.normal(2.0, 1.0, 50)), np.abs(rng.normal(0.02, 0.01, 50)),
                               rng.normal(7000.0, 300.0, 50)])
    messages = ["cutoff: PEG time to go elapsed"] * 50
    ins = insertion_statistics(np.arange(50), messages, keys, summary)
    assert ins["navigation"] == "inertial"
    rows = {r["variable"]: r for r in ins["navigation_errors"]}
    assert set(rows) == {"navigation_position_error_m", "navigation_velocity_error_mps", "navigation_attitude_error_deg"}
    assert rows["navigation_position_error_m"]["p50"] == pytest.approx(np.median(summary[:, 1]))
    perfect = insertion_statistics(np.arange(50), messages, keys[:1] + keys[4:], summary[:, [0, 4]])
    assert perfect["navigation"] == "perfect" and "navigation_errors" not in perfect


@pytest.mark.slow
def test_a_batch_with_and_without_navigation_errors(tmp_path):
    """One seed flown with both options: the other dispersions are the same draws, only the
    inertial batch has navigation errors, and its insertion spreads differ by them."""
    from savant_cli import api

    common = ["study=montecarlo", "study.n_runs=6", "study.workers=1", "output.plots=false", "sim.progress=false"]
    both = {mode: api.run([*common, f"navigation={mode}"], out_dir=tmp_path / mode) for mode in ("perfect", "inertial")}
    tables = {}
    for mode, res in both.items():
        doc = res.summary
        tables[mode] = doc["insertion"]
        assert doc["insertion"]["navigation"] == mode
    assert "navigation_errors" in tables["inertial"] and "navigation_errors" not in tables["perfect"]
    pos = {r["variable"]: r for r in tables["inertial"]["navigation_errors"]}["navigation_position_error_m"]
    assert pos["max_abs"] > 10.0  # metres: 0.005 deg/h, 30 µg and an 80-arcsec azimuth over 9 minutes
    perigee = {nav: {r["variable"]: r for r in t["accuracy"]}["insertion_perigee_error_km"] for nav, t in tables.items()}
    assert perigee["inertial"]["p0.135"] != perigee["perfect"]["p0.135"]
