"""Bitwise regression of a restructuring: the outputs of this checkout against the outputs
of a reference commit, flown case by case through the installed command line.

    python benchmarks/bitwise_regression.py --ref a15cafb            # reference from git
    python benchmarks/bitwise_regression.py --ref-dir /tmp/ref_out   # reuse recorded outputs
    python benchmarks/bitwise_regression.py --record DIR             # only record this checkout
    python benchmarks/bitwise_regression.py --ref 325fc54 --with guidance=ares_i_iss   # the same overrides on both

The cases are the acceptance set of issue 11: all 16 combinations of ``flex``, ``slosh``,
``twd`` and ``actuator`` (nominal flights), ``study=linear`` at the paper's four times with
full fidelity, and a 20-run full-fidelity Monte Carlo. Each case runs as its own
``python -m savant_cli.cli run ...`` process with ``PYTHONPATH`` set to the source tree
under test, so the reference is the reference commit's own code, not an import of it.

What is compared, exactly (``numpy.array_equal`` with NaNs equal, byte equality for
strings; ``savant_cli/io/bitwise.py``): every dataset and every group attribute of
``savant.h5`` except provenance and the stored config text, and of the root attributes
the run's ``complete``, ``status`` and ``message`` (the others are provenance: host, time, versions, wall time); every key of
every JSON file except the wall-clock ones and the Monte Carlo journal's config
fingerprint; every array of the journal's run records; and the bytes of every CSV the
study writes.
A difference is printed with its location and the largest absolute deviation.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import h5py
import numpy as np

from savant_cli.io import bitwise
from savant_cli.io.bitwise import WALL_CLOCK_KEYS
from savant_cli.montecarlo.journal import CHECKSUM_KEY

ROOT = Path(__file__).resolve().parents[1]
FULL = ["flex=on", "flex.n_modes=4", "slosh=on", "twd=on", "actuator=third_order"]
COMMON = ["output.plots=false", "sim.progress=false"]

#: Keys that hash the configuration's layout, not the flight (the Monte Carlo journal's
#: resume fingerprint changes whenever the config schema does).
CONFIG_HASH_KEYS = ("fingerprint",)
#: The summary's load-indicator keys (issue 15), a regex alternation.
LOAD_KEYS = (r"time_max_qalpha_s|max_qalpha_pitch_Pa_deg|time_max_qalpha_pitch_s|max_qbeta_Pa_deg|time_max_qbeta_s"
             r"|qalpha_limit_Pa_deg|qalpha_limit_ratio|time_above_qalpha_limit_s|qalpha_limit_exceeded")
#: Deliberate additions since the reference (a15cafb): output that only the new file may
#: hold, by ``compare_h5`` location (regex) → why. Anything else present in one file only
#: is a difference.
NAMED_ADDITIONS = {
    r"linear/margins@(requirements|exclusion_zones)":
        "issue 11 item 5: the linear study stores what its charts mark, for savant report",
    r"montecarlo@requirements": "issue 11 item 5: the batch stores its requirement set, for savant report",
    r"linear/t\d+/charts(/.*)?": "issue 11 item 5: the chart data of a charted point, for savant report",
    r"summary@(insertion_.*)": "issue 14: the insertion errors against the target at cutoff",
    r"montecarlo/summary/insertion_.*": "issue 14: the insertion errors of every run",
    r"montecarlo@insertion": "issue 14: the batch's insertion accuracy and flight-performance reserve",
    rf"summary@({LOAD_KEYS})": "issue 15: the load indicators (q-alpha, q-beta, their times, the q-alpha limit)",
    rf"montecarlo/summary/({LOAD_KEYS})": "issue 15: the load indicators of every run",
    r"montecarlo@loads": "issue 15: the batch's q-alpha extremes and runs above the limit",
    r"montecarlo/events/first_stage_cutoff_s": "issue 29: a liquid first stage's cutoff event (NaN for a motor)",
    r"montecarlo/events/booster_jettison_s": "issue 29: the strap-on boosters' jettison event (NaN without boosters)",
    r"(.*/)?booster_thrust(@.*)?": "issue 29: the strap-on boosters' delivered thrust (0 without boosters)",
}
#: Deliberate additions to the JSON summaries, the CSV tables and the journal records
#: (a key, a statistics row or a summary column only the new output holds), by name.
NAMED_KEYS = {r"insertion(_.*)?": "issue 14: insertion errors and statistics",
              rf"{LOAD_KEYS}|loads": "issue 15: load indicators and the batch's load extremes"}


def cases() -> dict[str, list[str]]:
    """Case name → command-line overrides."""
    out: dict[str, list[str]] = {}
    for flex, slosh, twd, act in itertools.product(("off", "on"), ("off", "on"), ("off", "on"),
                                                   ("third_order", "simplex")):
        extra = ["flex.n_modes=4"] if flex == "on" else []
        out[f"nominal_flex-{flex}_slosh-{slosh}_twd-{twd}_{act}"] = [
            f"flex={flex}", f"slosh={slosh}", f"twd={twd}", f"actuator={act}", *extra]
    # a run that diverges with slosh on: its divergence time is the one named fix of issue 11
    out["diverging_slosh"] = ["slosh=on", "sim.max_body_rate_deg_s=1.0"]
    out["linear_full"] = ["study=linear", "study.charts=none", *FULL]
    out["montecarlo_full_20"] = ["study=montecarlo", "study.n_runs=20", "study.workers=2", *FULL]
    return out


def record(source: Path, out_dir: Path, jobs: int = 2, extra: tuple[str, ...] = ()) -> None:
    """Fly every case with the code of ``source`` into ``out_dir/<case>`` (``extra``:
    overrides added to every case)."""
    env = dict(os.environ, PYTHONPATH=str(source))
    env.pop("SAVANT_SOURCE_DIR", None)

    def one(item: tuple[str, list[str]]) -> str:
        name, overrides = item
        run_dir = out_dir / name
        cmd = [sys.executable, "-m", "savant_cli.cli", "run", *overrides, *extra, *COMMON, f"hydra.run.dir={run_dir}"]
        proc = subprocess.run(cmd, cwd=source, env=env, capture_output=True, text=True)
        (out_dir / f"{name}.log").write_text(proc.stdout + proc.stderr)
        return f"{name}: exit {proc.returncode}"

    out_dir.mkdir(parents=True, exist_ok=True)
    with ThreadPoolExecutor(jobs) as pool:
        for line in pool.map(one, cases().items()):
            print(line, flush=True)


def compare_h5(a: Path, b: Path) -> list[str]:
    """Differences between two run files (empty: bitwise identical); the summary keys of
    :data:`NAMED_KEYS` may be new (``savant_cli/io/bitwise.py`` says what is compared)."""
    return bitwise.compare_h5(a, b, addition=_named)


def named_additions(diffs: list[str]) -> tuple[list[str], list[str]]:
    """Split differences into the deliberate additions of :data:`NAMED_ADDITIONS` (as
    ``location: why``) and the rest."""
    named, rest = [], []
    for d in diffs:
        rel, _, tail = d.partition(": ")  # "<file>: <location>: <what>"
        loc, _, what = tail.partition(": ") if rel.endswith(".h5") else ("", "", "")
        why = next((w for pat, w in NAMED_ADDITIONS.items() if re.fullmatch(pat, loc)), None)
        if why and what == "only in the new file":
            named.append(f"{loc}: {why}")
        else:
            rest.append(d)
    return named, rest


def compare_json(a: Path, b: Path) -> list[str]:
    ja, jb = json.loads(a.read_text()), json.loads(b.read_text())
    diffs = []

    def walk(x, y, path):
        if _rows(x) and _rows(y):  # statistics tables: rows by variable
            x, y = ({r["variable"]: r for r in x}, {r["variable"]: r for r in y})
        if isinstance(x, dict) and isinstance(y, dict):
            for k in sorted(set(x) | set(y)):
                if k in WALL_CLOCK_KEYS or k in CONFIG_HASH_KEYS:
                    continue
                if k not in x and _named(k):
                    continue  # a deliberate addition (NAMED_KEYS)
                if k not in x or k not in y:
                    diffs.append(f"{path}{k}: key only in one file")
                else:
                    walk(x[k], y[k], f"{path}{k}.")
        elif x != y and not (isinstance(x, float) and isinstance(y, float) and x != x and y != y):
            diffs.append(f"{path.rstrip('.')}: {x!r} vs {y!r}")

    walk(ja, jb, "")
    return diffs


def _named(key: str) -> bool:
    return any(re.fullmatch(pat, key) for pat in NAMED_KEYS)


def _rows(x) -> bool:
    """A list of statistics rows (dicts keyed by ``variable``)."""
    return isinstance(x, list) and bool(x) and all(isinstance(r, dict) and "variable" in r for r in x)


def compare_csv(a: Path, b: Path) -> list[str]:
    """Byte equality, or, for a table whose new rows are all deliberate additions (first
    field named in NAMED_KEYS), byte equality of the other rows."""
    la, lb = a.read_text().splitlines(), b.read_text().splitlines()
    if la == lb:
        return []
    old_rows = {ln.split(",", 1)[0] for ln in la}  # rows named as additions but already in the reference stay
    kept = [ln for ln in lb if ln.split(",", 1)[0] in old_rows or not _named(ln.split(",", 1)[0])]
    return [] if kept == la else ["bytes differ"]


def compare_dirs(ref: Path, new: Path) -> dict[str, list[str]]:
    """Case → differences, for every case of :func:`cases`."""
    out: dict[str, list[str]] = {}
    for name in cases():
        a, b = ref / name, new / name
        diffs: list[str] = []
        if not a.is_dir() or not b.is_dir():
            out[name] = [f"missing run folder ({a.is_dir()=}, {b.is_dir()=})"]
            continue
        files_a = {p.relative_to(a) for p in a.rglob("*") if p.is_file() and ".hydra" not in p.parts}
        files_b = {p.relative_to(b) for p in b.rglob("*") if p.is_file() and ".hydra" not in p.parts}
        for rel in sorted(files_a - files_b):
            diffs.append(f"{rel}: only in the reference")
        for rel in sorted(files_a & files_b):
            if rel.suffix == ".h5":
                diffs += [f"{rel}: {d}" for d in compare_h5(a / rel, b / rel)]
            elif rel.suffix == ".json":
                diffs += [f"{rel}: {d}" for d in compare_json(a / rel, b / rel)]
            elif rel.suffix == ".csv":
                diffs += [f"{rel}: {d}" for d in compare_csv(a / rel, b / rel)]
            elif rel.suffix == ".npz":
                diffs += [f"{rel}: {d}" for d in compare_npz(a / rel, b / rel)]
        out[name] = diffs
    return out


def compare_npz(a: Path, b: Path) -> list[str]:
    """Differences between two Monte Carlo journal records (wall-clock keys excepted, and
    the record's checksum, a digest that covers those wall-clock members: every member
    it covers is compared on its own). Event slots added since the reference (issue 29's
    ``first_stage_cutoff``) may follow the reference's events, NaN: a motor has none."""
    with np.load(a, allow_pickle=False) as za, np.load(b, allow_pickle=False) as zb:
        za, zb = dict(za), dict(zb)
        if "events" in za and "events" in zb and zb["events"].size > za["events"].size \
                and np.all(np.isnan(zb["events"][za["events"].size:])):
            zb["events"] = zb["events"][:za["events"].size]
        if "summary_keys" in za and "summary_keys" in zb:  # the summary by key; named columns added
            ka, kb = list(za["summary_keys"]), list(zb["summary_keys"])
            if [k for k in kb if k in ka or not _named(str(k))] == ka:
                keep = [i for i, k in enumerate(kb) if k in ka or not _named(str(k))]
                zb["summary_keys"], zb["summary"] = zb["summary_keys"][keep], zb["summary"][keep]
    keys = (set(za) | set(zb)) - set(WALL_CLOCK_KEYS) - {CHECKSUM_KEY}
    return [f"{k}: {'only in one file' if k not in za or k not in zb else bitwise.deviation(za[k], zb[k])}"
            for k in sorted(keys) if k not in za or k not in zb or not bitwise.equal(za[k], zb[k])]


def divergence_fix_only(ref: Path, new: Path) -> str | None:
    """The named difference of issue 11: the time a diverging run reports.

    Before the fix, the engine's step counter was reused by the slosh wall loop, so a
    run diverging with slosh on stopped its clock at the wrong step and closed its
    history with the final state at that wrong time. Returns a note when every
    difference between the two folders is that: a nominal run diverged in both with
    histories identical up to the divergence, or Monte Carlo runs that differ only where
    they diverged in both. ``None`` otherwise.
    """
    fa, fb = ref / "savant.h5", new / "savant.h5"
    if not (fa.is_file() and fb.is_file()):
        return None
    with h5py.File(fa, "r") as ha, h5py.File(fb, "r") as hb:
        if "montecarlo" in ha and "montecarlo" in hb:
            ra, rb = ha["montecarlo/runs"], hb["montecarlo/runs"]
            diverged = {i for i, (x, y) in enumerate(zip(ra["status"][()], rb["status"][()]))
                        if x == y == b"diverged"}
            differing = set()
            for group in ("montecarlo/runs", "montecarlo/summary"):
                for k in ha[group]:
                    if k in WALL_CLOCK_KEYS:
                        continue
                    x, y = np.asarray(ha[group][k][()]), np.asarray(hb[group][k][()])
                    same = (x == y) | ((x != x) & (y != y)) if x.dtype.kind == "f" else (x == y)
                    differing |= set(np.nonzero(~same)[0].tolist())
            for rec in sorted((ref / "runs").glob("run_*.npz")):
                run = int(rec.stem.split("_")[1])
                if run not in diverged and compare_npz(rec, new / "runs" / rec.name):
                    differing.add(run)  # a journal record of a run that did not diverge
            if differing and differing <= diverged:
                msgs = [f"run {i}: {ra['message'][i].decode()} → {rb['message'][i].decode()}" for i in sorted(differing)]
                return "only diverged runs differ, in their divergence time: " + "; ".join(msgs)
            return None
        if not (ha.attrs.get("status") == hb.attrs.get("status") == "diverged"):
            return None
        ta, tb = ha["time_history/time"][()], hb["time_history/time"][()]
        n = min(ta.size, tb.size) - 1
        for k in ha["time_history"]:
            if not bitwise.equal(ha["time_history"][k][()][:n], hb["time_history"][k][()][:n]):
                return None
        return (f"histories identical to t = {ta[n - 1]:.2f} s; {ha.attrs['message']} → {hb.attrs['message']}")


def reference_outputs(commit: str, work: Path, extra: tuple[str, ...] = ()) -> Path:
    """Record the reference commit's outputs (a detached git worktree of it)."""
    tree = work / "ref_tree"
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), commit], check=True,
                   capture_output=True)
    try:
        record(tree, work / "ref_out", extra=extra)
    finally:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], capture_output=True)
    return work / "ref_out"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ref", help="reference commit (recorded in a temporary git worktree)")
    ap.add_argument("--ref-dir", type=Path, help="outputs already recorded for the reference")
    ap.add_argument("--record", type=Path, help="only record this checkout's outputs into this folder")
    ap.add_argument("--keep", type=Path, help="keep the recorded outputs in this folder")
    ap.add_argument("--new-dir", type=Path, help="outputs already recorded for this checkout (skip recording)")
    ap.add_argument("--with", dest="extra", action="append", default=[], metavar="OVERRIDE",
                    help="an override added to every case of both checkouts (repeatable), e.g. "
                         "guidance=ares_i_iss when the default changed")
    args = ap.parse_args(argv)
    extra = tuple(args.extra)
    if args.record:
        record(ROOT, args.record, extra=extra)
        return 0
    if not (args.ref or args.ref_dir):
        ap.error("give --ref COMMIT or --ref-dir DIR")
    work = args.keep or Path(tempfile.mkdtemp(prefix="savant_bitwise_"))
    work.mkdir(parents=True, exist_ok=True)
    ref = args.ref_dir or reference_outputs(args.ref, work, extra)
    new = args.new_dir or work / "new_out"
    if not args.new_dir:
        record(ROOT, new, extra=extra)
    result = compare_dirs(ref, new)
    n_same = n_fix = n_added = 0
    for name, diffs in result.items():
        added, diffs = named_additions(diffs)
        note = divergence_fix_only(ref / name, new / name) if diffs else None
        if not diffs and added:
            print(f"identical but for named additions  {name}")
            for a in sorted(set(added)):
                print(f"    {a}")
            n_added += 1
        elif not diffs:
            print(f"identical  {name}")
            n_same += 1
        elif note:
            print(f"identical but for the divergence-time fix  {name}\n    {note}")
            n_fix += 1
        else:
            print(f"DIFFERENT  {name}")
            for d in diffs[:20]:
                print(f"    {d}")
    n_ok = n_same + n_fix + n_added
    print(f"{n_same} of {len(result)} cases bitwise identical, {n_fix} identical but for the divergence-time fix, "
          f"{n_added} identical but for named additions, {len(result) - n_ok} different (wall-clock keys excepted)")
    return 0 if n_ok == len(result) else 1


if __name__ == "__main__":
    raise SystemExit(main())
