"""study=flex_sweep: the scaled models against their own definitions (the linearized
flex poles move by exactly the frequency factor; vanishing mode shapes give back the
rigid vehicle's margins), bad grids refused by name, and the study end to end."""

from __future__ import annotations

import csv
import json
import warnings

import pytest

from conftest import assert_report_redraws, compose_config, linear_settings
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.linear.plant import linearize_plant
from savant_cli.linear.point_analysis import analyse
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.studies.flex_sweep import variant
from test_end_to_end import run

T = 55.0


def _point(overrides):
    model = prepare(validate(compose_config(overrides))).model
    k = int(round(T / model.rates.dt))
    return model, simulate(model, progress=False, snapshot_steps=(k,)).snapshots[k]


@pytest.fixture(scope="module")
def flex_point():
    return _point(["flex=on", "flex.n_modes=2"])


def test_scaled_models_change_exactly_the_modal_terms(flex_point):
    """Frequency × k changes the modal stiffness ∂q̈ᵢ/∂qᵢ by −(k² − 1)ωᵢ² (the
    follower-thrust stiffness, the same in both, cancels); shape × k scales the gyros'
    reading of q̇ᵢ by k. Only the chosen modes."""
    model, snap = flex_point
    nominal = linearize_plant(model, snap).sys
    names = nominal.state_labels
    w = model.tables.flex_freq[0, :2]
    for level, modes in ((0.8, []), (1.25, [2])):
        a = linearize_plant(variant(model, "frequency", level, modes), snap).sys.A
        for i in range(2):
            k = level if not modes or i + 1 in modes else 1.0
            r, c = names.index(f"flex_q{i + 1}_dot"), names.index(f"flex_q{i + 1}")
            assert a[r, c] - nominal.A[r, c] == pytest.approx(-(k * k - 1.0) * w[i] ** 2, rel=1e-4)
    shaped = linearize_plant(variant(model, "shape", 1.3, [1]), snap).sys
    gyros = [j for j, n in enumerate(nominal.output_labels) if n.startswith("gyro_")]
    for i, k in ((0, 1.3), (1, 1.0)):
        qd = names.index(f"flex_q{i + 1}_dot")
        row = max(gyros, key=lambda j: abs(nominal.C[j, qd]))  # the gyro axis in the mode's plane
        assert abs(nominal.C[row, qd]) > 1e-9
        assert shaped.C[row, qd] == pytest.approx(k * nominal.C[row, qd], rel=1e-5)


def test_vanishing_mode_shapes_give_the_rigid_margins(flex_point):
    model, snap = flex_point
    rigid_model, rigid_snap = _point([])
    lin = linear_settings([T])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows_flex = analyse(variant(model, "shape", 1e-6, []), snap, lin, 0.02).rows
        rows_rigid = analyse(rigid_model, rigid_snap, lin, 0.02).rows
    key = lambda r: (r.axis, r.kind, r.frequency_hz)  # noqa: E731
    rows_flex, rows_rigid = sorted(rows_flex, key=key), sorted(rows_rigid, key=key)
    # the same crossings, no flex resonance left: every margin as the rigid vehicle's
    assert [(r.axis, r.kind) for r in rows_flex] == [(r.axis, r.kind) for r in rows_rigid] and len(rows_flex) >= 6
    for a, b in zip(rows_flex, rows_rigid):
        assert a.frequency_hz == pytest.approx(b.frequency_hz, rel=0.01)
        assert a.value == pytest.approx(b.value, abs=0.05 if a.kind == "gain" else 0.1)


@pytest.mark.parametrize("overrides, key", [
    (["study.levels=[0.5,0.0]"], "study.levels[1]"),
    (["study.levels=[-1.0]"], "study.levels[0]"),
    (["study.parameters=[stiffness]"], "study.parameters[0]"),
    (["study.modes=[0]"], "study.modes[0]"),
])
def test_bad_grids_are_refused(overrides, key):
    with pytest.raises(ConfigError) as err:
        validate(compose_config(["study=flex_sweep", "flex=on", *overrides]))
    assert err.value.key == key


@pytest.mark.slow
def test_flex_sweep_end_to_end(tmp_path):
    out = tmp_path / "fs"
    proc = run(["run", "study=flex_sweep", "flex.n_modes=2", "study.times=[55,180]",  # flex=on by itself
                "study.levels=[0.8,1.0,1.2]", "sim.progress=false", f"hydra.run.dir={out}"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = list(csv.DictReader(open(out / "flex_sweep.csv")))
    cases = {(r["time_s"], r["parameter"], r["level"]) for r in rows}
    assert len(cases) == 2 * 2 * 3
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["cases"]) == 12
    # each case judged against the requirement set: failing cases name their worst offender
    for c in summary["cases"]:
        case_rows = [r for r in rows if (float(r["time_s"]), r["parameter"], float(r["level"]))
                     == (c["time_s"], c["parameter"], c["level"])]
        assert c["meets_requirements"] == (c["violations"] == 0)
        if any(r["meets_requirement"] == "False" for r in case_rows) or not c["closed_loop_stable"]:
            assert not c["meets_requirements"] and c["worst"].startswith(f"{c['time_s']:.1f} s")
    n_pass = sum(c["meets_requirements"] for c in summary["cases"])
    assert summary["requirements_verdict"].startswith(f"requirements ares_i: {'PASS' if n_pass == 12 else 'FAIL'}, "
                                                      f"{n_pass} of 12 cases pass")
    assert summary["requirements_verdict"] in proc.stdout
    for t in ("0055.0", "0180.0"):
        for prm in ("frequency", "shape"):
            assert (out / "plots" / "flex_sweep" / f"nichols_pitch_{prm}_t{t}.png").is_file()
    assert "flex_sweep/nichols_pitch_shape_t0180.0.png" in assert_report_redraws(out)
    off = run(["run", "study=flex_sweep", "flex=off", f"hydra.run.dir={tmp_path}/off"], cwd=tmp_path)
    assert off.returncode == 2 and "flex=on" in off.stderr + off.stdout  # the user's flex=off is refused
