"""study=flyoff: the comparison's percentiles and winners against numpy on synthetic
tables, unknown controllers refused by name, and end to end: both controllers fly the
same dispersed vehicles and the comparison files are written."""

from __future__ import annotations

import csv
import json

import h5py
import numpy as np
import pytest

from browser import assert_page_reads, require_chromium
from conftest import assert_report_redraws, compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir
from savant_cli.studies.flyoff import METRICS, _controllers, compare
from test_end_to_end import run


def _table(rng, shift: float, n: int = 200) -> dict[str, np.ndarray]:
    t = {"run": np.arange(n), "ok": np.ones(n, bool)}
    for m in METRICS:
        t[m] = rng.normal(10.0 + shift, 1.0, n)
    t["ok"][5] = False  # a failed run is left out of the percentiles
    t["max gimbal angle"][5] = 1e9
    return t


def test_compare_picks_the_better_tail_of_each_metric():
    rng = np.random.default_rng(1)
    a, b = _table(rng, 0.0), _table(rng, 0.5)
    rows = {r["metric"]: r for r in compare({"a": a, "b": b})}
    for m, (_, better, _) in METRICS.items():
        r = rows[m]
        pct = 99.865 if better == "low" else 0.135
        for name, t in (("a", a), ("b", b)):
            assert r[f"{name}_nominal"] == t[m][0]
            assert r[f"{name}_dispersed"] == pytest.approx(np.percentile(t[m][t["ok"]], pct))
        lower_a = r["a_dispersed"] < r["b_dispersed"]
        assert r["winner"] == ("a" if lower_a == (better == "low") else "b")
    tie = compare({"a": a, "b": {k: v.copy() for k, v in a.items()}})
    assert all(r["winner"] == "tie" for r in tie)


def test_unknown_or_single_controller_is_refused():
    cfg = validate(compose_config(["study=flyoff", "study.controllers=[msfc_pid,nasa_lqr]"]))
    with pytest.raises(ConfigError) as err:
        _controllers(cfg.study, [shipped_config_dir()])
    assert err.value.key == "study.controllers[1]" and "larc_pd" in str(err.value)
    with pytest.raises(ConfigError) as err:
        validate(compose_config(["study=flyoff", "study.controllers=[msfc_pid,msfc_pid]"]))
    assert err.value.key == "study.controllers"


@pytest.mark.slow
def test_flyoff_end_to_end(tmp_path):
    out = tmp_path / "fo"
    proc = run(["run", "study=flyoff", "phase=first_stage", "study.n_runs=4", "study.linear_times=[55]",
                "sim.progress=false", f"hydra.run.dir={out}"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = list(csv.DictReader(open(out / "flyoff.csv")))
    assert {r["metric"] for r in rows} == set(METRICS)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controllers"] == ["msfc_pid", "larc_pd"] and sum(summary["wins"].values()) <= len(METRICS)
    for ctrl in ("msfc_pid", "larc_pd"):  # each batch judged against the requirement set at 55 s
        with h5py.File(out / ctrl / "savant.h5") as f:
            g = f["montecarlo/requirements"]
            passed, run_of = g["checks/passed"][()], g["checks/run"][()]
            n_pass = sum(passed[run_of == r].all() for r in np.unique(run_of))
            assert summary["runs_meeting_requirements"][ctrl] == f"{n_pass} of {len(np.unique(run_of))}"
            assert summary["requirements_verdict"][ctrl] == g.attrs["verdict"]
            assert f"{ctrl}: {g.attrs['verdict']}" in proc.stdout
    with h5py.File(out / "msfc_pid" / "savant.h5") as a, h5py.File(out / "larc_pd" / "savant.h5") as b:
        for k in a["montecarlo/dispersions"]:  # the same dispersed vehicles
            assert np.array_equal(a[f"montecarlo/dispersions/{k}"][()], b[f"montecarlo/dispersions/{k}"][()],
                                  equal_nan=True)
        ga, gb = a["montecarlo/histories/gimbal_angle_pitch"][0], b["montecarlo/histories/gimbal_angle_pitch"][0]
        assert not np.allclose(ga, gb, equal_nan=True)  # different controllers fly differently
    assert (out / "plots" / "flyoff_histograms.png").is_file()
    assert (out / "plots" / "flyoff_attitude_error_pitch.png").is_file()
    assert "flyoff_histograms.png" in assert_report_redraws(out)
    require_chromium()
    assert_page_reads(out)  # the study's page as a reviewer reads it (tests/test_html_report.py reads the others)
    assert "histograms_01.png" in assert_report_redraws(out / "larc_pd")  # one controller's batch
    bad = run(["run", "study=flyoff", "study.controllers=[msfc_pid,nope]", f"hydra.run.dir={tmp_path}/bad"],
              cwd=tmp_path)
    assert bad.returncode == 2 and "study.controllers[1]" in bad.stderr + bad.stdout


def test_larc_controller_is_a_pd_design():
    """The shipped alternative has no integral paths (Ki = Kir = 0 on every breakpoint),
    attitude and rate gains everywhere, and the PID has its integral: the two laws differ
    as the paper's fly-off needs (both tuned by study=fcs_design, their own blends)."""
    pd = validate(compose_config(["controller=larc_pd"])).controller
    pid = validate(compose_config([])).controller
    for phase in ("stack", "upper"):
        g, h = getattr(pd.gains, phase).pitch, getattr(pid.gains, phase).pitch
        assert not any(g.ki) and not any(g.kir)
        assert all(k > 0 for k in g.kp) and all(k > 0 for k in g.kd)
        assert any(k > 0 for k in h.ki) and any(k > 0 for k in h.kir)
    assert pd.design.rules == "larc_pd" and pid.design.rules == "msfc_pid"
