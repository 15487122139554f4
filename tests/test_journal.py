"""The Monte Carlo journal is checked: each ``runs/run_NNNNNN.npz`` carries the SHA-256 of
its content; garbage, truncated, empty, tampered and misnamed entries are named (file and
run) as damaged, counted as missing by ``collect``'s inventory, and a write that fails
leaves no temporary file and the earlier entry whole. Nothing here flies: the entries
are written directly."""

from __future__ import annotations

import errno
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import DamagedFileError, OutputWriteError, SavantError
from savant_cli.montecarlo import journal as journal_mod
from savant_cli.montecarlo.batch import RUN_STAGES, Journal, RunOutcome, read_outcome, scan_entries
from savant_cli.montecarlo.inventory import inventory
from savant_cli.montecarlo.journal import CHECKSUM_KEY, payload_digest, read_entry, write_entry

SHORT = ["study=montecarlo", "phase=first_stage", "study.n_runs=6"]


@pytest.fixture(scope="module")
def cfg():
    return validate(compose_config(SHORT))


def _outcome(run: int) -> RunOutcome:
    rng = np.random.default_rng(run)
    return RunOutcome(run, "complete", "", 130.0 + run, 1.5, rng.normal(size=4), ["max_q_Pa", "t_s"],
                      rng.normal(size=2), rng.normal(size=3), rng.normal(size=(2, 5)).astype(np.float32),
                      stage_wall_s=np.arange(len(RUN_STAGES), dtype=float))


@pytest.fixture
def journal(cfg, tmp_path):
    j = Journal(tmp_path / "batch" / "runs", cfg, ["a", "b", "c", "d"])
    for r in range(6):
        j.write(_outcome(r))
    return j


def test_an_entry_reads_back_bit_for_bit_with_its_checksum(journal):
    path = journal.folder / "run_000003.npz"
    o, ref = read_outcome(path), _outcome(3)
    assert o.summary_keys == ref.summary_keys and np.array_equal(o.summary, ref.summary)
    assert np.array_equal(o.values, ref.values) and np.array_equal(o.histories, ref.histories)
    with np.load(path) as z:
        stored = str(z[CHECKSUM_KEY])
        payload = {k: z[k] for k in z.files if k != CHECKSUM_KEY}
    assert len(stored) == 64 and stored == payload_digest(payload)
    assert sorted(p.name for p in journal.folder.iterdir()) == ["manifest.json"] + [f"run_{r:06d}.npz" for r in range(6)]


def _damage(journal) -> dict[int, str]:
    """Garbage, a truncation, an empty file, a changed value under the old checksum and an
    entry holding another run; what each one's message must say."""
    f = journal.folder
    (f / "run_000001.npz").write_bytes(b"\x13\x37 not an archive " * 64)
    raw = (f / "run_000002.npz").read_bytes()
    (f / "run_000002.npz").write_bytes(raw[: len(raw) // 2])
    (f / "run_000003.npz").write_bytes(b"")
    with np.load(f / "run_000004.npz") as z:
        members = {k: z[k] for k in z.files}
    members["summary"] = members["summary"] + 1.0  # the stored digest no longer matches
    with open(f / "run_000004.npz", "wb") as fh:
        np.savez(fh, **members)
    os.replace(f / "run_000005.npz", f / "run_000009.npz")  # run 5's entry under run 9's name
    return {1: "not an npz archive", 2: "truncated or corrupt archive", 3: "empty (0 bytes)",
            4: "checksum mismatch", 9: "holds run 5, not run 9"}


def test_damaged_entries_are_named_with_file_and_run(journal):
    expected = _damage(journal)
    for run, words in expected.items():
        path = journal.folder / f"run_{run:06d}.npz"
        with pytest.raises(DamagedFileError) as err:
            read_outcome(path)
        text = str(err.value)
        assert isinstance(err.value, SavantError) and err.value.exit_code == 2
        assert err.value.path == path and str(path) in text and words in text, text
        assert f"flies run {run} again" in text and f"hydra.run.dir={journal.folder.parent}" in text
    found = scan_entries(journal.folder)
    assert sorted(found.good) == [0] and sorted(found.damaged) == sorted(expected)
    assert journal.done() == {0}


def test_collect_inventory_counts_damaged_entries_as_missing(journal):
    _damage(journal)
    inv = inventory([journal.folder], verify=True)
    assert sorted(inv.files) == [0] and sorted(inv.damaged) == [1, 2, 3, 4, 9]
    assert inv.missing(range(6)) == [1, 2, 3, 4, 5]
    assert sorted(inventory([journal.folder]).files) == [0, 1, 2, 3, 4, 9]  # unverified: names only


def test_a_legacy_entry_without_checksum_still_reads(journal):
    path = journal.folder / "run_000002.npz"
    with np.load(path) as z:
        members = {k: z[k] for k in z.files if k != CHECKSUM_KEY}
    with open(path, "wb") as fh:
        np.savez(fh, **members)
    assert np.array_equal(read_outcome(path).summary, _outcome(2).summary)


def test_a_failed_entry_write_leaves_no_temporary_file_and_the_old_entry_whole(journal, monkeypatch):
    path = journal.folder / "run_000002.npz"
    before = path.read_bytes()
    real_savez = np.savez

    def disk_full(fh, **arrays):
        real_savez(fh, **arrays)  # part of the file reaches the disk, then the disk is full
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(journal_mod.np, "savez", disk_full)
    with pytest.raises(OutputWriteError) as err:
        journal.write(_outcome(2))
    assert str(err.value) == f"could not write run_000002.npz in {journal.folder}: No space left on device (errno 28)"
    assert err.value.exit_code == 1
    assert path.read_bytes() == before
    assert [p.name for p in journal.folder.iterdir() if p.name.startswith(".")] == []


def test_resume_removes_the_temporary_entries_of_a_killed_writer(cfg, journal):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(dead.stdout)
    stale = [journal.folder / f".run_000007.npz.{dead_pid}.0a1b2c3d.tmp", journal.folder / f".run_000008.{dead_pid}.tmp.npz"]
    live = journal.folder / f".run_000009.npz.{os.getppid()}.0a1b2c3d.tmp"  # a running writer's: kept
    for p in (*stale, live):
        p.write_bytes(b"half an entry")
    again = Journal(journal.folder, cfg, ["a", "b", "c", "d"])
    assert sorted(again.removed_temps) == sorted(stale)
    assert not any(p.exists() for p in stale) and live.exists()


def test_a_damaged_manifest_is_named(cfg, journal):
    (journal.folder / "manifest.json").write_text('{"fingerprint": ')
    with pytest.raises(DamagedFileError) as err:
        Journal(journal.folder, cfg, ["a", "b", "c", "d"])
    assert str(journal.folder / "manifest.json") in str(err.value) and "JSONDecodeError" in str(err.value)
    with pytest.raises(DamagedFileError):
        inventory([journal.folder])


def test_the_checksum_member_name_is_reserved(tmp_path):
    with pytest.raises(ValueError, match="reserved"):
        write_entry(tmp_path / "run_000000.npz", {CHECKSUM_KEY: 1})
    write_entry(tmp_path / "run_000000.npz", {"x": np.arange(3)})
    assert np.array_equal(read_entry(tmp_path / "run_000000.npz", "")["x"], np.arange(3))
