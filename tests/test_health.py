"""Flight health (issue 12 item 8): the limit-cycle detector against signals whose
oscillation is known by construction, and the per-stage limit times, peak rates and the
run status of a flown run's history."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from savant_cli.config import HealthConfig, validate
from savant_cli.io.record import Signal
from savant_cli.models import actuator
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim.health import assess, detect_limit_cycle
from savant_cli.sim.run import SimResult
from savant_cli.sim.setup import prepare
from conftest import compose_config

FS = 50.0  # the default log rate, Hz
CFG = HealthConfig()


def _t(duration: float = 120.0) -> np.ndarray:
    return np.arange(0.0, duration, 1.0 / FS)


def _detect(t, y):
    return detect_limit_cycle(t, y, CFG.window_s, CFG.min_amplitude_deg, CFG.tonal_fraction, CFG.min_periods)


@pytest.mark.parametrize("f_hz, amp", [(0.4, 0.15), (2.4, 0.8), (8.6, 0.3)])
def test_sustained_oscillation_is_found_with_its_frequency_and_amplitude(f_hz, amp):
    """A sine on a slow guidance-like trend, with sensor-like noise: found, at its
    frequency (to the periodogram's bin, 1/20 Hz) and amplitude (5 %)."""
    rng = np.random.default_rng(1)
    t = _t()
    y = 2.0 - 0.01 * t + 1e-4 * t**2 + amp * np.sin(2 * np.pi * f_hz * t + 0.3) + 0.01 * rng.normal(size=t.size)
    found = _detect(t, y)
    assert found is not None
    f, a, start, end = found
    assert f == pytest.approx(f_hz, abs=1.0 / CFG.window_s)
    assert a == pytest.approx(amp, rel=0.05)
    assert start == 0.0 and end == pytest.approx(t[-1], abs=CFG.window_s)


def test_decaying_transient_noise_small_and_short_oscillations_are_not_limit_cycles():
    t = _t()
    rng = np.random.default_rng(2)
    decaying = 1.0 * np.exp(-t / 8.0) * np.sin(2 * np.pi * 1.0 * t)  # a damped mode after an event
    assert _detect(t, decaying) is None
    assert _detect(t, 0.5 * rng.normal(size=t.size)) is None  # broadband: not tonal
    assert _detect(t, 0.05 * np.sin(2 * np.pi * 1.0 * t)) is None  # below min_amplitude_deg
    short = _t(25.0)  # 25 s at 0.15 Hz: under 5 periods in a run of windows
    assert _detect(short, 0.5 * np.sin(2 * np.pi * 0.15 * short)) is None


@pytest.fixture(scope="module")
def model():
    return prepare(validate(compose_config([])), hydra_search_dirs()).model


def _history(n: int, t_sep: float) -> tuple[SimResult, dict[str, Signal]]:
    t = np.arange(n) / FS
    events = np.array([t_sep, t_sep + 1.5, t_sep + 31.5, np.nan])
    result = SimResult.__new__(SimResult)
    result.status, result.message, result.events, result.t_final = "complete", "cutoff", events, float(t[-1])
    zeros2 = np.zeros((n, 2))
    sig = {"time": Signal(t, "s", ""), "gimbal_rate": Signal(zeros2.copy(), "rad/s", ""),
           "gimbal_angle": Signal(zeros2.copy(), "rad", ""), "attitude_error": Signal(np.zeros((n, 3)), "rad", ""),
           "body_rate": Signal(np.zeros((n, 3)), "rad/s", "")}
    return result, sig


def test_limit_times_peak_rates_and_the_saturated_verdict(model):
    """2 s on the first-stage rate limit (pitch) and 0.5 s on the upper-stage gimbal stop
    (yaw), a 20 deg/s body-rate peak: the times by the log spacing, the per-stage peaks,
    and the status "saturated" (2 s > max_saturation_s = 1 s)."""
    p = model.p
    rate_fs = p[actuator.P_FS_THIRD + actuator.T3_RATE]
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
    ring = (t >= 130.0) & (t < 130.0 + CFG.window_s)
    sig["gimbal_angle"].data[ring, 0] = np.radians(0.5) * np.sin(2 * np.pi * 2.0 * t[ring])
    assert not assess(result, sig, model, CFG)["limit_cycle"] and result.status == "complete"
