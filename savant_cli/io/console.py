"""The end-of-run summary on the console (the only module of ``savant_cli.io`` that prints)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from rich.console import Console
from rich.table import Table
from rich.text import Text

#: Key suffix → (unit label, format of a float value). Longest suffixes first.
UNIT_SUFFIXES: tuple[tuple[str, str, str], ...] = (
    ("_Pa_deg", "Pa·deg", "{:,.0f}"),
    ("_Ns", "N·s", "{:,.0f}"),
    ("_deg_s", "deg/s", "{:.3f}"),
    ("_mps", "m/s", "{:,.2f}"),
    ("_deg", "deg", "{:.3f}"),
    ("_rad", "rad", "{:.5f}"),
    ("_kPa", "kPa", "{:,.3f}"),
    ("_Pa", "Pa", "{:,.0f}"),
    ("_km", "km", "{:,.2f}"),
    ("_kg", "kg", "{:,.1f}"),
    ("_m", "m", "{:,.1f}"),
    ("_s", "s", "{:,.3f}"),
    ("_N", "N", "{:,.0f}"),
    ("_hz", "Hz", "{:.3f}"),
)

#: Keys shown on the status line instead of in the table.
_STATUS_KEYS = ("status", "message", "mission_verdict", "mission_class_mask")


def split_unit(key: str) -> tuple[str, str, str | None]:
    """Split a summary key into a readable name, a unit label and a value format.

    Parameters
    ----------
    key : str
        Summary key such as ``max_dynamic_pressure_Pa``.

    Returns
    -------
    name : str
        Key without its unit suffix, underscores as spaces (``max dynamic pressure``).
    unit : str
        Unit label (``Pa``), ``""`` when the key has no recognised suffix.
    fmt : str or None
        Format for a float value, None for the generic one.
    """
    for suffix, unit, fmt in UNIT_SUFFIXES:
        if key.endswith(suffix) and len(key) > len(suffix):
            return key[: -len(suffix)].replace("_", " "), unit, fmt
    return key.replace("_", " "), "", None


def format_value(value: Any, fmt: str | None = None) -> str:
    """Text of one summary value.

    Parameters
    ----------
    value : Any
        float, int, bool, str or None.
    fmt : str, optional
        ``str.format`` pattern for finite floats; 6 significant digits by default.

    Returns
    -------
    str
        ``"—"`` for None, ``"nan"``/``"inf"`` for non-finite numbers, ``"yes"``/``"no"``
        for booleans.
    """
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return f"{value:,d}"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        if fmt is None:
            return f"{value:.6g}"
        return fmt.format(value)
    if hasattr(value, "item"):  # numpy scalar
        return format_value(value.item(), fmt)
    return str(value)


def print_run_summary(record_summary: Mapping[str, Any], status: str, message: str,
                      console: Console | None = None) -> None:
    """Print the summary of a run as a table, then a coloured status line.

    Parameters
    ----------
    record_summary : mapping
        The run summary (``RunRecord.summary``); units are taken from the key suffixes
        (``_Pa``, ``_s``, ``_deg``, ``_m``, ``_km``, ``_mps``, ``_kg`` ...). The
        ``status`` and ``message`` keys are not repeated in the table.
    status : str
        ``"complete"`` (printed in green) or anything else (printed in red).
    message : str
        Why the run stopped.
    console : rich.console.Console, optional
        Where to print; a new stdout console by default.
    """
    console = console if console is not None else Console()
    table = Table(title="savant run summary", title_justify="left", header_style="bold")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("units")
    for key, value in record_summary.items():
        if key in _STATUS_KEYS:
            continue
        name, unit, fmt = split_unit(key)
        table.add_row(name, format_value(value, fmt), unit)
    console.print(table)
    ok = status == "complete"
    line = Text()
    line.append("status: ", style="bold")
    line.append(status or "unknown", style="bold green" if ok else "bold red")
    if message:
        line.append(f" — {message}", style="green" if ok else "red")
    console.print(line)
    loads = loads_line(record_summary)
    if loads is not None:
        console.print(loads[0], style="red" if loads[1] else None, highlight=False, soft_wrap=True)
    verdict = record_summary.get("mission_verdict")
    if verdict:
        console.print(verdict, style="bold green" if record_summary.get("mission_success") == 1 else "bold red",
                      markup=False, highlight=False, soft_wrap=True)


def loads_line(summary: Mapping[str, Any]) -> tuple[str, bool] | None:
    """The load verdict of a run summary against its vehicle's q·α allowable: the line
    and whether the limit was exceeded; None when the vehicle declares no limit (or the
    run has no load indicators). A run above the limit keeps its status (docs/outputs.md,
    *Load indicators*), so this line is where the console says so."""
    limit = summary.get("qalpha_limit_Pa_deg")
    peak = summary.get("max_qalpha_Pa_deg")
    if limit is None or peak is None:
        return None
    exceeded = summary.get("qalpha_limit_exceeded") == 1
    text = (f"loads: max q·α_total {peak:,.0f} Pa·deg at {summary.get('time_max_qalpha_s', float('nan')):.2f} s "
            f"is {summary.get('qalpha_limit_ratio', peak / limit):.3f} of the limit {limit:,.0f} Pa·deg")
    if exceeded:
        text += f": EXCEEDED for {summary.get('time_above_qalpha_limit_s') or 0.0:.2f} s"
    return text, exceeded


def print_verdict(line: str, passed: bool, console: Console) -> None:
    """A one-line requirement verdict, green when it passes, red otherwise, unwrapped."""
    console.print(f"[{'green' if passed else 'red'}]{line}[/]", highlight=False, soft_wrap=True)
