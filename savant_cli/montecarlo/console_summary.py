"""A batch's summary on the console (rich): the extremes and margin-spread tables, the
run counts, the load extremes, the mission outcome by class and the demonstrated
success; and the load lines that report.html shows too."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from savant_cli.io.console import format_sig, print_verdict, readable_name
from savant_cli.montecarlo.analysis import LOAD_EXTREMES, Analysis
from savant_cli.montecarlo.insertion import print_insertion
from savant_cli.montecarlo.inventory import ranges_text
from savant_cli.montecarlo.results import Tables


def print_analysis(console: Console, tb: Tables, an: Analysis) -> None:
    """The batch's console summary: the tables, insertion, loads, mission and the
    demonstrated success."""
    print_tables(console, an.stats, an.spread, an.counts, an.missing, an.verdict if tb.checks.size else None)
    print_insertion(console, an.insertion)
    print_loads(console, an.loads)
    print_mission(console, an.mission)
    print_verdict(an.rel.line(), an.rel.target_met, console)


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
    """The batch's q·α verdict line (:func:`~savant_cli.montecarlo.analysis.load_extremes`)
    and whether no run exceeded the limit; None without a limit (what the console and
    report.html show)."""
    if not loads or loads.get("qalpha_limit_Pa_deg") is None:
        return None
    n = int(loads.get("runs_above_qalpha_limit", 0))
    text = (f"{n} of {loads['runs_with_results']} runs above the q-alpha limit "
            f"{loads['qalpha_limit_Pa_deg']:,.0f} Pa deg" + (f" (runs {loads['runs_above_qalpha_limit_list']})" if n else ""))
    return text, n == 0


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
