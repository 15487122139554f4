"""The end-of-run summary on the console (the only module of ``savant_cli.io`` that prints)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import StrEnum
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

#: ``output.console``: what a study prints on stdout (docs/outputs.md, "Console").
#: ``full``: every table and line (the whole flight summary, ~80 rows); ``summary``: the
#: study's tables and verdict lines, a flight's summary cut to :data:`HEADLINE_KEYS`;
#: ``quiet``: one status line and the study's verdict line (no progress bar, no table);
#: errors are printed on stderr in every mode.
class ConsoleMode(StrEnum):
    """``output.console``: ``full``, ``summary`` or ``quiet`` (above)."""

    full = "full"
    summary = "summary"
    quiet = "quiet"


CONSOLE_MODES = tuple(ConsoleMode)

#: The rows of a flight's summary under ``output.console=summary`` (those present).
HEADLINE_KEYS = (
    "max_dynamic_pressure_Pa", "time_max_dynamic_pressure_s", "max_alpha_deg", "max_qalpha_Pa_deg",
    "max_gimbal_deg", "max_gimbal_rate_deg_s", "max_attitude_error_deg", "rcs_on_time_s",
    "time_separation_s", "time_cutoff_s", "perigee_altitude_km", "apogee_altitude_km", "inclination_deg",
    "usable_propellant_remaining_kg", "limiting_propellant", "health_flags",
)


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


def format_sig(value: Any, digits: int = 4) -> str:
    """A number with ``digits`` significant digits, for tables a person reads.

    Parameters
    ----------
    value : Any
        A number (anything else as :func:`format_value` gives it).
    digits : int
        Significant digits of a float.

    Returns
    -------
    str
        Floats rounded to ``digits`` significant digits with thousands separators
        (``168,800``, ``7.48``, ``0.0001235``), scientific notation beyond 1e9 or below
        1e-4; integers in full; ``—``, ``nan``, ``inf``, ``yes``/``no`` as
        :func:`format_value`.
    """
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if not isinstance(value, float) or not math.isfinite(value):
        return format_value(value)
    if value == 0.0:
        return "0"
    mag = abs(value)
    if mag >= 1e9 or mag < 1e-4:
        return f"{value:.{digits - 1}e}"
    exponent = math.floor(math.log10(mag))
    decimals = digits - 1 - exponent  # negative: rounded to tens, hundreds …
    rounded = round(value, decimals)
    if abs(rounded) >= 10 ** (exponent + 1):  # 9.9996 -> 10.00: one digit more before the point
        decimals -= 1
        rounded = round(value, decimals)
    text = f"{rounded:,.{max(decimals, 0)}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def readable_name(key: str) -> str:
    """A summary or statistics key as a person reads it: ``insertion_radius_error_m`` →
    ``insertion radius error (m)`` (words wrap in a narrow table; the unit is kept)."""
    name, unit, _ = split_unit(key)
    return f"{name} ({unit})" if unit else name


def study_console(mode: str) -> Console:
    """The stdout console of a study under ``output.console`` = ``mode``: silent for
    ``quiet`` (the study's closing lines come from :func:`print_quiet_lines`)."""
    if mode not in CONSOLE_MODES:
        raise ValueError(f"output.console must be one of {', '.join(CONSOLE_MODES)}, not {mode!r}")
    return Console(quiet=mode == "quiet")


def live_display_ok(console: Console | None = None) -> bool:
    """Whether a progress bar can be drawn: anywhere but a Jupyter kernel without
    ``ipywidgets`` (where rich would warn on every refresh and draw nothing)."""
    console = console if console is not None else Console()
    if not console.is_jupyter:
        return True
    try:
        import ipywidgets  # noqa: F401
    except ImportError:
        return False
    return True


def verdict_line(summary: Mapping[str, Any]) -> tuple[str, bool] | None:
    """The one verdict line of a study's summary and whether it is met, the study's own
    judgement before a flight's: the demonstrated reliability of a Monte Carlo, the
    requirements of a linear study or flex sweep, the time margins, an FCS design's
    verdict after tuning, else the mission of a flight; None when there is none."""
    rel = summary.get("reliability")
    if isinstance(rel, Mapping) and rel.get("line"):
        return str(rel["line"]), bool(rel.get("target_met"))
    if isinstance(summary.get("requirements_verdict"), str):
        return summary["requirements_verdict"], bool(summary.get("requirements_met"))
    if isinstance(summary.get("time_margins_verdict"), str):
        line = summary["time_margins_verdict"]
        rows = summary.get("time_margins") or []
        bad = any(isinstance(r, Mapping) and (r.get("unstable_at_zero") or "differs by" in str(r.get("note", "")))
                  for r in rows)
        return line, not bad
    if isinstance(summary.get("verdict_after"), str):
        return summary["verdict_after"], bool(summary.get("requirements_met"))
    if isinstance(summary.get("mission_verdict"), str) and summary["mission_verdict"]:
        return summary["mission_verdict"], summary.get("mission_success") == 1
    return None


def print_quiet_lines(summary: Mapping[str, Any], out_dir: Any, console: Console | None = None) -> None:
    """What ``output.console=quiet`` prints at the end of a study: the status line (with
    the run folder) and the study's verdict line (:func:`verdict_line`), nothing else."""
    console = console if console is not None else Console()
    status = str(summary.get("status") or "unknown")
    ok = status == "complete"
    line = Text()
    line.append("status: ", style="bold")
    line.append(status, style="bold green" if ok else "bold red")
    if summary.get("message"):
        line.append(f" — {summary['message']}", style="green" if ok else "red")
    line.append(f" (outputs: {out_dir})")
    console.print(line, soft_wrap=True)
    verdict = verdict_line(summary)
    if verdict is not None:
        console.print(verdict[0], style="bold green" if verdict[1] else "bold red", markup=False, highlight=False,
                      soft_wrap=True)


def print_run_summary(record_summary: Mapping[str, Any], status: str, message: str,
                      console: Console | None = None, mode: str = "full") -> None:
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
    mode : str
        ``output.console``: ``full`` prints every key, ``summary`` only
        :data:`HEADLINE_KEYS`, ``quiet`` nothing (see :func:`print_quiet_lines`).
    """
    if mode == "quiet":
        return
    console = console if console is not None else Console()
    headline = mode == "summary"
    table = Table(title="savant run summary" + (" (headline; output.console=full for every key)" if headline else ""),
                  title_justify="left", header_style="bold")
    table.add_column("quantity", overflow="fold")
    table.add_column("value", justify="right", no_wrap=True)
    table.add_column("units", no_wrap=True)
    for key, value in record_summary.items():
        if key in _STATUS_KEYS or (headline and key not in HEADLINE_KEYS):
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
