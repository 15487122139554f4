"""From the journal of a batch (one or many shard folders) to the batch's outputs:
``savant.h5`` (group ``montecarlo``), ``minmax.csv``, ``percentiles.csv``,
``margin_spread.csv``, ``summary.json``, plots and the console tables.

Runs are streamed file by file into preallocated tables; the decimated histories go
row by row into HDF5 and are read back one signal at a time for the envelope plots,
so memory does not grow with the number of runs beyond the scalar tables.
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from omegaconf import OmegaConf
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from savant_cli.errors import ConfigError, DamagedFileError, OutputWriteError
from savant_cli.io.atomic import write_json_atomic, write_text_atomic
from savant_cli.io.h5write import atomic_h5
from savant_cli.io.console import format_sig, print_verdict, readable_name, split_unit
from savant_cli.io.record import FAILURE_CLASSES, FLOWN
from savant_cli.config import ReliabilitySpec, RequirementSet
from savant_cli.linear.requirements import (CHECK_ARRAY_COLUMNS, CRITERIA, STAGES, mode_code, mode_name, verdict_line,
                                            verdicts_of_array)
from savant_cli.montecarlo.batch import (AXIS_CODES, BAND_CODES, KIND_CODES, MARGIN_ARRAY_COLUMNS, read_manifest,
                                         read_outcome, scan_entries)
from savant_cli.montecarlo.insertion import insertion_statistics, print_insertion
from savant_cli.montecarlo.reliability import reliability
from savant_cli.sim.engine import EVENT_NAMES
from savant_cli.sim.mission import CLASS_LABELS, ERROR_STATUSES, class_mask, classes_of

PERCENTILES = (0.135, 50.0, 99.865)  # the ±3σ-equivalent tails of a normal distribution
N_MARGIN = 1 + len(MARGIN_ARRAY_COLUMNS)  # run, then the margin row
N_CHECK = 1 + len(CHECK_ARRAY_COLUMNS)  # run, then the check


@dataclass
class Inventory:
    """The journal files of a batch, by run number; with :func:`inventory`'s ``verify``,
    only the entries that read back whole and match their checksum, the damaged ones in
    ``damaged`` (and so counted as missing)."""

    files: dict[int, Path]
    manifest: dict
    duplicates: dict[int, list[Path]] = field(default_factory=dict)
    damaged: dict[int, DamagedFileError] = field(default_factory=dict)

    def missing(self, expected: range | list[int]) -> list[int]:
        return [r for r in expected if r not in self.files]


def inventory(run_dirs: list[Path], verify: bool = False) -> Inventory:
    """Index the journal folders (``runs/``) of one batch; every folder must hold the
    same configuration (manifest fingerprint). ``verify``: read every entry back and
    check it (``montecarlo/journal.py``); a damaged one goes to ``Inventory.damaged``."""
    files: dict[int, Path] = {}
    dups: dict[int, list[Path]] = {}
    damaged: dict[int, DamagedFileError] = {}
    manifest: dict | None = None
    for d in run_dirs:
        m = read_manifest(d / "manifest.json")
        if manifest is None:
            manifest = m
        elif m["fingerprint"] != manifest["fingerprint"]:
            raise ConfigError("collect", str(d), f"holds runs of a different configuration than {run_dirs[0]}")
        if verify:
            found = scan_entries(d)
            entries = found.good
            for run, exc in found.damaged.items():
                damaged.setdefault(run, exc)
        else:
            entries = {int(p.stem[4:]): p for p in sorted(d.glob("run_*.npz"))}
        for run, p in sorted(entries.items()):
            if run in files:
                dups.setdefault(run, [files[run]]).append(p)
            else:
                files[run] = p
    if manifest is None:
        raise ConfigError("collect", [str(d) for d in run_dirs], "no batch journal (runs/manifest.json) found")
    return Inventory(files, manifest, dups, damaged)


def ranges_text(runs: list[int]) -> str:
    """``[1, 2, 3, 7]`` → ``"1-3, 7"``."""
    out, start, prev = [], None, None
    for r in runs + [None]:
        if start is not None and (r is None or r != prev + 1):
            out.append(f"{start}" if start == prev else f"{start}-{prev}")
            start = None
        if r is not None and start is None:
            start = r
        prev = r
    return ", ".join(out)


@dataclass
class Tables:
    """The batch's scalar tables (rows: the runs present, by run number)."""

    runs: np.ndarray
    status: list[str]
    message: list[str]
    t_final: np.ndarray
    wall_s: np.ndarray
    values: np.ndarray  # (n, n_dispersions)
    summary_keys: list[str]
    summary: np.ndarray  # (n, n_keys)
    events: np.ndarray  # (n, n_events)
    margins: np.ndarray  # (m, 9): run, then batch.MARGIN_ARRAY_COLUMNS
    history_names: list[str]
    checks: np.ndarray = field(default_factory=lambda: np.zeros((0, 1 + len(CHECK_ARRAY_COLUMNS))))  # run, checks

    @property
    def ok(self) -> np.ndarray:
        """Runs with usable results: those that flew to their end (healthy or not) and the
        diverged or guidance-failed ones (they still flew, up to their stop)."""
        return np.array([s in (*FLOWN, "diverged", "guidance_failed") for s in self.status])


def _write_tables(h5: h5py.Group | None, inv: Inventory, runs: list[int], history_names: list[str],
                  history_time: np.ndarray) -> Tables:
    """Stream the journal entries of ``runs`` into the scalar tables, and their decimated
    histories into ``h5`` (group ``histories``; none without ``h5``)."""
    n = len(runs)
    nd = len(inv.manifest["dispersions"])
    status, message, keys = [], [], []
    t_final, wall = np.full(n, np.nan), np.full(n, np.nan)
    values = np.full((n, nd), np.nan)
    events = np.full((n, len(EVENT_NAMES)), np.nan)
    summary_cols: dict[str, np.ndarray] = {}
    margins, checks = [], []
    hist = None
    if history_names and h5 is not None:
        hg = h5.create_group("histories", track_order=True)
        hg.create_dataset("time", data=history_time)
        hist = {name: hg.create_dataset(name, shape=(n, history_time.size), dtype="f4", fillvalue=np.nan,
                                        chunks=(1, history_time.size), compression="gzip", compression_opts=1)
                for name in history_names}
    for i, run in enumerate(runs):
        o = read_outcome(inv.files[run])
        status.append(o.status)
        message.append(o.message)
        t_final[i], wall[i] = o.t_final, o.wall_s
        values[i, :o.values.size] = o.values
        events[i] = o.events
        for k, v in zip(o.summary_keys, o.summary):
            if k not in summary_cols:
                keys.append(k)
                summary_cols[k] = np.full(n, np.nan)
            summary_cols[k][i] = v
        if o.margins.size:
            margins.append(np.column_stack([np.full(len(o.margins), run), o.margins]))
        if o.checks.size:
            checks.append(np.column_stack([np.full(len(o.checks), run), o.checks]))
        if hist is not None and o.histories.size:
            for j, name in enumerate(history_names):
                hist[name][i] = o.histories[j]
    return Tables(np.asarray(runs), status, message, t_final, wall, values, keys,
                  np.column_stack([summary_cols[k] for k in keys]) if keys else np.zeros((n, 0)), events,
                  np.vstack(margins) if margins else np.zeros((0, N_MARGIN)), history_names,
                  np.vstack(checks) if checks else np.zeros((0, N_CHECK)))


def _strings(items: list[str]) -> np.ndarray:
    return np.array(items, dtype=h5py.string_dtype())


def percentile_rows(names: list[str], data: np.ndarray, runs: np.ndarray) -> list[dict[str, Any]]:
    """Per column: max and its run, min and its run, percentiles, mean, σ, mean ± 3σ
    (finite values only)."""
    rows = []
    for j, name in enumerate(names):
        col = data[:, j]
        good = np.isfinite(col)
        if not good.any():
            continue
        v, r = col[good], runs[good]
        p = np.percentile(v, PERCENTILES)
        mean, std = float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0
        rows.append({"variable": name, "max": float(v.max()), "max_run": int(r[np.argmax(v)]),
                     "min": float(v.min()), "min_run": int(r[np.argmin(v)]), "p0.135": float(p[0]),
                     "p50": float(p[1]), "p99.865": float(p[2]), "mean": mean, "std": std,
                     "mean_minus_3sigma": mean - 3 * std, "mean_plus_3sigma": mean + 3 * std, "n": int(v.size)})
    return rows


def margin_spread(margins: np.ndarray) -> list[dict[str, Any]]:
    """Per (time, axis, kind, mode): the critical crossing of each run (smallest |margin|),
    then its spread over the runs, and how many runs' critical crossing misses its
    requirement."""
    rows = []
    if not margins.size:
        return rows
    keys = np.unique(margins[:, [1, 2, 3, 7]], axis=0)
    for t, ax, kd, md in keys:
        sel = margins[(margins[:, 1] == t) & (margins[:, 2] == ax) & (margins[:, 3] == kd) & (margins[:, 7] == md)]
        crit: dict[int, tuple[float, bool]] = {}
        for run, value, ok in zip(sel[:, 0].astype(int), sel[:, 5], sel[:, 8]):
            if run not in crit or abs(value) < abs(crit[run][0]):
                crit[run] = (float(value), bool(ok))
        runs = np.array(list(crit))
        vals = np.array([v for v, _ in crit.values()])
        p = np.percentile(vals, PERCENTILES)
        rows.append({"time_s": float(t), "axis": AXIS_CODES[int(ax)], "kind": KIND_CODES[int(kd)],
                     "mode": mode_name(int(md)), "band": BAND_CODES[int(sel[0, 4])], "runs": int(vals.size),
                     "worst": float(vals[np.argmin(np.abs(vals))]), "worst_run": int(runs[np.argmin(np.abs(vals))]),
                     "min": float(vals.min()), "min_run": int(runs[np.argmin(vals)]),
                     "max": float(vals.max()), "max_run": int(runs[np.argmax(vals)]),
                     "p0.135": float(p[0]), "p50": float(p[1]), "p99.865": float(p[2]),
                     "runs_below_requirement": int(sum(not ok for _, ok in crit.values()))})
    return rows


def requirement_verdicts(checks: np.ndarray, requirement_set: str) -> dict[str, Any]:
    """The batch's requirement verdict from every run's checks: how many runs were judged
    (those with a linear point) and pass, the one-line verdict, and each failing run's
    worst offender."""
    per_run = {int(r): verdicts_of_array(checks[checks[:, 0] == r, 1:]) for r in np.unique(checks[:, 0])}
    failed = []
    for run, vs in per_run.items():
        bad = [v for v in vs if not v.passed]
        if bad:
            worst = min((v.worst for v in bad), key=lambda c: c.severity)
            failed.append({"run": run, "points_failed": len(bad), "worst": worst.text()})
    line = verdict_line([(f"run {r}", vs) for r, vs in per_run.items()], requirement_set, "runs")
    return {"set": requirement_set, "runs_judged": len(per_run), "runs_passing": len(per_run) - len(failed),
            "passed": bool(per_run) and not failed, "line": line, "failed_runs": failed}


#: (summary key, label, unit) of the load indicators :func:`load_extremes` reports
LOAD_EXTREMES = (("max_qalpha_Pa_deg", "max q-alpha total", "Pa deg"),
                 ("max_qalpha_pitch_Pa_deg", "max q-alpha pitch", "Pa deg"),
                 ("max_qbeta_Pa_deg", "max q-beta", "Pa deg"),
                 ("time_above_qalpha_limit_s", "time above q-alpha limit", "s"))


def load_extremes(tb: "Tables", dispersions: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """The batch's aerodynamic load extremes over the runs with results (``Tables.ok``):
    per indicator the largest value and its run; the q·α limit and the runs whose total
    q·α exceeded it (``qalpha_limit_exceeded``), counted and listed; with the batch's
    ``dispersions`` (rows of ``studies/montecarlo.py::dispersion_table``), the worst q·α
    per value of each numeric ``choice`` dispersion (``by_choice``,
    :func:`loads_by_choice`). Empty when the runs carry no load indicators (a batch
    recorded before them)."""
    keys = tb.summary_keys
    if "max_qalpha_pitch_Pa_deg" not in keys:
        return {}
    ok = tb.ok
    runs = tb.runs[ok]
    out: dict[str, Any] = {"runs_with_results": int(ok.sum())}
    for key, _, _ in LOAD_EXTREMES:
        if key not in keys:
            continue
        col = tb.summary[ok, keys.index(key)]
        good = np.isfinite(col)
        out[key] = ({"max": float(col[good].max()), "max_run": int(runs[good][np.argmax(col[good])])}
                    if good.any() else None)
    limit = tb.summary[ok, keys.index("qalpha_limit_Pa_deg")] if "qalpha_limit_Pa_deg" in keys else np.zeros(0)
    limit = limit[np.isfinite(limit)]
    out["qalpha_limit_Pa_deg"] = float(limit.max()) if limit.size else None
    if "qalpha_limit_exceeded" in keys:
        exc = tb.summary[ok, keys.index("qalpha_limit_exceeded")]
        above = [int(r) for r, e in zip(runs, exc) if e == 1.0]
        out["runs_above_qalpha_limit"] = len(above)
        out["runs_above_qalpha_limit_list"] = ranges_text(above)
    by_choice = loads_by_choice(tb, dispersions or [], out["qalpha_limit_Pa_deg"])
    if by_choice:
        out["by_choice"] = by_choice
    return out


def loads_by_choice(tb: "Tables", dispersions: list[dict[str, Any]], limit: float | None) -> list[dict[str, Any]]:
    """The worst total q·α for each value of each numeric ``choice`` dispersion (a swept
    discrete parameter, e.g. the gust length of ``dispersions=ares_i_gust``), over the
    dispersed runs with results; one row per value, in increasing value: ``dispersion``,
    ``value``, ``units``, ``runs``, ``max_qalpha_Pa_deg`` and its ``max_run``, and
    against the q·α ``limit`` (Pa·deg; None: no limit) ``ratio`` (worst / limit),
    ``margin_Pa_deg`` (limit − worst, negative when exceeded) and
    ``runs_above_limit``; the row of the largest worst value per dispersion has
    ``worst: True``. Group choices (a ``winds`` option) are left out: their numbers are
    option indices."""
    keys = tb.summary_keys
    if "max_qalpha_Pa_deg" not in keys:
        return []
    qa = tb.summary[:, keys.index("max_qalpha_Pa_deg")]
    use = tb.ok & (tb.runs > 0) & np.isfinite(qa)
    rows: list[dict[str, Any]] = []
    for j, d in enumerate(dispersions):
        if d.get("dist") != "choice" or "choices" in d or j >= tb.values.shape[1]:
            continue
        col = tb.values[:, j]
        mine: list[dict[str, Any]] = []
        for v in np.unique(col[use & np.isfinite(col)]):
            at = use & (col == v)
            k = int(np.argmax(np.where(at, qa, -np.inf)))
            worst = float(qa[k])
            row = {"dispersion": d["name"], "value": float(v), "units": d.get("units", ""), "runs": int(at.sum()),
                   "max_qalpha_Pa_deg": worst, "max_run": int(tb.runs[k]), "ratio": None, "margin_Pa_deg": None,
                   "runs_above_limit": None, "worst": False}
            if limit:
                row.update(ratio=worst / limit, margin_Pa_deg=limit - worst, runs_above_limit=int((qa[at] > limit).sum()))
            mine.append(row)
        if mine:
            max(mine, key=lambda r: r["max_qalpha_Pa_deg"])["worst"] = True
        rows += mine
    return rows


def print_loads(console: Console, loads: dict[str, Any]) -> None:
    """The load extremes on the console (a red count when runs exceeded the limit)."""
    if not loads:
        return
    parts = [f"{label} {loads[key]['max']:,.{0 if unit == 'Pa deg' else 2}f} {unit} (run {loads[key]['max_run']})"
             for key, label, unit in LOAD_EXTREMES if loads.get(key)]
    console.print("loads: " + "; ".join(parts), markup=False, highlight=False, soft_wrap=True)
    verdict = loads_verdict(loads)
    if verdict is not None:
        console.print(verdict[0], style=None if verdict[1] else "red", markup=False, highlight=False, soft_wrap=True)
    for line, ok in loads_by_choice_lines(loads):
        console.print(line, style="red" if ok is False else None, markup=False, highlight=False, soft_wrap=True)


def loads_by_choice_lines(loads: dict[str, Any]) -> list[tuple[str, bool | None]]:
    """One line per swept ``choice`` dispersion of ``loads["by_choice"]`` (what the
    console and report.html show): each value's worst total q·α with its run and ratio
    to the limit, then the worst value and its margin; with whether the worst is within
    the limit (None without a limit)."""
    lines = []
    rows = loads.get("by_choice") or []
    for name in dict.fromkeys(r["dispersion"] for r in rows):
        mine = [r for r in rows if r["dispersion"] == name]
        unit = f" {mine[0]['units']}" if mine[0]["units"] else ""
        parts = [f"{r['value']:g}{unit}: {r['max_qalpha_Pa_deg']:,.0f} (run {r['max_run']}"
                 + (f", {r['ratio']:.2f} of the limit, {r['runs_above_limit']} of {r['runs']} runs above" if r["ratio"]
                    is not None else f", {r['runs']} runs") + ")" for r in mine]
        worst = next(r for r in mine if r["worst"])
        has_limit = worst["margin_Pa_deg"] is not None
        tail = (f"; worst {worst['value']:g}{unit}, margin {worst['margin_Pa_deg']:,.0f} Pa deg to the limit"
                if has_limit else f"; worst {worst['value']:g}{unit}")
        lines.append((f"max q-alpha total by {name} (Pa deg): " + "; ".join(parts) + tail,
                      worst["margin_Pa_deg"] >= 0.0 if has_limit else None))
    return lines


def loads_verdict(loads: dict[str, Any]) -> tuple[str, bool] | None:
    """The batch's q·α verdict line (:func:`load_extremes`) and whether no run exceeded
    the limit; None without a limit (what the console and report.html show)."""
    if not loads or loads.get("qalpha_limit_Pa_deg") is None:
        return None
    n = int(loads.get("runs_above_qalpha_limit", 0))
    text = (f"{n} of {loads['runs_with_results']} runs above the q-alpha limit "
            f"{loads['qalpha_limit_Pa_deg']:,.0f} Pa deg" + (f" (runs {loads['runs_above_qalpha_limit_list']})" if n else ""))
    return text, n == 0


def mission_outcomes(tb: Tables, counted: tuple[str, ...]) -> dict[str, Any]:
    """The batch's mission outcome by class (``savant_cli/sim/mission.py``).

    Each run's classes come from its ``mission_class_mask``; a run that was not flown to a
    verdict (status ``failed`` or ``invalid``) is ``run_error``; an ``interrupted`` run
    has no outcome and is left out. Returns ``counted_classes``, ``runs`` (with an
    outcome), ``successes``, ``failures``, ``by_class`` (per class: runs in it, whether it
    counts, the run list), ``failed_runs`` (``run``, ``classes``) and ``success`` (per
    counted run, for the reliability)."""
    col = tb.summary_keys.index("mission_class_mask") if "mission_class_mask" in tb.summary_keys else None
    counted_mask = class_mask(counted)
    masks: list[tuple[int, int]] = []  # (run, mask) of every run with an outcome
    for i, (run, status) in enumerate(zip(tb.runs, tb.status)):
        if status == "interrupted":
            continue
        if status in ERROR_STATUSES:
            mask = class_mask(["run_error"])
        else:
            value = tb.summary[i, col] if col is not None else np.nan
            mask = int(value) if np.isfinite(value) else class_mask(["run_error"])
        masks.append((int(run), mask))
    by_class = []
    for c in FAILURE_CLASSES:
        bit = class_mask([c])
        in_class = [r for r, m in masks if m & bit]
        by_class.append({"class": c, "label": CLASS_LABELS[c], "runs": len(in_class), "counted": c in counted,
                         "run_list": ranges_text(in_class)})
    success = [not (m & counted_mask) for _, m in masks]
    failed = [{"run": r, "classes": ",".join(c for c in classes_of(m) if c in counted)}
              for (r, m), ok in zip(masks, success) if not ok]
    return {"counted_classes": list(counted), "runs": len(masks), "successes": int(sum(success)),
            "failures": len(failed), "by_class": by_class, "failed_runs": failed, "success": success}


def print_mission(console: Console, mission: dict[str, Any]) -> None:
    """The mission outcome by class: one line per class with runs in it (red when it
    counts as a failure), or one green line when no run falls in any class."""
    rows = [c for c in mission["by_class"] if c["runs"]]
    if not rows:
        console.print(f"mission: no run of {mission['runs']} in any failure class", style="green", markup=False,
                      highlight=False)
        return
    for c in rows:
        console.print(f"mission {c['label']}: {c['runs']} of {mission['runs']} runs (runs {c['run_list']})"
                      + ("" if c["counted"] else "; not counted as a failure"),
                      style="red" if c["counted"] else None, markup=False, highlight=False, soft_wrap=True)


def _csv(path: Path, rows: list[dict[str, Any]]) -> None:
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    write_text_atomic(path, buf.getvalue())


@dataclass
class Analysis:
    """What a batch's tables say: everything :func:`write_outputs` writes and prints
    beside the tables themselves."""

    stats: list[dict[str, Any]]
    disp_stats: list[dict[str, Any]]
    spread: list[dict[str, Any]]
    counts: dict[str, int]
    missing: list[int]
    mission: dict[str, Any]
    rel: Any  # montecarlo.reliability.Reliability
    insertion: dict[str, Any]
    loads: dict[str, Any]
    verdict: dict[str, Any]
    summary: dict[str, Any]  # the summary.json content


def analyse(tb: Tables, expected: list[int], missing: list[int], dispersions: list[dict[str, Any]],
            requirements: RequirementSet | None, spec: ReliabilitySpec) -> Analysis:
    """Statistics, margin spread, mission outcome, demonstrated success, insertion,
    loads and requirement verdict of a batch's tables, and its ``summary.json`` content."""
    set_name = requirements.name if requirements is not None else "none"
    counted = tuple(requirements.mission.failure_classes if requirements is not None else FAILURE_CLASSES)
    mission = mission_outcomes(tb, counted)
    rel = reliability(mission["success"], counted, spec.confidence, spec.target_probability)
    insertion = insertion_statistics(tb.runs, tb.message, tb.summary_keys, tb.summary, spec.reserve_probability,
                                     spec.confidence)
    loads = load_extremes(tb, dispersions)
    verdict = requirement_verdicts(tb.checks, set_name)
    ok = tb.ok
    stats = percentile_rows(tb.summary_keys, tb.summary[ok], tb.runs[ok])
    disp_stats = percentile_rows([d["name"] for d in dispersions], tb.values[tb.runs > 0], tb.runs[tb.runs > 0])
    spread = margin_spread(tb.margins)
    failures = [{"run": int(r), "status": s, "message": m, "t_final_s": t}
                for r, s, m, t in zip(tb.runs, tb.status, tb.message, tb.t_final) if s != "complete"]
    counts = {s: tb.status.count(s) for s in sorted(set(tb.status))}
    summary = {"study": "montecarlo", "n_runs_expected": len(expected), "n_runs_present": int(tb.runs.size),
               "missing_runs": ranges_text(missing), "status_counts": counts,
               "mission": {k: v for k, v in mission.items() if k != "success"}, "reliability": rel.as_dict(),
               "failures": failures,
               "statistics": stats, "dispersion_statistics": disp_stats, "margin_spread": spread,
               "insertion": insertion}
    if loads:
        summary["loads"] = loads
    if tb.checks.size:
        summary.update({"requirements_met": verdict["passed"], "requirements_verdict": verdict["line"],
                        "requirements": verdict})
    return Analysis(stats, disp_stats, spread, counts, missing, mission, rel, insertion, loads, verdict, summary)


def print_analysis(console: Console, tb: Tables, an: Analysis) -> None:
    """The batch's console summary: the tables, insertion, loads, mission and the
    demonstrated success."""
    print_tables(console, an.stats, an.spread, an.counts, an.missing, an.verdict if tb.checks.size else None)
    print_insertion(console, an.insertion)
    print_loads(console, an.loads)
    print_mission(console, an.mission)
    print_verdict(an.rel.line(), an.rel.target_met, console)


def _write_group(g: h5py.Group, tb: Tables, an: Analysis, inv: Inventory, expected: list[int],
                 dispersions: list[dict[str, Any]], config_yaml: str, provenance: dict[str, str],
                 requirements: RequirementSet | None) -> None:
    """Group ``montecarlo``'s attributes and datasets beside the histories."""
    bands = requirements.by_band() if requirements is not None else {}
    g.attrs.update({"n_runs_expected": len(expected), "n_runs_present": int(tb.runs.size),
                    "seed": inv.manifest.get("seed", -1), "config_yaml": config_yaml, "percentiles": PERCENTILES,
                    "missing_runs": ranges_text(an.missing),
                    "requirements": json.dumps({b: list(r) for b, r in bands.items()})})
    for k, v in provenance.items():
        g.attrs[f"provenance_{k}"] = str(v)
    g.attrs["mission"] = json.dumps({k: v for k, v in an.mission.items() if k != "success"})
    g.attrs["reliability"] = json.dumps(an.rel.as_dict())
    g.attrs["insertion"] = json.dumps(an.insertion)
    if an.loads:
        g.attrs["loads"] = json.dumps(an.loads)
    rg = g.create_group("runs")
    rg.create_dataset("run", data=tb.runs)
    rg.create_dataset("status", data=_strings(tb.status))
    rg.create_dataset("message", data=_strings(tb.message))
    rg.create_dataset("t_final_s", data=tb.t_final)
    rg.create_dataset("wall_time_s", data=tb.wall_s)
    eg = g.create_group("events")
    for j, name in enumerate(EVENT_NAMES):
        eg.create_dataset(f"{name}_s", data=tb.events[:, j])
    dg = g.create_group("dispersions", track_order=True)
    for j, d in enumerate(dispersions):
        ds = dg.create_dataset(d["name"], data=tb.values[:, j])
        ds.attrs.update({k: json.dumps(v) if isinstance(v, (list, tuple)) else v for k, v in d.items() if k != "name"})
    sg = g.create_group("summary", track_order=True)
    for j, k in enumerate(tb.summary_keys):
        sg.create_dataset(k, data=tb.summary[:, j])
    mg = g.create_group("margins")
    for j, col in enumerate(("run",) + MARGIN_ARRAY_COLUMNS):
        data = tb.margins[:, j]
        if col in ("axis", "kind", "band"):
            codes = {"axis": AXIS_CODES, "kind": KIND_CODES, "band": BAND_CODES}[col]
            mg.create_dataset(col, data=_strings([codes[int(c)] for c in data]))
        elif col == "mode":
            mg.create_dataset(col, data=_strings([mode_name(int(c)) for c in data]))
        else:
            mg.create_dataset(col, data=data.astype(int) if col == "run" else data.astype(bool)
                              if col == "meets_requirement" else data)
    _write_checks(g.create_group("requirements", track_order=True), tb.checks, an.verdict, requirements)


def write_outputs(out_dir: Path, inv: Inventory, expected: list[int], dispersions: list[dict[str, Any]],
                  config_yaml: str, provenance: dict[str, str], history_names: list[str],
                  history_time: np.ndarray, requirements: RequirementSet | None,
                  plots: bool, console: Console | None = None,
                  reliability_spec: ReliabilitySpec | None = None) -> dict[str, Any]:
    """Write every batch output into ``out_dir``; returns the ``summary.json`` content.
    ``requirements``: the set the runs' margins were judged against (its band values
    mark the margin-spread plot); ``reliability_spec``: the demonstrated success's
    confidence, target and success statuses (``study.reliability``; its defaults when
    None).

    An output that cannot be written (disk full, folder not writable) raises
    :class:`~savant_cli.errors.OutputWriteError` after the console summary has been
    printed (from the journal, when ``savant.h5`` itself failed); every file written
    before it stays whole, and the failed one keeps its previous content or does not
    exist (atomic writes)."""
    spec = reliability_spec or ReliabilitySpec()
    runs = sorted(r for r in expected if r in inv.files)
    missing = inv.missing(expected)
    bands = requirements.by_band() if requirements is not None else {}
    done: dict[str, Any] = {}
    try:
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputWriteError(out_dir / "savant.h5", exc) from exc
        with atomic_h5(out_dir / "savant.h5") as f:
            g = f.create_group("montecarlo")
            tb = done["tb"] = _write_tables(g, inv, runs, history_names, history_time)
            an = done["an"] = analyse(tb, expected, missing, dispersions, requirements, spec)
            _write_group(g, tb, an, inv, expected, dispersions, config_yaml, provenance, requirements)
        _csv(out_dir / "minmax.csv", [{k: r[k] for k in ("variable", "max", "max_run", "min", "min_run")}
                                      for r in an.stats])
        _csv(out_dir / "percentiles.csv", an.stats)
        _csv(out_dir / "dispersion_statistics.csv", an.disp_stats)
        if an.spread:
            _csv(out_dir / "margin_spread.csv", an.spread)
        if an.insertion["accuracy"]:
            # with navigation=inertial, the navigation errors' rows follow
            _csv(out_dir / "insertion_accuracy.csv", an.insertion["accuracy"] + an.insertion.get("navigation_errors", []))
        write_json_atomic(out_dir / "summary.json", an.summary)
        if plots:
            _plots(out_dir, tb, dispersions, bands or None)
    except OutputWriteError:
        if console is not None:  # the summary still reaches the console
            tb = done.get("tb") or _write_tables(None, inv, runs, [], history_time)
            an = done.get("an") or analyse(tb, expected, missing, dispersions, requirements, spec)
            print_analysis(console, tb, an)
        raise
    if console is not None:
        print_analysis(console, tb, an)
    return an.summary


def _write_checks(g: h5py.Group, checks: np.ndarray, verdict: dict[str, Any],
                  requirements: RequirementSet | None) -> None:
    """Group ``montecarlo/requirements``: attributes ``set`` (JSON), ``verdict`` (the one
    line), ``passed``; ``checks/<column>`` (every check of every run: ``run`` and
    ``linear/requirements.py::CHECK_ARRAY_COLUMNS``, names for the codes) and
    ``failed_runs/{run, points_failed, worst}``."""
    if requirements is not None:
        g.attrs["set"] = json.dumps(OmegaConf.to_container(OmegaConf.structured(requirements)))
    g.attrs["verdict"] = verdict["line"]
    g.attrs["passed"] = bool(verdict["passed"])
    cg = g.create_group("checks", track_order=True)
    names = {"axis": lambda c: AXIS_CODES[int(c)] if c >= 0 else "", "mode": lambda c: mode_name(int(c)),
             "criterion": lambda c: CRITERIA[int(c)], "stage": lambda c: STAGES[int(c)]}
    for j, col in enumerate(("run",) + CHECK_ARRAY_COLUMNS):
        data = checks[:, j]
        if col in names:
            cg.create_dataset(col, data=_strings([names[col](c) for c in data]))
        else:
            cg.create_dataset(col, data=data.astype(int) if col == "run" else data.astype(bool)
                              if col == "passed" else data)
    fg = g.create_group("failed_runs", track_order=True)
    fg.create_dataset("run", data=np.array([f["run"] for f in verdict["failed_runs"]], dtype=int))
    fg.create_dataset("points_failed", data=np.array([f["points_failed"] for f in verdict["failed_runs"]], dtype=int))
    fg.create_dataset("worst", data=_strings([f["worst"] for f in verdict["failed_runs"]]))


def read_tables(g: h5py.Group) -> Tables:
    """The scalar tables of a batch's ``montecarlo`` group (as :func:`write_outputs` wrote
    them; margins re-coded)."""
    summary_keys = list(g["summary"])
    runs = g["runs/run"][()]
    m = g["margins"]
    margins = np.zeros((0, N_MARGIN))
    if m["run"].size:
        codes = {col: np.array([names.index(s) for s in m[col].asstr()[()]], dtype=float)
                 for col, names in (("axis", AXIS_CODES), ("kind", KIND_CODES), ("band", BAND_CODES))}
        codes["mode"] = np.array([mode_code(s) for s in m["mode"].asstr()[()]], dtype=float)
        margins = np.column_stack([m["run"][()]] + [codes[c] if c in codes else m[c][()].astype(float)
                                                    for c in MARGIN_ARRAY_COLUMNS])
    return Tables(runs, list(g["runs/status"].asstr()[()]), list(g["runs/message"].asstr()[()]),
                  g["runs/t_final_s"][()], g["runs/wall_time_s"][()],
                  np.column_stack([ds[()] for ds in g["dispersions"].values()]) if len(g["dispersions"])
                  else np.zeros((runs.size, 0)),
                  summary_keys, np.column_stack([g["summary"][k][()] for k in summary_keys]) if summary_keys
                  else np.zeros((runs.size, 0)),
                  np.column_stack([g["events"][f"{n}_s"][()] for n in EVENT_NAMES]),
                  margins, [k for k in g["histories"] if k != "time"] if "histories" in g else [])


def redraw(out_dir: Path) -> list[Path]:
    """Redraw a batch's plots into ``out_dir/plots`` from its ``savant.h5`` alone."""
    with h5py.File(out_dir / "savant.h5", "r") as f:
        g = f["montecarlo"]
        tb = read_tables(g)
        dispersions = [{"name": k, "units": str(ds.attrs.get("units", ""))} for k, ds in g["dispersions"].items()]
        requirements = {b: (float(r[0]), float(r[1])) for b, r in json.loads(g.attrs.get("requirements", "{}")).items()}
    return _plots(out_dir, tb, dispersions, requirements or None)


def _plots(out_dir: Path, tb: Tables, dispersions: list[dict[str, Any]],
           requirements: dict[str, tuple[float, float]] | None) -> list[Path]:
    from savant_cli.plots import montecarlo as mcp

    folder = out_dir / "plots"
    paths = []
    ok = tb.ok
    nominal_row = np.nonzero(tb.runs == 0)[0]
    values = {k: tb.summary[ok, j] for j, k in enumerate(tb.summary_keys)}
    units = {k: split_unit(k)[1] for k in tb.summary_keys}
    nominal = {k: float(tb.summary[nominal_row[0], j]) for j, k in enumerate(tb.summary_keys)} if nominal_row.size else None
    paths += mcp.plot_histograms(values, folder, units=units, nominal=nominal)
    disp = {d["name"]: tb.values[tb.runs > 0, j] for j, d in enumerate(dispersions)}
    if disp:
        paths += mcp.plot_histograms(disp, folder / "dispersions",
                                     units={d["name"]: d.get("units", "") for d in dispersions})
    if tb.history_names:
        with h5py.File(out_dir / "savant.h5", "r") as f:
            hg = f["montecarlo/histories"]
            t = hg["time"][()]
            for name in tb.history_names:  # one signal in memory at a time
                paths += mcp.plot_envelopes(t, {name: hg[name][()]}, folder, units=None)
    if tb.margins.size:
        m = tb.margins
        table = {"run": m[:, 0].astype(int), "time_s": m[:, 1],
                 "axis": np.array([AXIS_CODES[int(c)] for c in m[:, 2]]),
                 "kind": np.array([KIND_CODES[int(c)] for c in m[:, 3]]),
                 "band": np.array([BAND_CODES[int(c)] for c in m[:, 4]]), "value": m[:, 5], "frequency_hz": m[:, 6]}
        paths.append(mcp.plot_margin_spread(table, folder / "margin_spread.png", requirements=requirements))
    return paths


def print_tables(console: Console, stats: list[dict], spread: list[dict], counts: dict[str, int],
                 missing: list[int], verdict: dict[str, Any] | None = None) -> None:
    """The min/max table (and the margin spread and requirement verdict) on the console."""
    # names as words with their unit (they wrap at spaces in a narrow terminal instead of
    # being cut to a common prefix), numbers to 4 significant digits, never wrapped
    tb = Table(title="Monte Carlo: extremes over the runs (run number in brackets)")
    tb.add_column("variable", justify="left", overflow="fold", min_width=12, ratio=1)
    for col in ("max [run]", "min [run]", "p0.135", "p50", "p99.865"):
        tb.add_column(escape(col), justify="right", no_wrap=True)
    for r in stats:
        tb.add_row(readable_name(r["variable"]), f"{format_sig(r['max'])} [{r['max_run']}]",
                   f"{format_sig(r['min'])} [{r['min_run']}]", format_sig(r["p0.135"]), format_sig(r["p50"]),
                   format_sig(r["p99.865"]))
    console.print(tb)
    if spread:
        ms = Table(title="margin spread (critical crossing per run and mode; gain dB, phase deg)")
        for col in ("t (s)", "axis", "kind", "mode", "runs", "worst [run]", "p0.135", "p50", "p99.865", "below req."):
            ms.add_column(col)
        for r in spread:
            below = r["runs_below_requirement"]
            ms.add_row(f"{r['time_s']:.1f}", r["axis"], r["kind"], r["mode"], str(r["runs"]),
                       f"{r['worst']:.2f} [{r['worst_run']}]", f"{r['p0.135']:.2f}", f"{r['p50']:.2f}",
                       f"{r['p99.865']:.2f}", f"[red]{below}[/red]" if below else "0")
        console.print(ms)
    console.print("runs: " + ", ".join(f"{k} {v}" for k, v in counts.items())
                  + (f"; missing {ranges_text(missing)}" if missing else ""))
    if verdict is not None:
        print_verdict(verdict["line"], verdict["passed"], console)
