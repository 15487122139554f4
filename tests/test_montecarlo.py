"""Monte Carlo: sampling against the distributions' own moments (scipy.stats and closed
forms), the correlation a Gaussian copula must give, spec errors before anything flies,
bit-identical results whatever the workers or sharding, failure recording, and a batch
killed mid-way that resumes without losing or repeating a run."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from scipy import stats

from conftest import compose_config
from savant_cli.config import CorrelationGroup, DispersionSetConfig, DispersionSpec, validate
from savant_cli.errors import ConfigError
from savant_cli.montecarlo.batch import RUN_STAGES, Journal, execute, read_outcome, shard_runs
from savant_cli.montecarlo.inventory import inventory, ranges_text
from savant_cli.montecarlo.spec import parse
from savant_cli.montecarlo.targets import apply_samples
from savant_cli.paths import shipped_config_dir
from savant_cli.sim.setup import prepare
from savant_cli.studies.montecarlo import make_case

SHORT = ["study=montecarlo", "phase=first_stage", "study.histories.rate_hz=2"]


@pytest.fixture(scope="module")
def base():
    cfg = validate(compose_config(SHORT))
    return cfg, prepare(cfg).vehicle


def _study(cfg, dispersions: dict, correlations=()):
    """A dispersion set of these items and correlations."""
    return DispersionSetConfig(name="test", items={k: DispersionSpec(**v) for k, v in dispersions.items()},
                               correlations=[CorrelationGroup(*c) for c in correlations])


def _draws(dset, n: int) -> np.ndarray:
    return np.array([dset.numbers(r, dset.sample(r)) for r in range(1, n + 1)])


def test_each_distribution_has_its_moments(base):
    cfg, vehicle = base
    spec = {
        "n": {"target": "winds.scale", "apply": "value", "mean": 1.2, "sigma": 0.1},
        "tn": {"target": "tables.aero.CA", "apply": "scale", "sigma": 0.05, "truncate_sigma": 1.5},
        "u": {"target": "tables.aero.CN", "apply": "scale", "dist": "uniform", "low": 0.9, "high": 1.3},
        "tri": {"target": "tables.stack.cg_x", "apply": "offset", "dist": "triangular", "low": -0.2, "mode": 0.1,
                "high": 0.3},
        "c": {"target": "winds.scale", "apply": "scale", "dist": "choice", "values": [0.5, 1.0, 2.0],
              "weights": [1.0, 2.0, 1.0]},
        "k": {"target": "tables.aero.Cm", "apply": "scale", "dist": "constant", "value": 1.1},
        "w": {"target": "winds", "apply": "value", "dist": "choice", "values": ["ksc_mean_annual", "none"]},
    }
    dset = parse(_study(cfg, spec), cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    n = 12000
    x = _draws(dset, n)
    col = {name: x[:, i] for i, name in enumerate(dset.names)}
    se = 4.0 / np.sqrt(n)  # 4 standard errors (per unit σ)
    assert abs(col["n"].mean() - 1.2) < se * 0.1 and abs(col["n"].std() - 0.1) < 0.1 * 4 / np.sqrt(2 * n)
    tn = stats.truncnorm(-1.5, 1.5, loc=1.0, scale=0.05)
    assert col["tn"].min() >= 1.0 - 0.075 and col["tn"].max() <= 1.0 + 0.075
    assert abs(col["tn"].std() - tn.std()) < 0.02 * tn.std()
    assert abs(col["u"].mean() - 1.1) < se * 0.4 / np.sqrt(12) and col["u"].min() >= 0.9 and col["u"].max() <= 1.3
    assert abs(col["u"].var() - 0.4**2 / 12) < 0.03 * 0.4**2 / 12
    tri = stats.triang((0.1 + 0.2) / 0.5, loc=-0.2, scale=0.5)
    assert abs(col["tri"].mean() - tri.mean()) < se * tri.std() and abs(col["tri"].std() - tri.std()) < 0.02 * tri.std()
    freq = np.array([np.mean(col["c"] == v) for v in (0.5, 1.0, 2.0)])
    assert np.allclose(freq, [0.25, 0.5, 0.25], atol=4 * np.sqrt(0.25 / n))
    assert np.all(col["k"] == 1.1)
    assert set(np.unique(col["w"])) == {0.0, 1.0}  # option index
    # run 0 is the nominal: scale 1, offset 0, value NaN
    nom = dict(zip(dset.names, dset.numbers(0, dset.sample(0))))
    assert nom["tn"] == 1.0 and nom["tri"] == 0.0 and np.isnan(nom["n"])


def test_correlation_is_honoured(base):
    """Gaussian copula: normal pairs keep ρ; uniform marginals get (6/π) asin(ρ/2)."""
    cfg, vehicle = base
    spec = {"a": {"target": "tables.aero.CA", "sigma": 0.1}, "b": {"target": "tables.aero.CN", "sigma": 0.2},
            "c": {"target": "tables.aero.CY", "dist": "uniform", "low": 0.0, "high": 1.0},
            "d": {"target": "tables.aero.Cm", "dist": "uniform", "low": 0.0, "high": 2.0}}
    rho = 0.7
    dset = parse(_study(cfg, spec, [(["a", "b"], [[1, rho], [rho, 1]]), (["c", "d"], [[1, -rho], [-rho, 1]])]),
                 cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    x = _draws(dset, 10000)
    tol = 4 * (1 - rho**2) / np.sqrt(10000)
    assert np.corrcoef(x[:, 0], x[:, 1])[0, 1] == pytest.approx(rho, abs=tol)
    assert np.corrcoef(x[:, 2], x[:, 3])[0, 1] == pytest.approx(6 / np.pi * np.arcsin(-rho / 2), abs=tol)
    assert abs(np.corrcoef(x[:, 0], x[:, 2])[0, 1]) < 4 / np.sqrt(10000)  # groups independent
    # a run's draws do not depend on which other dispersions exist
    both = parse(_study(cfg, {"a": spec["a"], "c": spec["c"]}), cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    alone = parse(_study(cfg, {"a": spec["a"]}), cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    assert both.normals(5)[0] == alone.normals(5)[0] and both.normals(5)[1] != both.normals(6)[1]


@pytest.mark.parametrize("spec, corr, key, words", [
    ({"x": {"target": "winds.nope"}}, [], "dispersions.items.x.target", "unknown target"),
    ({"x": {"target": "tables.aero.CQ"}}, [], "dispersions.items.x.target", "unknown table target"),
    ({"x": {"target": "winds.enabled"}}, [], "dispersions.items.x.target", "must name a number"),
    ({"x": {"target": "winds.scale", "sigma": -0.1}}, [], "dispersions.items.x.sigma", "zero or positive"),
    ({"x": {"target": "winds.scale", "dist": "uniform", "low": 2.0, "high": 1.0}}, [], "dispersions.items.x.low",
     "must not exceed"),
    ({"x": {"target": "winds.scale", "dist": "uniform", "low": 0.0, "high": 1.0, "sigma": 0.1}}, [],
     "dispersions.items.x.sigma", "not used by dist uniform"),
    ({"x": {"target": "winds.scale", "dist": "choice", "values": [1.0, 2.0], "weights": [1.0]}}, [],
     "dispersions.items.x.weights", "non-negative"),
    ({"x": {"target": "winds", "apply": "value", "dist": "choice", "values": ["ksc_mean_annual", "hurricane"]}}, [],
     "dispersions.items.x.values", "unknown winds options"),
    ({"x": {"target": "tables.first_stage.burn_rate", "apply": "offset", "sigma": 0.1}}, [], "dispersions.items.x.apply",
     "takes apply: scale"),
    ({"x": {"target": "tables.first_stage.thrust", "sigma": 0.01}}, [], "dispersions.items.x.target",
     "tables.first_stage.burn_rate"),
    ({"a": {"target": "tables.aero.CA", "sigma": 0.1}, "b": {"target": "tables.aero.CN", "sigma": 0.1},
      "c": {"target": "tables.aero.CY", "sigma": 0.1}},
     [(["a", "b", "c"], [[1, 0.9, -0.9], [0.9, 1, 0.9], [-0.9, 0.9, 1]])], "dispersions.correlations[0].matrix",
     "positive semi-definite"),
    ({"a": {"target": "tables.aero.CA", "sigma": 0.1}}, [(["a", "zz"], [[1, 0], [0, 1]])],
     "dispersions.correlations[0].names", "not a dispersion"),
])
def test_bad_specs_are_refused_before_anything_runs(base, spec, corr, key, words):
    cfg, vehicle = base
    with pytest.raises(ConfigError) as err:
        parse(_study(cfg, spec, corr), cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    assert err.value.key == key and words in str(err.value)


def test_a_key_of_a_model_switched_off_is_an_inactive_dispersion(base):
    """flex.damping with flex=off, a third-order key with the simplex actuator: drawn and
    recorded, applied to nothing, and named as such; the other dispersions' draws do
    not change."""
    cfg, vehicle = base
    spec = {"fl": {"target": "flex.damping", "sigma": 0.1}, "w": {"target": "winds.scale", "sigma": 0.1}}
    dset = parse(_study(cfg, spec), cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    fl = dset.items[0]
    assert fl.target.kind == "inactive" and "flex=on" in fl.target.note and "flex=off" in fl.target.note
    alone = parse(_study(cfg, {"w": spec["w"]}), cfg.study.seed, cfg, vehicle, [shipped_config_dir()])
    assert dset.sample(3)[1] == alone.sample(3)[0]
    applied = apply_samples(cfg, vehicle, dset.triples(dset.sample(3)), {})
    assert applied.cfg.flex == cfg.flex and applied.cfg.winds.scale == pytest.approx(cfg.winds.scale * dset.sample(3)[1])
    simplex = validate(compose_config([*SHORT, "actuator=simplex"]))
    act = parse(_study(simplex, {"a": {"target": "actuator.first_stage.natural_frequency_hz", "sigma": 0.05}}),
                simplex.study.seed, simplex, vehicle, [shipped_config_dir()]).items[0]
    assert act.target.kind == "inactive" and "actuator=third_order" in act.target.note


def test_study_keys_are_checked_by_compose():
    with pytest.raises(ConfigError) as err:
        validate(compose_config(SHORT + ["study.n_runs=0"]))
    assert err.value.key == "study.n_runs"
    with pytest.raises(ConfigError) as err:
        validate(compose_config(SHORT + ["study.shards=4", "study.shard=4"]))
    assert err.value.key == "study.shard"
    with pytest.raises(ConfigError) as err:
        validate(compose_config(SHORT + ["+dispersions.items.bad.wrong_key=1"]))
    assert "dispersions.items.bad.wrong_key" in err.value.key


@pytest.fixture(scope="module")
def case():
    cfg = validate(compose_config(SHORT + ["study.n_runs=6", "study.histories.signals=[dynamic_pressure,gimbal_angle]"]))
    return make_case(cfg)[0]


def _fly(case, folder: Path, runs, workers: int) -> dict[int, object]:
    journal = Journal(folder, case.cfg, case.dispersions.names)
    stop = execute(case, runs, journal, workers, lambda o: None)
    assert stop.reason == "done"
    return {r: read_outcome(p) for r, p in inventory([folder]).files.items()}


def test_results_are_bit_identical_for_workers_and_shards(case, tmp_path):
    one = _fly(case, tmp_path / "one" / "runs", range(6), 1)
    two = _fly(case, tmp_path / "two" / "runs", range(6), 2)
    for s in range(3):
        _fly(case, tmp_path / f"shard{s}" / "runs", shard_runs(6, 3, s), 1)
    merged = inventory([tmp_path / f"shard{s}" / "runs" for s in range(3)])
    assert sorted(merged.files) == list(range(6)) and not merged.duplicates
    for r in range(6):
        a, b, c = one[r], two[r], read_outcome(merged.files[r])
        assert a.status == "complete"
        for o in (b, c):
            assert o.summary_keys == a.summary_keys
            assert np.array_equal(o.summary, a.summary) and np.array_equal(o.histories, a.histories, equal_nan=True)
            assert np.array_equal(o.values, a.values, equal_nan=True)
    # dispersed runs differ from the nominal and from each other
    q = [one[r].summary[one[r].summary_keys.index("max_dynamic_pressure_Pa")] for r in range(6)]
    assert len(set(q)) == 6
    # the journal keeps where each run's time went: its stages add up to its wall time
    for o in one.values():
        assert o.stage_wall_s.shape == (len(RUN_STAGES),) and np.all(o.stage_wall_s >= 0.0)
        assert o.stage_wall_s.sum() == pytest.approx(o.wall_s, rel=1e-12)
        assert o.stage_wall_s[RUN_STAGES.index("simulate")] > 0.0


def test_failing_runs_are_recorded_and_the_batch_goes_on(tmp_path):
    cfg = validate(compose_config(SHORT + ["study.n_runs=8", "study.histories.signals=[]"]))
    # a destabilizing pitch moment in some runs, an invalid gyro damping in others
    cfg.dispersions = DispersionSetConfig(name="failing", items={
        "cm": DispersionSpec(target="tables.aero.Cm", dist="choice", values=[1.0, 200.0], weights=[0.5, 0.5]),
        "gyro": DispersionSpec(target="sensors.rate_gyro.damping", apply="value", dist="choice", values=[0.7, -1.0],
                               weights=[0.75, 0.25]),
    })
    case, _ = make_case(cfg)
    out = _fly(case, tmp_path / "runs", range(8), 2)
    status = {r: o.status for r, o in out.items()}
    assert len(out) == 8 and status[0] == "complete"
    assert "diverged" in status.values() and "invalid" in status.values() and "complete" in status.values()
    for o in out.values():
        cm, gyro = o.values
        if gyro < 0:
            assert o.status == "invalid" and "sensors.rate_gyro.damping" in o.message
        elif cm > 1.0:
            assert o.status == "diverged" and "diverged at t =" in o.message and o.t_final < 130.0
        else:
            assert o.status == "complete"


def test_journal_refuses_a_different_configuration(case, tmp_path):
    Journal(tmp_path / "runs", case.cfg, case.dispersions.names)
    other = dataclasses.replace(case.cfg, study=dataclasses.replace(case.cfg.study, seed=1))
    with pytest.raises(ConfigError) as err:
        Journal(tmp_path / "runs", other, case.dispersions.names)
    assert "different configuration" in str(err.value)
    assert ranges_text([0, 1, 2, 5, 7, 8]) == "0-2, 5, 7-8"


@pytest.mark.slow
def test_killed_batch_resumes_without_losing_or_repeating_runs(tmp_path):
    """SIGKILL the whole batch (main process and workers) part-way, restart the same
    command: every run is there once and equals the uninterrupted batch."""
    out = tmp_path / "mc"
    cmd = [sys.executable, "-m", "savant_cli.cli", "run", *SHORT, "study.n_runs=24", "study.workers=2",
           "study.histories.signals=[]", "output.plots=false", "sim.progress=false", f"hydra.run.dir={out}"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[1]), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 300
    while time.time() < deadline and len(list((out / "runs").glob("run_*.npz"))) < 6:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    first = sorted(p.name for p in (out / "runs").glob("run_*.npz"))
    assert 6 <= len(first) < 24, "the kill came too late to test a resume"
    again = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stdout + again.stderr
    assert "resuming" in again.stdout
    files = sorted((out / "runs").glob("run_*.npz"))
    assert [int(p.stem[4:]) for p in files] == list(range(24))
    with h5py.File(out / "savant.h5") as f:
        runs = f["montecarlo/runs/run"][()]
        assert sorted(runs.tolist()) == list(range(24))
        q = f["montecarlo/summary/max_dynamic_pressure_Pa"][()]
    # the same runs flown in one uninterrupted batch in this process
    cfg = validate(compose_config(SHORT + ["study.n_runs=24", "study.histories.signals=[]"]))
    ref = _fly(make_case(cfg)[0], tmp_path / "ref" / "runs", [0, 5, 23], 1)
    for r in (0, 5, 23):
        k = ref[r].summary_keys.index("max_dynamic_pressure_Pa")
        assert q[list(runs).index(r)] == ref[r].summary[k]


def test_margins_of_every_run_and_their_spread(tmp_path):
    """study.linear_times: each run carries its loop margins (the aerodynamic gain margin
    at max-Q among them) with their requirement checks, and the spread keeps each run's
    critical crossing per mode and counts the runs whose crossing misses its requirement."""
    from savant_cli.linear.requirements import CHECK_ARRAY_COLUMNS, mode_code
    from savant_cli.montecarlo.analysis import margin_spread
    from savant_cli.montecarlo.batch import MARGIN_ARRAY_COLUMNS

    cfg = validate(compose_config(SHORT + ["study.n_runs=3", "study.histories.signals=[]", "study.linear_times=[55]"]))
    case = make_case(cfg)[0]
    out = _fly(case, tmp_path / "runs", range(3), 1)
    for o in out.values():
        m = o.margins
        assert m.shape[1] == len(MARGIN_ARRAY_COLUMNS) == 8 and np.all(m[:, 0] == 55.0)
        aero = m[(m[:, 1] == 0) & (m[:, 2] == 0) & (m[:, 4] < 0)]  # pitch gain margins below 0 dB
        assert aero.size and -20.0 < aero[0, 4] < -3.0 and aero[0, 6] == mode_code("aero")
        # the verdict of each row is |margin| >= 6 (the ares_i set: 6 dB, 30 deg everywhere)
        assert np.array_equal(m[:, 7] == 1.0, np.abs(m[:, 4]) >= np.where(m[:, 2] == 0, 6.0, 30.0))
        c = o.checks
        assert c.shape[1] == len(CHECK_ARRAY_COLUMNS) and np.all(c[:, 0] == 55.0)
        assert (c[:, 2] == mode_code("closed_loop")).sum() == 1  # one stability check per point
    rigid, aero = mode_code("rigid"), mode_code("aero")
    table = np.array([[0, 55.0, 0, 0, 0, -9.0, 0.09, aero, 1], [0, 55.0, 0, 0, 0, 13.0, 1.3, rigid, 1],
                      [1, 55.0, 0, 0, 0, -7.5, 0.09, aero, 1], [1, 55.0, 0, 0, 0, 12.0, 1.3, rigid, 1],
                      [2, 55.0, 0, 0, 0, -11.0, 0.09, aero, 1], [2, 55.0, 0, 0, 0, 5.0, 1.3, rigid, 0]])
    rows = {r["mode"]: r for r in margin_spread(table)}
    assert set(rows) == {"rigid", "aero"}
    assert rows["rigid"]["runs"] == 3 and rows["rigid"]["worst"] == 5.0 and rows["rigid"]["worst_run"] == 2
    assert rows["rigid"]["runs_below_requirement"] == 1 and rows["aero"]["runs_below_requirement"] == 0
    assert rows["aero"]["worst"] == -7.5 and rows["aero"]["worst_run"] == 1  # the critical crossings: -9, -7.5, -11
    assert rows["aero"]["min"] == -11.0 and rows["aero"]["max"] == -7.5


def test_slosh_modes_are_named_by_the_vehicles_tanks(case, tmp_path):
    """A vehicle's first two sloshing tanks take the slosh codes every batch wrote before
    (3, 4: ``slosh_lox``, ``slosh_lh2`` for the default names), its others −1, −2; the
    batch's manifest records tanks other than the default, and its tables, spread and
    verdicts name the modes by them."""
    from savant_cli.linear.requirements import DEFAULT_SLOSH_TANKS, mode_code, mode_name
    from savant_cli.montecarlo.analysis import margin_spread
    from savant_cli.montecarlo.storage import write_tables

    tanks = ("first_stage_lox", "rp1", "lox", "lh2")
    codes = [mode_code(f"slosh_{t}", tanks) for t in tanks]
    assert codes == [3, 4, -1, -2]
    assert [mode_name(c, tanks) for c in codes] == [f"slosh_{t}" for t in tanks]
    assert [mode_code(m) for m in ("slosh_lox", "slosh_lh2", "closed_loop", "flex_1")] == [3, 4, 5, 6]
    assert [mode_name(c) for c in (3, 4, 7)] == ["slosh_lox", "slosh_lh2", "flex_2"]
    Journal(tmp_path / "runs", case.cfg, case.dispersions.names, tanks)
    assert write_tables(None, inventory([tmp_path / "runs"]), [], [], np.zeros(0)).slosh_tanks == tanks
    Journal(tmp_path / "default" / "runs", case.cfg, case.dispersions.names)
    default = inventory([tmp_path / "default" / "runs"])
    assert "slosh_tanks" not in default.manifest
    assert write_tables(None, default, [], [], np.zeros(0)).slosh_tanks == DEFAULT_SLOSH_TANKS
    table = np.array([[0, 55.0, 0, 0, 1, 40.0, 0.6, -2, 1], [0, 55.0, 0, 0, 1, 35.0, 0.6, 3, 1]])
    assert {r["mode"] for r in margin_spread(table, tanks)} == {"slosh_lh2", "slosh_first_stage_lox"}
