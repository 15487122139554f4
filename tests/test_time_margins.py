"""Time-domain stability margins (``study=time_margins``): the stability verdict (a stated
decay per period) against neutral sines, triangles and clipped sines at any frequency,
against modes damped just above and below the threshold, and against a delay loop whose
margin at the threshold damping is known in closed form; the inserted perturbation
against its definition, the window rules, and the nonlinear margins of the rigid vehicle
at 55, 180 and 230 s against python-control-based frequency-domain margins of the same
points."""

from __future__ import annotations

import csv
import json
import warnings

import numpy as np
import pytest
from scipy import optimize, signal

from conftest import assert_report_redraws, compose_config
from savant_cli.config import shipped_option, validate
from savant_cli.errors import ConfigError
from savant_cli.linear.margins import MarginRow
from savant_cli.linear.point_analysis import analyse
from savant_cli.models import layout
from savant_cli.sim import loop_perturbation
from savant_cli.studies import flight as flight_mod
from savant_cli.studies.time_margins import COLUMNS, frequency_margin, read_group, window
from savant_cli.timedomain.growth import assess, decay_threshold
from savant_cli.timedomain.search import Search, find_margin


def delay_loop(k: float, tau: float, t_end: float = 60.0, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """y' = −k y(t − τ) after a unit pulse of y' over the first 0.1 s (forward Euler on a
    delay line): characteristic equation s + k e^{−sτ} = 0, stable exactly while
    k τ < π/2, oscillating at ω = k at the boundary (a lightly damped loop near it)."""
    n = int(t_end / dt)
    lag = int(round(tau / dt))
    y = np.zeros(n)
    for i in range(1, n):
        past = y[i - 1 - lag] if i - 1 - lag >= 0 else 0.0
        y[i] = y[i - 1] + dt * (-k * past + (1.0 if i * dt < 0.1 else 0.0))
    return np.arange(n) * dt, y


ZETA = shipped_option("study", "time_margins").min_damping_ratio  # the shipped threshold, 0.01


def delay_margin_at_damping(k: float, zeta: float) -> tuple[float, float]:
    """The delay τ at which the dominant root of s + k e^{−sτ} = 0 has damping ratio ζ,
    and the root's damped frequency ω (rad/s), in closed form: with s = ω(−c + i),
    c = ζ/√(1 − ζ²), the phase condition gives ωτ = π/2 − atan c and the modulus
    condition e^{cωτ} = ω√(1 + c²)/k. ζ = 0: τ = π/(2k), ω = k."""
    c = zeta / np.sqrt(1.0 - zeta * zeta)
    theta = np.pi / 2 - np.arctan(c)
    w = k * np.exp(c * theta) / np.sqrt(1.0 + c * c)
    return theta / w, w


def dominant_root(k: float, tau: float, guess: complex) -> complex:
    """The root of s + k e^{−sτ} = 0 near ``guess`` (scipy's fsolve on its real and
    imaginary parts)."""
    def f(v):
        r = complex(*v) + k * np.exp(-complex(*v) * tau)
        return [r.real, r.imag]
    return complex(*optimize.fsolve(f, [guess.real, guess.imag], xtol=1e-13))


def test_closed_form_delay_margin_solves_the_characteristic_equation():
    tau, w = delay_margin_at_damping(1.0, ZETA)
    c = ZETA / np.sqrt(1 - ZETA**2)
    s = w * complex(-c, 1.0)
    assert abs(s + 1.0 * np.exp(-s * tau)) < 1e-12
    assert dominant_root(1.0, tau, complex(0.0, 1.0)) == pytest.approx(s, abs=1e-9)
    # the threshold's bias: the measured delay margin sits 2.2 % short of neutral stability
    assert tau / (np.pi / 2) == pytest.approx(0.9783, abs=1e-4)
    assert delay_margin_at_damping(1.0, 0.0) == pytest.approx((np.pi / 2, 1.0))


@pytest.mark.parametrize("factor,unstable", [(0.98, False), (1.02, True)])
def test_detector_on_a_loop_of_known_delay_margin(factor, unstable):
    """Just inside and just outside the delay at which the delay loop's dominant root
    has the threshold damping: stable, then not; the envelope rate and frequency are
    the dominant root's."""
    k = 1.0  # rad/s
    tau_z, w = delay_margin_at_damping(k, ZETA)
    t, y = delay_loop(k, factor * tau_z)
    g = assess(t, y, 5.0, ZETA)
    assert g.unstable is unstable
    root = dominant_root(k, factor * tau_z, complex(-ZETA * w, w))
    assert g.frequency_hz == pytest.approx(root.imag / (2 * np.pi), rel=0.02)
    assert g.rate_per_s == pytest.approx(root.real, abs=0.002)


def test_delay_loop_margin_by_bisection_shows_the_thresholds_bias():
    """Bisect the delay loop's margin with the detector: it lands on the closed-form
    τ at the threshold damping (1 %), not on the neutral π/(2k); a delay between the two,
    stable in theory but decaying less than the threshold, is judged not stable."""
    k = 1.0
    tau_z, _ = delay_margin_at_damping(k, ZETA)
    lo, hi = 0.5 * tau_z, np.pi / (2 * k) * 1.1
    while hi - lo > 0.002:
        mid = 0.5 * (lo + hi)
        t, y = delay_loop(k, mid)
        if assess(t, y, 5.0, ZETA).unstable:
            hi = mid
        else:
            lo = mid
    assert 0.5 * (lo + hi) == pytest.approx(tau_z, rel=0.01)
    t, y = delay_loop(k, 0.5 * (tau_z + np.pi / (2 * k)))
    assert assess(t, y, 5.0, ZETA).unstable


@pytest.mark.parametrize("wave", ["sine", "triangle", "clipped"])
def test_neutral_oscillations_are_not_stable_at_any_frequency(wave):
    """Constant-amplitude oscillations (a sine, a rate-limited triangle, a sine clipped
    at a gimbal stop) read "not stable" at 300 frequencies from 0.05 to 2.5 Hz, among
    them the 0.20 and 0.25 Hz that a bare growth-rate sign split; at two sample rates."""
    freqs = np.concatenate([np.linspace(0.05, 2.5, 298), [0.20, 0.25]])
    for dt in (0.02, 0.005):
        t = np.arange(0.0, 40.0, dt)
        for f in freqs:
            phase = 2 * np.pi * f * t + 0.3
            y = {"sine": np.sin(phase), "triangle": signal.sawtooth(phase, 0.5),
                 "clipped": np.clip(1.6 * np.sin(phase), -1.0, 1.0)}[wave]
            g = assess(t, np.radians(1.0) * y, 2.0, ZETA)
            assert g.unstable, (wave, f, dt, g.reason)
            assert abs(g.decay_per_period - 1.0) < 0.02, (wave, f, dt)


@pytest.mark.parametrize("zeta,stable", [(0.9 * ZETA, False), (1.1 * ZETA, True)])
def test_decay_just_slower_or_faster_than_the_threshold(zeta, stable):
    """A mode decaying per period like damping 0.9 ζ_min is not stable; like 1.1 ζ_min it
    is (the ratios 0.945 and 0.933 about the threshold 0.939), at any frequency."""
    assert decay_threshold(ZETA) == pytest.approx(np.exp(-2 * np.pi * 0.01 / np.sqrt(1 - 1e-4)))
    t = np.arange(0.0, 60.0, 0.01)
    for f in (0.05, 0.2, 0.25, 0.8, 1.3):
        wn = 2 * np.pi * f / np.sqrt(1 - zeta**2)
        g = assess(t, np.exp(-zeta * wn * t) * np.sin(2 * np.pi * f * t), 2.0, ZETA)
        assert g.unstable is not stable, (f, g.reason)
        assert g.decay_per_period == pytest.approx(np.exp(-2 * np.pi * zeta / np.sqrt(1 - zeta**2)), abs=0.002)


@pytest.mark.parametrize("share,stable", [(1e-2, False), (1e-4, True)])
def test_a_small_neutral_mode_under_a_fast_decay(share, stable):
    """A well-damped mode (ζ = 0.3 at 1 Hz) plus a neutral 0.2 Hz sine: seen, and not
    stable, at 1e-2 of the response's peak; below the documented −60 dB floor (1e-4 of
    it) the response counts as died out (growth.DEAD_FLOOR, the detection limit)."""
    t = np.arange(0.0, 40.0, 0.01)
    wn, z = 2 * np.pi * 1.0, 0.3
    y = np.exp(-z * wn * t) * np.sin(wn * np.sqrt(1 - z * z) * t)
    y += share * np.max(np.abs(y)) * np.sin(2 * np.pi * 0.2 * t)
    g = assess(t, y, 0.0, ZETA)
    assert g.unstable is not stable, g.reason
    assert ("died out" in g.reason) is stable


def test_detector_on_a_divergence_and_on_noise_free_decay():
    t = np.linspace(0.0, 20.0, 2001)
    assert assess(t, 1e-3 * np.exp(0.2 * t), 1.0, ZETA).unstable  # no oscillation: a divergence
    assert assess(t, np.ones_like(t), 1.0, ZETA).unstable  # a held offset does not decay
    assert not assess(t, np.exp(-0.5 * t), 1.0, ZETA).unstable  # an aperiodic decay
    g = assess(t, np.exp(-0.2 * t) * np.sin(2 * np.pi * 0.5 * t), 1.0, ZETA)
    assert not g.unstable and g.rate_per_s == pytest.approx(-0.2, abs=0.03)
    assert g.frequency_hz == pytest.approx(0.5, rel=0.02)
    assert g.decay_per_period == pytest.approx(np.exp(-0.2 / 0.5), abs=0.03)
    assert assess(t, np.sin(t), 1.0, ZETA, diverged=True).unstable


@pytest.mark.parametrize("which", ["excited", "unexcited"])
def test_a_saturated_oscillation_is_beyond_the_margin(monkeypatch, which):
    """A trial whose response decays well (ζ = 0.02) but whose excited (or unexcited) run
    rides the actuator limits longer than max_saturation_s after the settling time is
    not stable: the search's margin lands where the saturation starts (7 dB here, the
    trial responses built by hand in place of the flights)."""
    from savant_cli.timedomain import search

    t = np.arange(0.0, 20.0, 0.02)
    decaying = np.exp(-0.02 * 2 * np.pi * t) * np.sin(2 * np.pi * t)  # x0.88 per period

    def fake_response(model, snap, s, value):
        sat = 2.0 if value >= 7.0 else 0.0
        return t, decaying, False, (sat if which == "excited" else 0.0), (sat if which == "unexcited" else 0.0)

    monkeypatch.setattr(search, "response", fake_response)
    res = find_margin(None, None, Search(55.0, "pitch", "gain_high", 0, 0.0, 20.0, 20.0, 0.1, 8,
                                         np.radians(0.5), 0.4, 2.0, ZETA, max_saturation_s=1.0))
    assert res.margin == pytest.approx(7.0, abs=0.1)
    bad = [tr for tr in res.trials if tr.growth.unstable]
    assert bad and all(f"the {which} run rides the actuator limits" in tr.growth.reason for tr in bad)
    assert all(tr.growth.decay_per_period < decay_threshold(ZETA) for tr in res.trials)  # the envelope: stable


def test_perturbation_applies_gain_delay_and_doublet():
    """Feed a ramp command through apply() step by step: the output is K·c(t − τ) (linear
    between plant steps), plus +a then −a over the doublet, and the held command outside
    the window; the yaw slot is untouched."""
    dt = 0.005
    pert = loop_perturbation.perturbation("pitch", 1.0, 2.0, gain=2.0, delay_s=0.0123, pulse_rad=0.1, pulse_s=0.2, dt=dt)
    u = np.zeros(layout.N_INPUT)
    out = []
    for k in range(600):
        t = k * dt
        u[layout.U_DPC] = 0.5 + t  # a new command every step
        u[layout.U_DYC] = 7.0
        loop_perturbation.apply(pert, k, t, dt, True, u)
        out.append(u[layout.U_DPC])
        assert u[layout.U_DYC] == 7.0
    out = np.array(out)
    t = np.arange(600) * dt
    expect = np.where((t >= 1.0) & (t < 2.0), 2.0 * (0.5 + t - 0.0123), 0.5 + t)
    tp = t - 1.0  # time into the window, as apply() forms it
    expect += np.where((tp >= 0.0) & (tp < 0.1), 0.1, 0.0) - np.where((tp >= 0.1) & (tp < 0.2), 0.1, 0.0)
    assert np.allclose(out, expect, atol=1e-12)


def test_frequency_margin_picks_the_nearest_crossings():
    rows = [MarginRow(55.0, "pitch", "gain", -6.0, 0.06, "rigid/aero", "aero"),
            MarginRow(55.0, "pitch", "gain", -12.0, 0.02, "rigid/aero", "aero"),
            MarginRow(55.0, "pitch", "gain", 13.0, 0.8, "rigid/aero", "rigid"),
            MarginRow(55.0, "pitch", "gain", 9.0, 2.5, "flex", "flex_1"),
            MarginRow(55.0, "pitch", "phase", 36.0, 0.2, "rigid/aero", "rigid"),
            MarginRow(55.0, "pitch", "phase", -300.0, 2.5, "flex", "flex_1"),
            MarginRow(55.0, "yaw", "gain", 1.0, 0.8, "rigid/aero", "rigid")]
    assert frequency_margin(rows, "pitch", "gain_high") == (9.0, 2.5, "flex_1")
    assert frequency_margin(rows, "pitch", "gain_low") == (-6.0, 0.06, "aero")
    # 36°/(360°·0.2 Hz) = 500 ms; −300° ≡ 60°: 60/(360·2.5) = 66.7 ms, the smaller
    value, f, mode = frequency_margin(rows, "pitch", "delay")
    assert value == pytest.approx(1000 * 60 / (360 * 2.5)) and mode == "flex_1"
    assert np.isnan(frequency_margin(rows, "yaw", "gain_low")[0])


def test_window_stretches_and_keeps_clear_of_events():
    s = shipped_option("study", "time_margins")  # lead 10, window 20, 3 periods, up to 60 s, clearance 0.2
    assert window(55.0, 1.0, s, [130.5], 500.0)[:2] == (45.0, 65.0)
    start, end, notes = window(55.0, 0.0638, s, [130.5], 500.0)  # 3/0.0638 = 47.0 s, lead 23.5 s
    assert (start, end) == pytest.approx((55.0 - 23.51, 55.0 + 23.51), abs=0.01) and "stretched" in notes[0]
    start, end, notes = window(130.0, 1.0, s, [130.47], 500.0)  # moved back from separation
    assert (start, end) == pytest.approx((110.27, 130.27)) and not notes
    assert "before the point" in window(130.3, 1.0, s, [130.47], 500.0)[2][-1]
    start, end, _ = window(135.0, 1.0, s, [130.47, 132.0, 160.0], 500.0)  # moved forward from an event behind
    assert (start, end) == pytest.approx((132.2, 152.2))
    start, end, notes = window(140.0, 1.0, s, [132.0, 150.0], 500.0)
    assert (start, end) == pytest.approx((132.2, 149.8)) and "cut" in notes[-1]


@pytest.mark.parametrize("override,message", [("study.kinds=[gain]", "study.kinds[0]"),
                                              ("study.lead_s=30", "study.lead_s"),
                                              ("study.axes=[roll]", "study.axes[0]"),
                                              ("study.delay_bound_ms=0", "study.delay_bound_ms"),
                                              ("study.min_damping_ratio=0", "study.min_damping_ratio"),
                                              ("study.min_damping_ratio=1", "study.min_damping_ratio")])
def test_bad_study_keys_are_refused(override, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[")):
        validate(compose_config(["study=time_margins", override]))


@pytest.mark.parametrize("point", [55.0, 180.0, 230.0])
def test_rigid_margins_agree_with_the_frequency_domain(point):
    """Issue 15's acceptance, kept by issue 26 with the decay threshold: on the rigid
    vehicle at 55, 180 and 230 s (where the frozen-time model holds), the nonlinear
    time-domain gain margins agree with the frequency-domain ones within 1 dB and the
    delay margin with min PM / (360° f_c) within 10 %, at the crossing's frequency."""
    cfg = validate(compose_config(["study=time_margins", "sim.progress=false", f"study.times=[{point}]"]))
    s = cfg.study
    flight = flight_mod.fly(cfg, progress=False, snapshot_steps=flight_mod.control_steps(cfg, [point]))
    model, result = flight.prep.model, flight.result
    rt = model.rates
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = analyse(model, result.snapshots[flight_mod.control_steps(cfg, [point])[0]], s, rt.dt * rt.n_fcs).rows
    for kind in ("gain_high", "gain_low", "delay"):
        fd, f_fd, _ = frequency_margin(rows, "pitch", kind)
        start, end, _ = window(point, f_fd, s, [te for _, te in flight_mod.events_of(result)], result.t_final)
        k = flight_mod.control_steps(cfg, [start])[0]
        snap = flight_mod.fly(cfg, progress=False, snapshot_steps=(k,)).result.snapshots[k]
        bound, step = (20.0, 0.1) if kind != "delay" else (1000.0, 2.0)
        res = find_margin(model, snap, Search(point, "pitch", kind, 0, k * rt.dt, end, bound, step, 8,
                                              np.radians(0.5), 0.4, 2.0, s.min_damping_ratio))
        td = -res.margin if kind == "gain_low" else res.margin
        if kind != "delay":
            assert td == pytest.approx(fd, abs=1.0), kind
        else:
            assert td == pytest.approx(fd, rel=0.10)
        assert res.frequency_hz == pytest.approx(f_fd, rel=0.15), kind  # the oscillation is the crossing's


@pytest.mark.slow
def test_time_margins_command_writes_its_table(tmp_path):
    from test_end_to_end import run

    run_dir = tmp_path / "run"
    proc = run(["run", "study=time_margins", "study.times=[180]", "study.axes=[yaw]", f"hydra.run.dir={run_dir}",
                "sim.progress=false"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = list(csv.DictReader((run_dir / "time_margins.csv").open()))
    assert tuple(rows[0]) == COLUMNS and [r["kind"] for r in rows] == ["gain_high", "gain_low", "delay"]
    s = json.loads((run_dir / "summary.json").read_text())
    assert s["time_margins_verdict"] in proc.stdout.replace("\n", "")
    for r, js in zip(rows, s["time_margins"]):
        assert float(r["time_domain"]) == pytest.approx(js["time_domain"], rel=1e-5)
    assert len(list((run_dir / "plots" / "time_margins").glob("*.png"))) == 3
    assert (run_dir / "time_margin_trials.csv").is_file()
    # savant report redraws the figures from savant.h5 alone, byte for byte; the stored
    # trials are the CSV's
    drawn = assert_report_redraws(run_dir)
    assert sorted(n for n in drawn if n.startswith("time_margins/")) == [
        "time_margins/t180_yaw_delay.png", "time_margins/t180_yaw_gain_high.png", "time_margins/t180_yaw_gain_low.png"]
    stored = read_group(run_dir / "savant.h5")
    trials = list(csv.DictReader((run_dir / "time_margin_trials.csv").open()))
    assert [(r.search.kind, tr.value, tr.growth.unstable) for r in stored for tr in r.trials] == [
        (t["kind"], pytest.approx(float(t["value"]), rel=1e-5), t["unstable"] == "yes") for t in trials]
    assert [r.margin for r in stored] == [pytest.approx(js["time_domain"] * (-1 if js["kind"] == "gain_low" else 1))
                                           for js in s["time_margins"]]
