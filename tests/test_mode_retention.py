"""study=mode_retention: the change measures against numpy on synthetic responses and
margins, the recommendation rule, the rigid/flex configs of a count, and end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import assert_report_redraws, compose_config
from savant_cli.config import validate
from savant_cli.studies.mode_retention import CountResult, _config, _margin_change, _response_change, recommend
from test_end_to_end import run


def test_change_measures():
    t = np.linspace(0.0, 5.0, 251)
    a = CountResult(1, t, {"x": np.sin(t), "y": 2.0 * t}, {(55.0, "pitch", "gain", "all"): -9.0,
                                                           (55.0, "pitch", "phase", "all"): 40.0})
    b = CountResult(2, t, {"x": np.sin(t) + 0.1 * np.cos(3 * t), "y": 2.0 * t},
                    {(55.0, "pitch", "gain", "all"): -8.2, (55.0, "pitch", "phase", "all"): 37.0})
    ch = _response_change(a, b)
    assert ch["x"] == pytest.approx(np.max(np.abs(0.1 * np.cos(3 * t))) / np.max(np.abs(np.sin(t))))
    assert ch["y"] == 0.0
    assert _margin_change(a, b) == pytest.approx((0.8, 3.0))
    b.margins[(55.0, "yaw", "gain", "flex")] = 12.0  # a crossing that appears
    assert _margin_change(a, b)[0] == float("inf")


@pytest.mark.parametrize("flags, expected", [
    ([False, False, True, True], (2, True)),
    ([True, True, True, True], (0, True)),
    ([False, True, False], (3, False)),
])
def test_recommendation(flags, expected):
    rows = [{"from_modes": i, "to_modes": i + 1, "converged": f} for i, f in enumerate(flags)]
    assert recommend(rows, list(range(len(flags) + 1))) == expected


def test_count_configs():
    cfg = validate(compose_config(["study=mode_retention"]))
    assert cfg.flex.enabled and cfg.flex.n_modes == 4  # the study switches the flexible body on itself
    assert not _config(cfg, 0).flex.enabled
    three = _config(cfg, 3)
    assert three.flex.enabled and three.flex.n_modes == 3 and cfg.flex.n_modes == 4  # the original untouched
    assert _config(validate(compose_config(["study=mode_retention", "flex=off"])), 2).flex.n_modes == 2


@pytest.mark.slow
def test_mode_retention_end_to_end(tmp_path):
    out = tmp_path / "mr"
    proc = run(["run", "study=mode_retention", "study.max_modes=2", "study.times=[55]", "sim.progress=false",
                f"hydra.run.dir={out}"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["counts"] == [0, 1, 2] and len(summary["steps"]) == 2
    assert summary["recommended_n_modes"] in (0, 1, 2)
    assert (out / "mode_retention.csv").is_file() and (out / "plots" / "mode_retention_margins.png").is_file()
    assert (out / "plots" / "mode_retention_t55_pitch_attitude.png").is_file()
    assert "mode_retention_margins.png" in assert_report_redraws(out)
    bad = run(["run", "study=mode_retention", "study.max_modes=40", "study.times=[55]",
               f"hydra.run.dir={tmp_path}/bad"], cwd=tmp_path)
    assert bad.returncode == 2 and "study.max_modes" in bad.stderr + bad.stdout
