"""Discrete gust and wind shear (models/winds.py): the compiled kernels against their
closed forms (1 − cos shape, peak, length, impulse; the shear's Δv over its band; the
flight-path frame built by hand), the off switch adding nothing, and the config checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import synthetic
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.models import earth, winds
from savant_cli.sim.plant import pack_tables

W = constants.OMEGA_EARTH


def _p(**kw) -> np.ndarray:
    p = synthetic.parameters()
    p[winds.P_SCALE] = 1.0
    for name, value in kw.items():
        p[getattr(winds, name)] = value
    return p


def _gust_p(amp=9.0, by_time=0.0, start=12000.0, length=240.0, frame=0.0, direction_deg=0.0):
    return _p(P_DISCRETE=1.0, P_GUST_AMP=amp, P_GUST_BY_TIME=by_time, P_GUST_START=start, P_GUST_LENGTH=length,
              P_GUST_FRAME=frame, P_GUST_COS=math.cos(math.radians(direction_deg)),
              P_GUST_SIN=math.sin(math.radians(direction_deg)))


@pytest.mark.parametrize("d", [1.0, 240.0, 3000.0])
def test_one_minus_cosine_has_its_peak_length_and_impulse(d):
    f = winds.one_minus_cosine
    assert f(0.5 * d, d) == pytest.approx(1.0, abs=1e-15)  # peak 1 at mid-length
    assert f(0.0, d) == 0.0 and f(d, d) == 0.0 and f(-0.1 * d, d) == 0.0 and f(1.1 * d, d) == 0.0
    assert f(0.25 * d, d) == pytest.approx(0.5, rel=1e-14)  # half the peak at a quarter length
    area, _ = quad(lambda s: f(s, d), -0.5 * d, 1.5 * d, points=[0.0, d], epsabs=1e-12 * d)
    assert area == pytest.approx(0.5 * d, rel=1e-10)  # ∫ g ds = d/2
    s = np.linspace(0.0, d, 2001)
    g = np.array([f(x, d) for x in s])
    assert np.argmax(g) == 1000 and np.all(g >= 0.0) and np.all(g <= 1.0)


@pytest.mark.parametrize("by_time, start, length", [(0.0, 11880.0, 240.0), (1.0, 55.0, 0.8)])
def test_gust_speed_peaks_at_mid_length_and_integrates_to_a_d_over_2(by_time, start, length):
    p = _gust_p(amp=9.0, by_time=by_time, start=start, length=length)

    def v(s):  # the gust coordinate runs in altitude (m) or time (s); the other is held
        return winds.gust_speed(s, 3000.0, p) if by_time else winds.gust_speed(10.0, s, p)

    assert v(start + 0.5 * length) == pytest.approx(9.0, rel=1e-14)
    assert v(start) == 0.0 and v(start + length) == 0.0 and v(start - 1.0) == 0.0
    impulse, _ = quad(v, start - length, start + 2.0 * length, points=[start, start + length], epsabs=1e-9)
    assert impulse == pytest.approx(9.0 * length / 2.0, rel=1e-10)


@pytest.mark.parametrize("cosine", [0.0, 1.0])
@pytest.mark.parametrize("ret", [0.0, 800.0])
def test_shear_realises_its_delta_v_over_the_band(cosine, ret):
    base, thick, dv, az = 10000.0, 1000.0, 15.0, 75.0
    p = _p(P_DISCRETE=1.0, P_SHEAR_DV=dv, P_SHEAR_BASE=base, P_SHEAR_THICK=thick, P_SHEAR_RETURN=ret,
           P_SHEAR_COSINE=cosine, P_SHEAR_NORTH=math.cos(math.radians(az)), P_SHEAR_EAST=math.sin(math.radians(az)))
    sh = winds.shear_speed
    assert sh(base - 1.0, p) == 0.0 and sh(base, p) == 0.0
    assert sh(base + thick, p) == pytest.approx(dv, rel=1e-15)  # Δv across the band
    assert sh(base + 0.5 * thick, p) == pytest.approx(0.5 * dv, rel=1e-14)
    q = sh(base + 0.25 * thick, p)
    assert q == pytest.approx(dv * (0.25 if cosine == 0.0 else 0.5 * (1 - math.cos(math.pi / 4))), rel=1e-14)
    above = sh(base + thick + ret + 500.0, p)
    assert above == (0.0 if ret > 0.0 else pytest.approx(dv))  # removed again, or held
    if ret > 0.0:
        assert sh(base + thick + 0.5 * ret, p) == pytest.approx(0.5 * dv, rel=1e-14)
    # as the plant sees it: the NED wind changes by Δv along the azimuth across the band
    n0, e0, d0 = winds.discrete_ned(0.0, base, 100.0, 200.0, -300.0, p)
    n1, e1, d1 = winds.discrete_ned(0.0, base + thick, 100.0, 200.0, -300.0, p)
    np.testing.assert_allclose([n1 - n0, e1 - e0, d1 - d0],
                               [dv * math.cos(math.radians(az)), dv * math.sin(math.radians(az)), 0.0], atol=1e-13)


def test_ned_gust_blows_toward_its_azimuth():
    p = _gust_p(amp=9.0, start=11880.0, length=240.0, frame=0.0, direction_deg=30.0)
    np.testing.assert_allclose(winds.discrete_ned(0.0, 12000.0, 300.0, 200.0, -250.0, p),
                               [9.0 * math.cos(math.radians(30.0)), 9.0 * math.sin(math.radians(30.0)), 0.0],
                               rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("phi, expect", [(0.0, "up"), (90.0, "left"), (180.0, "down"), (270.0, "right")])
def test_flight_path_gust_is_across_the_path(phi, expect):
    gamma, psi = math.radians(50.0), math.radians(60.0)  # climbing at 50 deg toward azimuth 60 deg
    v = 450.0 * np.array([math.cos(gamma) * math.cos(psi), math.cos(gamma) * math.sin(psi), -math.sin(gamma)])
    p = _gust_p(amp=9.0, start=11880.0, length=240.0, frame=1.0, direction_deg=phi)
    w = np.array(winds.discrete_ned(0.0, 12000.0, *v, p))
    assert np.linalg.norm(w) == pytest.approx(9.0, rel=1e-12) and abs(w @ v) < 1e-9  # A, across the path
    # the frame by hand: up across the path in the vertical plane; left is horizontal
    up = np.array([-math.sin(gamma) * math.cos(psi), -math.sin(gamma) * math.sin(psi), -math.cos(gamma)])
    left = np.array([math.sin(psi), -math.cos(psi), 0.0])
    want = {"up": up, "left": left, "down": -up, "right": -left}[expect]
    np.testing.assert_allclose(w, 9.0 * want, atol=1e-12)


def test_flight_path_gust_raises_alpha_or_beta_in_body_axes():
    """The air moving up across the path gives a body w > 0 (α up) for a wings-level body
    (x along the path, z toward the local down); moving left, a body v > 0 (β up)."""
    gamma = math.radians(40.0)
    v = 400.0 * np.array([math.cos(gamma), 0.0, -math.sin(gamma)])  # NED, toward north
    x_b = v / np.linalg.norm(v)
    z_b = np.array([math.sin(gamma), 0.0, math.cos(gamma)])  # down, perpendicular to x_b
    y_b = np.cross(z_b, x_b)
    for phi, axis in ((0.0, z_b), (90.0, y_b)):
        p = _gust_p(amp=9.0, start=11880.0, length=240.0, frame=1.0, direction_deg=phi)
        v_air = v - np.array(winds.discrete_ned(0.0, 12000.0, *v, p))
        assert v_air @ axis == pytest.approx(9.0, rel=1e-12)


def test_a_vertical_path_has_no_flight_path_gust():
    p = _gust_p(amp=9.0, start=11880.0, length=240.0, frame=1.0)
    assert winds.discrete_ned(0.0, 12000.0, 0.0, 0.0, -300.0, p) == (0.0, 0.0, 0.0)
    assert winds.discrete_ned(0.0, 12000.0, 0.1, 0.0, 0.0, p) == (0.0, 0.0, 0.0)  # below 1 m/s


def _packed():
    tb = synthetic.tables()._replace(wind_alt=np.array([0.0, 1000.0, 20000.0]),
                                     wind_north=np.array([0.0, 10.0, 30.0]), wind_east=np.array([5.0, -5.0, 15.0]))
    return pack_tables(tb)


def test_off_switch_leaves_the_profile_alone_bit_for_bit():
    tb = _packed()
    lat, lon = math.radians(28.6), math.radians(-80.6)
    args = (math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon), math.cos(0.1), math.sin(0.1), 100.0, -50.0, 20.0)
    p_off = _p()
    p_off_armed = _gust_p(frame=1.0, direction_deg=45.0)  # gust parameters set, the switch off
    p_off_armed[winds.P_DISCRETE] = 0.0
    base = winds.air_relative_velocity(57.0, 12000.0, *args, tb, p_off)
    assert winds.air_relative_velocity(57.0, 12000.0, *args, tb, p_off_armed) == base
    # and that is the profile rotated into ECI (explicit matrices), the down component 0
    wind = np.array([*winds.wind_ned(12000.0, tb, p_off), 0.0])
    expect = earth.dcm_eci_to_ecef(0.1 / W, W).T @ (earth.dcm_ecef_to_ned(lat, lon).T @ wind)
    np.testing.assert_allclose(base[:3], np.array(args[6:]) - expect, atol=1e-12)
    assert base[5] == 0.0


@pytest.mark.parametrize("lat_deg, lon_deg, t", [(28.6, -80.6, 57.0), (-10.0, 30.0, 400.0)])
def test_gust_reaches_the_air_velocity_rotated_into_eci(lat_deg, lon_deg, t):
    tb = _packed()
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    p = _gust_p(amp=9.0, by_time=1.0, start=t - 0.5, length=1.0, frame=1.0, direction_deg=30.0)
    c_ecef_ned = earth.dcm_ecef_to_ned(lat, lon)
    c_eci_ecef = earth.dcm_eci_to_ecef(t, W)
    v_earth = np.array([300.0, -120.0, 350.0])
    v_ned = c_ecef_ned @ (c_eci_ecef @ v_earth)
    gust = np.array(winds.discrete_ned(t, 12000.0, *v_ned, p))
    assert np.linalg.norm(gust) == pytest.approx(9.0, rel=1e-12)  # t at mid-duration
    wind = np.array([*winds.wind_ned(12000.0, tb, p), 0.0]) + gust
    got = winds.air_relative_velocity(t, 12000.0, math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon),
                                      math.cos(W * t), math.sin(W * t), *v_earth, tb, p)
    np.testing.assert_allclose(got[:3], v_earth - c_eci_ecef.T @ (c_ecef_ned.T @ wind), atol=1e-10)
    np.testing.assert_allclose(got[3:], wind, atol=1e-12)


# ------------------------------------------------------------------------- config


def test_design_gust_config_builds_its_parameters(compose_cfg):
    from savant_cli.sim.setup import prepare

    cfg = validate(compose_cfg(["winds=design_gust"]))
    assert cfg.winds.gust.enabled and cfg.winds.shear.enabled
    p = prepare(cfg).model.p
    assert p[winds.P_DISCRETE] == 1.0 and p[winds.P_GUST_AMP] == 9.0 and p[winds.P_GUST_FRAME] == 1.0
    assert p[winds.P_GUST_START] == cfg.winds.gust.onset_altitude_m
    assert p[winds.P_GUST_LENGTH] == cfg.winds.gust.length_m
    assert p[winds.P_SHEAR_DV] == cfg.winds.shear.delta_mps and p[winds.P_SHEAR_COSINE] == 1.0
    for name in ("ksc_mean_annual", "ksc_strong_jet", "none"):  # the other profiles: switched off
        assert prepare(validate(compose_cfg([f"winds={name}"]))).model.p[winds.P_DISCRETE] == 0.0


def test_design_wind_puts_the_95th_percentile_speed_at_the_reference_altitude(compose_cfg):
    """The design wind's construction (docs/models.md, *Design wind*): the steady profile
    plus the shear build-up below the 11 km reference altitude reach there the
    95th-percentile scalar speed of the data sheet, 75 m/s (shared/data/
    ares_i_public_data.md); the build-up starts at the profile 1 km below and the wind is
    back on the profile 1 km above; the gust (9 m/s) peaks at the reference altitude."""
    from savant_cli.sim.setup import prepare

    cfg = validate(compose_cfg(["winds=design_gust"]))
    model = prepare(cfg).model
    p, tb = model.p, model.packed_tables

    def speed(h: float, shear: bool = True) -> float:
        n, e = winds.wind_ned(h, tb, p)
        sv = winds.shear_speed(h, p) if shear else 0.0
        return math.hypot(n + sv * p[winds.P_SHEAR_NORTH], e + sv * p[winds.P_SHEAR_EAST])

    assert speed(11000.0) == pytest.approx(75.0, abs=0.05)
    assert speed(10000.0) == speed(10000.0, shear=False) and speed(12000.0) == speed(12000.0, shear=False)
    h = np.linspace(8000.0, 14000.0, 6001)
    v = np.array([speed(x) for x in h])
    # the envelope's peak at the reference altitude (the steady jet still rising above it moves it 20 m up)
    assert abs(h[np.argmax(v)] - 11000.0) <= 50.0 and v.max() < 75.1
    g = cfg.winds.gust
    assert g.onset_altitude_m + g.length_m / 2 == 11000.0
    assert winds.gust_speed(0.0, 11000.0, p) == pytest.approx(9.0, abs=1e-12)


@pytest.mark.parametrize("override, key, words", [
    ("winds.gust.onset=height", "winds.gust.onset", "altitude, time"),
    ("winds.gust.frame=body", "winds.gust.frame", "ned, flight_path"),
    ("winds.gust.amplitude_mps=80", "winds.gust.amplitude_mps", "±50 m/s"),
    ("winds.gust.length_m=0", "winds.gust.length_m", "positive"),
    ("winds.gust.onset_altitude_m=-5", "winds.gust.onset_altitude_m", "zero or positive"),
    ("winds.shear.thickness_m=-100", "winds.shear.thickness_m", "positive"),
    ("winds.shear.shape=step", "winds.shear.shape", "linear, cosine"),
    ("winds.shear.delta_mps=150", "winds.shear.delta_mps", "±100 m/s"),
    ("winds.shear.return_thickness_m=-1", "winds.shear.return_thickness_m", "zero or positive"),
])
def test_bad_gust_and_shear_values_are_refused(compose_cfg, override, key, words):
    with pytest.raises(ConfigError) as exc:
        validate(compose_cfg(["winds=design_gust", override]))
    assert exc.value.key == key and words in exc.value.allowed
    assert str(override.split("=")[1]) in str(exc.value)


def test_time_onset_needs_a_positive_duration(compose_cfg):
    with pytest.raises(ConfigError) as exc:
        validate(compose_cfg(["winds=design_gust", "winds.gust.onset=time", "winds.gust.duration_s=0"]))
    assert exc.value.key == "winds.gust.duration_s"
    validate(compose_cfg(["winds=design_gust", "winds.gust.onset=time", "winds.gust.length_m=0"]))  # not read


def test_a_switched_off_gust_is_checked_too(compose_cfg):
    with pytest.raises(ConfigError) as exc:
        validate(compose_cfg(["winds=ksc_mean_annual", "winds.gust.frame=nonsense"]))
    assert exc.value.key == "winds.gust.frame"
