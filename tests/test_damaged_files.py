"""Damaged run files are named: ``savant report``, :func:`savant_cli.load` and ``savant
collect`` say which file, what is wrong with it and what rebuilds it (exit 2, a
``SavantError`` from the API, no traceback); a Monte Carlo batch with garbled,
truncated and tampered journal entries names them on ``rerun``, lists them on
``collect`` and flies them again on resume, bit for bit; re-running the command a
damaged batch ``savant.h5`` names rebuilds it."""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from omegaconf import OmegaConf

import savant_cli
from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import DamagedFileError, SavantError
from savant_cli.io.bitwise import compare_h5
from savant_cli.io.hdf5 import write_run
from savant_cli.io.integrity import rebuild_hint, verify_h5
from savant_cli.io.record import RunRecord, Signal
from savant_cli.montecarlo.batch import Journal, RunOutcome, read_outcome

ROOT = Path(__file__).parents[1]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]), "COLUMNS": "200"}
SAVANT = [sys.executable, "-m", "savant_cli.cli"]


def savant(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([*SAVANT, *args], cwd=cwd, env=ENV, capture_output=True, text=True, timeout=1200)


@pytest.fixture
def run_dir(tmp_path):
    """A small run folder as ``savant run winds=none`` leaves it: ``.hydra/``, a
    ``savant.h5`` with a compressed history, ``summary.json``."""
    d = tmp_path / "run"
    (d / ".hydra").mkdir(parents=True)
    (d / ".hydra" / "overrides.yaml").write_text("- winds=none\n- sim.max_time_s=10\n")
    t = np.linspace(0.0, 10.0, 4001)
    rec = RunRecord(signals={"time": Signal(t, "s", "time"), "altitude": Signal(50.0 * t ** 2, "m", "altitude")},
                    events=[("liftoff", 0.0)], summary={"max_altitude_m": 5000.0, "status": "complete"},
                    config_yaml="study:\n  name: nominal\n", provenance={"savant_version": "test"},
                    complete=True, status="complete", message="")
    write_run(d / "savant.h5", rec)
    (d / "summary.json").write_text(json.dumps(rec.summary))
    return d


def _truncate(path: Path) -> int:
    size = path.stat().st_size
    path.write_bytes(path.read_bytes()[: size // 3])
    return size


def test_load_names_a_truncated_or_garbage_run_file(run_dir):
    assert savant_cli.load(run_dir).status == "complete"
    h5 = run_dir / "savant.h5"
    size = _truncate(h5)
    with pytest.raises(DamagedFileError) as err:
        savant_cli.load(run_dir)
    text = str(err.value)
    assert isinstance(err.value, SavantError) and err.value.exit_code == 2 and err.value.path == h5
    assert str(h5) in text and f"truncated: {size // 3:,} of {size:,} bytes" in text
    assert f"savant run winds=none sim.max_time_s=10 hydra.run.dir={run_dir}" in text
    h5.write_bytes(b"garbage " * 1000)
    with pytest.raises(DamagedFileError, match=r"not an HDF5 file \(no HDF5 signature in its 8,000 bytes\)"):
        savant_cli.load(run_dir)
    h5.write_bytes(b"")
    with pytest.raises(DamagedFileError, match=r"empty \(0 bytes\)"):
        savant_cli.load(run_dir)


def _spoil_a_chunk(h5: Path) -> None:
    """Overwrite the first compressed chunk of the altitude history (the file still opens)."""
    with h5py.File(h5, "r") as f:
        info = f["time_history/altitude"].id.get_chunk_info(0)
    with open(h5, "r+b") as fh:
        fh.seek(info.byte_offset)
        fh.write(b"\xff" * min(info.size, 64))


def test_damage_inside_the_file_is_found_by_report_and_by_the_lazy_history(run_dir):
    _spoil_a_chunk(run_dir / "savant.h5")
    result = savant_cli.load(run_dir)  # the header reads
    with pytest.raises(DamagedFileError) as err:
        result.history
    assert str(run_dir / "savant.h5") in str(err.value)
    with pytest.raises(DamagedFileError, match="object /time_history/altitude unreadable"):
        verify_h5(run_dir / "savant.h5")


def test_report_names_the_damaged_file_and_exits_2(run_dir):
    _truncate(run_dir / "savant.h5")
    proc = savant("report", str(run_dir), cwd=run_dir.parent)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    text = " ".join(proc.stderr.split())
    assert "Traceback" not in proc.stdout + proc.stderr
    assert f"{run_dir / 'savant.h5'} is damaged (truncated:" in text
    assert "run the same command again to rebuild it: savant run winds=none" in text
    assert not (run_dir / "plots").exists()  # nothing drawn from a damaged file


def test_summary_json_damage_is_named(run_dir):
    (run_dir / "summary.json").write_text('{"max_altitude_m": 50')
    with pytest.raises(DamagedFileError, match="summary.json is damaged"):
        savant_cli.load(run_dir)


def test_rebuild_hints_name_the_command_that_writes_the_folder_again(tmp_path, run_dir):
    batch = tmp_path / "batch"
    (batch / "runs").mkdir(parents=True)
    (batch / ".hydra").mkdir()
    (batch / ".hydra" / "overrides.yaml").write_text("- study=montecarlo\n- study.n_runs=3\n- hydra.run.dir=old\n")
    (batch / "runs" / "manifest.json").write_text("{}")
    for r in range(2):
        (batch / "runs" / f"run_{r:06d}.npz").write_bytes(b"")
    assert rebuild_hint(batch) == (f"run the same command again to rebuild it: savant run study=montecarlo "
                                   f"study.n_runs=3 hydra.run.dir={batch} (the 2 runs in its journal runs/ are not "
                                   f"flown again)")
    multi = tmp_path / "multi"
    (multi / "0" / "runs").mkdir(parents=True)
    (multi / "0" / "runs" / "manifest.json").write_text("{}")
    assert rebuild_hint(multi) == f"rebuild it from the shards' journals with: savant collect {multi}"
    assert rebuild_hint(batch / "rerun_000004") == f"rebuild it with: savant rerun {batch} run=4"
    assert rebuild_hint(tmp_path / "nothing") == "run the command that wrote this folder again to rebuild it"
    spaced = tmp_path / "a folder"
    (spaced / ".hydra").mkdir(parents=True)
    (spaced / ".hydra" / "overrides.yaml").write_text("- 'winds=none'\n")
    assert shlex.split(rebuild_hint(spaced).split(": ", 1)[1]) == ["savant", "run", "winds=none",
                                                                   f"hydra.run.dir={spaced}"]


def _outcome(run: int) -> RunOutcome:
    rng = np.random.default_rng(run)
    return RunOutcome(run, "complete", "", 130.0, 1.0, rng.normal(size=1), ["max_q_Pa"], rng.normal(size=1))


def test_collect_lists_damaged_entries_with_the_missing_ones(tmp_path):
    """Nothing flies: a shard folder's journal written directly, two entries damaged."""
    raw = compose_config(["study=montecarlo", "phase=first_stage", "study.n_runs=6"])
    cfg = validate(raw)
    shard = tmp_path / "multi" / "0"
    (shard / ".hydra").mkdir(parents=True)
    (shard / ".hydra" / "config.yaml").write_text(OmegaConf.to_yaml(raw))
    journal = Journal(shard / "runs", cfg, ["x"])
    for r in (0, 1, 2, 3, 5):
        journal.write(_outcome(r))
    (shard / "runs" / "run_000001.npz").write_bytes(b"\0" * 300)
    _truncate(shard / "runs" / "run_000003.npz")
    proc = savant("collect", str(tmp_path / "multi"), cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    out = " ".join(proc.stdout.split())
    assert "Traceback" not in proc.stdout + proc.stderr
    assert f"damaged journal entry {shard / 'runs' / 'run_000001.npz'} (run 1): not an npz archive" in out
    assert f"damaged journal entry {shard / 'runs' / 'run_000003.npz'} (run 3): truncated or corrupt archive" in out
    assert "missing runs (3 of 6): 1, 3-4" in out and "nothing written" in out
    assert not (tmp_path / "multi" / "savant.h5").exists()
    (shard / ".hydra" / "config.yaml").write_text("study: [unclosed\n")
    bad = savant("collect", str(tmp_path / "multi"), cwd=tmp_path)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert f"{shard / '.hydra' / 'config.yaml'} is damaged" in " ".join(bad.stderr.split())


@pytest.mark.slow
def test_a_damaged_journal_is_named_collected_as_missing_and_flown_again_bit_for_bit(tmp_path):
    out = tmp_path / "mc"
    args = ["run", "study=montecarlo", "phase=first_stage", "study.n_runs=6", "study.workers=2",
            "study.histories.rate_hz=2", "output.plots=false", "sim.progress=false", f"hydra.run.dir={out}"]
    first = savant(*args, cwd=tmp_path)
    assert first.returncode == 0, first.stdout + first.stderr
    reference = tmp_path / "reference.h5"
    shutil.copy(out / "savant.h5", reference)
    runs = out / "runs"
    (runs / "run_000002.npz").write_bytes(os.urandom(5000))
    _truncate(runs / "run_000003.npz")
    with np.load(runs / "run_000004.npz") as z:
        members = {k: z[k] for k in z.files}
    members["summary"] = members["summary"] * 1.01
    with open(runs / "run_000004.npz", "wb") as fh:
        np.savez(fh, **members)

    rerun = savant("rerun", str(out), "run=2", cwd=tmp_path)
    assert rerun.returncode == 2, rerun.stdout + rerun.stderr
    text = " ".join(rerun.stdout.split())
    assert "Traceback" not in rerun.stdout + rerun.stderr
    assert f"{runs / 'run_000002.npz'} is damaged" in text and "flies run 2 again" in text
    assert (out / "rerun_000002" / "savant.h5").is_file()  # the flight itself is written

    collect = savant("collect", str(out), cwd=tmp_path)
    assert collect.returncode == 1, collect.stdout + collect.stderr
    text = " ".join(collect.stdout.split())
    for run in (2, 3, 4):
        assert f"damaged journal entry {runs / f'run_{run:06d}.npz'} (run {run})" in text
    assert "checksum mismatch" in text and "missing runs (3 of 6): 2-4" in text
    assert compare_h5(reference, out / "savant.h5") == []  # nothing written

    again = savant(*args, cwd=tmp_path)
    assert again.returncode == 0, again.stdout + again.stderr
    text = " ".join(again.stdout.split())
    assert "resuming: 3 of 6 runs" in text and "flying run 3 again" in text
    for run in (2, 3, 4):
        read_outcome(runs / f"run_{run:06d}.npz")  # whole again
    assert compare_h5(reference, out / "savant.h5") == []  # the re-flown runs are bit for bit the first ones

    _truncate(out / "savant.h5")
    report = savant("report", str(out), cwd=tmp_path)
    assert report.returncode == 2 and "Traceback" not in report.stdout + report.stderr
    hint = " ".join(report.stderr.split()).split("run the same command again to rebuild it: ", 1)[1]
    command, tail = hint.split(" (the 6 runs in its journal runs/ are not flown again)")
    rebuilt = savant(*shlex.split(command)[1:], cwd=tmp_path)  # the command the message gives
    assert rebuilt.returncode == 0, rebuilt.stdout + rebuilt.stderr
    assert "resuming: 6 of 6 runs" in rebuilt.stdout
    assert compare_h5(reference, out / "savant.h5") == []
    assert savant("report", str(out), cwd=tmp_path).returncode == 0
