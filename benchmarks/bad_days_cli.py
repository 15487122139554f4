"""Reproduce the bad days of issue 27 (items 1, 5 and 6) against the installed CLI and
say, for each, what happens now.

    python benchmarks/bad_days_cli.py [--keep DIR]

Each case runs real ``savant`` processes (``python -m savant_cli.cli`` of the
interpreter running this script) in a scratch folder:

* two writers into one folder (``hydra.run.dir=S`` twice), and two identical Monte Carlo
  commands into one folder;
* a refused run (``winds.scale=nan``) into a finished folder, and the Monte Carlo
  manifest refusal, which must leave every file as it was; refused commands in a fresh
  working directory, which must leave no ``outputs/`` folder;
* Ctrl-C at start-up, in flight, while plotting and between a batch's runs: one line,
  exit 130, no traceback, true counts, nothing written or the folder marked
  ``interrupted.json``;
* the unbounded inputs: ``study.n_runs=1000000000000``, ``winds.scale=1e6``,
  ``study.times=[900]`` (beyond ``sim.max_time_s``), refused at once; and
  ``study.times=[700]``, inside ``sim.max_time_s`` but after the flight's end, refused
  as soon as the flight has flown, naming its end.

The moments are made deterministic with the CLI's test pause (``SAVANT_TEST_PAUSE_AT``,
``savant_cli/lifecycle.py``). The script prints one line per case, ``fixed`` or
``DEFECT``, with what it saw, and exits 1 when any defect is back. The first run of a
session compiles the plant (minutes on a loaded 2-core machine).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SHORT = ["winds=none", "sim.max_time_s=40", "sim.chunk_s=5", "sim.progress=false"]
BATCH = ["study=montecarlo", "study.n_runs=4", "study.workers=2", "sim.max_time_s=20", "winds=none",
         "sim.progress=false", "output.plots=false"]
WAIT_S = 900.0


def _env(pause: str | None = None) -> dict[str, str]:
    e = dict(os.environ, COLUMNS="200")
    e.pop("SAVANT_TEST_PAUSE_AT", None)
    if pause:
        e["SAVANT_TEST_PAUSE_AT"] = pause
    return e


def savant(args: list[str], cwd: Path, timeout: float = WAIT_S) -> subprocess.CompletedProcess:
    """``savant ARGS`` to its end."""
    return subprocess.run([sys.executable, "-m", "savant_cli.cli", *args], cwd=cwd, env=_env(), capture_output=True,
                          text=True, timeout=timeout)


class Paused:
    """``savant ARGS`` held at a stage (the CLI's test pause) in its own process group."""

    def __init__(self, stage: str, args: list[str], cwd: Path) -> None:
        self.stage = stage
        self.p = subprocess.Popen([sys.executable, "-m", "savant_cli.cli", *args], cwd=cwd, env=_env(stage),
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
        self.err = ""
        assert self.p.stderr is not None
        for line in self.p.stderr:
            self.err += line
            if f"paused at {stage}" in line:
                return
        raise RuntimeError(f"never reached {stage}:\n{self.err}{self.p.communicate()[1]}")

    def send(self, sig: int) -> tuple[int, str, str]:
        os.killpg(self.p.pid, sig)
        out, err = self.p.communicate(timeout=WAIT_S)
        return self.p.returncode, out, err

    def go_on(self) -> tuple[int, str, str]:
        self.p.send_signal(signal.SIGUSR1)
        out, err = self.p.communicate(timeout=WAIT_S)
        return self.p.returncode, out, err

    def leftovers(self) -> bool:
        """Whether any process of its group is still alive, 10 s after it ended."""
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            try:
                os.killpg(self.p.pid, 0)
            except ProcessLookupError:
                return False
            time.sleep(0.1)
        os.killpg(self.p.pid, signal.SIGKILL)
        return True


def tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def flat(text: str) -> str:
    return " ".join(text.split())


RESULTS: list[tuple[str, bool, str]] = []


def case(name: str, ok: bool, seen: str) -> None:
    RESULTS.append((name, ok, seen))
    print(f"{'fixed ' if ok else 'DEFECT'}  {name}: {seen}", flush=True)


# --------------------------------------------------------------------------- cases


def two_writers(root: Path) -> None:
    s = root / "S"
    first = Paused("startup", ["run", *SHORT, f"hydra.run.dir={s}"], root)
    before = tree(s)
    second = savant(["run", "winds=ksc_mean_annual", "sim.max_time_s=300", f"hydra.run.dir={s}"], root)
    same = tree(s) == before
    code, _, _ = first.go_on()
    said = flat(second.stderr)
    case("two writers into one folder", second.returncode == 2 and f"PID {first.p.pid}" in said and same
         and code == 0, f"second exit {second.returncode}, '{said[:160]}…', folder untouched {same}, first exit {code}")

    mc = root / "MC2"
    first = Paused("runs", ["run", *BATCH, f"hydra.run.dir={mc}"], root)
    second = savant(["run", *BATCH, f"hydra.run.dir={mc}"], root)
    code, _, _ = first.go_on()
    case("two identical Monte Carlo commands", second.returncode == 2 and code == 0,
         f"second exit {second.returncode} ({flat(second.stderr)[:100]}…), first exit {code}")


def stale_lock(root: Path) -> None:
    s = root / "K"
    first = Paused("flight", ["run", *SHORT, f"hydra.run.dir={s}"], root)
    first.send(signal.SIGKILL)
    again = savant(["run", *SHORT, "output.plots=false", f"hydra.run.dir={s}"], root)
    case("a holder killed with kill -9 does not block", again.returncode == 0, f"next run exit {again.returncode}")


def refused_into_finished(root: Path) -> None:
    f = root / "F"
    done = savant(["run", *SHORT, "output.plots=false", f"hydra.run.dir={f}"], root)
    before = tree(f)
    refused = savant(["run", "winds.scale=nan", f"hydra.run.dir={f}"], root)
    overrides = (f / ".hydra" / "overrides.yaml").read_text()
    case("a refused run into a finished folder", done.returncode == 0 and refused.returncode == 2
         and tree(f) == before, f"exit {refused.returncode}, overrides.yaml {overrides.split()}")

    mc = root / "MCF"
    (mc / "runs").mkdir(parents=True)
    (mc / "runs" / "manifest.json").write_text(json.dumps({"fingerprint": "another configuration"}))
    before = tree(mc)
    refused = savant(["run", *BATCH, f"hydra.run.dir={mc}"], root)
    case("the Monte Carlo manifest refusal", refused.returncode == 2 and tree(mc) == before,
         f"exit {refused.returncode}, folder untouched {tree(mc) == before}")

    fresh = root / "fresh"
    fresh.mkdir()
    codes = [savant(args, fresh).returncode for args in (["run", "winds.scale=nan"], ["run", "winds.scale=1e6"],
                                                         ["run", "study=linear", "study.times=[900]"])]
    left = sorted(p.name for p in fresh.rglob("*"))
    case("refused commands leave no folder", codes == [2, 2, 2] and not left, f"exits {codes}, left {left}")


def interrupts(root: Path) -> None:
    for stage, args in (("startup", SHORT), ("flight", SHORT), ("plots", SHORT), ("runs", BATCH)):
        folder = root / f"C_{stage}"
        p = Paused(stage, ["run", *args, f"hydra.run.dir={folder}"], root)
        code, out, err = p.send(signal.SIGINT)
        orphans = p.leftovers()
        lines = [ln for ln in err.splitlines() if ln.strip()]
        marker = folder / "interrupted.json"
        state = "removed" if not folder.exists() else ("marked interrupted" if marker.is_file() else "NOT marked")
        ok = code == 130 and len(lines) == 1 and "Traceback" not in err and not orphans and state != "NOT marked"
        if stage == "runs":
            journaled = len(list((folder / "runs").glob("run_*.npz")))
            ok = ok and f"{journaled} run(s) flown this time" in lines[-1] and "flown" not in out
        case(f"Ctrl-C {stage}", ok, f"exit {code}, {len(lines)} line(s): '{lines[-1] if lines else ''}', folder "
             f"{state}, processes left {orphans}")


def unbounded(root: Path) -> None:
    for args, key in ((["study=montecarlo", "study.n_runs=1000000000000"], "study.n_runs"),
                      (["winds.scale=1e6"], "winds.scale"), (["study=linear", "study.times=[900]"], "study.times")):
        t0 = time.perf_counter()
        p = savant(["run", *args], root, timeout=120)
        wall = time.perf_counter() - t0
        case(f"{' '.join(args)}", p.returncode == 2 and key in p.stderr and wall < 60,
             f"exit {p.returncode} in {wall:.1f} s: {flat(p.stderr)[:150]}")
    t0 = time.perf_counter()
    p = savant(["run", "study=linear", "study.times=[700]", f"hydra.run.dir={root / 'T700'}"], root)
    case("study.times=[700] (inside sim.max_time_s, after the flight's end)",
         p.returncode == 2 and "inside the flight" in p.stderr,
         f"exit {p.returncode} after {time.perf_counter() - t0:.1f} s, once the flight's end is known: "
         f"{flat(p.stderr)[-120:]}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", type=Path, default=None, help="work in this folder and keep it")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bad_days_") as tmp:
        root = (args.keep or Path(tmp)).resolve()
        root.mkdir(parents=True, exist_ok=True)
        for step in (two_writers, stale_lock, refused_into_finished, interrupts, unbounded):
            try:
                step(root)
            except Exception as exc:  # noqa: BLE001 - a case that cannot even run is a defect
                case(step.__name__, False, f"{type(exc).__name__}: {exc}")
    bad = [name for name, ok, _ in RESULTS if not ok]
    print(f"{len(RESULTS) - len(bad)} of {len(RESULTS)} fixed" + (f"; DEFECTS: {', '.join(bad)}" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
