"""Bad days for a batch (issue 27, items 2, 3, 4 and 8): reproduce each defect of the
issue's "Why" against the installed ``savant`` command and print what happens now.

    python benchmarks/bad_days_batch.py [--keep DIR]

1. **Damaged journal.** A small Monte Carlo batch; one entry overwritten with garbage,
   one truncated, one with a changed value under its old checksum. ``savant rerun`` of a
   damaged run, ``savant collect`` and the resume (the same command again) must name
   them (file and run), never crash, and the resumed batch must equal the undamaged one
   bit for bit (``savant_cli/io/bitwise.py``).
2. **kill -9 of the parent.** A batch on two workers; ``kill -9`` of its main process
   alone; both workers must be gone within 5 s.
3. **Disk full.** A nominal run and a batch on a 2 MB / 1 MB tmpfs in a private mount
   namespace (``unshare -rm``), or, where that is not allowed (or with
   ``--simulate-enospc``), a nominal run with ``ENOSPC`` injected where ``savant.h5`` is
   written: one line naming the file and folder, the summary on the console, no
   traceback, exit 1, no temporary file left, every file written whole.
4. **Damaged savant.h5.** ``savant report`` (exit 2, the file, the problem, the command
   that rebuilds it) and ``savant_cli.load`` (a ``SavantError``), then the command the
   message gives rebuilds it.

Prints one line per check (``ok`` or ``DEFECT``) and exits 1 if any defect is back.
Takes a few minutes on the 2-core reference machine (the plant compiles on first use).
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BATCH = ["study=montecarlo", "phase=first_stage", "study.n_runs=8", "study.workers=2", "study.histories.rate_hz=2",
         "output.plots=false", "sim.progress=false"]
RESULTS: list[tuple[str, bool, str]] = []


def savant_cmd() -> list[str]:
    exe = shutil.which("savant")
    return [exe] if exe else [sys.executable, "-m", "savant_cli.cli"]


def savant(*args: str, cwd: Path, timeout: float = 1800) -> subprocess.CompletedProcess:
    return subprocess.run([*savant_cmd(), *args], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "COLUMNS": "200"})


def flat(text: str) -> str:
    return " ".join(text.split())


def check(name: str, ok: bool, detail: str) -> None:
    RESULTS.append((name, ok, detail))
    print(f"{'ok     ' if ok else 'DEFECT '} {name}: {detail}", flush=True)


def no_traceback(proc: subprocess.CompletedProcess) -> bool:
    return "Traceback" not in proc.stdout + proc.stderr


# ------------------------------------------------------------------------- 1. journal


def damaged_journal(work: Path) -> Path:
    from savant_cli.io.bitwise import compare_h5

    out = work / "mc"
    args = ["run", *BATCH, f"hydra.run.dir={out}"]
    first = savant(*args, cwd=work)
    if first.returncode != 0:
        check("batch flies", False, f"exit {first.returncode}: {first.stderr[-500:]}")
        return out
    reference = work / "reference.h5"
    shutil.copy(out / "savant.h5", reference)
    runs = out / "runs"
    (runs / "run_000003.npz").write_bytes(os.urandom(4096))
    raw = (runs / "run_000005.npz").read_bytes()
    (runs / "run_000005.npz").write_bytes(raw[: len(raw) // 2])
    with np.load(runs / "run_000006.npz") as z:
        members = {k: z[k] for k in z.files}
    members["summary"] = members["summary"] * 1.001
    with open(runs / "run_000006.npz", "wb") as fh:
        np.savez(fh, **members)

    rerun = savant("rerun", str(out), "run=3", cwd=work)
    text = flat(rerun.stdout + rerun.stderr)
    check("rerun of a garbled run", rerun.returncode == 2 and no_traceback(rerun)
          and f"{runs / 'run_000003.npz'} is damaged" in text and "run 3" in text,
          f"exit {rerun.returncode}; " + next((ln for ln in (rerun.stdout + rerun.stderr).splitlines()
                                               if "damaged" in ln), "no line names the damaged entry"))
    collect = savant("collect", str(out), cwd=work)
    text = flat(collect.stdout + collect.stderr)
    named = [r for r in (3, 5, 6) if f"damaged journal entry {runs / f'run_{r:06d}.npz'} (run {r})" in text]
    check("collect lists damaged entries as missing", collect.returncode == 1 and no_traceback(collect)
          and named == [3, 5, 6] and "missing runs (3 of 8): 3, 5-6" in text,
          f"exit {collect.returncode}; damaged named: {named}; "
          + ("'missing runs (3 of 8): 3, 5-6'" if "missing runs (3 of 8): 3, 5-6" in text else "missing list wrong"))
    again = savant(*args, cwd=work)
    text = flat(again.stdout + again.stderr)
    diffs = compare_h5(reference, out / "savant.h5") if (out / "savant.h5").is_file() else ["no savant.h5"]
    check("resume re-flies damaged entries bit for bit", again.returncode == 0 and no_traceback(again)
          and "resuming: 5 of 8 runs" in text and all(f"flying run {r} again" in text for r in (3, 5, 6))
          and diffs == [], f"exit {again.returncode}; savant.h5 differences from the undamaged batch: {len(diffs)}")
    temps = [p.name for p in runs.iterdir() if p.name.startswith(".")]
    check("no temporary journal files", temps == [], f"left: {temps}")
    return out


# -------------------------------------------------------------------- 2. orphans


def _children(pid: int) -> list[int]:
    mine = Path(f"/proc/{pid}/cmdline").read_bytes()
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            if int(stat[stat.rindex(")") + 2:].split()[1]) == pid and (entry / "cmdline").read_bytes() == mine:
                out.append(int(entry.name))
        except (OSError, ValueError):
            continue
    return out


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2:].split()[0] not in ("Z", "X")


def orphans(work: Path) -> None:
    if not Path("/proc/self/stat").is_file():
        check("kill -9 leaves no worker", True, "skipped: no /proc to find the workers")
        return
    out = work / "killed"
    proc = subprocess.Popen([*savant_cmd(), "run", *BATCH, "study.n_runs=400", f"hydra.run.dir={out}"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 900
        workers: list[int] = []
        while time.monotonic() < deadline and not (len(workers) == 2 and any((out / "runs").glob("run_*.npz"))):
            workers = _children(proc.pid) if proc.poll() is None else []
            time.sleep(0.2)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        t0 = time.monotonic()
        while time.monotonic() - t0 < 5.0 and any(_alive(p) for p in workers):
            time.sleep(0.1)
        left = [p for p in workers if _alive(p)]
        check("kill -9 of a batch leaves no worker", len(workers) == 2 and not left,
              f"workers {workers}; alive 5 s after the kill: {left}")
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


# ------------------------------------------------------------------ 3. disk full


def _namespaces() -> bool:
    if shutil.which("unshare") is None:
        return False
    return subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /tmp"],
                          capture_output=True).returncode == 0


INJECT = """
import errno, os, sys
import savant_cli.io.atomic as atomic
_real = atomic._fsync_file
def _full(path):
    if path.name.startswith(PREFIX):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    _real(path)
atomic._fsync_file = _full
from savant_cli.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _leftovers(folder: Path) -> list[str]:
    return [str(p.relative_to(folder)) for p in folder.rglob("*") if p.name.endswith(".tmp") or ".tmp." in p.name]


def disk_full(work: Path, simulate: bool) -> None:
    if not simulate and _namespaces():
        for name, size, args, summary_words in (
                ("nominal on a 2 MB tmpfs", "2m", ["run", "phase=first_stage", "sim.progress=false"],
                 "savant run summary"),
                ("batch on a 1 MB tmpfs", "1m", ["run", *BATCH, "study.n_runs=400"], "runs: complete")):
            disk = work / f"disk_{size}"
            disk.mkdir()
            logs = work / f"logs_{size}"
            logs.mkdir()
            cmd = " ".join(map(shlex.quote, [*savant_cmd(), *args, f"hydra.run.dir={disk}/out"]))
            find = (f"find {shlex.quote(str(disk))} -name '*.tmp' -o -name '*.tmp.*' > {shlex.quote(str(logs / 'temps'))}")
            script = (f"mount -t tmpfs -o size={size} tmpfs {shlex.quote(str(disk))} || exit 99\n"
                      f"{cmd} > {logs}/stdout 2> {logs}/stderr; echo $? > {logs}/rc\n{find}\n")
            subprocess.run(["unshare", "-rm", "sh", "-c", script], env={**os.environ, "COLUMNS": "200"}, timeout=1800)
            rc = int((logs / "rc").read_text())
            out, err = (logs / "stdout").read_text(), (logs / "stderr").read_text()
            lines = [ln for ln in (out + err).splitlines() if "could not write" in ln and "No space left" in ln]
            temps = (logs / "temps").read_text().split()
            summary = summary_words in out
            check(f"disk full: {name}", rc == 1 and "Traceback" not in out + err and len(lines) >= 1 and summary
                  and not temps, f"exit {rc}; {' / '.join(ln.strip() for ln in lines) or 'no line names the file'}; "
                                 f"summary printed: {summary}; temporary files left: {len(temps)}")
        return
    # no mount namespace here: ENOSPC injected where savant.h5 is written
    out = work / "enospc"
    proc = subprocess.run([sys.executable, "-c", "PREFIX = '.savant.h5'\n" + INJECT, "run", "phase=first_stage",
                           "sim.progress=false", f"hydra.run.dir={out}"], capture_output=True, text=True,
                          timeout=1800, env={**os.environ, "COLUMNS": "200"})
    line = next((ln for ln in proc.stderr.splitlines() if "could not write savant.h5" in ln), "")
    check("disk full (simulated ENOSPC): nominal", proc.returncode == 1 and no_traceback(proc) and bool(line)
          and "savant run summary" in proc.stdout and not _leftovers(out),
          f"exit {proc.returncode}; {line.strip() or 'no line names the file'}")


# ---------------------------------------------------------------- 4. savant.h5


def damaged_h5(work: Path, batch: Path) -> None:
    if not (batch / "savant.h5").is_file():
        check("damaged savant.h5", False, "no batch to damage")
        return
    reference = (batch / "savant.h5").read_bytes()
    (batch / "savant.h5").write_bytes(reference[: len(reference) // 3])
    report = savant("report", str(batch), cwd=work)
    text = flat(report.stderr)
    hint = text.split("run the same command again to rebuild it: ", 1)[1] if "rebuild it: " in text else ""
    check("report of a truncated savant.h5", report.returncode == 2 and no_traceback(report)
          and f"{batch / 'savant.h5'} is damaged (truncated:" in text and bool(hint),
          f"exit {report.returncode}; {text[:300]}")
    load = subprocess.run([sys.executable, "-c", "import sys, savant_cli\nfrom savant_cli.errors import SavantError\n"
                           "try:\n    savant_cli.load(sys.argv[1])\nexcept SavantError as e:\n"
                           "    print(type(e).__name__, e)\n", str(batch)], capture_output=True, text=True)
    check("savant_cli.load of a truncated savant.h5", load.stdout.startswith("DamagedFileError") and no_traceback(load),
          load.stdout.strip()[:200] or load.stderr.strip()[-300:])
    if hint:
        command = hint.split(" (the ")[0]
        rebuilt = savant(*shlex.split(command)[1:], cwd=work)
        check("the command the message gives rebuilds it", rebuilt.returncode == 0
              and savant("report", str(batch), cwd=work).returncode == 0, f"exit {rebuilt.returncode}: {command}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--keep", type=Path, default=None, help="work in this folder and keep it")
    ap.add_argument("--simulate-enospc", action="store_true",
                    help="inject ENOSPC at the write layer even where a tmpfs could be mounted")
    args = ap.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="savant-bad-days-"))
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    try:
        batch = damaged_journal(work)
        orphans(work)
        disk_full(work, args.simulate_enospc)
        damaged_h5(work, batch)
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    bad = [name for name, ok, _ in RESULTS if not ok]
    print(f"{len(RESULTS) - len(bad)} of {len(RESULTS)} checks pass in {time.perf_counter() - t0:.0f} s"
          + (f"; defects back: {', '.join(bad)}" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
