"""Orbit-insertion statistics of a batch: the accuracy table and the flight-performance
reserve.

**Insertion accuracy.** Over the runs that cut off on guidance (PEG's time to go or the
stored profile's energy target; not on depletion, not on the time limit), the 0.135, 50
and 99.865 percentiles of the insertion errors against the target (perigee, apogee,
inclination, node, radius, speed, flight-path angle, velocity), and the half-width of
the 0.135–99.865 % band: the ±3σ-equivalent spread a performance analyst quotes. With
``navigation=inertial`` the errors are the true orbit's (what the vehicle reached, not
what its navigation believed), and the same statistics of the navigation errors at cutoff
(navigated minus true position, velocity, attitude) follow in their own table: the
spread with navigation errors against the same batch flown with ``navigation=perfect``
is the navigation's share (docs/montecarlo.md).

**Flight-performance reserve (FPR).** The propellant the vehicle must carry, beyond what
the nominal flight burns, for a stated share ``P`` of dispersed flights (99.865 %, the
3σ-low flight, by default) to reach the target, at a stated confidence ``C`` (that of the
success line, 90 % by default): ``FPR = R_nominal − R_(k)``. ``R`` is the **usable**
upper-stage propellant at cutoff: what can still burn at the run's engine mixture ratio
(the limiting propellant and its partner; the other tank's excess is *unusable* and is
reported apart, never as reserve). ``R_(k)`` is the ``k``-th smallest ``R`` over the runs
that cut off on guidance or ran out of propellant (a run that ran out ranks below every
run that cut off), with ``k`` the largest order statistic that lies at or below the
``1 − P`` quantile of ``R`` with probability at least ``C``
(:func:`savant_cli.montecarlo.reliability.lower_quantile_rank`; Hanson and Beard,
NASA/TP-2010-216447). With too few runs for even the lowest (``n < ln(1 − C)/ln P``,
1705 runs for 99.865 % at 90 %) the reserve is not determined and the runs needed are
stated; when ``R_(k)`` is a run that ran out, the reserve is not covered.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from savant_cli.montecarlo.reliability import lower_quantile_rank, runs_for_quantile

#: the summary keys of the accuracy table, in order
ACCURACY_KEYS = ("insertion_perigee_error_km", "insertion_apogee_error_km", "insertion_inclination_error_deg",
                 "insertion_node_error_deg", "insertion_radius_error_m", "insertion_speed_error_mps",
                 "insertion_flight_path_angle_error_deg", "insertion_velocity_error_mps")
#: the navigation-error keys of a navigation=inertial batch (sim/summary.py NAVIGATION_KEYS)
NAVIGATION_ERROR_KEYS = ("navigation_position_error_m", "navigation_velocity_error_mps",
                         "navigation_attitude_error_deg")
#: run messages of a cutoff on guidance
GUIDED_CUTOFFS = ("cutoff: PEG time to go elapsed", "cutoff: target orbital energy reached")
DEPLETED = "cutoff: upper-stage propellant depleted before the target"
TAIL = 0.135  # percent: the 3σ-low tail
USABLE = "usable_propellant_remaining_kg"  # burnable at the engine mixture ratio (sim/summary.py)
UNUSABLE = "unusable_propellant_kg"
TOTAL = "propellant_remaining_kg"


def insertion_statistics(runs: np.ndarray, messages: list[str], keys: list[str], summary: np.ndarray,
                         probability: float = 1.0 - TAIL / 100.0, confidence: float = 0.9) -> dict[str, Any]:
    """The accuracy rows and the reserve of a batch (module notes).

    Parameters
    ----------
    runs : ndarray (n,)
        Run numbers (0 is the nominal).
    messages : list of str
        Each run's stop message (a health verdict's message quotes it).
    keys : list of str
        The summary table's column names; ``summary`` (n, len(keys)) its values.
    probability, confidence : float
        The reserve covers ``probability`` of the flights at ``confidence``
        (``study.reliability.reserve_probability`` and ``confidence``).
    """
    col = {k: j for j, k in enumerate(keys)}
    # a health verdict (limit cycle, saturated) keeps the stop message in its own
    guided = np.array([any(c in m for c in GUIDED_CUTOFFS) for m in messages], dtype=bool)
    depleted = np.array([DEPLETED in m for m in messages], dtype=bool)
    navigated = NAVIGATION_ERROR_KEYS[0] in col
    out: dict[str, Any] = {"runs_cut_off_on_guidance": int(guided.sum()), "runs_depleted": int(depleted.sum()),
                           "navigation": "inertial" if navigated else "perfect",
                           "accuracy": _percentile_rows(ACCURACY_KEYS, col, summary[guided])}
    if navigated:
        out["navigation_errors"] = _percentile_rows(NAVIGATION_ERROR_KEYS, col, summary[guided])
    if guided.any() or depleted.any():
        out["reserve"] = flight_performance_reserve(runs, guided, depleted, keys, summary, probability, confidence)
    return out


def _percentile_rows(keys: tuple[str, ...], col: dict[str, int], summary: np.ndarray) -> list[dict[str, Any]]:
    """The 0.135, 50 and 99.865 percentiles, half spread and largest magnitude of each key
    present (finite values of the given runs' summary rows)."""
    rows = []
    for key in keys:
        if key not in col:
            continue
        v = summary[:, col[key]]
        v = v[np.isfinite(v)]
        if not v.size:
            continue
        lo, mid, hi = np.percentile(v, (TAIL, 50.0, 100.0 - TAIL))
        rows.append({"variable": key, "n": int(v.size), "p0.135": float(lo), "p50": float(mid),
                     "p99.865": float(hi), "half_spread": float(0.5 * (hi - lo)),
                     "max_abs": float(np.max(np.abs(v)))})
    return rows


def flight_performance_reserve(runs: np.ndarray, guided: np.ndarray, depleted: np.ndarray, keys: list[str],
                               summary: np.ndarray, probability: float, confidence: float) -> dict[str, Any]:
    """The reserve block (module notes): the order statistic ``k`` of the counted runs'
    usable propellant that lies at or below its ``1 − probability`` quantile with
    ``confidence`` (:func:`~savant_cli.montecarlo.reliability.lower_quantile_rank`), and
    ``FPR = R_nominal − R_(k)``. A run that ran out ranks below every run that cut off.
    Too few runs for any order statistic: ``flight_performance_reserve_kg`` None,
    ``runs_needed`` says how many; ``R_(k)`` on a run that ran out: not covered."""
    col = {k: j for j, k in enumerate(keys)}
    counted = guided | depleted
    usable = USABLE in col
    measure = USABLE if usable else TOTAL
    remaining = np.where(depleted, -np.inf, summary[:, col[measure]] if measure in col else np.nan)
    n = int(counted.sum())
    order = np.argsort(remaining[counted], kind="stable")
    k = lower_quantile_rank(n, probability, confidence)
    nominal = remaining[runs == 0]
    nominal_value = float(nominal[0]) if nominal.size and np.isfinite(nominal[0]) else None
    low = low_run = None
    if k is not None:
        low = float(remaining[counted][order[k - 1]])
        low_run = int(runs[counted][order[k - 1]])
    covered = bool(low is not None and np.isfinite(low))
    out: dict[str, Any] = {
        "runs": n, "propellant": "usable" if usable else "total (usable propellant not recorded by these runs)",
        "probability": probability, "confidence": confidence, "order_statistic": k, "order_statistic_run": low_run,
        "runs_needed": runs_for_quantile(probability, confidence),
        "nominal_remaining_kg": nominal_value, "remaining_at_order_statistic_kg": low if covered else None,
        "flight_performance_reserve_kg": (nominal_value - low) if covered and nominal_value is not None else None,
        "covered": covered, "runs_depleted": int(depleted.sum()),
    }
    if UNUSABLE in col:
        un = summary[counted & ~depleted, col[UNUSABLE]]
        un = un[np.isfinite(un)]
        nominal_un = summary[runs == 0, col[UNUSABLE]]
        out["unusable_nominal_kg"] = float(nominal_un[0]) if nominal_un.size else None
        out["unusable_p50_kg"] = float(np.median(un)) if un.size else None
        out["unusable_max_kg"] = float(un.max()) if un.size else None
    return out


def reserve_line(ins: dict[str, Any]) -> str:
    """One console line for the flight-performance reserve."""
    r = ins.get("reserve")
    if r is None:
        return "flight-performance reserve: no run reached cutoff"
    what = f"{100 * r['probability']:.3f} % of flights at {100 * r['confidence']:g} % confidence"
    if r["order_statistic"] is None:
        return (f"flight-performance reserve ({what}): NOT DETERMINED — {r['runs']} runs are too few, the lowest of "
                f"them bounds the {100 * (1 - r['probability']):.3g} % quantile with less confidence; "
                f"{r['runs_needed']} runs needed")
    stat = f"order statistic {r['order_statistic']} of {r['runs']} (run {r['order_statistic_run']})"
    if not r["covered"]:
        return (f"flight-performance reserve ({what}): NOT COVERED — {r['runs_depleted']} of {r['runs']} runs ran out "
                f"of propellant before the target, and the {stat} is one of them")
    if r["flight_performance_reserve_kg"] is None:
        return f"flight-performance reserve ({what}): no nominal run in the batch to measure it from"
    unusable = (f"; unusable {r['unusable_nominal_kg']:.0f} kg nominal, up to {r['unusable_max_kg']:.0f} kg"
                if r.get("unusable_nominal_kg") is not None and r.get("unusable_max_kg") is not None else "")
    return (f"flight-performance reserve ({what}): {r['flight_performance_reserve_kg']:.0f} kg of {r['propellant']} "
            f"propellant (nominal {r['nominal_remaining_kg']:.0f} kg less {r['remaining_at_order_statistic_kg']:.0f} kg "
            f"at the {stat}; {r['runs_depleted']} runs ran out{unusable})")


def print_insertion(console: Console, ins: dict[str, Any]) -> None:
    """The accuracy table and the reserve line."""
    nav = ins.get("navigation", "perfect")
    for rows, title, prefix in (
            (ins["accuracy"], f"insertion accuracy ({ins['runs_cut_off_on_guidance']} runs cut off on guidance, "
                              f"navigation={nav})", "insertion_"),
            (ins.get("navigation_errors", []), "navigation error at cutoff (|navigated − true|)", "navigation_")):
        if not rows:
            continue
        tb = Table(title=title)
        for c in ("error", "p0.135", "p50", "p99.865", "± half spread", "max |error|"):
            tb.add_column(c, justify="left" if c == "error" else "right")
        for r in rows:
            tb.add_row(r["variable"].removeprefix(prefix), f"{r['p0.135']:.4g}", f"{r['p50']:.4g}",
                       f"{r['p99.865']:.4g}", f"{r['half_spread']:.4g}", f"{r['max_abs']:.4g}")
        console.print(tb)
    covered = (ins.get("reserve") or {}).get("covered", False)
    console.print(reserve_line(ins), style=None if covered else "bold red", markup=False, highlight=False,
                  soft_wrap=True)
