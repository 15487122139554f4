"""The mission outcome (savant_cli/sim/mission.py): the rules on summaries built to fall
just inside and just outside each threshold, the batch's count by class, the config's
refusals, and every class reached by the override docs/requirements.md documents for it."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

import savant_cli
from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.record import FAILURE_CLASSES
from savant_cli.montecarlo.analysis import mission_outcomes
from savant_cli.montecarlo.results import Tables
from savant_cli.sim.mission import Tolerance, class_mask, classes_of, classify, mission_keys

TOL = Tolerance(perigee_km=10.0, apogee_km=10.0, inclination_deg=0.1)
ON_TARGET = {"insertion_perigee_error_km": 0.5, "insertion_apogee_error_km": -0.3,
             "insertion_inclination_error_deg": 0.002, "qalpha_limit_exceeded": 0, "health_flags": "",
             "loss_of_control": False, "final_time_s": 561.0}


def _classes(summary=None, status="complete", stop="cutoff_guidance", judge=True, tolerance=TOL):
    return classify({**ON_TARGET, **(summary or {})}, status, stop, judge, tolerance).classes


def test_an_insertion_on_target_is_a_success():
    outcome = classify(ON_TARGET, "complete", "cutoff_guidance", True, TOL)
    assert outcome.classes == () and outcome.success() and outcome.line() == "mission: SUCCESS"


@pytest.mark.parametrize("key, tol", [("insertion_perigee_error_km", 10.0), ("insertion_apogee_error_km", 10.0),
                                      ("insertion_inclination_error_deg", 0.1)])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_insertion_tolerance_edges(key, tol, sign):
    """An error equal to its tolerance is inside; the next float beyond it is outside,
    on either side of the target."""
    assert _classes({key: sign * tol}) == ()
    assert _classes({key: sign * math.nextafter(tol, math.inf)}) == ("insertion_tolerance",)


@pytest.mark.parametrize("value", [None, float("nan"), float("inf")])
def test_a_missing_or_non_finite_insertion_error_is_not_on_target(value):
    assert _classes({"insertion_apogee_error_km": value}) == ("insertion_tolerance",)


def test_insertion_is_judged_only_at_a_cutoff_of_a_phase_that_ends_there():
    far = {"insertion_perigee_error_km": 500.0}
    assert _classes(far, stop="separation", judge=False) == ()  # phase=first_stage: no orbit to judge
    assert _classes(far, judge=False) == ()
    assert _classes(far, tolerance=None) == ()
    assert _classes(far, stop="cutoff_energy") == ("insertion_tolerance",)  # the stored profile's cutoff too


def test_depletion_and_time_limit_are_failures_whatever_the_status():
    assert _classes(stop="depletion") == ("propellant_depletion",)
    assert _classes(stop="time_limit") == ("time_limit",)
    # an unhealthy run that also ran out keeps both verdicts
    assert _classes({"health_flags": "saturated", "time_at_rate_limit_upper_stage_s": 2.0}, status="saturated",
                    stop="depletion") == ("propellant_depletion", "unhealthy_flight")


def test_loss_of_control_from_a_divergence_or_the_bound():
    assert _classes(status="diverged", stop="diverged") == ("loss_of_control",)
    outcome = classify({**ON_TARGET, "loss_of_control": True,
                        "loss_of_control_reason": "attitude error 23.4 deg > 20 deg at 87.3 s"},
                       "complete", "cutoff_guidance", True, TOL)
    assert outcome.classes == ("loss_of_control",) and "23.4 deg" in outcome.line()
    assert _classes({"loss_of_control": False}) == ()


def test_guidance_failure():
    assert _classes(status="guidance_failed", stop="guidance_failed") == ("guidance_failure",)


@pytest.mark.parametrize("exceeded, expected", [(0, ()), (None, ()), (1, ("structural_allowable",))])
def test_structural_allowable(exceeded, expected):
    assert _classes({"qalpha_limit_exceeded": exceeded, "max_qalpha_Pa_deg": 1.6e5 * 1.01,
                     "qalpha_limit_ratio": 1.01}) == expected


@pytest.mark.parametrize("met, expected", [(1, ()), (None, ()), (0, ("separation_state",))])
def test_separation_state(met, expected):
    assert _classes({"separation_requirements_met": met, "separation_violations": "body rate 2.1 deg/s > 2"}) == expected


@pytest.mark.parametrize("value, met", [(2.0, 1), (math.nextafter(2.0, 3.0), 0), (None, None)])
def test_separation_requirement_edges(value, met):
    """A quantity equal to its bound meets it, the next float above does not; no
    separation, no verdict."""
    from savant_cli.config import SeparationRequirement
    from savant_cli.sim.run_summary import judge_separation

    out = judge_separation({"separation_body_rate_deg_s": value, "separation_attitude_error_deg": 0.1 if value else None,
                            "separation_qalpha_Pa_deg": 100.0 if value else None},
                           SeparationRequirement(2.0, 5.0, 1e4))
    assert out["separation_requirements_met"] == met
    assert ("body rate" in out["separation_violations"]) is (met == 0)


def test_separation_state_is_the_sample_at_the_separation_step():
    from savant_cli.sim.summary import separation_state

    t = np.arange(0.0, 10.0, 0.02)
    w = np.zeros((t.size, 3))
    w[:, 1] = np.radians(t)  # 1 deg/s per s
    err = np.zeros((t.size, 3))
    err[:, 1], err[:, 2] = np.radians(3.0), np.radians(4.0)
    s = separation_state(t, w, err, 10.0 * t, 5.01)  # between samples: the one at 5.00 s
    assert s["separation_body_rate_deg_s"] == pytest.approx(5.0)
    assert s["separation_attitude_error_deg"] == pytest.approx(5.0)  # 3-4-5
    assert s["separation_qalpha_Pa_deg"] == pytest.approx(50.0)
    assert separation_state(t, w, err, t, None) == dict.fromkeys(s)


@pytest.mark.parametrize("flags, unhealthy", [("limit_cycle", True), ("saturated", True), ("slow_divergence", True),
                                              ("limit_cycle,saturated", True), ("", False),
                                              ("loss_of_control", False)])
def test_unhealthy_flight_from_the_health_flags(flags, unhealthy):
    assert ("unhealthy_flight" in _classes({"health_flags": flags})) is unhealthy


@pytest.mark.parametrize("status", ["failed", "invalid"])
def test_a_run_not_flown_is_a_run_error_only(status):
    assert _classes({"message": "ValueError: boom"}, status=status, stop="") == ("run_error",)


def test_counted_classes_decide_success_and_the_rest_are_named():
    outcome = classify({**ON_TARGET, "qalpha_limit_exceeded": 1, "max_qalpha_Pa_deg": 2e5, "qalpha_limit_ratio": 1.25,
                        "time_above_qalpha_limit_s": 3.0}, "complete", "depletion", True, TOL)
    assert outcome.classes == ("propellant_depletion", "structural_allowable")
    assert not outcome.success() and not outcome.success(["propellant_depletion"])
    assert outcome.success(["loss_of_control", "run_error"])
    line = outcome.line(["structural_allowable"])
    assert line.startswith("mission: FAILURE — structural allowable exceeded: q·α 200,000 Pa·deg = 1.250 ×")
    assert "(not counted as failures: propellant depletion" in line
    keys = mission_keys(outcome, ["loss_of_control"])
    assert keys["mission_success"] == 1 and keys["mission_classes"] == "propellant_depletion,structural_allowable"
    assert classes_of(keys["mission_class_mask"]) == outcome.classes


def test_class_masks_round_trip_every_subset():
    for m in range(1 << len(FAILURE_CLASSES)):
        assert class_mask(classes_of(m)) == m


def _tables(status, masks):
    n = len(status)
    return Tables(np.arange(n), list(status), [""] * n, np.zeros(n), np.zeros(n), np.zeros((n, 0)),
                  ["mission_class_mask"], np.array(masks, float)[:, None], np.zeros((n, 4)), np.zeros((0, 9)), [])


def test_batch_counts_by_class_with_the_runs_listed():
    depl, loads = class_mask(["propellant_depletion"]), class_mask(["structural_allowable"])
    tb = _tables(["complete", "complete", "complete", "failed", "interrupted", "complete", "diverged"],
                 [0, depl | loads, loads, np.nan, np.nan, loads, class_mask(["loss_of_control"])])
    m = mission_outcomes(tb, FAILURE_CLASSES)
    assert m["runs"] == 6 and m["successes"] == 1 and m["failures"] == 5  # the interrupted run 4 is not counted
    by = {c["class"]: c for c in m["by_class"]}
    assert by["structural_allowable"]["runs"] == 3 and by["structural_allowable"]["run_list"] == "1-2, 5"
    assert by["run_error"]["run_list"] == "3" and by["loss_of_control"]["run_list"] == "6"
    assert by["time_limit"]["runs"] == 0
    m = mission_outcomes(tb, ("loss_of_control", "run_error"))
    assert m["successes"] == 4 and [f["run"] for f in m["failed_runs"]] == [3, 6]
    by = {c["class"]: c for c in m["by_class"]}
    assert by["run_error"]["counted"] and not by["structural_allowable"]["counted"]


@pytest.mark.parametrize("override, key", [
    ("requirements.mission.failure_classes=[loss_of_control,crash]", "requirements.mission.failure_classes[1]"),
    ("requirements.mission.failure_classes=[time_limit,time_limit]", "requirements.mission.failure_classes"),
    ("guidance.target.tolerance.perigee_km=0", "guidance.target.tolerance.perigee_km"),
    ("requirements.separation.max_body_rate_deg_s=-1", "requirements.separation.max_body_rate_deg_s"),
    ("guidance.target.tolerance.inclination_deg=-0.1", "guidance.target.tolerance.inclination_deg"),
    ("study.reliability.reserve_probability=1.0", "study.reliability.reserve_probability"),
])
def test_bad_mission_settings_are_refused(override, key):
    overrides = [override] + (["study=montecarlo"] if override.startswith("study.") else [])
    with pytest.raises(ConfigError) as err:
        validate(compose_config(overrides))
    assert err.value.key == key


def documented_overrides() -> list[tuple[str, list[str]]]:
    """(class, overrides) of every row of docs/requirements.md's mission-outcome table."""
    docs = Path(__file__).resolve().parents[1] / "docs" / "requirements.md"
    rows = []
    for line in docs.read_text().splitlines():
        m = re.match(r"^\| `([a-z_]+)` \| .* \| `([^`]+)` \|$", line)
        if m and m.group(1) in FAILURE_CLASSES:
            rows.append((m.group(1), m.group(2).split()))
    return rows


def test_every_class_has_a_documented_override():
    assert sorted(c for c, _ in documented_overrides()) == sorted(FAILURE_CLASSES)


@pytest.mark.slow
@pytest.mark.parametrize("klass, overrides", documented_overrides(), ids=[c for c, _ in documented_overrides()])
def test_every_class_is_reached_by_its_documented_override(klass, overrides, tmp_path):
    r = savant_cli.run(overrides + ["sim.progress=false", "output.plots=false"], out_dir=tmp_path / "run")
    s = r.summary
    if "mission" in s:  # a batch
        by = {c["class"]: c for c in s["mission"]["by_class"]}
        assert by[klass]["runs"] >= 1 and by[klass]["counted"]
        assert s["reliability"]["failures"] == s["mission"]["failures"] >= by[klass]["runs"]
    else:
        assert klass in s["mission_classes"].split(",") and s["mission_success"] == 0
        assert s["mission_verdict"].startswith("mission: FAILURE")


@pytest.mark.slow
def test_a_batch_with_a_short_upper_stage_load_counts_its_depletions(tmp_path):
    """Every dispersed run of a batch loaded with half its LOX runs out before the target
    (57 t of LOX burn 67 t of propellant at the mixture ratio, 10 t of LH2 left as dead
    weight: about 3.4 km/s of upper-stage delta-v against the nominal's 5.3 km/s); the
    nominal (run 0, nothing applied) inserts. The batch counts the depletions as failed
    missions. (A short load also lightens both stages: a LOX load 20 % short, or both
    tanks 30 % short, still reach the orbit on the nominal's 7.7 t usable residual.)"""
    r = savant_cli.run(["study=montecarlo", "study.n_runs=3", "study.workers=1", "+dispersions.items.us_lox_load.mean=0.5",
                        "sim.progress=false", "output.plots=false"], out_dir=tmp_path / "mc")
    s = r.summary
    by = {c["class"]: c for c in s["mission"]["by_class"]}
    assert by["propellant_depletion"]["run_list"] == "1-2" and by["propellant_depletion"]["counted"]
    assert s["reliability"]["successes"] == 1 and s["reliability"]["failures"] == 2
    assert s["insertion"]["runs_depleted"] == 2
