"""The summary of a study as HTML tables a reviewer reads (``report.html``'s summary).

Every value of ``summary.json`` lands in a real table cell, never as a Python repr:

* a mapping becomes rows ``quantity | value | unit``, nested mappings flattened into
  ``outer · inner`` names; sibling mappings with the same keys (the Monte Carlo loads
  ``{max, max_run}`` per quantity, a fly-off's per-controller counts, the critical
  margins per mode count) become one table, a row per mapping and a column per key;
* a list of records becomes a table, a column per key, nested records flattened into
  ``outer inner`` columns and lists of records drawn as their own tables below;
* a list of scalars is one cell, its items joined with commas.

Units come from the key suffixes (:func:`savant_cli.io.console.split_unit`) into the
column header or the unit column; numbers are rounded to 4 significant digits (5 for
times, keys ending ``_s``), integers in full (:func:`savant_cli.io.console.format_sig`).

**Failing rows and the worst offender.** A record fails when one of its verdict flags
(:data:`PASS_FLAGS`) is false or one of its counts of violations (:data:`FAIL_COUNTS`)
is positive; its row is red. The worst offender is the record with the smallest
requirement ratio (:func:`requirement_ratio`: ``ratio_after``, ``ratio``, or
``|value| / required`` of the record or of its ``worst`` sub-record) over every table of
the summary (tables of points the requirement does not judge, ``not_judged``, left
out); where no record carries a ratio, the first failing record. Its row is
highlighted and marked, and :func:`worst_offender` gives the line the page shows
directly below the requirement verdict.
"""

from __future__ import annotations

import html
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from savant_cli.io.console import format_sig, readable_name, split_unit

#: Rows shown of a table (the study's CSV files have them all).
MAX_ROWS = 200
#: Boolean keys of a record that say whether it meets its requirement.
PASS_FLAGS = ("passed", "passed_after", "met", "meets_requirement", "meets_requirements", "closed_loop_stable",
              "target_met", "covered")
#: Count keys of a record that say how often it fails.
FAIL_COUNTS = ("violations", "runs_below_requirement")
#: Keys that identify a record in the worst-offender line, in order.
_ID_KEYS = ("time_s", "corner", "controller", "stage", "variable", "metric", "parameter", "level", "axis", "kind",
            "mode", "band", "criterion")


def _esc(value: Any) -> str:
    return html.escape(str(value), quote=True)


def format_cell(key: str, value: Any) -> str:
    """The text of one value under ``key``: numbers to 4 significant digits (5 for a
    time, ``_s``), lists joined with commas, records counted; never a repr."""
    if isinstance(value, Mapping):
        return "; ".join(f"{readable_name(k)}: {format_cell(k, v)}" for k, v in value.items()) or "—"
    if isinstance(value, (list, tuple)):
        if not value:
            return "—"
        if all(isinstance(v, Mapping) for v in value):
            return f"{len(value)} rows (table below)"
        return ", ".join(format_cell(key, v) for v in value)
    if isinstance(value, str):
        return value or "—"
    digits = 5 if key.endswith("_s") else 4
    return format_sig(value, digits)


def _numeric(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _td(key: str, value: Any) -> str:
    text = _esc(format_cell(key, value))
    return f'<td class="num">{text}</td>' if _numeric(value) else f"<td>{text}</td>"


def is_records(value: Any) -> bool:
    """A non-empty list of mappings (drawn as a table)."""
    return isinstance(value, list) and bool(value) and all(isinstance(v, Mapping) for v in value)


def _flatten(record: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings of a record as ``outer_inner`` keys (so the inner key keeps its
    unit suffix); lists of records are left out (drawn as their own tables)."""
    out: dict[str, Any] = {}
    for k, v in record.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            out.update(_flatten(v, f"{key}_"))
        elif not is_records(v):
            out[key] = v
    return out


def requirement_ratio(record: Mapping[str, Any]) -> float | None:
    """How far a record is from its requirement (1: on it, below 1: short of it):
    ``ratio_after`` or ``ratio``, else ``|value| / required`` of the record or of its
    ``worst`` sub-record; None when the record carries no requirement."""
    for key in ("ratio_after", "ratio"):
        if _numeric(record.get(key)):
            return float(record[key])
    for rec in (record, record.get("worst")):
        if isinstance(rec, Mapping) and _numeric(rec.get("value")) and _numeric(rec.get("required")) \
                and rec["required"] != 0:
            return abs(float(rec["value"])) / abs(float(rec["required"]))
    return None


def fails(record: Mapping[str, Any]) -> bool:
    """Whether a record misses its requirement (a false verdict flag or a positive
    count of violations)."""
    return any(record.get(k) is False for k in PASS_FLAGS) or \
        any(_numeric(record.get(k)) and record[k] > 0 for k in FAIL_COUNTS)


def describe(record: Mapping[str, Any]) -> str:
    """One line naming a record: its own ``worst`` text when it has one, else its
    identifying fields and its requirement."""
    for key in ("worst_after", "worst"):
        if isinstance(record.get(key), str) and record[key]:
            return record[key]
    worst = record.get("worst")
    if isinstance(worst, Mapping) and "value" in worst:
        unit = worst.get("unit", "")
        parts = [f"{format_cell('time_s', worst['time_s'])} s" if "time_s" in worst else ""]
        parts += [str(worst[k]) for k in ("axis", "mode", "criterion") if worst.get(k)]
        parts.append(f"{format_cell('value', worst['value'])} {unit}".strip())
        if "required" in worst:
            parts.append(f"(required {format_cell('required', worst['required'])} {unit})".replace(" )", ")"))
        return " ".join(p for p in parts if p)
    parts = []
    for k in _ID_KEYS:
        if k in record and record[k] not in (None, ""):
            parts.append(f"{format_cell(k, record[k])} s" if k == "time_s" else f"{readable_name(k)} {format_cell(k, record[k])}")
    ratio = requirement_ratio(record)
    if ratio is not None:
        parts.append(f"at {format_sig(ratio, 3)} of its requirement")
    return ", ".join(parts) or "a row"


@dataclass(frozen=True)
class Offender:
    """The worst offender of a summary: the table it is in, its row and its line."""

    table: str
    row: int
    line: str
    failing: bool


def record_tables(summary: Mapping[str, Any], path: str = "") -> Iterator[tuple[str, list[Mapping[str, Any]]]]:
    """Every list of records in a summary, at any depth, with its title (``a: b``)."""
    for key, value in summary.items():
        title = f"{path}: {key}" if path else str(key)
        if is_records(value):
            yield title, value
            for i, rec in enumerate(value[:MAX_ROWS]):
                yield from record_tables({k: v for k, v in rec.items() if is_records(v)}, f"{title} [{i}]")
        elif isinstance(value, Mapping):
            yield from record_tables(value, title)


def worst_offender(summary: Mapping[str, Any]) -> Offender | None:
    """The record with the smallest requirement ratio over the summary's tables, else
    the first failing record; None when there is neither."""
    best: tuple[float, str, int, Mapping[str, Any]] | None = None
    first_failing: tuple[str, int, Mapping[str, Any]] | None = None
    for title, records in record_tables(summary):
        if "not_judged" in title:
            continue  # points the requirement does not judge (docs/requirements.md) are no offenders
        for i, rec in enumerate(records[:MAX_ROWS]):
            ratio = requirement_ratio(rec)
            if ratio is not None and (best is None or ratio < best[0]):
                best = (ratio, title, i, rec)
            if first_failing is None and fails(rec):
                first_failing = (title, i, rec)
    if best is not None:
        _, title, i, rec = best
    elif first_failing is not None:
        title, i, rec = first_failing
    else:
        return None
    return Offender(table=title, row=i, line=describe(rec), failing=fails(rec))


def _table(header: list[str], rows: list[str], row_classes: list[str] | None = None, title: str = "") -> str:
    head = "".join(f"<th>{h}</th>" for h in header)
    cls = row_classes or [""] * len(rows)
    body = "".join(f'<tr class="{c}">{r}</tr>' if c else f"<tr>{r}</tr>" for r, c in zip(rows, cls))
    data = f' data-table="{_esc(title)}"' if title else ""
    return f'<div class="scroll"><table{data}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>'


def _header(key: str) -> str:
    name, unit, _ = split_unit(key)
    return _esc(name) + (f' <span class="unit">({_esc(unit)})</span>' if unit else "")


def records_table(title: str, records: list[Mapping[str, Any]], worst: Offender | None = None) -> str:
    """A list of records as a table: a column per (flattened) key with its unit, failing
    rows red, the worst offender's row highlighted."""
    flat = [_flatten(r) for r in records]
    cols: list[str] = []
    for r in flat:
        cols += [k for k in r if k not in cols]
    shown = flat[:MAX_ROWS]
    rows, classes = [], []
    for i, r in enumerate(shown):
        is_worst = worst is not None and worst.table == title and worst.row == i
        marker = '<td class="mark">◀ worst</td>' if is_worst else "<td></td>"
        rows.append("".join(_td(c, r.get(c)) for c in cols) + marker)
        classes.append(" ".join(c for c in ("fail" if fails(records[i]) else "", "worst" if is_worst else "") if c))
    more = (f'<p class="sub">{len(records) - MAX_ROWS} more rows in the study\'s CSV files.</p>'
            if len(records) > MAX_ROWS else "")
    return _table([_header(c) for c in cols] + [""], rows, classes, title) + more


def _flat_leaf(value: Any) -> bool:
    """A value that fits one cell: a scalar or a list of scalars."""
    return not isinstance(value, Mapping) and not is_records(value)


def _pivot_groups(mapping: Mapping[str, Any]) -> list[list[str]]:
    """The keys of the sub-mappings made of cell values only, when there are two or
    more: drawn as one table, a row per sub-mapping (none when fewer)."""
    keys = [k for k, v in mapping.items() if isinstance(v, Mapping) and v and all(_flat_leaf(x) for x in v.values())]
    return [keys] if len(keys) >= 2 else []


def mapping_tables(title: str, mapping: Mapping[str, Any], worst: Offender | None = None) -> str:
    """A mapping as HTML: its scalars as ``quantity | value | unit`` rows, same-shaped
    sub-mappings as one table, other sub-mappings flattened into ``outer · inner``
    rows, and every list of records (at any depth) as its own table."""
    parts: list[str] = []
    pivoted = {k for keys in _pivot_groups(mapping) for k in keys}
    rows = []

    def scalar_rows(node: Mapping[str, Any], names: list[str]) -> None:
        for k, v in node.items():
            if k in pivoted and not names:
                continue
            if isinstance(v, Mapping):
                scalar_rows(v, names + [str(k)])
            elif not is_records(v):
                label = " · ".join([readable_name(n) for n in names] + [split_unit(str(k))[0]])
                unit = split_unit(str(k))[1] or next((split_unit(n)[1] for n in reversed(names) if split_unit(n)[1]), "")
                unit_key = str(k) if split_unit(str(k))[1] else next((n for n in reversed(names) if split_unit(n)[1]), k)
                rows.append(f"<td>{_esc(label)}</td>{_td(unit_key, v)}<td>{_esc(unit)}</td>")

    scalar_rows(mapping, [])
    if rows:
        parts.append(_table(["quantity", "value", "unit"], rows, title=title))
    for keys in _pivot_groups(mapping):
        cols: list[str] = []
        for k in keys:
            cols += [c for c in mapping[k] if c not in cols]
        body = [f"<td>{_esc(readable_name(k))}</td>" + "".join(_td(k if c in ("max", "min", "mean") else c,
                                                                   mapping[k].get(c)) for c in cols) for k in keys]
        parts.append(_table([""] + [_header(c) for c in cols], body, title=f"{title}: by key"))
    for k, v in mapping.items():
        sub = f"{title}: {k}"
        if is_records(v):
            parts.append(f"<h3>{_esc(sub.replace('_', ' '))}</h3>" + records_table(sub, v, worst))
            for i, rec in enumerate(v[:MAX_ROWS]):
                for kk, vv in rec.items():
                    if is_records(vv):
                        inner = f"{sub} [{i}]: {kk}"
                        parts.append(f"<h3>{_esc(inner.replace('_', ' '))}</h3>" + records_table(inner, vv, worst))
        elif isinstance(v, Mapping):
            nested = "".join(_nested_records(sub, v, worst))
            parts.append(nested)
    return "".join(parts)


def _nested_records(title: str, mapping: Mapping[str, Any], worst: Offender | None) -> Iterator[str]:
    """The lists of records inside a sub-mapping (its scalars are in the parent's rows)."""
    for k, v in mapping.items():
        sub = f"{title}: {k}"
        if is_records(v):
            yield f"<h3>{_esc(sub.replace('_', ' '))}</h3>" + records_table(sub, v, worst)
        elif isinstance(v, Mapping):
            yield from _nested_records(sub, v, worst)


def summary_tables(summary: Mapping[str, Any], worst: Offender | None = None) -> str:
    """Every table of a summary's structured values (its scalars are drawn apart), each
    under a heading."""
    parts = []
    for key, value in summary.items():
        title = str(key)
        if is_records(value):
            parts.append(f"<h3>{_esc(title.replace('_', ' '))}</h3>" + records_table(title, value, worst))
            for i, rec in enumerate(value[:MAX_ROWS]):
                for kk, vv in rec.items():
                    if is_records(vv):
                        inner = f"{title} [{i}]: {kk}"
                        parts.append(f"<h3>{_esc(inner.replace('_', ' '))}</h3>" + records_table(inner, vv, worst))
        elif isinstance(value, Mapping) and value:
            parts.append(f"<h3>{_esc(title.replace('_', ' '))}</h3>" + mapping_tables(title, value, worst))
    return "".join(parts)
