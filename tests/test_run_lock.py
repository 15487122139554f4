"""One writer per run folder (issue 27, item 1): the lock, its refusal, a holder killed
with ``kill -9``, and refused or invalid commands that write nothing."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap

import pytest

from lifecycle_helpers import Paused, env, savant, tree
from savant_cli import run_lock
from savant_cli.errors import ConfigError

SHORT = ["winds=none", "sim.max_time_s=20", "output.plots=false", "sim.progress=false"]


# ------------------------------------------------------------------ in one process


def _hold_in_child(folder, ready, release) -> subprocess.Popen:
    """Another process that locks ``folder`` and holds it until ``release`` exists."""
    code = textwrap.dedent(f"""
        import pathlib, time
        from savant_cli import run_lock
        run_lock.acquire({str(folder)!r})
        pathlib.Path({str(ready)!r}).touch()
        while not pathlib.Path({str(release)!r}).exists():
            time.sleep(0.05)
    """)
    p = subprocess.Popen([sys.executable, "-c", code], env=env())
    for _ in range(600):
        if ready.exists():
            return p
        assert p.poll() is None, "the holder died"
        import time
        time.sleep(0.05)
    raise AssertionError("the holder never locked the folder")


def test_second_writer_refused_naming_pid_and_host(tmp_path):
    folder = tmp_path / "run"
    holder = _hold_in_child(folder, tmp_path / "ready", tmp_path / "release")
    try:
        before = tree(folder)
        with pytest.raises(run_lock.FolderBusy) as err:
            run_lock.acquire(folder)
        assert isinstance(err.value, ConfigError) and err.value.exit_code == 2
        text = str(err.value)
        assert str(folder) in text and f"PID {holder.pid}" in text and socket.gethostname() in text
        with pytest.raises(run_lock.FolderBusy):
            run_lock.refuse_if_busy(folder)
        assert tree(folder) == before  # the refusals wrote nothing
    finally:
        (tmp_path / "release").touch()
        holder.wait(timeout=60)
    lock = run_lock.acquire(folder)  # the holder ended: free again
    try:
        assert json.loads((folder / run_lock.LOCK_NAME).read_text())["pid"] == os.getpid()
        assert not lock.created
    finally:
        lock.release()


def test_kill_9_leaves_no_stale_lock(tmp_path):
    folder = tmp_path / "run"
    holder = _hold_in_child(folder, tmp_path / "ready", tmp_path / "never")
    with pytest.raises(run_lock.FolderBusy):
        run_lock.acquire(folder)
    holder.send_signal(signal.SIGKILL)
    holder.wait(timeout=60)
    assert json.loads((folder / run_lock.LOCK_NAME).read_text())["pid"] == holder.pid  # its record is still there
    lock = run_lock.acquire(folder)  # ... but the kernel released its lock
    lock.release()


def test_forked_child_does_not_keep_the_lock(tmp_path):
    """A worker forked while the lock is held closes its copy: the lock dies with the
    command even if the worker lives on."""
    folder = tmp_path / "run"
    code = textwrap.dedent(f"""
        import os, sys, time
        from savant_cli import run_lock
        run_lock.acquire({str(folder)!r})
        pid = os.fork()
        if pid == 0:  # lives on, its output away from the pipes (the test does not wait for it)
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 1)
            os.dup2(devnull, 2)
            time.sleep(30)
            os._exit(0)
        print(pid, flush=True)
        os.kill(os.getpid(), 9)
    """)
    p = subprocess.run([sys.executable, "-c", code], env=env(), capture_output=True, text=True, timeout=120)
    child = int(p.stdout.split()[0])
    try:
        os.kill(child, 0)  # the worker outlives its parent ...
        lock = run_lock.acquire(folder)  # ... and does not hold the folder
        lock.release()
    finally:
        os.kill(child, signal.SIGKILL)


def test_discard_removes_only_a_folder_it_made_and_left_empty(tmp_path):
    new = run_lock.acquire(tmp_path / "new")
    assert new.created
    new.discard()
    assert not (tmp_path / "new").exists()
    (tmp_path / "old").mkdir()
    old = run_lock.acquire(tmp_path / "old")
    old.discard()
    assert (tmp_path / "old").is_dir()


# --------------------------------------------------------------- the command line


@pytest.mark.slow
def test_two_writers_into_one_folder(tmp_path):
    """``savant run hydra.run.dir=S`` while another run writes S: refused with exit 2
    naming S, the holder's PID and host; S's record untouched; the first finishes."""
    folder = tmp_path / "S"
    first = Paused("startup", "run", *SHORT, f"hydra.run.dir={folder}").wait()
    try:
        before = tree(folder)
        second = savant("run", "winds=ksc_mean_annual", "sim.max_time_s=300", f"hydra.run.dir={folder}", cwd=tmp_path)
        assert second.code == 2, second.stderr
        text = " ".join(second.stderr.split())
        assert str(folder) in text and f"PID {first.proc.pid}" in text and socket.gethostname() in text
        assert "Traceback" not in second.stderr
        assert tree(folder) == before  # overrides.yaml, the log and the lock record as they were
        done = first.resume()
    finally:
        first.kill()
    assert done.code == 0, done.stderr
    assert (folder / "summary.json").is_file()


@pytest.mark.slow
def test_killed_holder_does_not_block(tmp_path):
    """A run killed with ``kill -9`` while holding its folder: the next run into it
    flies."""
    folder = tmp_path / "S"
    first = Paused("flight", "run", *SHORT, f"hydra.run.dir={folder}").wait()
    first.signal(signal.SIGKILL)
    again = savant("run", *SHORT, f"hydra.run.dir={folder}", cwd=tmp_path)
    assert again.code == 0, again.stderr
    assert json.loads((folder / "summary.json").read_text())["status"] in ("complete", "saturated")


@pytest.mark.slow
def test_refused_run_leaves_a_finished_folder_as_it_was(tmp_path):
    """A finished folder F: ``savant run winds.scale=nan hydra.run.dir=F`` exits 2 and
    leaves every file of F byte for byte as it was (``.hydra/overrides.yaml`` included)."""
    folder = tmp_path / "F"
    first = savant("run", *SHORT, f"hydra.run.dir={folder}", cwd=tmp_path)
    assert first.code == 0, first.stderr
    before = tree(folder)
    for bad in (["winds.scale=nan"], ["winds.scale=1e6"], ["study=montecarlo", "study.n_runs=1000000000000"]):
        refused = savant("run", *SHORT, *bad, f"hydra.run.dir={folder}", cwd=tmp_path)
        assert refused.code == 2, refused.stderr
        assert "Traceback" not in refused.stderr
        assert tree(folder) == before, bad


def test_invalid_command_leaves_no_folder(tmp_path):
    """Refused commands in a fresh working directory create no ``outputs/`` folder."""
    for bad in (["winds.scale=nan"], ["study=linear", "study.times=[900]"], ["sim.log_rate_hz=1000"]):
        refused = savant("run", *bad, cwd=tmp_path, timeout=300)
        assert refused.code == 2, refused.stderr
        assert bad[-1].split("=")[0] in refused.stderr
    assert list(tmp_path.iterdir()) == []


def test_montecarlo_manifest_refusal_writes_nothing(tmp_path):
    """A Monte Carlo folder whose journal holds another configuration's runs is refused
    before Hydra writes into it: nothing in it changes."""
    folder = tmp_path / "MC"
    (folder / "runs").mkdir(parents=True)
    (folder / ".hydra").mkdir()
    (folder / ".hydra" / "overrides.yaml").write_text("- study=montecarlo\n- study.n_runs=10\n")
    (folder / "runs" / "manifest.json").write_text(json.dumps({"fingerprint": "another configuration",
                                                                "n_runs": 10}))
    before = tree(folder)
    refused = savant("run", "study=montecarlo", "study.n_runs=20", f"hydra.run.dir={folder}", cwd=tmp_path,
                     timeout=300)
    assert refused.code == 2, refused.stderr
    assert "different configuration" in refused.stderr
    assert tree(folder) == before
    assert list(tmp_path.iterdir()) == [folder]


def test_api_refuses_a_held_folder(tmp_path):
    import savant_cli

    folder = tmp_path / "run"
    holder = _hold_in_child(folder, tmp_path / "ready", tmp_path / "release")
    try:
        before = tree(folder)
        with pytest.raises(run_lock.FolderBusy) as err:
            savant_cli.run(SHORT, out_dir=folder)
        assert err.value.key == "out_dir" and f"PID {holder.pid}" in str(err.value)
        assert tree(folder) == before
    finally:
        (tmp_path / "release").touch()
        holder.wait(timeout=60)


def test_report_refuses_a_held_folder(tmp_path):
    folder = tmp_path / "run"
    holder = _hold_in_child(folder, tmp_path / "ready", tmp_path / "release")
    try:
        done = savant("report", str(folder), timeout=300)
        assert done.code == 2 and f"PID {holder.pid}" in " ".join(done.stderr.split())
    finally:
        (tmp_path / "release").touch()
        holder.wait(timeout=60)
