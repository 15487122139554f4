"""What a batch's tables say (:func:`analyse` → :class:`Analysis`): percentile
statistics of every summary scalar and dispersion, the spread of the margins, the
requirement verdict, the aerodynamic load extremes, the mission outcome by class, the
demonstrated success and the insertion accuracy, and the ``summary.json`` content."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from savant_cli.config import ReliabilitySpec, RequirementSet
from savant_cli.io.record import FAILURE_CLASSES
from savant_cli.linear.requirements import DEFAULT_SLOSH_TANKS, mode_name, verdict_line, verdicts_of_array
from savant_cli.montecarlo.batch import AXIS_CODES, BAND_CODES, KIND_CODES
from savant_cli.montecarlo.insertion import insertion_statistics
from savant_cli.montecarlo.inventory import ranges_text
from savant_cli.montecarlo.reliability import reliability
from savant_cli.montecarlo.results import Tables
from savant_cli.sim.mission import CLASS_LABELS, ERROR_STATUSES, class_mask, classes_of

PERCENTILES = (0.135, 50.0, 99.865)  # the ±3σ-equivalent tails of a normal distribution


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


def margin_spread(margins: np.ndarray, slosh_tanks: tuple[str, ...] = DEFAULT_SLOSH_TANKS) -> list[dict[str, Any]]:
    """Per (time, axis, kind, mode): the critical crossing of each run (smallest |margin|),
    then its spread over the runs, and how many runs' critical crossing misses its
    requirement (slosh modes named by ``slosh_tanks``, the batch's)."""
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
                     "mode": mode_name(int(md), slosh_tanks), "band": BAND_CODES[int(sel[0, 4])],
                     "runs": int(vals.size),
                     "worst": float(vals[np.argmin(np.abs(vals))]), "worst_run": int(runs[np.argmin(np.abs(vals))]),
                     "min": float(vals.min()), "min_run": int(runs[np.argmin(vals)]),
                     "max": float(vals.max()), "max_run": int(runs[np.argmax(vals)]),
                     "p0.135": float(p[0]), "p50": float(p[1]), "p99.865": float(p[2]),
                     "runs_below_requirement": int(sum(not ok for _, ok in crit.values()))})
    return rows


def requirement_verdicts(checks: np.ndarray, requirement_set: str,
                         slosh_tanks: tuple[str, ...] = DEFAULT_SLOSH_TANKS) -> dict[str, Any]:
    """The batch's requirement verdict from every run's checks: how many runs were judged
    (those with a linear point) and pass, the one-line verdict, and each failing run's
    worst offender (slosh modes named by ``slosh_tanks``, the batch's)."""
    per_run = {int(r): verdicts_of_array(checks[checks[:, 0] == r, 1:], slosh_tanks) for r in np.unique(checks[:, 0])}
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


@dataclass
class Analysis:
    """What a batch's tables say: everything
    :func:`~savant_cli.montecarlo.outputs.write_outputs` writes and prints
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
    verdict = requirement_verdicts(tb.checks, set_name, tb.slosh_tanks)
    ok = tb.ok
    stats = percentile_rows(tb.summary_keys, tb.summary[ok], tb.runs[ok])
    disp_stats = percentile_rows([d["name"] for d in dispersions], tb.values[tb.runs > 0], tb.runs[tb.runs > 0])
    spread = margin_spread(tb.margins, tb.slosh_tanks)
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
