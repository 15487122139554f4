"""Requirement sets in config and their verdicts (issue 12 item 7): the rules of
``linear/requirements.py`` on hand-made margins, a bending mode's peak against
python-control's own frequency response, and the ``requirements`` config group."""

from __future__ import annotations

import dataclasses
import warnings

import control as ct
import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import FlexModeOverride, FlexModeRequirement, shipped_option, validate
from savant_cli.errors import ConfigError
from savant_cli.linear.margins import MarginRow
from savant_cli.linear.modes import MarginLabeler, ModePeak
from savant_cli.linear.requirements import (
    CHECK_ARRAY_COLUMNS, checks_array, evaluate_point, mode_code, mode_name, verdict_line, verdicts_of_array
)
from test_margin_modes import _synthetic_loop

T = 55.0


def _ares_i():
    """A fresh copy of the shipped Ares I requirement set (``conf/requirements/ares_i.yaml``)."""
    return shipped_option("requirements", "ares_i")


def _row(kind: str, value: float, f: float, mode: str, axis: str = "pitch") -> MarginRow:
    band = "slosh" if mode.startswith("slosh") else "flex" if mode.startswith("flex") else "rigid/aero"
    return MarginRow(T, axis, kind, value, f, band, mode)


def _verdict(rows, peaks=(), stage="first_stage", stable=True, req=None):
    return evaluate_point(T, stage, list(rows), list(peaks), stable, -0.1 if stable else 0.2, req or _ares_i())


def test_rigid_aero_integrator_and_slosh_margins_against_their_own_requirements():
    req = _ares_i()
    req.rigid.gain_dB, req.rigid.gain_reduction_dB, req.rigid.phase_deg = 6.0, 4.0, 30.0
    req.aero.gain_dB, req.slosh.gain_dB, req.slosh.phase_deg = 5.0, 3.0, 20.0
    rows = [_row("gain", 5.9, 1.1, "rigid"), _row("gain", -5.5, 0.09, "aero"), _row("gain", -4.5, 0.05, "integrator"),
            _row("phase", 31.0, 0.3, "rigid"), _row("phase", -25.0, 0.5, "slosh_lox"),
            _row("gain", -2.5, 0.5, "slosh_lh2")]
    v = _verdict(rows, req=req)
    # 5.9 < 6 fails; |-5.5| >= 5; |-4.5| >= 4; 31 >= 30; |-25| >= 20; |-2.5| < 3 fails
    assert v.row_verdicts == (False, True, True, True, True, False)
    assert [c.criterion for c in v.checks[:3]] == ["gain margin", "gain-reduction margin", "gain-reduction margin"]
    assert [c.required for c in v.checks[:6]] == [6.0, 5.0, 4.0, 30.0, 20.0, 3.0]
    assert not v.passed and len(v.failed) == 2
    # the worst offender is the furthest below its requirement: 2.5/3 = 0.83 < 5.9/6 = 0.98
    assert v.worst.mode == "slosh_lh2" and v.worst.ratio == pytest.approx(2.5 / 3.0)
    assert v.checks[-1].criterion == "stability" and v.checks[-1].passed


def test_a_lost_closed_loop_fails_the_point_and_is_its_worst_offender():
    v = _verdict([_row("gain", 12.0, 1.1, "rigid"), _row("phase", 45.0, 0.3, "rigid")], stable=False)
    assert v.row_verdicts == (True, True) and not v.passed
    assert v.worst.criterion == "stability" and "UNSTABLE" in v.worst.text()


def test_the_fastest_lost_closed_loop_is_the_worst_offender():
    slow = evaluate_point(10.0, "first_stage", [], [], False, 1e-4, _ares_i())
    fast = evaluate_point(130.0, "first_stage", [], [], False, 0.05, _ares_i())
    margin = _verdict([_row("phase", 5.0, 0.3, "rigid")])
    line = verdict_line([("", [slow]), ("", [margin]), ("", [fast])], "ares_i")
    assert line.endswith("worst: 130.0 s closed loop UNSTABLE (largest real part 0.05 1/s)")


def _peak(peak_dB: float, mode: str = "flex_1", axis: str = "pitch") -> ModePeak:
    return ModePeak(T, axis, mode, peak_dB, 1.0)


@pytest.mark.parametrize("stabilization, peak_dB, rows, passed, judged_by", [
    # gain: the attenuation (-peak) against gain_dB, whatever the crossings
    ("gain", -7.0, [], True, "attenuation"),
    ("gain", -5.0, [], False, "attenuation"),
    ("gain", 3.0, [("phase", 50.0)], False, "attenuation"),
    # phase: every crossing of the mode; none: it stays below 0 dB
    ("phase", 3.0, [("phase", 35.0), ("phase", -40.0)], True, "phase margin"),
    ("phase", 3.0, [("phase", 35.0), ("phase", 25.0)], False, "phase margin"),
    ("phase", -3.0, [("gain", 4.0)], False, "gain margin"),
    ("phase", -3.0, [], True, "attenuation"),
    # either: gain-stabilized when the attenuation suffices, else judged on the crossings
    ("either", -7.0, [("gain", 7.5)], True, "attenuation"),
    ("either", 3.0, [("phase", 40.0), ("phase", 120.0)], True, "phase margin"),
    ("either", 3.0, [("phase", 20.0), ("phase", 120.0)], False, "phase margin"),
    ("either", -3.0, [("gain", 4.0)], False, "attenuation"),
])
def test_bending_mode_stabilization(stabilization, peak_dB, rows, passed, judged_by):
    req = _ares_i()
    req.flex.first_stage.default = FlexModeRequirement(stabilization, 6.0, 30.0)
    v = _verdict([_row(kind, value, 1.0 + 0.01 * i, "flex_1") for i, (kind, value) in enumerate(rows)],
                 [_peak(peak_dB)], req=req)
    flex = [c for c in v.checks if c.mode == "flex_1"]
    assert v.passed is passed
    assert {c.criterion for c in flex} == {judged_by}
    if judged_by == "attenuation" and rows == [] and stabilization == "phase":
        assert flex[0].required == 0.0 and flex[0].value == pytest.approx(3.0)  # below 0 dB
    elif judged_by == "attenuation":
        assert flex[0].value == pytest.approx(-peak_dB) and flex[0].required == 6.0
    # a row's verdict: its own check when the mode is judged on its crossings, else the mode's
    mode_ok = all(c.passed for c in flex)
    for r, ok in zip(rows, v.row_verdicts):
        own = abs(r[1]) >= (6.0 if r[0] == "gain" else 30.0)
        assert ok == (own if judged_by != "attenuation" else mode_ok)


def test_per_stage_and_per_mode_requirements():
    """The Ares I choice (shared/data/ares_i_public_data.md): the first stage
    phase-stabilizes its first bending mode and gain-stabilizes the others; the upper
    stage gain-stabilizes all."""
    req = _ares_i()
    req.flex.first_stage.default = FlexModeRequirement("gain", 6.0, 30.0)
    req.flex.first_stage.modes = {"flex_1": FlexModeOverride("phase", 6.0, 30.0)}
    req.flex.upper_stage.default = FlexModeRequirement("gain", 10.0, 30.0)
    rows = [_row("phase", 40.0, 1.0, "flex_1")]
    peaks = [_peak(2.0, "flex_1"), _peak(-8.0, "flex_3")]
    first = _verdict(rows, peaks, stage="first_stage", req=req)
    assert first.passed  # flex_1 phase-stabilized with 40 deg, flex_3 attenuated by 8 >= 6 dB
    upper = _verdict(rows, peaks, stage="upper_stage", req=req)
    assert not upper.passed  # all gain-stabilized by 10 dB: flex_1 (+2 dB) and flex_3 (8 dB) fail
    assert {c.mode for c in upper.failed} == {"flex_1", "flex_3"}
    assert upper.worst.mode == "flex_1" and upper.worst.ratio == pytest.approx(-0.2)


def test_verdict_line_names_the_worst_offender_of_its_group():
    good = _verdict([_row("gain", 12.0, 1.1, "rigid")])
    bad = evaluate_point(180.0, "upper_stage", [MarginRow(180.0, "yaw", "phase", 22.0, 0.3, "rigid/aero", "rigid")],
                         [], True, -0.1, dataclasses.replace(_ares_i(), name="crew"))
    assert verdict_line([("", [good]), ("", [bad])], "crew") == (
        "requirements crew: FAIL, 1 of 2 points pass; worst: 180.0 s yaw rigid phase margin 22.0 deg < 30 deg at 0.3 Hz")
    assert verdict_line([("run 3", [good, bad]), ("run 4", [good])], "crew", "runs").startswith(
        "requirements crew: FAIL, 1 of 2 runs pass; worst: run 3: 180.0 s yaw rigid phase margin")
    assert verdict_line([("", [good])], "crew") == "requirements crew: PASS, 1 of 1 points pass"


def test_checks_survive_their_numeric_encoding():
    v = _verdict([_row("gain", 5.9, 1.1, "rigid"), _row("phase", 33.0, 1.0, "flex_3", "yaw")], [_peak(2.0, "flex_3", "yaw")],
                 stage="upper_stage")
    arr = checks_array([v])
    assert arr.shape == (len(v.checks), len(CHECK_ARRAY_COLUMNS))
    (back,) = verdicts_of_array(arr)
    assert back.stage == "upper_stage" and repr(back.checks) == repr(v.checks)  # NaN frequency of the stability check
    for name in ("rigid", "aero", "integrator", "slosh_lox", "slosh_lh2", "closed_loop", "flex_1", "flex_12"):
        assert mode_name(mode_code(name)) == name


def test_bending_peak_matches_python_controls_frequency_response():
    """The synthetic loop's 2 Hz mode (|L| = 3 at resonance by construction): the peak
    found by the labeler against the maximum of control.frequency_response on a dense
    grid across the resonance."""
    loop, groups = _synthetic_loop()
    for scale in (1.0, 0.1):  # a phase-stabilizable (+9.5 dB) and a gain-stabilized (-10.5 dB) mode
        sys = loop * scale
        from savant_cli.linear.response import FastResponse

        (peak,) = MarginLabeler(sys, groups, aero_unstable=False).flex_peaks(FastResponse(sys), 0.0, "pitch")
        w = 2 * np.pi * np.linspace(1.9, 2.1, 20001)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mag = np.abs(ct.frequency_response(sys, w).complex).ravel()
        assert peak.mode == "flex_1"
        assert peak.peak_dB == pytest.approx(20 * np.log10(mag.max()), abs=0.01)
        assert peak.frequency_hz == pytest.approx(w[np.argmax(mag)] / (2 * np.pi), rel=1e-3)
    assert 20 * np.log10(3.0 * 0.1) - 0.5 < peak.peak_dB < 20 * np.log10(3.0 * 0.1) + 0.5


def test_the_vehicle_selects_its_requirement_set():
    assert validate(compose_config([])).requirements.name == "ares_i"
    cfg = validate(compose_config(["vehicle=small_launcher"]))
    assert cfg.requirements.name == "small_launcher"
    assert cfg.requirements.flex.upper_stage.default.stabilization == "either"
    over = validate(compose_config(["+requirements.flex.first_stage.modes.flex_1.stabilization=phase"]))
    assert over.requirements.flex_mode("first_stage", "flex_1").stabilization == "phase"
    assert over.requirements.flex_mode("first_stage", "flex_3").stabilization == "either"


def test_a_per_mode_override_replaces_only_the_keys_it_gives():
    """``modes.flex_1: {stabilization: phase}`` over a stage default of 8 dB / 35 deg:
    flex_1 is phase-stabilized and keeps the default's 8 dB and 35 deg (not the
    shipped file's 6 dB / 30 deg); a mode without an entry is the default itself."""
    cfg = validate(compose_config(["requirements.flex.first_stage.default.gain_dB=8",
                                   "requirements.flex.first_stage.default.phase_deg=35",
                                   "+requirements.flex.first_stage.modes.flex_1.stabilization=phase",
                                   "+requirements.flex.first_stage.modes.flex_2.gain_dB=12"]))
    req = cfg.requirements
    assert req.flex_mode("first_stage", "flex_1") == FlexModeRequirement("phase", 8.0, 35.0)
    assert req.flex_mode("first_stage", "flex_2") == FlexModeRequirement("either", 12.0, 35.0)
    assert req.flex_mode("first_stage", "flex_3") == FlexModeRequirement("either", 8.0, 35.0)
    assert req.flex_mode("upper_stage", "flex_1") == FlexModeRequirement("either", 6.0, 30.0)
    rows = [_row("phase", 34.0, 1.0, "flex_1")]  # 34 deg: short of the inherited 35 deg
    assert not _verdict(rows, [_peak(2.0, "flex_1")], req=req).passed
    assert _verdict([_row("phase", 36.0, 1.0, "flex_1")], [_peak(2.0, "flex_1")], req=req).passed


@pytest.mark.parametrize("override, key", [
    ("requirements.rigid.phase_deg=-30", "requirements.rigid.phase_deg"),
    ("requirements.flex.upper_stage.default.stabilization=notch", "requirements.flex.upper_stage.default.stabilization"),
    ("+requirements.flex.first_stage.modes.mode1.gain_dB=6", "requirements.flex.first_stage.modes.mode1"),
])
def test_bad_requirements_are_refused_naming_the_key(override, key):
    with pytest.raises(ConfigError) as err:
        validate(compose_config([override]))
    assert err.value.key == key


def _scan(times, crossover_hz, mu):
    from savant_cli.linear.frozen_time import ScanPoint

    return [ScanPoint(float(t), {"pitch": float(f), "yaw": float(f) * 1.5}, float(m))
            for t, f, m in zip(times, crossover_hz, mu)]


def test_period_criterion_closed_form():
    """A crossover period growing linearly, T_c = 2 + 0.5 (t − 100) s, against the time
    left to separation at 110 s: T_c = 110 − t at t = 105.33 s (2 + 0.5 u = 10 − u, u =
    16/3). The window starts there (the margin is linear in t: interpolation is exact).
    The yaw loop's higher crossover does not set it: the slower loop does."""
    from savant_cli.linear.frozen_time import window

    t = np.arange(100.0, 110.0, 0.5)
    w = window(_scan(t, 1.0 / (2.0 + 0.5 * (t - 100.0)), np.full(t.size, 3.0)), 110.0, ("period",), 6.0)
    assert w.starts["period"] == pytest.approx(100.0 + 16.0 / 3.0, abs=1e-9)
    assert w.start_s == w.starts["period"] and w.bounds == (w.start_s, 110.0)
    assert w.contains(105.4) and not w.contains(105.3) and not w.contains(110.0)
    # a constant control power still falls to zero at separation: once a period reaches
    # past separation the control-power criterion fails too, so it starts no later (within
    # the scan step, where its margin jumps)
    assert w.starts["period"] - 0.5 <= w.starts["control_power"] <= w.starts["period"]


def test_control_power_criterion_closed_form():
    """Control power falling linearly to zero at 120 s, μc = 3 (120 − t)/20 1/s², with a
    constant 2 s crossover period: over one period it falls by 2/(120 − t), which reaches
    the 6 dB limit 1 − 10^(−6/20) = 0.49881 at t = 120 − 2/0.49881 = 115.990 s (within
    0.01 s: the fall is not linear in t between the 0.25 s scan points). The period
    criterion starts where 2 s = 125 − t: 123 s (separation at 125 s)."""
    from savant_cli.linear.frozen_time import gain_fall_limit, window

    limit = gain_fall_limit(6.0)
    assert limit == pytest.approx(1.0 - 10.0 ** (-0.3))
    t = np.arange(100.0, 124.6, 0.25)
    mu = 3.0 * np.maximum(120.0 - t, 0.0) / 20.0
    w = window(_scan(t, np.full(t.size, 0.5), mu), 125.0, ("period", "control_power"), 6.0)
    assert w.starts["control_power"] == pytest.approx(120.0 - 2.0 / limit, abs=0.01)
    assert w.starts["period"] == pytest.approx(123.0, abs=1e-9)
    assert w.start_s == w.starts["control_power"]  # the earlier of the two
    only_period = window(_scan(t, np.full(t.size, 0.5), mu), 125.0, ("period",), 6.0)
    assert only_period.start_s == pytest.approx(123.0)


def test_no_crossover_fails_the_period_criterion_and_no_criterion_no_window():
    from savant_cli.linear.frozen_time import failing_start, window

    t = np.arange(100.0, 105.0, 1.0)
    f = np.array([0.5, 0.5, 0.5, np.nan, np.nan])  # the crossover vanishes at 103 s
    w = window(_scan(t, f, np.full(t.size, 3.0)), 200.0, ("period",), 6.0)
    assert w.starts["period"] == 103.0  # no interpolation to an infinite margin
    assert window(_scan(t, f, np.full(t.size, 3.0)), 200.0, (), 6.0).start_s is None
    assert failing_start(t, np.array([-1.0, -1.0, 1.0, 1.0, 1.0])) is None  # passes at the end: no window
    assert failing_start(t, np.array([-1.0, 1.0, 1.0, -1.0, -3.0])) == pytest.approx(102.5)  # the final stretch
    assert failing_start(t, -np.ones(5)) == 100.0


def test_tailoff_verdict_fails_on_one_check_outside_the_separation_bounds():
    """The window's clause passes only when every check reaches separation inside
    requirements.separation: one check just over its body-rate bound, or one that never
    separated, fails the clause and is named; no check at all is not a pass."""
    from savant_cli.timedomain.tailoff import TailoffCheck, verdict_text

    def chk(kind, met, separated=True, violations=""):
        return TailoffCheck("pitch", kind, 6.0, "dB", "complete" if separated else "diverged", separated,
                            {"separation_body_rate_deg_s": 2.01 if not met else 0.2}, met, violations)

    ok = [chk("gain_high", True), chk("gain_low", True)]
    line, passed = verdict_text("tail-off", ok)
    assert passed and "PASS, 2 of 2 checks" in line
    line, passed = verdict_text("tail-off", ok + [chk("delay", False, violations="body rate 2.01 deg/s > 2")])
    assert not passed and "FAIL, 2 of 3 checks pass" in line and "body rate 2.01 deg/s > 2" in line
    line, passed = verdict_text("tail-off", ok + [chk("gain_high", False, separated=False)])
    assert not passed and "did not reach separation (diverged)" in line
    assert verdict_text("tail-off", []) == ("tail-off judged in the time domain: no check could be flown", False)
