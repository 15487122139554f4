"""``savant run study=linear`` end to end: files, reload, bad times."""

from __future__ import annotations

import csv
import json

import control as ct
import h5py
import numpy as np
import pytest
from scipy.io import loadmat

from conftest import assert_report_redraws
from test_end_to_end import run

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def linear_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("linear")
    proc = run(["run", "study=linear", "study.times=[55,180]", f"hydra.run.dir={out}/run", "sim.progress=false"],
               cwd=out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out / "run", proc


def test_margins_csv_summary_console_and_charts(linear_run):
    run_dir, proc = linear_run
    rows = list(csv.DictReader(open(run_dir / "margins.csv")))
    assert {r["axis"] for r in rows} == {"pitch", "yaw"}
    assert {float(r["time_s"]) for r in rows} == {55.0, 180.0}
    s = json.loads((run_dir / "summary.json").read_text())
    assert len(s["margins"]) == len(rows) and "roll" in s["linear_note"]
    # every row carries its requirement verdict: |margin| against its mode's requirement
    # (conf/requirements/ares_i.yaml: 6 dB and 30 deg for every mode of the rigid vehicle)
    for r in rows:
        need = 6.0 if r["kind"] == "gain" else 30.0
        assert r["meets_requirement"] == ("yes" if abs(float(r["value"])) >= need else "no"), r
    n_ok = sum(r["meets_requirement"] == "yes" for r in rows)
    assert s["margins_meeting_requirements"] == f"{n_ok} of {len(rows)}"
    # a point passes when its margins do and its closed loop is stable; the verdict in one line
    stable = {p["time_s"]: p["closed_loop_stable"] for p in s["linear_points"]}
    passes = {t: stable[t] and all(r["meets_requirement"] == "yes" for r in rows if float(r["time_s"]) == t)
              for t in stable}
    assert [p["passed"] for p in s["requirements"]["points"]] == [passes[55.0], passes[180.0]]
    assert s["requirements_met"] == all(passes.values())
    line = s["requirements_verdict"]
    assert line.startswith(f"requirements ares_i: {'PASS' if all(passes.values()) else 'FAIL'}, "
                           f"{sum(passes.values())} of 2 points pass") and line in proc.stdout
    checks = list(csv.DictReader(open(run_dir / "requirements.csv")))
    assert {c["stage"] for c in checks} == {"first_stage", "upper_stage"}
    assert sum(c["criterion"] == "stability" for c in checks) == 2
    with h5py.File(run_dir / "savant.h5") as f:
        g = f["linear/requirements"]
        assert g.attrs["verdict"] == line and len(g["checks/passed"]) == len(checks)
        assert list(f["linear/margins/meets_requirement"][()]) == [r["meets_requirement"] == "yes" for r in rows]
    # at max-Q the vehicle is aerodynamically unstable: a gain-reduction margin exists
    assert any(r["kind"] == "gain" and float(r["value"]) < 0 and float(r["time_s"]) == 55.0 for r in rows)
    assert "stability margins" in proc.stdout and "left out of the linear analysis" in proc.stdout
    from savant_cli.plots.linear import point_tag

    charts = {p.name for p in (run_dir / "plots" / "linear").iterdir()}
    for kind in ("bode", "nichols", "nyquist", "rootlocus", "pzmap", "response"):
        for t in (55.0, 180.0):
            assert f"{kind}_{point_tag(t)}.png" in charts
    assert "margin_envelope.png" in charts


def test_report_redraws_the_linear_charts(linear_run):
    run_dir, _ = linear_run
    drawn = assert_report_redraws(run_dir)
    assert "linear/rootlocus_t0180.0.png" in drawn and "altitude_mach.png" in drawn
    with h5py.File(run_dir / "savant.h5") as f:  # the chart data an analyst can read
        g = f["linear/t055000/charts"]
        assert g["loop_pitch/f_hz"][0] == pytest.approx(0.01) and g["loop_pitch/response"].dtype.kind == "c"
        assert g["root_locus_yaw/branches"].shape[1] == f["linear/t055000/open_yaw/A"].shape[0]


def test_reloaded_point_reproduces_the_margin_table(linear_run):
    from savant_cli.linear.store import load_point

    run_dir, _ = linear_run
    loop = load_point(run_dir / "savant.h5", 55.0, "open_pitch")
    assert isinstance(loop, ct.StateSpace) and loop.dt == pytest.approx(0.02)
    assert loop.input_labels and loop.output_labels
    from savant_cli.linear.margins import Bands, loop_margins

    again = loop_margins(loop, 55.0, "pitch", Bands())
    rows = [r for r in csv.DictReader(open(run_dir / "margins.csv")) if r["axis"] == "pitch" and r["time_s"] == "55.000"]
    assert len(again) == len(rows)
    for a, r in zip(sorted(again, key=lambda x: (x.kind, x.frequency_hz)), rows):
        assert a.value == pytest.approx(float(r["value"]), abs=1e-3)
    with pytest.raises(KeyError):
        load_point(run_dir / "savant.h5", 56.0)
    with h5py.File(run_dir / "savant.h5") as f:
        names = [n.decode() if isinstance(n, bytes) else n for n in f["linear/t055000/plant_continuous/states"][()]]
        assert "dtheta_y" in names and "q" in names
    mat = loadmat(run_dir / "linear.mat", simplify_cells=True)
    a = mat["t055000"]["open_pitch"]["A"]
    assert np.allclose(a, loop.A)


@pytest.mark.parametrize("times,message", [
    ("[900]", "must be earlier than sim.max_time_s = 800 s"),  # refused before flying (config/study/__init__.py)
    ("[700]", "inside the flight"),  # within sim.max_time_s but after the flown cutoff: known once flown
    ("[130.45]", "event separation"),
])
def test_bad_times_are_config_errors(tmp_path, times, message):
    proc = run(["run", "study=linear", f"study.times={times}", f"hydra.run.dir={tmp_path}/run", "sim.progress=false",
                "output.plots=false"], cwd=tmp_path)
    assert proc.returncode == 2
    assert message in (proc.stdout + proc.stderr).replace("\n", " ")


def test_tailoff_points_are_reported_not_judged(tmp_path):
    """The first-stage tail-off window from the physical criteria (linear/frozen_time.py):
    checked here against the scan the study stores — the period criterion's start lies
    where the stored crossover period equals the time left to separation (linear between
    the bracketing scan points) — and 130 s lies in it, 55 s before it. The window's
    point is analysed (its margins in margins.csv, its checks in requirements.csv) but left
    out of the frequency-domain verdict, and the line says what it would score; the
    time-domain checks judge the window: six flights through separation with a required
    margin used up, each handing over a separation state inside requirements.separation."""
    run_dir = tmp_path / "run"
    proc = run(["run", "study=linear", "study.times=[55,130]", f"hydra.run.dir={run_dir}", "sim.progress=false",
                "output.plots=false"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    s = json.loads((run_dir / "summary.json").read_text())
    with h5py.File(run_dir / "savant.h5") as f:
        names = [n.decode() if isinstance(n, bytes) else n for n in f["events/name"][()]]
        t_sep = float(f["events/time_s"][()][names.index("separation")])
        judged = f["linear/requirements/points/judged"][()]
        assert f["linear/requirements"].attrs["verdict"] == s["requirements_verdict"]
    w = s["tailoff_window"]
    scan = w["scan"]
    left = np.array([t_sep - p["time_s"] - p["period_s"] for p in scan])
    i = int(np.flatnonzero(left > 0)[-1])
    expected = scan[i]["time_s"] + (scan[i + 1]["time_s"] - scan[i]["time_s"]) * left[i] / (left[i] - left[i + 1])
    assert w["starts"]["period"] == pytest.approx(expected, abs=1e-9)
    assert w["end_s"] == pytest.approx(t_sep) and s["tailoff_window_start_s"] == min(w["starts"].values())
    assert 110.0 < s["tailoff_window_start_s"] < 130.0
    assert list(judged) == [True, False] and s["points_not_judged"] == 1
    not_judged = s["requirements"]["not_judged"]
    assert [p["time_s"] for p in not_judged] == [130.0]
    pm130 = [m for m in s["margins"] if m["time_s"] == 130.0 and m["kind"] == "phase"]
    assert pm130 and min(m["value"] for m in pm130) < 30.0  # it fails the 30 deg, and says so
    assert not not_judged[0]["passed"] and "would fail" in s["requirements_verdict"]
    assert s["requirements"]["points_passing"] == "1 of 1"
    checks = s["tailoff_checks"]
    assert [(c["axis"], c["kind"]) for c in checks] == [(a, k) for a in ("pitch", "yaw")
                                                         for k in ("gain_high", "gain_low", "delay")]
    assert all(c["separated"] and c["met"] for c in checks) and s["tailoff_checks_met"]
    assert all(c["separation_body_rate_deg_s"] <= 2.0 for c in checks)
    assert "judged in the time domain: PASS, 6 of 6 checks" in proc.stdout.replace("\n", " ")
    assert {float(r["time_s"]) for r in csv.DictReader(open(run_dir / "requirements.csv"))} == {55.0, 130.0}
