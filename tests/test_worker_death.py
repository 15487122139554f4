"""Pool workers die with their parent: ``kill -9`` of the process that owns a pool ends
its workers within seconds, through Linux's parent-death signal and through the portable
watchdog on the parent PID; and a real Monte Carlo's main process killed with ``kill -9``
leaves no worker behind."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="reads process parents from /proc")


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, parent PID) of a process from /proc; None when it no longer exists."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return None
    fields = text[text.rindex(")") + 2:].split()
    return fields[0], int(fields[1])


def _cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def workers_of(pid: int) -> list[int]:
    """The children of ``pid`` forked from it (the same command line: the pool workers,
    not a helper such as multiprocessing's resource tracker)."""
    mine = _cmdline(pid)
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            st = _stat(int(entry.name))
            if st is not None and st[1] == pid and _cmdline(int(entry.name)) == mine:
                out.append(int(entry.name))
    return out


def alive(pid: int) -> bool:
    """Running (a zombie waiting for a reaper counts as gone)."""
    st = _stat(pid)
    return st is not None and st[0] not in ("Z", "X")


def wait_gone(pids: list[int], timeout_s: float) -> list[int]:
    """The PIDs still alive after ``timeout_s`` seconds (empty as soon as all are gone)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        left = [p for p in pids if alive(p)]
        if not left:
            return []
        time.sleep(0.1)
    return [p for p in pids if alive(p)]


OWNER = textwrap.dedent("""
    import sys, time
    from concurrent.futures import ProcessPoolExecutor
    from savant_cli import processes

    if sys.argv[1] == "watchdog":  # a platform without prctl
        processes._set_parent_death_signal = lambda sig: False

    def mechanism(_):
        return processes.die_with_parent(processes.os.getppid())  # what the initializer chose (idempotent)

    def sleep(_):
        time.sleep(600)

    if __name__ == "__main__":
        pool = ProcessPoolExecutor(2, mp_context=processes.process_context(), **processes.worker_initializer())
        print(pool.submit(mechanism, 0).result(), flush=True)
        for i in range(2):
            pool.submit(sleep, i)
        time.sleep(600)
""")


def _kill_owner_and_watch(tmp_path: Path, mode: str, timeout_s: float) -> tuple[str, list[int], list[int]]:
    script = tmp_path / "owner.py"
    script.write_text(OWNER)
    proc = subprocess.Popen([sys.executable, str(script), mode], env=ENV, stdout=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        chosen = proc.stdout.readline().strip()
        deadline = time.monotonic() + 60
        workers: list[int] = []
        while time.monotonic() < deadline and len(workers) < 2:
            workers = workers_of(proc.pid)
            time.sleep(0.05)
        assert len(workers) == 2, f"the pool did not start two workers: {workers}"
        os.kill(proc.pid, signal.SIGKILL)  # the owner alone, not its process group
        proc.wait()
        return chosen, workers, wait_gone(workers, timeout_s)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # whatever the test leaves, never an orphan
        except ProcessLookupError:
            pass


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_workers_die_with_their_parent_by_the_parent_death_signal(tmp_path):
    chosen, workers, left = _kill_owner_and_watch(tmp_path, "prctl", timeout_s=3.0)
    assert chosen == "prctl"
    assert left == [], f"workers {left} outlived their parent"


def test_workers_die_with_their_parent_by_the_watchdog(tmp_path):
    chosen, workers, left = _kill_owner_and_watch(tmp_path, "watchdog", timeout_s=5.0)
    assert chosen == "watchdog"
    assert left == [], f"workers {left} outlived their parent"


@pytest.mark.slow
def test_kill_9_of_a_monte_carlo_leaves_no_worker(tmp_path):
    """``kill -9`` of a running batch's main process: both pool workers are gone within
    a few seconds (they were seen flying runs first)."""
    out = tmp_path / "mc"
    cmd = [sys.executable, "-m", "savant_cli.cli", "run", "study=montecarlo", "phase=first_stage",
           "study.n_runs=200", "study.workers=2", "study.histories.signals=[]", "output.plots=false",
           "sim.progress=false", f"hydra.run.dir={out}"]
    proc = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 600
        workers: list[int] = []
        while time.monotonic() < deadline and not (len(workers) == 2 and any((out / "runs").glob("run_*.npz"))):
            workers = workers_of(proc.pid)
            time.sleep(0.1)
        assert len(workers) == 2 and any((out / "runs").glob("run_*.npz")), "the batch never got flying"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        left = wait_gone(workers, 5.0)
        assert left == [], f"workers {left} outlived the batch's main process"
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
