"""Monte Carlo shards on the launchers that go past one machine (docs/montecarlo.md,
"Scale beyond one machine"): a sharded batch through ``hydra/launcher=savant_submitit_local``
(submitit's local executor: the code path of ``savant_slurm`` without the scheduler) and
through a local Ray instance (``savant_ray``), each collected and bitwise identical to the
single-process batch (``savant_cli/io/bitwise.py``); a resumed batch whose journal lost
runs and a whole shard flies exactly those runs; ``savant collect`` on a partial set
writes nothing, or a partial result with ``--allow-missing``.

The launcher plugins come with the ``test`` extra (``savant[slurm,ray]``). A missing
plugin skips these tests, or fails them when ``SAVANT_REQUIRE_LAUNCHERS=1`` (CI sets it).
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess

import h5py
import pytest

from savant_cli.io.bitwise import compare_h5
from test_end_to_end import run, savant_cmd

pytestmark = pytest.mark.slow

BASE = ["study=montecarlo", "phase=first_stage", "study.n_runs=6", "sim.progress=false", "output.plots=false",
        "study.histories.signals=[altitude,alpha]"]
SHARDED = [*BASE, "study.shards=3", "study.shard=range(0,3)", "study.workers=1"]


def require(*modules: str) -> None:
    """Skip (or, with SAVANT_REQUIRE_LAUNCHERS=1, fail) when a plugin is not installed."""
    absent = [m for m in modules if importlib.util.find_spec(m) is None]
    if absent:
        why = f"not installed: {', '.join(absent)} (pip install \"savant[slurm,ray]\")"
        if os.environ.get("SAVANT_REQUIRE_LAUNCHERS") == "1":
            pytest.fail(why)
        pytest.skip(why)


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    """The unsharded batch, flown first in one process (it also warms the numba cache the
    shard processes read)."""
    root = tmp_path_factory.mktemp("launchers")
    proc = run(["run", *BASE, "study.workers=1", f"hydra.run.dir={root}/single"], cwd=root)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return root


@pytest.fixture(scope="module")
def submitit_sweep(root):
    require("hydra_plugins.hydra_submitit_launcher", "submitit")
    sweep = root / "submitit"
    proc = run(["run", "-m", *SHARDED, "hydra/launcher=savant_submitit_local", f"hydra.sweep.dir={sweep}"], cwd=root)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return sweep


def _shard_folders(sweep) -> list[str]:
    return sorted(p.parent.parent.name for p in sweep.glob("*/runs/manifest.json"))


def _collected_equals_single(root, sweep) -> None:
    proc = run(["collect", str(sweep)], cwd=root)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "collected 6 runs from 3 shard folder(s)" in proc.stdout
    with h5py.File(sweep / "savant.h5") as f:
        assert sorted(f["montecarlo/runs/run"][()].tolist()) == list(range(6))
        assert f["montecarlo"].attrs["missing_runs"] == ""
    assert compare_h5(root / "single" / "savant.h5", sweep / "savant.h5") == []


def test_submitit_local_shards_collect_bitwise_to_the_single_batch(root, submitit_sweep):
    assert _shard_folders(submitit_sweep) == ["0", "1", "2"]
    logs = sorted(submitit_sweep.glob(".submitit/*/*_log.out"))
    assert len(logs) == 3  # one submitit job per shard
    for shard in range(3):  # each job flew its own block of two runs
        summary = json.loads((submitit_sweep / str(shard) / "summary.json").read_text())
        assert summary["n_runs_present"] == 2 and summary["missing_runs"] == ""
    _collected_equals_single(root, submitit_sweep)


def test_ray_shards_collect_bitwise_to_the_single_batch(root):
    require("hydra_plugins.hydra_ray_launcher", "ray")
    sweep = root / "ray"
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}  # Ray sends nothing anywhere
    proc = subprocess.run(savant_cmd() + ["run", "-m", *SHARDED, "hydra/launcher=savant_ray", f"hydra.sweep.dir={sweep}"],
                          cwd=root, env=env, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Ray Launcher is launching 3 jobs" in proc.stdout + proc.stderr
    assert _shard_folders(sweep) == ["0", "1", "2"]
    _collected_equals_single(root, sweep)


def _journal(sweep) -> dict[int, tuple[int, int]]:
    """Run number → (inode, mtime ns) of its journal file: a run flown again is a new file."""
    out = {}
    for p in sweep.glob("*/runs/run_*.npz"):
        st = p.stat()
        out[int(p.stem[4:])] = (st.st_ino, st.st_mtime_ns)
    return out


def test_resume_fills_exactly_the_gaps_and_collect_refuses_a_partial_set(root, submitit_sweep):
    """Shard 2's folder lost, run 3 lost from shard 1's journal: collect writes nothing
    (exit 1, the runs and the shard named), --allow-missing writes a partial result
    (exit 1, missing_runs), and the multirun command again for shards 1 and 2 flies runs
    3, 4 and 5 and nothing else; then the collected batch is the single one, bit for bit."""
    sweep = root / "resume"
    sweep.mkdir()
    for shard in ("0", "1"):
        shutil.copytree(submitit_sweep / shard, sweep / shard)
    (sweep / "1" / "runs" / "run_000003.npz").unlink()
    for name in ("savant.h5", "summary.json", "report.html", "minmax.csv"):
        for shard in ("0", "1"):
            assert (sweep / shard / name).is_file()
    before = sorted(p.name for p in sweep.iterdir())

    refused = run(["collect", str(sweep)], cwd=root)
    assert refused.returncode == 1, refused.stdout + refused.stderr
    text = " ".join(refused.stdout.split())
    assert "missing runs (3 of 6): 3-5" in text
    assert "shard 1 (" in text and "runs 3" in text and "shard 2 (no shard folder with a journal): runs 4-5" in text
    assert "nothing written" in text
    assert sorted(p.name for p in sweep.iterdir()) == before  # nothing created

    partial = run(["collect", str(sweep), "--allow-missing"], cwd=root)
    assert partial.returncode == 1, partial.stdout + partial.stderr
    assert "PARTIAL result" in partial.stdout
    summary = json.loads((sweep / "summary.json").read_text())
    assert summary["missing_runs"] == "3-5" and summary["n_runs_present"] == 3
    assert "PARTIAL batch: 3 of 6 runs present, missing runs 3-5" in (sweep / "report.html").read_text()
    with h5py.File(sweep / "savant.h5") as f:
        assert f["montecarlo"].attrs["missing_runs"] == "3-5"

    kept = _journal(sweep)
    assert sorted(kept) == [0, 1, 2]
    proc = run(["run", "-m", *SHARDED[:-2], "study.shard=1,2", "study.workers=1", "hydra.sweep.subdir=${study.shard}",
                "hydra/launcher=savant_submitit_local", f"hydra.sweep.dir={sweep}"], cwd=root)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    after = _journal(sweep)
    assert sorted(after) == list(range(6))
    flown = sorted(r for r in after if kept.get(r) != after[r])
    assert flown == [3, 4, 5]  # exactly the gaps: runs 0-2 are the same files as before
    logs = {p.read_text() for p in sweep.glob(".submitit/*/*_log.out")}
    assert len(logs) == 2
    assert any("resuming: 1 of 2 runs already" in " ".join(t.split()) for t in logs)
    assert _shard_folders(sweep) == ["0", "1", "2"]
    _collected_equals_single(root, sweep)


def _launcher(name: str, overrides: list[str]) -> dict:
    """The resolved ``hydra.launcher`` of ``savant run -m … hydra/launcher=<name>``."""
    from hydra import compose, initialize_config_dir
    from omegaconf import OmegaConf

    from savant_cli.paths import shipped_config_dir

    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        cfg = compose(config_name="config", overrides=[f"hydra/launcher={name}", *overrides], return_hydra_config=True)
    return OmegaConf.to_container(cfg.hydra.launcher, resolve=True)


def test_slurm_config_makes_one_array_task_per_shard(tmp_path, monkeypatch):
    """savant_slurm as the submitit launcher hands it to submitit (no scheduler here): the
    sbatch script of a 40-shard batch is one array of 40 tasks, 40 at once, each with
    study.workers CPUs, the partition, account, time limit and memory asked for."""
    require("hydra_plugins.hydra_submitit_launcher", "submitit")
    import submitit
    from submitit.slurm.slurm import _make_sbatch_string

    params = _launcher("savant_slurm", ["study=montecarlo", "study.shards=40", "study.workers=8",
                                        "hydra.launcher.partition=compute", "hydra.launcher.account=proj",
                                        "hydra.launcher.array_parallelism=40", f"hydra.sweep.dir={tmp_path}"])
    assert params["_target_"].endswith("SlurmLauncher") and params["cpus_per_task"] == 8
    # the launcher's own mapping (hydra_submitit_launcher.submitit_launcher.BaseSubmititLauncher.launch)
    from hydra_plugins.hydra_submitit_launcher.config import BaseQueueConf
    from omegaconf import OmegaConf

    base = set(OmegaConf.structured(BaseQueueConf).keys())
    (tmp_path / "bin").mkdir()
    (tmp_path / "bin" / "srun").write_text("#!/bin/sh\nexit 1\n")  # submitit only looks for it on PATH
    (tmp_path / "bin" / "srun").chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path / 'bin'}{os.pathsep}{os.environ['PATH']}")
    ex = submitit.AutoExecutor(cluster="slurm", folder=params["submitit_folder"],
                               slurm_max_num_timeout=params["max_num_timeout"])
    ex.update_parameters(**{k if k in base else f"slurm_{k}": v for k, v in params.items()
                            if k not in ("submitit_folder", "max_num_timeout", "_target_")})
    script = _make_sbatch_string(command="savant", folder=ex.folder, map_count=40, **ex._executor.parameters)
    for line in ("#SBATCH --array=0-39%40", "#SBATCH --cpus-per-task=8", "#SBATCH --partition=compute",
                 "#SBATCH --account=proj", "#SBATCH --time=120", "#SBATCH --mem=8GB", "#SBATCH --ntasks-per-node=1",
                 "#SBATCH --nodes=1"):
        assert line in script.splitlines(), (line, script)
    assert f"#SBATCH --output={tmp_path}/.submitit/%A_%a/%A_%a_0_log.out" in script.splitlines()


def test_local_launcher_configs_resolve(tmp_path):
    require("hydra_plugins.hydra_submitit_launcher", "hydra_plugins.hydra_ray_launcher")
    local = _launcher("savant_submitit_local", ["study=montecarlo", "study.workers=2", f"hydra.sweep.dir={tmp_path}"])
    assert local["_target_"].endswith("LocalLauncher") and local["cpus_per_task"] == 2
    ray = _launcher("savant_ray", ["study=montecarlo", "study.workers=1"])
    assert ray["_target_"].endswith("RayLauncher")
    assert ray["ray"]["init"]["address"] is None and ray["ray"]["init"]["num_cpus"] == 2
    assert ray["ray"]["remote"] == {"num_cpus": 1, "max_retries": 0}
