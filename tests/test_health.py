"""Flight health (issue 12 item 8, issue 26 item 4): the limit-cycle detector against a
signal set whose oscillations are known by construction (``tests/health_signals.py``),
the slow-divergence and loss-of-control verdicts, and the per-stage limit times, peak
rates and run status of a flown run's history."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from conftest import compose_config
from health_signals import FS, oscillation, sweep_frequencies, trend
from savant_cli.config import shipped_option, validate
from savant_cli.errors import ConfigError
from savant_cli.io.record import FLOWN, STATUSES, Signal
from savant_cli.models import actuator
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim import engine
from savant_cli.sim.health import assess
from savant_cli.sim.oscillation import band_top_hz, find_limit_cycle, find_limit_cycles, find_slow_divergence
from savant_cli.sim.run import SimResult
from savant_cli.sim.setup import prepare

CFG = shipped_option("sim").health  # the shipped detector settings
TOP = band_top_hz(50.0, FS, CFG.min_periods)  # 22.73 Hz at the defaults
F_TOL = 0.02  # relative frequency tolerance of a detection
A_TOL = 0.10  # relative amplitude tolerance (issue 26)
AMPLITUDES = (0.11, 0.3, 1.0, 5.0)  # deg; 0.11: the 0.1 deg threshold plus the amplitude tolerance
SNR_DB = 20.0  # the noisy members: noise RMS 7.1 % of the amplitude
#: with white noise at SNR_DB a window of min_periods periods must hold this many samples
#: to be told from noise at the false-alarm probability (Fisher's test): f ≤ 12.5 Hz
NOISY_SAMPLES = 20
TRIANGLE_TOP = FS / 20.0  # Hz: a triangle's 3rd to 9th harmonics under the band's top


def _detect(t, y, **kw):
    c = dataclasses.replace(CFG, **kw)
    return find_limit_cycle(t, y, TOP, c.min_amplitude_deg, c.tonal_fraction, c.min_periods, c.max_damping_ratio)


def _signal_set(kind: str, snr_db: float | None):
    """One row per sweep frequency of the class (amplitudes and durations cycling:
    min_periods periods, 12 periods, 200 s), on one 240 s time base."""
    freqs = sweep_frequencies(TOP)
    if kind == "triangle":
        freqs = freqs[freqs <= TRIANGLE_TOP]
    if snr_db is not None:
        freqs = freqs[freqs <= CFG.min_periods * FS / NOISY_SAMPLES]
    n = int(round(240.0 * FS))
    rows, cases = [], []
    for i, f in enumerate(freqs):
        amp = AMPLITUDES[i % 4]
        duration = (CFG.min_periods / f, 12.0 / f, 200.0)[(i // 4 + i) % 3]
        duration = min(duration, 200.0)
        t, y = oscillation(f, amp, duration, kind, snr_db=snr_db, seed=i, phase=(7.31 * f) % (2 * np.pi))
        rows.append(np.r_[y, trend(np.arange(y.size, n) / FS, f)][:n])
        cases.append((f, amp, duration))
    return np.arange(n) / FS, np.array(rows), cases


@pytest.mark.parametrize("kind, snr_db", [("sine", None), ("sine", SNR_DB), ("triangle", None), ("triangle", SNR_DB)])
def test_every_member_of_the_signal_set_is_detected(kind, snr_db):
    """At least 200 frequencies log-spaced over 0.05 Hz .. the band's top plus the
    frequencies the former detector missed, amplitudes 0.11-5 deg, durations from
    min_periods periods to 200 s, on a guidance-like trend: every one found, at its
    frequency (2 %) and amplitude (10 %), over its span (to a period)."""
    t, rows, cases = _signal_set(kind, snr_db)
    if kind == "sine" and snr_db is None:
        assert len(cases) >= 212
    found = find_limit_cycles(t, rows, TOP, CFG.min_amplitude_deg, CFG.tonal_fraction, CFG.min_periods,
                              CFG.max_damping_ratio)
    bad = []
    for (f, amp, duration), osc in zip(cases, found):
        ok = (osc is not None and abs(osc.frequency_hz / f - 1.0) <= F_TOL and abs(osc.amplitude_deg / amp - 1.0) <= A_TOL
              and abs(osc.start_s - 20.0) <= 1.0 / f and abs(osc.end_s - 20.0 - duration) <= 1.0 / f)
        if not ok:
            bad.append((round(f, 4), amp, round(duration, 2), osc))
    assert not bad


@pytest.mark.parametrize("f_hz", [0.05, 0.175, 0.225, 1.0, 8.0])
def test_decaying_and_growing_oscillations_by_their_damping_ratio(f_hz):
    """The envelope of a mode of damping ratio ζ: sustained while |ζ| < max_damping_ratio
    (0.005, the structure's own damping: an oscillation the control system damps less than
    the bare structure is not being damped), a decaying transient (or a growth) beyond.
    The record starts in the oscillation, as a stage's stretch after an event's quiet
    time starts in that event's transient."""
    duration = min(20.0 / f_hz, 300.0)
    for zeta, sustained in ((0.004, True), (-0.004, True), (0.006, False), (-0.006, False), (0.02, False)):
        t, y = oscillation(f_hz, 1.0, duration, decay_zeta=zeta, margin_s=0.0)
        y = y[:-1]  # the record ends in it
        assert (_detect(t, y) is not None) is sustained, zeta


@pytest.mark.parametrize("f_hz, too_short", [(0.05, 4.5), (0.3, 4.5), (2.0, 4.5), (15.0, 4.0)])
def test_the_duration_and_amplitude_thresholds(f_hz, too_short):
    """Just inside and just outside: min_periods (5) periods found, fewer not (a window
    is 5 periods rounded down to whole log samples and must be filled: 4.5 periods are
    refused where a period holds 10 samples or more, 4.0 above, where a window's edge is
    a sample); 0.11 deg found and 0.09 not (the 0.1 deg threshold within the amplitude
    tolerance)."""
    assert _detect(*oscillation(f_hz, 1.0, 5.0 / f_hz)) is not None
    assert _detect(*oscillation(f_hz, 1.0, too_short / f_hz)) is None
    assert _detect(*oscillation(f_hz, 0.11, 12.0 / f_hz)) is not None
    assert _detect(*oscillation(f_hz, 0.09, 12.0 / f_hz)) is None
    assert _detect(*oscillation(f_hz, 0.09, 12.0 / f_hz), min_amplitude_deg=0.08) is not None


def test_the_tonality_threshold():
    """A second, unrelated tone (at 2.5 f) holding 44 % of the variance: the oscillation
    at f (56 %) is found; at 44 % (the other tone 56 %) it is not (tonal_fraction 0.5)."""
    f = 2.0
    for share, found in ((0.56, True), (0.44, False)):
        t, y = oscillation(f, 1.0, 20.0)
        on = (t >= 20.0) & (t < 40.0)
        y = y + np.where(on, np.sqrt((1.0 - share) / share) * np.sin(2 * np.pi * 2.5 * f * t + 1.1), 0.0)
        osc = _detect(t, y)
        at_f = osc is not None and abs(osc.frequency_hz / f - 1.0) <= F_TOL
        assert at_f is found
        if found:
            assert osc.amplitude_deg == pytest.approx(1.0, rel=A_TOL)


def test_noise_and_trends_are_not_limit_cycles():
    """White noise (0.5 deg RMS), a guidance-like trend alone, a ramp with a knee and a
    step: nothing found."""
    t = np.arange(0.0, 400.0, 1.0 / FS)
    rng = np.random.default_rng(7)
    assert _detect(t, 0.5 * rng.normal(size=t.size)) is None
    assert _detect(t, trend(t, 0.05)) is None
    assert _detect(t, np.where(t < 100.0, 0.0, 0.02 * (t - 100.0))) is None
    assert _detect(t, np.where(t < 150.0, 0.0, 1.0)) is None


def test_the_band_top():
    """Half the flight-control rate, and below the log's Nyquist frequency by what
    min_periods periods resolve: f_N · 2M/(2M + 1)."""
    assert band_top_hz(50.0, 50.0, 5.0) == pytest.approx(25.0 * 10.0 / 11.0)
    assert band_top_hz(50.0, 200.0, 5.0) == 25.0
    assert band_top_hz(100.0, 50.0, 10.0) == pytest.approx(25.0 * 20.0 / 21.0)


def test_slow_divergence_of_the_issue_and_bounded_trends():
    """The issue's case, an attitude error growing from 0.01 to 4 deg over the flight
    (exponentially), is a slow divergence; an error settling to a bound, a growth of 9
    (under the 10 of divergence_growth) and one ending under min_amplitude_deg are not."""
    t = np.arange(0.0, 430.0, 1.0 / FS)
    grow = 0.01 * np.exp(np.log(400.0) * t / t[-1])
    found = find_slow_divergence(t, grow, CFG.divergence_growth, CFG.divergence_min_amplitude_deg)
    assert found is not None and found.end_deg == pytest.approx(4.0, rel=1e-3)
    assert found.growth == pytest.approx(4.0 / grow[int(round(20.0 * FS)) - 1], rel=1e-3)
    assert find_slow_divergence(t, 1.0 - np.exp(-t / 50.0), 10.0, 0.1) is None  # bounded
    assert find_slow_divergence(t, 0.5 * (1.0 - np.exp(-t / 100.0)), 10.0, 0.1) is None  # bounded
    ramp = 0.02 + 0.01 * t  # a steady drift: unbounded, still growing at its end
    assert find_slow_divergence(t, ramp, 10.0, 0.1) is not None
    nine = 0.5 * np.exp(np.log(9.0) * (t - 20.0) / (t[-1] - 20.0))
    eleven = 0.5 * np.exp(np.log(11.0) * (t - 20.0) / (t[-1] - 20.0))
    assert find_slow_divergence(t, nine, 10.0, 0.1) is None
    assert find_slow_divergence(t, eleven, 10.0, 0.1).growth == pytest.approx(11.0, rel=1e-3)
    assert find_slow_divergence(t, grow * 0.02, 10.0, 0.1) is None  # ends at 0.08 deg
    # the shipped floor, a tenth of the 10 deg loss-of-control bound: just under and over
    assert CFG.divergence_min_amplitude_deg == 0.1 * CFG.max_attitude_error_deg
    assert find_slow_divergence(t, grow * 0.99 / 4.0, 10.0, CFG.divergence_min_amplitude_deg) is None
    assert find_slow_divergence(t, grow * 1.01 / 4.0, 10.0, CFG.divergence_min_amplitude_deg) is not None


@pytest.fixture(scope="module")
def model():
    return prepare(validate(compose_config([])), hydra_search_dirs()).model


def _history(n: int, t_sep: float) -> tuple[SimResult, dict[str, Signal]]:
    t = np.arange(n) / FS
    events = np.full(len(engine.EVENT_NAMES), np.nan)  # (sim/engine.py EVENT_NAMES)
    events[[engine.EV_SEPARATION, engine.EV_IGNITION, engine.EV_LES]] = t_sep, t_sep + 1.5, t_sep + 31.5
    result = SimResult.__new__(SimResult)
    result.status, result.message, result.events, result.t_final = "complete", "cutoff", events, float(t[-1])
    zeros2 = np.zeros((n, 2))
    sig = {"time": Signal(t, "s", ""), "gimbal_rate": Signal(zeros2.copy(), "rad/s", ""),
           "gimbal_angle": Signal(zeros2.copy(), "rad", ""), "attitude_error": Signal(np.zeros((n, 3)), "rad", ""),
           "body_rate": Signal(np.zeros((n, 3)), "rad/s", ""), "alpha": Signal(np.zeros(n), "rad", ""),
           "beta": Signal(np.zeros(n), "rad", ""), "dynamic_pressure": Signal(np.full(n, 2e4), "Pa", "")}
    return result, sig


def test_limit_times_peak_rates_and_the_saturated_verdict(model):
    """2 s on the first-stage rate limit (pitch) and 0.5 s on the upper-stage gimbal stop
    (yaw), a 20 deg/s body-rate peak: the times by the log spacing, the per-stage peaks,
    and the status "saturated" (2 s > max_saturation_s = 1 s)."""
    p = model.p
    rate_fs = p[actuator.P_FS_THIRD + actuator.T3_RATE_LIMIT]
    lim_us = p[actuator.P_US_GIMBAL + actuator.G_LIMIT]
    result, sig = _history(int(300 * FS), 130.0)
    t = sig["time"].data
    sig["gimbal_rate"].data[(t >= 50.0) & (t < 52.0), 0] = rate_fs
    sig["gimbal_rate"].data[t == 60.0, 1] = 0.5 * rate_fs
    sig["gimbal_angle"].data[(t >= 200.0) & (t < 200.5), 1] = -lim_us
    sig["body_rate"].data[t == 70.0] = np.radians([12.0, 16.0, 0.0])
    h = assess(result, sig, model, CFG)
    assert h["time_at_rate_limit_first_stage_s"] == pytest.approx(2.0, abs=1e-9)
    assert h["time_at_gimbal_stop_upper_stage_s"] == pytest.approx(0.5, abs=1e-9)
    assert h["time_at_rate_limit_upper_stage_s"] == 0.0 and h["time_at_gimbal_stop_first_stage_s"] == 0.0
    assert h["max_gimbal_rate_first_stage_deg_s"] == pytest.approx(np.degrees(rate_fs))
    assert h["max_gimbal_rate_upper_stage_deg_s"] == 0.0
    assert h["max_body_rate_deg_s"] == pytest.approx(20.0)
    assert not h["limit_cycle"] and h["health_flags"] == "saturated"
    assert result.status == "saturated" and "first stage rate limit" in result.message


def test_limit_cycle_verdict_and_precedence(model):
    result, sig = _history(int(300 * FS), 130.0)
    t = sig["time"].data
    on = (t > 160.0) & (t < 280.0)
    sig["attitude_error"].data[on, 2] = np.radians(0.25) * np.sin(2 * np.pi * 8.6 * t[on])
    h = assess(result, sig, model, CFG)
    assert h["limit_cycle"] and h["limit_cycle_signal"] == "attitude_error_yaw"
    assert h["limit_cycle_frequency_hz"] == pytest.approx(8.6, abs=0.05)
    assert h["limit_cycle_amplitude_deg"] == pytest.approx(0.25, rel=0.05)
    assert result.status == "limit_cycle" and "8.6 Hz" in result.message
    # a diverged run keeps its status: the health keys are still there
    result2, sig2 = _history(int(300 * FS), 130.0)
    sig2["attitude_error"].data[:] = sig["attitude_error"].data
    result2.status = "diverged"
    assert assess(result2, sig2, model, CFG)["limit_cycle"] and result2.status == "diverged"
    # a looser amplitude threshold than the oscillation: no verdict
    result3, sig3 = _history(int(300 * FS), 130.0)
    sig3["attitude_error"].data[:] = sig["attitude_error"].data
    loose = dataclasses.replace(CFG, min_amplitude_deg=0.5)
    assert not assess(result3, sig3, model, loose)["limit_cycle"] and result3.status == "complete"


def test_event_windows_are_left_out(model):
    """A ringing that starts at separation and lasts only the window after it is a
    transient, not a limit cycle."""
    result, sig = _history(int(300 * FS), 130.0)
    t = sig["time"].data
    ring = (t >= 130.0) & (t < 130.0 + CFG.event_quiet_s)
    sig["gimbal_angle"].data[ring, 0] = np.radians(0.5) * np.sin(2 * np.pi * 2.0 * t[ring])
    assert not assess(result, sig, model, CFG)["limit_cycle"] and result.status == "complete"


def test_loss_of_control_bounds_and_the_status_priority(model):
    """The attitude-error bound (pitch/yaw magnitude) just above and just below, the
    optional α bound (total angle of attack, from the dynamic-pressure floor on), and
    the order loss_of_control > limit_cycle > slow_divergence > saturated."""
    result, sig = _history(int(300 * FS), 130.0)
    t = sig["time"].data
    sig["attitude_error"].data[t >= 87.3, 1] = np.radians(8.0)
    sig["attitude_error"].data[t >= 87.3, 2] = np.radians(6.1)  # √(8² + 6.1²) = 10.06 deg
    h = assess(result, sig, model, CFG)
    assert h["loss_of_control"] and h["loss_of_control_time_s"] == pytest.approx(87.3)
    assert h["loss_of_control_reason"] == "attitude error 10.1 deg > 10 deg at 87.3 s"
    assert result.status == "loss_of_control" and result.message.startswith("loss of control: attitude error")
    result, sig = _history(int(300 * FS), 130.0)
    sig["attitude_error"].data[:, 1] = np.radians(9.95)
    h = assess(result, sig, model, CFG)
    assert not h["loss_of_control"] and h["loss_of_control_time_s"] is None and h["loss_of_control_reason"] == ""
    # α: off by default; 15 deg bound from 1 kPa on; 40 deg at liftoff's low q ignored
    result, sig = _history(int(300 * FS), 130.0)
    t = sig["time"].data
    sig["dynamic_pressure"].data[t < 5.0] = 500.0
    sig["alpha"].data[t < 5.0] = np.radians(40.0)
    sig["alpha"].data[t >= 60.0] = np.radians(12.0)
    sig["beta"].data[t >= 60.0] = np.radians(9.2)  # α_t = 15.1 deg
    assert not assess(result, sig, model, CFG)["loss_of_control"]
    result.status = "complete"
    h = assess(result, sig, model, dataclasses.replace(CFG, max_alpha_deg=15.0))
    assert h["loss_of_control"] and h["loss_of_control_time_s"] == pytest.approx(60.0)
    assert h["loss_of_control_reason"].startswith("total angle of attack 15.1 deg > 15 deg at 60.0 s")
    result.status = "complete"
    assert not assess(result, sig, model, dataclasses.replace(CFG, max_alpha_deg=15.5))["loss_of_control"]
    # every verdict at once: the flags in order, the status the first
    result, sig = _history(int(400 * FS), 130.0)
    t = sig["time"].data
    sig["gimbal_rate"].data[(t >= 50.0) & (t < 52.0), 0] = model.p[actuator.P_FS_THIRD + actuator.T3_RATE_LIMIT]
    on = (t > 160.0) & (t < 280.0)
    sig["gimbal_angle"].data[on, 0] = np.radians(0.25) * np.sin(2 * np.pi * 1.3 * t[on])
    up = t >= 151.5
    sig["attitude_error"].data[up, 1] = np.radians(0.01 * np.exp((t[up] - 151.5) / 40.0))  # to 0.44 deg
    sig["attitude_error"].data[(t >= 100.0) & (t < 100.5), 2] = np.radians(10.5)
    h = assess(result, sig, model, CFG)
    assert h["health_flags"] == "loss_of_control,limit_cycle,slow_divergence,saturated"
    assert h["slow_divergence_signal"] == "attitude_error_pitch" and h["slow_divergence_growth"] > 10.0
    assert result.status == "loss_of_control"
    for drop, status in (("loss_of_control", "limit_cycle"), ("limit_cycle", "slow_divergence"),
                         ("slow_divergence", "saturated")):
        if drop == "loss_of_control":
            sig["attitude_error"].data[:, 2] = 0.0
        elif drop == "limit_cycle":
            sig["gimbal_angle"].data[on, 0] = 0.0
        else:
            sig["attitude_error"].data[up, 1] = 0.0
        result.status, result.message = "complete", "cutoff"
        assess(result, sig, model, CFG)
        assert result.status == status
    assert result.message.startswith("saturated: ")
    assert set(FLOWN) == {"complete", "loss_of_control", "limit_cycle", "slow_divergence", "saturated"}
    assert set(FLOWN) <= set(STATUSES)


@pytest.mark.parametrize("key, value", [
    ("min_periods", 1.5), ("tonal_fraction", 0.0), ("tonal_fraction", 1.2), ("max_damping_ratio", 0.0),
    ("event_quiet_s", -1.0), ("divergence_growth", 1.0), ("max_attitude_error_deg", 0.0),
    ("max_attitude_error_deg", 180.0), ("max_alpha_deg", -5.0), ("alpha_min_dynamic_pressure_Pa", -1.0),
    ("min_amplitude_deg", 0.0), ("divergence_min_amplitude_deg", 0.0), ("divergence_min_amplitude_deg", 10.5)])
def test_bad_health_settings_are_refused_by_key(key, value):
    with pytest.raises(ConfigError) as err:
        validate(compose_config([f"sim.health.{key}={value}"]))
    assert err.value.key == f"sim.health.{key}"


@pytest.mark.slow
@pytest.mark.parametrize("overrides", [["vehicle=ares_i"], ["vehicle=small_launcher"],
                                       ["flex=on", "flex.n_modes=4", "slosh=on", "twd=on"]])
def test_the_shipped_nominal_flights_are_healthy(overrides):
    """Neither vehicle's nominal flight (rigid; ares_i also at full fidelity) is flagged."""
    from savant_cli.studies.flight import fly

    flight = fly(validate(compose_config(overrides + ["sim.progress=false"])), progress=False)
    s = flight.summary
    assert flight.result.status == "complete", flight.result.message
    assert s["health_flags"] == "" and not s["limit_cycle"] and not s["slow_divergence"] and not s["loss_of_control"]


@pytest.fixture(scope="module")
def cluster_model():
    """The page's two-engine cluster (docs/vehicles.md): four gimbal channels."""
    from savant_cli.io.guidance_file import read_guidance
    from savant_cli.paths import shipped_config_dir
    from savant_cli.sim.build import build_model
    from savant_cli.vehicle import load_vehicle
    from test_vehicle_examples import example_node
    cfg = validate(compose_config(["sim.progress=false"]))
    vehicle = load_vehicle(example_node("a-two-engine-cluster"), shipped_config_dir() / "vehicle" / "ares_i")
    return build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file))


@pytest.mark.parametrize("scale, found", [(1.1, True), (0.9, False)])
def test_a_limit_cycle_on_the_second_engine_s_channel_alone_is_found(cluster_model, scale, found):
    """A roll limit cycle by differential gimbal moves the two engines' nozzles against
    each other, here only the second's: the first engine's channels and the attitude
    errors stay quiet, and the second engine's pitch channel (``pitch2``) carries a 1.3 Hz
    oscillation just above (found) or just below (not) the amplitude floor."""
    assert len(cluster_model.layout.channels) == 4
    result, sig = _history(int(300 * FS), 130.0)
    n = sig["time"].data.size
    sig["gimbal_angle"] = Signal(np.zeros((n, 4)), "rad", "")
    sig["gimbal_rate"] = Signal(np.zeros((n, 4)), "rad/s", "")
    t = sig["time"].data
    on = (t > 20.0) & (t < 120.0)
    sig["gimbal_angle"].data[on, 2] = np.radians(scale * CFG.min_amplitude_deg) * np.sin(2 * np.pi * 1.3 * t[on])
    h = assess(result, sig, cluster_model, CFG)
    assert h["limit_cycle"] is found
    if found:
        assert h["limit_cycle_signal"] == "gimbal_angle_pitch2"
        assert h["limit_cycle_frequency_hz"] == pytest.approx(1.3, abs=0.02)
        assert result.status == "limit_cycle"
