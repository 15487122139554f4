"""Monte Carlo through the `savant` command: a Hydra joblib-launcher multirun of shards,
`savant collect` (identical to one unsharded batch; missing runs named), `savant rerun`
(bit-identical to the batch record) and the batch outputs and plots."""

from __future__ import annotations

import csv
import json

import h5py
import numpy as np
import pytest

from conftest import assert_report_redraws
from savant_cli.io.bitwise import compare_h5
from test_end_to_end import run

pytestmark = pytest.mark.slow

BASE = ["study=montecarlo", "phase=first_stage", "study.n_runs=6", "sim.progress=false"]


@pytest.fixture(scope="module")
def batches(tmp_path_factory):
    root = tmp_path_factory.mktemp("mc")
    single = run(["run", *BASE, "study.workers=2", f"hydra.run.dir={root}/single"], cwd=root)
    assert single.returncode == 0, single.stdout + single.stderr
    (root / "single_stdout.txt").write_text(single.stdout)
    multi = run(["run", "-m", *BASE, "study.shards=3", "study.shard=range(0,3)", "study.workers=1",
                 "hydra/launcher=joblib", "hydra.launcher.n_jobs=2", "output.plots=false",
                 f"hydra.sweep.dir={root}/multi"], cwd=root)
    assert multi.returncode == 0, multi.stdout + multi.stderr
    return root


def _tables(path):
    with h5py.File(path) as f:
        g = f["montecarlo"]
        order = np.argsort(g["runs/run"][()])
        return {k: g[f"summary/{k}"][()][order] for k in g["summary"]}, g["runs/run"][()][order], \
            {k: g[f"dispersions/{k}"][()][order] for k in g["dispersions"]}


def test_single_batch_writes_every_output(batches):
    out = batches / "single"
    for name in ("savant.h5", "summary.json", "minmax.csv", "percentiles.csv", "dispersion_statistics.csv",
                 "plots/histograms_01.png", "plots/envelope_dynamic_pressure.png", "plots/dispersions/histograms_01.png"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["n_runs_present"] == 6 and summary["status_counts"] == {"complete": 6}
    rel = summary["reliability"]  # 6 successes of 6 at 90 %: (1 - 0.9)^(1/6), closed form
    assert (rel["runs"], rel["successes"], rel["failures"]) == (6, 6, 0)
    assert rel["demonstrated_probability"] == pytest.approx(0.1 ** (1 / 6), rel=1e-9) and not rel["target_met"]
    assert "success 6 of 6 runs" in (batches / "single_stdout.txt").read_text()
    drawn = assert_report_redraws(out)
    assert {"histograms_01.png", "envelope_dynamic_pressure.png", "dispersions/histograms_01.png"} <= set(drawn)
    rows = {r["variable"]: r for r in csv.DictReader(open(out / "minmax.csv"))}
    q, runs, _ = _tables(out / "savant.h5")
    k = "max_dynamic_pressure_Pa"
    assert float(rows[k]["max"]) == pytest.approx(q[k].max(), rel=1e-9)
    assert int(rows[k]["max_run"]) == runs[np.argmax(q[k])] and int(rows[k]["min_run"]) == runs[np.argmin(q[k])]
    with h5py.File(out / "savant.h5") as f:
        assert f["montecarlo/histories/dynamic_pressure"].shape[0] == 6
        assert f["montecarlo/dispersions/wind_profile"].attrs["dist"] == "choice"


def test_joblib_shards_collected_equal_the_single_batch(batches):
    multi = batches / "multi"
    proc = run(["collect", str(multi)], cwd=batches)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    a, runs_a, da = _tables(batches / "single" / "savant.h5")
    b, runs_b, db = _tables(multi / "savant.h5")
    assert runs_b.tolist() == list(range(6)) == runs_a.tolist()
    for k in a:
        assert np.array_equal(a[k], b[k], equal_nan=True), k
    for k in da:
        assert np.array_equal(da[k], db[k], equal_nan=True), k
    assert compare_h5(batches / "single" / "savant.h5", multi / "savant.h5") == []  # every dataset, bit for bit


def test_rerun_reproduces_one_run_with_its_history(batches):
    proc = run(["rerun", str(batches / "single"), "run=4"], cwd=batches)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "identical to the batch record" in proc.stdout
    out = batches / "single" / "rerun_000004"
    assert (out / "savant.h5").is_file() and (out / "plots").is_dir()
    summary = json.loads((out / "summary.json").read_text())
    q, runs, _ = _tables(batches / "single" / "savant.h5")
    assert summary["max_dynamic_pressure_Pa"] == q["max_dynamic_pressure_Pa"][list(runs).index(4)]


def test_collect_names_missing_runs(batches, tmp_path):
    import shutil

    copy = tmp_path / "multi"
    shutil.copytree(batches / "multi", copy)
    next(copy.rglob("runs/run_000004.npz")).unlink()
    proc = run(["collect", str(copy)], cwd=tmp_path)
    assert proc.returncode == 1
    assert "missing runs" in proc.stdout and "4" in proc.stdout
    text = "".join(proc.stdout.split())  # the console wraps at 80 columns, anywhere in a long path
    assert "shard2(" in text and "):runs4" in text and "nothingwritten" in text  # without --allow-missing
    bad = run(["rerun", str(batches / "single"), "run=99"], cwd=tmp_path)
    assert bad.returncode == 2 and "run" in bad.stderr
