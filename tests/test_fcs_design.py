"""``study=fcs_design``: the physical parameterization reproduces the design rules, the
search maximizes the smallest ratio on a problem with a known optimum, and the study runs
end to end into a controller config that loads and flies."""

from __future__ import annotations

import dataclasses
import json
import types

import numpy as np
import pytest

from browser import assert_page_reads, require_chromium
from conftest import assert_report_redraws, compose_config
from savant_cli.config import shipped_option, validate
from savant_cli.datagen import fcs_gains
from savant_cli.design import parameters as dp, points as dpts, search as ds
from savant_cli.errors import ConfigError
from savant_cli.linear.requirements import Check, PointVerdict
from test_end_to_end import run


def test_rule_values_are_the_design_rules():
    """The rules' values (the first estimate: the pole placement and flex_filters.DESIGN), and
    a changed copy leaving the rules untouched."""
    spec = fcs_gains.FIRST_ESTIMATE
    blend = [0.401, 0.0, 0.599]
    assert dp.rule_value(spec, "stack", "omega", blend) == 1.3
    assert dp.rule_value(spec, "upper", "notch1_hz", blend) == 9.5
    assert dp.rule_value(spec, "stack", "notch2_q", blend) == 1.5
    assert dp.rule_value(spec, "stack", "kir_share", blend) == 0.2
    assert dp.rule_value(spec, "upper", "omega_end", blend) == 1.0 and dp.rule_value(spec, "stack", "integral_ratio",
                                                                                     blend) == 0.15
    assert dp.rule_value(spec, "stack", "blend_first", blend) == 0.599
    moved = dp.apply(spec, {("stack", "notch2_q"): 0.8, ("upper", "omega"): 1.1, ("stack", "blend_first"): 0.65})
    assert moved["filters"]["stack"]["notch_q"] == (1.5, 0.8) and moved["upper"]["omega"] == 1.1
    assert moved["stack_blend"] == [0.35, 0.0, 0.65]
    assert spec["upper"]["omega"] == 1.0 and spec["filters"] is None  # the rules themselves untouched


#: The reference ascent (``fcs_gains.solve``) of each vehicle, solved once for its controllers.
_REFERENCES: dict = {}


@pytest.mark.slow
@pytest.mark.parametrize("vehicle, controller", [("ares_i", "msfc_pid"), ("ares_i", "larc_pd"),
                                                 ("small_launcher", "small_pid"), ("small_launcher", "small_pd")])
def test_shipped_controller_is_its_rules_with_its_design_values(vehicle, controller, monkeypatch):
    """Each shipped controller is exactly (text, bitwise) the YAML its design rules write
    with the values of its own ``design`` block (what study=fcs_design tuned), at the
    reference ascent's design points: the file is reproducible from its provenance."""
    from savant_cli.datagen import flex_filters
    from savant_cli.paths import shipped_config_dir
    from savant_cli.sim.setup import prepare

    overrides = [] if vehicle == "ares_i" else ["vehicle=small_launcher", "guidance=small_launcher_leo"]
    cfg = validate(compose_config(overrides + [f"controller={controller}"]))
    design = cfg.controller.design
    assert design.rules == controller and design.parameters, "the shipped file records its design"
    prep = prepare(cfg)
    spec = fcs_gains.CONTROLLERS[design.rules]
    blend = flex_filters.vehicle_stack_blend(cfg.vehicle, prep.vehicle_dir)
    values = {(sched, name): v for sched, vals in design.parameters.items() for name, v in vals.items()}
    solve = fcs_gains.solve

    def solved_once(*args, **kwargs):  # one reference ascent per vehicle: its controllers share it
        if vehicle not in _REFERENCES:
            _REFERENCES[vehicle] = solve(*args, **kwargs)
        return _REFERENCES[vehicle]

    monkeypatch.setattr(fcs_gains, "solve", solved_once)
    points = fcs_gains.design_points(cfg, prep.vehicle, spec)
    text = dp.controller_text(dp.apply(spec, values), points, blend, vehicle,
                              {"rules": design.rules, "parameters": values})
    assert text == (shipped_config_dir() / "controller" / f"{controller}.yaml").read_text()


def test_design_values_round_trip_through_the_controller_config():
    """The design block the study writes reads back through the schema unchanged."""
    values = {("stack", "omega"): 0.1 + 0.2, ("upper", "notch1_q"): 1 / 3}
    text = fcs_gains.controller_yaml(fcs_gains.gain_tables(
        {"stack": [(0.0, 0.0, 1.0)], "upper": [(0.0, 0.0, 1.0)], "ignition_fade": (0.3, 2.8)},
        dict(fcs_gains.DESIGN, stack_altitudes_m=[0], upper_speeds_mps=[0])), [0.5, 0.0, 0.5],
        fcs_gains.DESIGN, "ares_i", {"rules": "msfc_pid", "parameters": values})
    d = dp.controller_config(text).design
    assert d.rules == "msfc_pid" and d.parameters == {"stack": {"omega": 0.1 + 0.2}, "upper": {"notch1_q": 1 / 3}}


def test_ignition_fade_is_the_engines_thrust_build_up():
    """The fade window is read from the start-transient table: its last zero-thrust time
    and the first time it reaches rated thrust (a hand-made table); every shipped
    controller carries its vehicle's (the J-2X profile: thrust from 0.3 s, rated at 2.8 s)."""
    from savant_cli.sim.setup import prepare

    assert fcs_gains.ignition_fade(np.array([0.0, 0.5, 1.0, 1.5, 2.0]), np.array([0.0, 0.0, 0.5, 1.0, 1.0])) == (0.5, 1.5)
    assert fcs_gains.ignition_fade(np.array([0.0, 1.0]), np.array([0.2, 1.0])) == (0.0, 1.0)
    with pytest.raises(ValueError):
        fcs_gains.ignition_fade(np.array([0.0, 1.0]), np.array([0.0, 0.9]))
    for vehicle, controller in [("ares_i", "msfc_pid"), ("ares_i", "larc_pd"),
                                ("small_launcher", "small_pid"), ("small_launcher", "small_pd")]:
        overrides = [] if vehicle == "ares_i" else ["vehicle=small_launcher", "guidance=small_launcher_leo"]
        cfg = validate(compose_config(overrides + [f"controller={controller}"]))
        us = prepare(cfg).vehicle.upper_stage
        fade = fcs_gains.ignition_fade(us.startup_time_s, us.startup_fraction)
        assert fade == (0.3, 2.8) and (cfg.controller.ignition_fade.start_s, cfg.controller.ignition_fade.end_s) == fade
        assert not any(any(getattr(cfg.controller.gains.coast.pitch, g)) for g in ("kp", "ki", "kd", "kir"))


def _optimizer(**settings):
    """The shipped ``study=fcs_design`` optimizer with ``settings`` in place."""
    return dataclasses.replace(shipped_option("study", "fcs_design").optimizer, **settings)


def _verdict(ratio: float) -> PointVerdict:
    # an attenuation check: its ratio keeps its sign (a margin's is its magnitude's)
    c = Check(0.0, "pitch", "flex_1", "attenuation", 6.0 * ratio, 6.0, "dB", 1.0, ratio >= 1.0)
    return PointVerdict(0.0, "first_stage", (c, Check(0.0, "", "closed_loop", "stability", -0.1, 0.0, "1/s",
                                                      float("nan"), True)), ())


@pytest.mark.parametrize("method", ["nelder_mead", "cobyla"])
def test_search_climbs_to_the_known_max_min(monkeypatch, method):
    """Two 'points' whose ratios are 2 − (x − 0.3)² − y² and 2 − (x − 0.7)² − y²: the
    smallest is largest at x = 0.5, y = 0, where it is 1.96 (the x range 0–1, y −1–1)."""
    params = [dp.FreeParameter("stack", "x", 0.9, 0.0, 1.0), dp.FreeParameter("stack", "y", 0.6, -1.0, 1.0)]

    def fake_judge(points, values, dt, axes):
        x, y = values[("stack", "x")], values[("stack", "y")]
        return [_verdict(2.0 - (x - 0.3) ** 2 - y ** 2), _verdict(2.0 - (x - 0.7) ** 2 - y ** 2)]

    monkeypatch.setattr(dpts, "judge_all", fake_judge)
    res = ds.search(params, lambda v: v, [None, None], 0.02,
                    _optimizer(method=method, max_evaluations=400, tolerance=1e-6, initial_step=0.2), ("pitch",))
    assert res.values[("stack", "x")] == pytest.approx(0.5, abs=0.01)
    assert res.values[("stack", "y")] == pytest.approx(0.0, abs=0.02)
    assert res.score == pytest.approx(1.96, abs=1e-3) and res.initial_score < res.score
    assert res.evaluations == len(res.history) <= 400 + 2


def test_an_unfixable_point_does_not_stop_the_search_fixing_the_others(monkeypatch):
    """Point 2 is stuck at 0.5 whatever x; point 3 passes only for x > 0.446. A bare
    max-min is flat (0.5 everywhere) and would stay at x = 0.1; the goal-attainment
    objective (minus the total shortfall below 1) moves x until point 3 passes."""
    params = [dp.FreeParameter("stack", "x", 0.1, 0.0, 1.0)]

    def fake_judge(points, values, dt, axes):
        x = values[("stack", "x")]
        return [_verdict(2.0 - (x - 0.3) ** 2), _verdict(0.5), _verdict(1.5 - 4.0 * (x - 0.8) ** 2)]

    monkeypatch.setattr(dpts, "judge_all", fake_judge)
    res = ds.search(params, lambda v: v, [None] * 3, 0.02,
                    _optimizer(max_evaluations=200, tolerance=1e-6, initial_step=0.1), ("pitch",))
    x = res.values[("stack", "x")]
    assert 1.5 - 4.0 * (x - 0.8) ** 2 >= 1.0 and res.score == pytest.approx(-0.5)
    assert ds.objective(np.array([1.2, 1.5])) == 1.2 and ds.objective(np.array([0.5, 2.0, -0.4])) == pytest.approx(-1.9)


def test_a_lost_closed_loop_scores_below_any_kept_one():
    lost = PointVerdict(0.0, "first_stage", (Check(0.0, "", "closed_loop", "stability", 0.02, 0.0, "1/s",
                                                   float("nan"), False),), ())
    assert dpts.point_score(lost) == pytest.approx(-1.2) and dpts.point_score(_verdict(0.01)) > dpts.point_score(lost)
    # a bending peak 4 dB above 0 dB with no crossing of its own (a zero requirement): graded, above a lost loop
    above = PointVerdict(0.0, "first_stage", (Check(0.0, "pitch", "flex_1", "attenuation", -4.0, 0.0, "dB", 1.0, False),
                                              Check(0.0, "", "closed_loop", "stability", -0.1, 0.0, "1/s",
                                                    float("nan"), True)), ())
    assert dpts.point_score(above) == pytest.approx(-0.8) and dpts.point_score(lost) < dpts.point_score(above) < 0


@pytest.mark.parametrize("override, key", [
    ("study.parameters.stack.omega.initial=5", "study.parameters.stack.omega.initial"),
    ("study.optimizer.method=bfgs", "study.optimizer.method"),
    ("+study.parameters.upper.blend_first={low: 0.1, high: 0.9}", "study.parameters.upper.blend_first"),
    ("study.schedules=[coast]", "study.schedules[0]"),
    ("+study.parameters.upper.tailoff_kd_cap={low: 1, high: 2}", "study.parameters.upper.tailoff_kd_cap"),
    ("study.controller_name=larc_pd", "study.controller_name"),  # shadowed by the shipped file
    ("study.workers=-1", "study.workers"),
])
def test_bad_design_settings_are_refused(override, key):
    with pytest.raises(ConfigError) as err:
        validate(compose_config(["study=fcs_design", override]))
    assert err.value.key == key


@pytest.mark.slow
def test_fcs_design_end_to_end(tmp_path):
    out = tmp_path / "fd"
    # two corners of the five (the band's ends) keep the verification's cost down
    proc = run(["run", "study=fcs_design", "study.optimizer.max_evaluations=6", "study.every_s.stack=40",
                "study.every_s.upper=150", "study.verify_every_s=60", "study.controller_name=tuned_test",
                "~study.corners.flex_below", "~study.corners.flex_damping_low", "~study.corners.flex_above",
                "sim.progress=false", f"hydra.run.dir={out}"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["controller"] == "tuned_test" and set(s["searches"]) == {"stack", "upper"}
    for r in s["searches"].values():
        assert 1 <= r["evaluations"] <= 6 + 2 and r["objective_after"] >= r["objective_before"]
    assert s["verdict_before"].startswith("requirements ares_i:") and s["verdict_after"] in proc.stdout
    yaml = out / "controller" / "tuned_test.yaml"
    assert yaml.is_file() and "tuned by study=fcs_design" in yaml.read_text()
    assert "fcs_design/margin_envelope_after.png" in assert_report_redraws(out)
    require_chromium()
    assert_page_reads(out)  # the study's page as a reviewer reads it (tests/test_html_report.py reads the others)
    fly = run(["run", f"--config-dir={out}", "controller=tuned_test", "phase=first_stage", "sim.progress=false",
               f"hydra.run.dir={tmp_path}/fly"], cwd=tmp_path)
    assert fly.returncode == 0, fly.stdout + fly.stderr


def test_pole_placement_gains_follow_the_frequency_ramp():
    """Kp + Kir = (ω² + max(μα, 0))/μc, Kd = 2ζω/μc, Ki = ratio·ω·(Kp + Kir), with ω going
    linearly from omega to omega_end over the breakpoints (hand-computed here)."""
    pts = {"stack": [(0.0, 0.1, 2.0), (1.0, -0.2, 3.0), (2.0, 0.0, 1.0)], "upper": [(0.0, 0.0, 4.0), (1.0, 0.0, 4.0)]}
    spec = dict(fcs_gains.DESIGN, stack={"omega": 1.0, "omega_end": 2.0, "zeta": 0.5, "kir_share": 0.25,
                                         "integral_ratio": 0.1},
                upper={"omega": 0.8, "zeta": 0.7}, stack_altitudes_m=[0, 1, 2], upper_speeds_mps=[0, 1])
    tb = fcs_gains.gain_tables(pts, spec)["stack"]
    for w, (_, mu_a, mu_c), kp, kir, kd, ki in zip((1.0, 1.5, 2.0), pts["stack"], tb["kp"], tb["kir"], tb["kd"],
                                                   tb["ki"]):
        k = (w * w + max(mu_a, 0.0)) / mu_c
        assert kp == pytest.approx(0.75 * k) and kir == pytest.approx(0.25 * k)
        assert kd == pytest.approx(2 * 0.5 * w / mu_c) and ki == pytest.approx(0.1 * w * k)
    up = fcs_gains.gain_tables(pts, spec)["upper"]  # no omega_end: constant, the spec's shares
    assert up["kd"] == [pytest.approx(2 * 0.7 * 0.8 / 4.0)] * 2 and up["kir"][0] == pytest.approx(0.2 * 0.64 / 4.0)


def test_tailoff_gains_are_capped_pole_placements_without_integral():
    """Past the last regular breakpoint the stack schedule goes on at the tail-off
    breakpoints: stiffness min((ω² + μα)/μc, cap_p·k_last), Kd min(2ζω/μc, cap_d·Kd_last),
    Ki 0 (hand-computed)."""
    pts = {"stack": [(0.0, 0.0, 2.0), (1.0, 0.1, 3.0)], "upper": [(0.0, 0.0, 4.0)],
           "stack_tailoff": [(60.0, 2.0, 0.05, 2.0), (70.0, 3.0, 0.02, 0.3)]}
    spec = dict(fcs_gains.DESIGN, stack={"omega": 1.0, "zeta": 0.5, "kir_share": 0.0, "integral_ratio": 0.1,
                                         "tailoff_kp_cap": 1.5, "tailoff_kd_cap": 2.0},
                upper={"omega": 0.8, "zeta": 0.7}, stack_altitudes_m=[0, 50], upper_speeds_mps=[0])
    tb = fcs_gains.gain_tables(pts, spec)["stack"]
    k_last, kd_last = (1.0 + 0.1) / 3.0, 1.0 / 3.0
    assert tb["breakpoints"] == [0.0, 50.0, 60.0, 70.0]
    assert tb["kp"][2:] == [pytest.approx((1.0 + 0.05) / 2.0), pytest.approx(1.5 * k_last)]  # uncapped, capped
    assert tb["kd"][2:] == [pytest.approx(0.5), pytest.approx(2.0 * kd_last)]
    assert tb["ki"][2:] == [0.0, 0.0] and tb["ki"][1] == pytest.approx(0.1 * 1.0 * k_last)


def test_corner_requirements_scale_every_margin():
    from savant_cli.studies.fcs_design import corner_requirements

    r = dataclasses.replace(shipped_option("requirements", "ares_i"), name="set")
    out = corner_requirements(r, {"a": {"flex.damping": 0.002}, "b": {"requirement_fraction": 0.25},
                                  "c": {"requirement_fraction": 0}})
    assert out["a"] is r and out["b"].name == "set × 0.25" and out["c"].name == "set × 0"
    assert (out["b"].rigid.phase_deg, out["b"].slosh.gain_dB, out["b"].flex.upper_stage.default.phase_deg) == \
        (7.5, 1.5, 7.5)
    assert out["c"].aero.gain_dB == 0.0 and r.rigid.phase_deg == 30.0  # the nominal set untouched
    assert out["b"].separation == r.separation and out["b"].mission == r.mission  # bounds, not margins
    with pytest.raises(ConfigError, match="requirement_fraction"):
        corner_requirements(r, {"d": {"requirement_fraction": 1.5}})


def test_a_pd_design_keeps_its_integral_paths_off():
    """larc_pd's and small_pd's rules fix Ki = Kir = 0: the study does not tune them,
    whatever study.parameters offers."""
    cfg = validate(compose_config(["study=fcs_design", "study.design=larc_pd"]))
    for design in ("larc_pd", "small_pd"):
        names = {p.name for p in dp.free_parameters(cfg.study.parameters, ["stack", "upper"],
                                                    fcs_gains.CONTROLLERS[design], [0.4, 0.0, 0.6])}
        assert "omega" in names and not names & {"integral_ratio", "kir_share"}
    names = {p.name for p in dp.free_parameters(cfg.study.parameters, ["stack"], fcs_gains.DESIGN, [0.4, 0.0, 0.6])}
    assert {"integral_ratio", "kir_share"} <= names


def test_the_score_pool_returns_every_point_score_in_order(monkeypatch):
    """Scores computed on 2 forked workers come back in the points' order, for a subset
    of the pool's points as the search asks (each worker gets an interleaved share)."""
    from savant_cli.design import pool as dpool

    def fake_scores(points, ft, dt, axes):  # a point's score: its value x the 'tables'
        return np.array([p.value * ft for p in points])

    monkeypatch.setattr(dpool, "point_scores", fake_scores)
    points = [types.SimpleNamespace(value=float(k)) for k in range(11)]
    subset = points[1::2] + [points[0]]
    with dpool.ScorePool(points, 2) as pool:
        assert pool.workers == 2
        np.testing.assert_array_equal(pool.scores(subset, 3.0, 0.02, ("pitch",)),
                                      [3.0 * p.value for p in subset])
        np.testing.assert_array_equal(pool.scores(points, -1.0, 0.02, ("pitch",)), -np.arange(11.0))
    with dpool.ScorePool(points[:1], 4) as one:  # never more workers than points
        assert one.workers == 1 and one.scores(points[:1], 2.0, 0.02, ("pitch",)).tolist() == [0.0]
