"""Ctrl-C anywhere (issue 27, item 5): real ``savant run`` processes interrupted with
SIGINT at start-up, in flight, while plotting and between a batch's runs give one line,
exit status 130 and no traceback, and leave nothing or a folder marked interrupted."""

from __future__ import annotations

import json
import os
import re
import signal
import time

import pytest

from lifecycle_helpers import Paused, after_pause
from savant_cli.lifecycle import MARKER
from savant_cli.run_lock import LOCK_NAME

SHORT = ["winds=none", "sim.max_time_s=40", "sim.chunk_s=5", "sim.progress=false"]


def _group_ends(pgid: int, within_s: float = 10.0) -> bool:
    """Whether every process of the group ``pgid`` (the command and its workers) is
    gone within ``within_s``."""
    deadline = time.monotonic() + within_s
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.1)
    return False


def _interrupt(stage: str, *args: str, cwd, stdout_before: str | None = "",
               inactive_notes: bool = False) -> tuple[str, int]:
    """Interrupt ``savant run ARGS`` at ``stage``: the one line it said and its status.
    Its stdout must be ``stdout_before`` (what it printed before the pause) only; ``None``:
    the run's console summary, which a study prints before it writes its files, ending on
    its mission line. ``inactive_notes``: a batch's notes of its inactive dispersions
    precede it (one per reason, wrapped at the terminal's width)."""
    p = Paused(stage, "run", *args, cwd=cwd).wait()
    try:
        done = p.signal(signal.SIGINT)
        assert _group_ends(p.proc.pid), "a process of the command outlived it"
    finally:
        if p.proc.poll() is None:
            p.kill()
        else:
            try:
                os.killpg(p.proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    said = after_pause(done.stderr).strip()
    assert "Traceback" not in done.stderr and "KeyboardInterrupt" not in done.stderr, done.stderr
    assert len(said.splitlines()) == 1, said  # one line
    out = done.stdout.strip()
    if inactive_notes:  # the notes (one per reason, wrapped at the terminal's width): drop them
        assert out.startswith("inactive dispersions"), done.stdout
        out = re.sub(r"inactive dispersions, drawn but applied to nothing \([^)]*\): [\w,\s]*", "", out).strip()
    if stdout_before is None:
        assert out.startswith("savant run summary") and out.splitlines()[-1].startswith("mission:"), done.stdout
    else:
        assert out.startswith(stdout_before) and len(out) <= len(stdout_before) + 400, done.stdout
    return said, done.code


def test_interrupt_at_startup_writes_nothing(tmp_path):
    folder = tmp_path / "S"
    said, code = _interrupt("startup", *SHORT, f"hydra.run.dir={folder}", cwd=tmp_path)
    assert code == 130
    assert said.startswith("interrupted while starting up") and "nothing was written" in said
    assert not folder.exists() and list(tmp_path.iterdir()) == []


def test_interrupt_at_startup_of_an_existing_folder_marks_it(tmp_path):
    """A folder that was there before is not removed: it is marked."""
    folder = tmp_path / "S"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    said, code = _interrupt("startup", *SHORT, f"hydra.run.dir={folder}", cwd=tmp_path)
    assert code == 130 and "marked interrupted" in said
    assert (folder / "notes.txt").read_text() == "mine"
    marker = json.loads((folder / MARKER).read_text())
    assert marker["status"] == "interrupted" and marker["stage"] == "startup"


@pytest.mark.slow
def test_interrupt_in_flight_writes_the_flight_so_far(tmp_path):
    folder = tmp_path / "S"
    said, code = _interrupt("flight", *SHORT, f"hydra.run.dir={folder}", cwd=tmp_path)
    assert code == 130
    assert said.startswith("interrupted while flying") and "t = 5.00 s" in said
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["stop_reason"] == "interrupted"
    assert summary["final_time_s"] == pytest.approx(5.0)
    assert (folder / "savant.h5").is_file() and not (folder / "plots").exists()
    marker = json.loads((folder / MARKER).read_text())
    assert marker["stage"] == "flight" and "savant.h5" in marker["complete_files"]
    assert not list(folder.glob(".*.tmp"))


@pytest.mark.slow
def test_interrupt_while_plotting_marks_the_folder_and_report_finishes_it(tmp_path):
    folder = tmp_path / "S"
    said, code = _interrupt("plots", *SHORT, f"hydra.run.dir={folder}", cwd=tmp_path, stdout_before=None)
    assert code == 130 and said.startswith("interrupted while drawing the plots")
    assert f"savant report {folder}" in said
    assert json.loads((folder / "summary.json").read_text())["status"] != "interrupted"  # the flight was whole
    marker = json.loads((folder / MARKER).read_text())
    assert marker["stage"] == "plots" and {"savant.h5", "summary.json"} <= set(marker["complete_files"])
    assert not (folder / "report.html").exists()
    from lifecycle_helpers import savant

    done = savant("report", str(folder))
    assert done.code == 0, done.stderr
    assert (folder / "report.html").is_file() and not (folder / MARKER).exists()
    assert (folder / LOCK_NAME).is_file()


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 2])
def test_interrupted_batch_counts_the_runs_it_flew(tmp_path, workers):
    """A Monte Carlo interrupted after its first journaled run says one run flown, not
    the batch's size, writes no batch tables, leaves no worker behind (they ignore the
    terminal's SIGINT and are ended by the main process), and resumes to the end."""
    folder = tmp_path / "MC"
    args = ["study=montecarlo", "study.n_runs=4", f"study.workers={workers}", "sim.max_time_s=20", "winds=none",
            "sim.progress=false", "output.plots=false", f"hydra.run.dir={folder}"]
    said, code = _interrupt("runs", *args, cwd=tmp_path, inactive_notes=True)
    assert code == 130
    assert "1 run(s) flown this time, 1 of 4 in" in said and "to resume" in said
    assert len(list((folder / "runs").glob("run_*.npz"))) == 1
    assert not (folder / "savant.h5").exists()
    assert json.loads((folder / MARKER).read_text())["stage"] == "runs"
    from lifecycle_helpers import savant

    done = savant("run", *args, cwd=tmp_path)
    assert done.code == 0, done.stderr
    assert "3 of 3 runs flown" in " ".join(done.stdout.split())
    assert not (folder / MARKER).exists()


def test_api_interrupt_settles_the_folder_and_raises(tmp_path, monkeypatch, capfd):
    """``savant_cli.run`` interrupted while loading: the folder it made goes again, one
    line on stderr, ``KeyboardInterrupt`` raised, the Ctrl-C handler given back."""
    import threading

    import savant_cli
    from savant_cli import lifecycle

    monkeypatch.setenv("SAVANT_TEST_PAUSE_AT", "prepare")
    monkeypatch.setattr(lifecycle, "_paused", set())
    monkeypatch.setattr(lifecycle, "_current", "startup")
    handler = signal.getsignal(signal.SIGINT)

    def interrupt_when_paused() -> None:
        deadline = time.monotonic() + 300
        while lifecycle.current() != "prepare" and time.monotonic() < deadline:
            time.sleep(0.02)
        time.sleep(0.3)
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=interrupt_when_paused, daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        savant_cli.run(SHORT, out_dir=tmp_path / "run")
    assert not (tmp_path / "run").exists()
    said = after_pause(capfd.readouterr().err).strip()
    assert said == f"interrupted while loading the vehicle and building the model: nothing was written " \
                   f"({tmp_path / 'run'} removed)"
    assert signal.getsignal(signal.SIGINT) is handler


@pytest.mark.slow
def test_interrupt_between_parallel_searches_leaves_no_worker(tmp_path):
    """``study=time_margins`` on two workers interrupted after its first search: one
    line, 130, the other worker's search abandoned and the worker gone."""
    folder = tmp_path / "TM"
    said, code = _interrupt("searches", "study=time_margins", "study.times=[55]", "study.axes=[pitch]",
                            "study.kinds=[gain_high,gain_low]", "study.workers=2", "study.scan_points=2",
                            "winds=none", "sim.progress=false", f"hydra.run.dir={folder}", cwd=tmp_path)
    assert code == 130 and said.startswith("interrupted while running the time-margin searches")
