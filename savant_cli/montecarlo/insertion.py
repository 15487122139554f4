"""Orbit-insertion statistics of a batch: the accuracy table and the flight-performance
reserve.

**Insertion accuracy.** Over the runs that cut off on guidance (PEG's time to go or the
stored profile's energy target; not on depletion, not on the time limit), the 0.135, 50
and 99.865 percentiles of the insertion errors against the target (perigee, apogee,
inclination, node, radius, speed, flight-path angle, velocity), and the half-width of
the 0.135–99.865 % band: the ±3σ-equivalent spread a performance analyst quotes.

**Flight-performance reserve (FPR).** The propellant the vehicle must carry, beyond what
the nominal flight burns, for 99.865 % of dispersed flights to reach the target:
``FPR = R_nominal − R_0.135``, with ``R`` the upper-stage propellant remaining at cutoff
and ``R_0.135`` its 0.135 percentile (linear interpolation between order statistics) over
the runs that reached cutoff on guidance or ran out of propellant (those rank below any
run that cut off). When that percentile falls on or next to a run that ran out, the
3σ-low flight does not reach the target and the reserve is reported as not covered
(``covered: false``), with their count.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

#: the summary keys of the accuracy table, in order
ACCURACY_KEYS = ("insertion_perigee_error_km", "insertion_apogee_error_km", "insertion_inclination_error_deg",
                 "insertion_node_error_deg", "insertion_radius_error_m", "insertion_speed_error_mps",
                 "insertion_flight_path_angle_error_deg", "insertion_velocity_error_mps")
#: run messages of a cutoff on guidance
GUIDED_CUTOFFS = ("cutoff: PEG time to go elapsed", "cutoff: target orbital energy reached")
DEPLETED = "cutoff: upper-stage propellant depleted before the target"
TAIL = 0.135  # percent: the 3σ-low tail


def insertion_statistics(runs: np.ndarray, messages: list[str], keys: list[str], summary: np.ndarray) -> dict[str, Any]:
    """The accuracy rows and the reserve of a batch (module notes).

    Parameters
    ----------
    runs : ndarray (n,)
        Run numbers (0 is the nominal).
    messages : list of str
        Each run's stop message (a health verdict's message quotes it).
    keys : list of str
        The summary table's column names; ``summary`` (n, len(keys)) its values.
    """
    col = {k: j for j, k in enumerate(keys)}
    # a health verdict (limit cycle, saturated) keeps the stop message in its own
    guided = np.array([any(c in m for c in GUIDED_CUTOFFS) for m in messages], dtype=bool)
    depleted = np.array([DEPLETED in m for m in messages], dtype=bool)
    rows = []
    for key in ACCURACY_KEYS:
        if key not in col:
            continue
        v = summary[guided, col[key]]
        v = v[np.isfinite(v)]
        if not v.size:
            continue
        lo, mid, hi = np.percentile(v, (TAIL, 50.0, 100.0 - TAIL))
        rows.append({"variable": key, "n": int(v.size), "p0.135": float(lo), "p50": float(mid),
                     "p99.865": float(hi), "half_spread": float(0.5 * (hi - lo)),
                     "max_abs": float(np.max(np.abs(v)))})
    out: dict[str, Any] = {"runs_cut_off_on_guidance": int(guided.sum()), "runs_depleted": int(depleted.sum()),
                           "accuracy": rows}
    key = "propellant_remaining_kg"
    if key in col and (guided | depleted).any():
        counted = guided | depleted
        # the runs that ran out rank below every run that cut off (−inf): a percentile
        # interpolated from one of them is not finite, and the reserve is not covered
        remaining = np.where(depleted, -np.inf, summary[:, col[key]])[counted]
        with np.errstate(invalid="ignore"):
            low = float(np.percentile(remaining, TAIL))
        low = low if np.isfinite(low) else None
        nominal = summary[runs == 0, col[key]]
        nominal_value = float(nominal[0]) if nominal.size and np.isfinite(nominal[0]) else None
        out["reserve"] = {
            "runs": int(counted.sum()),
            "nominal_remaining_kg": nominal_value,
            "remaining_p0.135_kg": low,
            "flight_performance_reserve_kg": (nominal_value - low) if low is not None and nominal_value is not None
            else None,
            "covered": low is not None and low >= 0.0,
        }
    return out


def reserve_line(ins: dict[str, Any]) -> str:
    """One console line for the flight-performance reserve."""
    r = ins.get("reserve")
    if r is None:
        return "flight-performance reserve: no run reached cutoff"
    if r["flight_performance_reserve_kg"] is None:
        return (f"flight-performance reserve: NOT COVERED — {ins['runs_depleted']} of {r['runs']} runs ran out of "
                f"propellant before the target, and the {TAIL} percentile of the propellant remaining falls on them")
    return (f"flight-performance reserve (99.865 %): {r['flight_performance_reserve_kg']:.0f} kg "
            f"(nominal remaining {r['nominal_remaining_kg']:.0f} kg, 3σ-low {r['remaining_p0.135_kg']:.0f} kg; "
            f"{ins['runs_depleted']} of {r['runs']} runs ran out)")


def print_insertion(console: Console, ins: dict[str, Any]) -> None:
    """The accuracy table and the reserve line."""
    if ins["accuracy"]:
        tb = Table(title=f"insertion accuracy ({ins['runs_cut_off_on_guidance']} runs cut off on guidance)")
        for c in ("error", "p0.135", "p50", "p99.865", "± half spread", "max |error|"):
            tb.add_column(c, justify="left" if c == "error" else "right")
        for r in ins["accuracy"]:
            tb.add_row(r["variable"].removeprefix("insertion_"), f"{r['p0.135']:.4g}", f"{r['p50']:.4g}",
                       f"{r['p99.865']:.4g}", f"{r['half_spread']:.4g}", f"{r['max_abs']:.4g}")
        console.print(tb)
    covered = (ins.get("reserve") or {}).get("covered", False)
    console.print(reserve_line(ins), style=None if covered else "bold red")
