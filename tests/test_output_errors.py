"""Disk full and unwritable folders: an output that cannot be written is said in one line
naming the file and its folder, the console summary is still printed, every file already
written stays whole (no temporary file left), and the command exits 1 without a
traceback.

The disk is filled for real where the machine lets an unprivileged process make its own
mount namespace (``unshare -rm``): a 2 MB tmpfs, or a read-only bind mount for an
unwritable folder. The in-process tests inject ``ENOSPC``/``EACCES`` at the write layer
and run everywhere."""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from savant_cli.errors import OutputWriteError
from savant_cli.io import atomic
from savant_cli.io.atomic import atomic_path, write_text_atomic

ROOT = Path(__file__).parents[1]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
SAVANT = [sys.executable, "-m", "savant_cli.cli"]


def _namespaces() -> bool:
    """Whether this process may make a private mount namespace with a tmpfs in it."""
    if shutil.which("unshare") is None or not sys.platform.startswith("linux"):
        return False
    probe = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt 2>/dev/null || "
                            "mount -t tmpfs -o size=64k tmpfs /tmp"], capture_output=True)
    return probe.returncode == 0


NAMESPACES = _namespaces()
needs_namespace = pytest.mark.skipif(not NAMESPACES, reason="no unprivileged mount namespace (unshare -rm) here")


def _q(text: str) -> str:
    import shlex

    return shlex.quote(str(text))


def run_in_namespace(tmp_path: Path, setup: str, command: list[str], check: str,
                     timeout: int = 900) -> tuple[int, str, str, dict]:
    """(exit status, stdout, stderr, the check's JSON) of ``command`` run in a private
    mount namespace prepared by ``setup``."""
    logs = tmp_path / "logs"
    logs.mkdir()
    cmd = " ".join(map(_q, command))
    script = (f"set -e\n{setup}\nset +e\n{cmd} > {_q(logs / 'stdout')} 2> {_q(logs / 'stderr')}\n"
              f"echo $? > {_q(logs / 'rc')}\n{_q(sys.executable)} -c {_q(check)} > {_q(logs / 'check')}\n")
    proc = subprocess.run(["unshare", "-rm", "sh", "-c", script], env={**ENV, "COLUMNS": "200"},
                          capture_output=True, text=True, timeout=timeout)
    assert (logs / "rc").is_file(), proc.stdout + proc.stderr
    check_out = (logs / "check").read_text().strip().splitlines()
    assert check_out, proc.stderr
    return (int((logs / "rc").read_text()), (logs / "stdout").read_text(), (logs / "stderr").read_text(),
            json.loads(check_out[-1]))


# A check run inside the namespace: every file of the folder reads back whole, no
# temporary file is left.
FOLDER_CHECK = textwrap.dedent("""
    import json
    from pathlib import Path
    import h5py
    root = Path(FOLDER)
    files, bad, temps = [], [], []
    for p in sorted(root.rglob("*")):
        if not p.is_file():
            continue
        rel = str(p.relative_to(root))
        files.append(rel)
        if p.name.endswith(".tmp") or ".tmp." in p.name:
            temps.append(rel)
            continue
        try:
            if p.suffix == ".h5":
                with h5py.File(p, "r") as f:
                    f.visit(lambda name: None)
            elif p.suffix == ".json":
                json.loads(p.read_text())
            elif p.suffix == ".npz":
                from savant_cli.montecarlo.batch import read_outcome
                read_outcome(p)
            elif p.suffix == ".png":
                assert p.read_bytes()[:8] == b"\\x89PNG\\r\\n\\x1a\\n" and p.read_bytes()[-8:-4] == b"IEND"
        except Exception as exc:
            bad.append(f"{rel}: {exc}")
    print(json.dumps({"files": files, "bad": bad, "temps": temps}))
""")


def folder_check(folder: Path) -> str:
    return f"FOLDER = {str(folder)!r}\n" + FOLDER_CHECK


# ------------------------------------------------------------------ the write layer


def test_a_write_that_fails_names_the_file_and_keeps_the_old_one(tmp_path, monkeypatch):
    target = tmp_path / "out" / "summary.json"
    write_text_atomic(target, "old\n")

    def full(path):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic, "_fsync_file", full)
    with pytest.raises(OutputWriteError) as err:
        write_text_atomic(target, "new\n")
    assert str(err.value) == f"could not write summary.json in {target.parent}: No space left on device (errno 28)"
    assert err.value.exit_code == 1 and err.value.path == target
    assert target.read_text() == "old\n"
    assert [p.name for p in target.parent.iterdir()] == ["summary.json"]  # the temporary file is gone


def test_a_write_error_crosses_a_process_boundary_whole():
    """A figure drawn by a worker process into a full disk: its OutputWriteError is
    pickled back to the main process with the same file, reason and exit code."""
    import pickle

    sent = OutputWriteError("/run/plots/altitude.png", OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
    got = pickle.loads(pickle.dumps(sent))
    assert type(got) is OutputWriteError
    assert (got.path, got.reason, got.exit_code, str(got)) == (sent.path, sent.reason, 1, str(sent))
    assert got.reason == f"{os.strerror(errno.ENOSPC)} (errno {errno.ENOSPC})"


def test_a_folder_that_cannot_be_made_is_named(tmp_path):
    (tmp_path / "plots").write_text("a file where a folder should be")
    with pytest.raises(OutputWriteError) as err:
        with atomic_path(tmp_path / "plots" / "altitude.png") as tmp:
            tmp.write_bytes(b"png")
    assert "could not write altitude.png in" in str(err.value) and str(tmp_path / "plots") in str(err.value)


def test_an_error_of_the_block_itself_is_not_taken_for_a_write_error(tmp_path):
    with pytest.raises(ZeroDivisionError):
        with atomic_path(tmp_path / "x.txt") as tmp:
            tmp.write_text("half")
            1 / 0
    with pytest.raises(FileNotFoundError, match="nothing was written"):
        with atomic_path(tmp_path / "y.txt"):
            pass
    assert list(tmp_path.iterdir()) == []


class _SmallDisk:
    """A raw file that takes ``room`` bytes, then refuses with ENOSPC (a write that
    straddles the limit is taken in part, as the kernel does)."""

    def __init__(self, fh, room: int) -> None:
        self.fh, self.room = fh, room

    def write(self, data) -> int:
        left = self.room - self.fh.seek(0, os.SEEK_CUR)
        if left <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return self.fh.write(bytes(data)[:left])

    def __getattr__(self, name):
        return getattr(self.fh, name)


def test_hdf5_written_through_the_guard_reports_a_refusal_once(tmp_path, monkeypatch):
    import numpy as np

    from savant_cli.io import h5write

    real_init = h5write.GuardedFile.__init__

    def small(self, path):
        real_init(self, path)
        self._fh = _SmallDisk(self._fh, 100_000)

    monkeypatch.setattr(h5write.GuardedFile, "__init__", small)
    target = tmp_path / "savant.h5"
    target.write_bytes(b"previous")
    with pytest.raises(OutputWriteError) as err:
        with h5write.atomic_h5(target, track_order=True) as f:
            for i in range(8):
                f.create_dataset(f"s{i}", data=np.random.default_rng(i).random((200, 300)), chunks=(1, 300))
    assert str(err.value) == f"could not write savant.h5 in {tmp_path}: No space left on device (errno 28)"
    assert target.read_bytes() == b"previous" and sorted(p.name for p in tmp_path.iterdir()) == ["savant.h5"]
    monkeypatch.setattr(h5write.GuardedFile, "__init__", real_init)
    with h5write.atomic_h5(target) as f:  # with room, the same file reads back
        f["x"] = np.arange(5.0)
    import h5py

    with h5py.File(target, "r") as f:
        assert f["x"][()].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]


@needs_namespace
def test_hdf5_on_a_full_disk_is_one_write_error_and_no_crash(tmp_path):
    """Several chunked, compressed datasets open when the 2 MB disk fills: written
    straight to disk, HDF5 prints an "Exception ignored" traceback per object and can
    crash at exit; through :func:`atomic_h5` it is one ``OutputWriteError``, a clean exit
    and the earlier files whole."""
    writer = textwrap.dedent("""
        import json, sys
        from pathlib import Path
        import numpy as np
        from savant_cli.errors import OutputWriteError
        from savant_cli.io.atomic import write_text_atomic
        from savant_cli.io.h5write import atomic_h5
        d = Path(sys.argv[1])
        write_text_atomic(d / "first.txt", "whole")
        (d / "savant.h5").write_bytes(b"the previous run")
        rng = np.random.default_rng(0)
        try:
            with atomic_h5(d / "savant.h5", track_order=True) as f:
                sets = [f.create_dataset(f"s{i}", shape=(400, 300), dtype="f4", chunks=(1, 300),
                                         compression="gzip") for i in range(20)]
                for row in range(400):
                    for ds in sets:
                        ds[row] = rng.random(300)
            print("written")
        except OutputWriteError as exc:
            print(exc)
        print("previous kept" if (d / "savant.h5").read_bytes() == b"the previous run" else "previous lost")
    """)
    disk = tmp_path / "disk"
    disk.mkdir()
    rc, out, err, got = run_in_namespace(tmp_path, f"mount -t tmpfs -o size=2m tmpfs {_q(disk)}",
                                         [sys.executable, "-c", writer, str(disk)], folder_check(disk))
    assert rc == 0 and err == "", err[-2000:]
    assert out.split("\n")[:2] == [f"could not write savant.h5 in {disk}: No space left on device (errno 28)",
                                    "previous kept"]
    assert sorted(got["files"]) == ["first.txt", "savant.h5"] and got["temps"] == []


# -------------------------------------------------------------- the command line


def _one_error_line(stderr: str, words: str) -> None:
    assert "Traceback" not in stderr, stderr
    lines = [ln for ln in stderr.splitlines() if words in ln]
    assert len(lines) == 1, stderr


@pytest.mark.slow
@needs_namespace
def test_a_run_on_a_full_disk_says_what_and_still_prints_its_summary(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    run_dir = disk / "run"
    rc, out, err, got = run_in_namespace(
        tmp_path, f"mount -t tmpfs -o size=2m tmpfs {_q(disk)}",
        [*SAVANT, "run", "phase=first_stage", "sim.progress=false", f"hydra.run.dir={run_dir}"], folder_check(run_dir))
    assert rc == 1, out + err
    _one_error_line(err, f"could not write savant.h5 in {run_dir}: No space left on device (errno 28)")
    assert "savant run summary" in out and "status:" in out  # the summary reached the console
    assert got["temps"] == [] and got["bad"] == [], got
    assert "savant.h5" not in got["files"] and ".hydra/config.yaml" in got["files"]


@pytest.mark.slow
@needs_namespace
def test_a_batch_on_a_full_disk_stops_with_its_journal_whole(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    out_dir = disk / "mc"
    rc, out, err, got = run_in_namespace(
        tmp_path, f"mount -t tmpfs -o size=1m tmpfs {_q(disk)}",
        [*SAVANT, "run", "study=montecarlo", "phase=first_stage", "study.n_runs=400", "study.workers=2",
         "study.histories.rate_hz=10", "output.plots=false", "sim.progress=false", f"hydra.run.dir={out_dir}"],
        folder_check(out_dir))
    assert rc == 1, out + err
    text = " ".join((out + err).split())
    assert "Traceback" not in out + err, out + err
    assert f"in {out_dir / 'runs'}: No space left on device (errno 28)" in text  # the journal entry that failed
    assert got["temps"] == [] and got["bad"] == [], got  # no .run_*.tmp left; every entry checks
    journaled = [f for f in got["files"] if f.startswith("runs/run_")]
    assert 0 < len(journaled) < 400


@pytest.mark.slow
@needs_namespace
def test_report_into_an_unwritable_folder_says_what_and_keeps_the_run(tmp_path):
    run_dir = tmp_path / "run"
    first = subprocess.run([*SAVANT, "run", "phase=first_stage", "sim.progress=false", "output.plots=false",
                            f"hydra.run.dir={run_dir}"], env=ENV, capture_output=True, text=True, timeout=900)
    assert first.returncode == 0, first.stdout + first.stderr
    (run_dir / "plots").mkdir()
    h5_before = (run_dir / "savant.h5").read_bytes()
    plots = _q(run_dir / "plots")
    rc, out, err, got = run_in_namespace(tmp_path, f"mount --bind {plots} {plots}\nmount -o remount,bind,ro {plots}",
                                         [*SAVANT, "report", str(run_dir)], folder_check(run_dir))
    assert rc == 1, out + err
    _one_error_line(err, f"in {run_dir / 'plots'}: Read-only file system (errno 30)")
    assert "savant run summary" in out
    assert got["temps"] == [] and got["bad"] == []
    assert (run_dir / "savant.h5").read_bytes() == h5_before
