"""``report.html``: one self-contained page of a finished study, for a design review.

Every study writes it into its run folder (:func:`savant_cli.runner.run_study`, through
:func:`write_report_or_say`);
``savant report DIR`` writes it again after redrawing the figures. It is built from the
folder's files alone (:func:`savant_cli.result.load`): ``summary.json``, ``savant.h5``
and ``plots/``. Sections, in order:

1. the verdicts, the requirement verdict first: the study's verdict lines
   (requirements, time margins, the mission, the Monte Carlo's demonstrated success),
   then the worst offender of the summary's tables
   (:func:`savant_cli.html_tables.worst_offender`), then the run's status, the loads and
   any other verdict line; green when met, red when not;
2. the summary: every scalar of ``summary.json`` with its unit, then every table the
   summary holds (margins, statistics, margin spread, time margins …) as real tables
   with units and 4 significant digits (:mod:`savant_cli.html_tables`), failing rows
   red and the worst offender's row highlighted, up to
   :data:`savant_cli.html_tables.MAX_ROWS` rows each (the CSV files have them all);
3. the events timeline: an SVG time axis with the flight's events, each label in the
   lowest lane where it overlaps no other label and inside the drawing
   (:func:`timeline_layout`), and their table;
4. the figures: every PNG of ``plots/``, embedded, by folder;
5. the configuration as a diff from the shipped defaults (``savant run`` with no
   overrides), key by key;
6. the provenance (versions, host, git commit, time).

The page has no script, font, style sheet or image outside itself: inline CSS, PNGs as
``data:`` URIs, the timeline as inline SVG. It reads on a laptop screen: one column of at
most 1,150 px, tables that scroll sideways when wide, figures scaled to the column.
"""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from savant_cli.html_tables import format_cell, summary_tables, worst_offender
from savant_cli.io.atomic import write_text_atomic
from savant_cli.io.console import loads_line, split_unit
from savant_cli.montecarlo.console_summary import loads_by_choice_lines, loads_verdict
from savant_cli.result import Result, load

if TYPE_CHECKING:
    from rich.console import Console

REPORT_FILE = "report.html"

_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif;
       margin: 0; color: #1d2330; background: #f5f6f8; line-height: 1.4; }
main { max-width: 1150px; margin: 0 auto; padding: 16px 20px 40px; background: #fff; }
h1 { font-size: 1.5em; margin: 0.3em 0; } h2 { font-size: 1.2em; margin-top: 1.6em;
     border-bottom: 1px solid #d5d9e0; padding-bottom: 4px; } h3 { font-size: 1.0em; margin: 1.2em 0 0.4em; }
.sub { color: #5a6272; font-size: 0.9em; }
.verdict { padding: 6px 10px; margin: 4px 0; border-radius: 4px; font-family: ui-monospace, Menlo, Consolas, monospace;
           font-size: 0.88em; white-space: pre-wrap; word-break: break-word; }
.ok { background: #e6f4ea; border-left: 4px solid #1e7b34; } .bad { background: #fbe9e7; border-left: 4px solid #b3261e; }
.neutral { background: #eef1f6; border-left: 4px solid #6b7a90; }
.verdict.worst { font-weight: 600; background: #ffe08a; border-left: 8px solid #b07d00; }
tr.fail td { background: #fbe9e7; } tr.worst td { background: #ffe08a; font-weight: 600; }
td.mark { color: #b3261e; white-space: nowrap; } .unit { color: #5a6272; font-weight: normal; }
.scroll { overflow-x: auto; max-height: 520px; overflow-y: auto; border: 1px solid #e2e5ea; }
table { border-collapse: collapse; font-size: 0.84em; width: auto; min-width: 40%; }
th, td { padding: 3px 8px; border-bottom: 1px solid #eceef2; text-align: left; vertical-align: top; }
th { background: #f0f2f5; position: sticky; top: 0; } td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tr.changed td { background: #fff8e1; } tbody td:first-child { white-space: nowrap; }
figure { margin: 10px 0 18px; } figure img { max-width: 100%; height: auto; border: 1px solid #e2e5ea; }
figcaption { font-size: 0.82em; color: #5a6272; }
nav a { margin-right: 12px; font-size: 0.9em; }
code { font-size: 0.9em; }
"""


def _esc(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _cell(value: Any, key: str = "") -> str:
    """One cell: the value as :func:`savant_cli.html_tables.format_cell` gives it under
    ``key`` (significant digits by its unit), numbers right-aligned."""
    text = format_cell(key, value)
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    return f'<td class="num">{_esc(text)}</td>' if numeric else f"<td>{_esc(text)}</td>"


def _table(header: Iterable[str], rows: Iterable[Iterable[str]], classes: Iterable[str] | None = None) -> str:
    head = "".join(f"<th>{_esc(h)}</th>" for h in header)
    cls = list(classes) if classes is not None else None
    body = "".join(f'<tr{f" class={chr(34)}{cls[i]}{chr(34)}" if cls and cls[i] else ""}>{"".join(r)}</tr>'
                   for i, r in enumerate(rows))
    return f'<div class="scroll"><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>'


# ------------------------------------------------------------------------------ verdicts

def verdicts(result: Result) -> list[tuple[str, bool | None]]:
    """The verdict lines of a study, each with whether it is met (None: no judgement)."""
    s = result.summary
    out: list[tuple[str, bool | None]] = []
    status = f"status: {result.status}" + (f" — {result.message}" if result.message else "")
    if s.get("missing_runs"):  # a Monte Carlo collected with --allow-missing: never looks complete
        out.append((f"PARTIAL batch: {s.get('n_runs_present')} of {s.get('n_runs_expected')} runs present, "
                    f"missing runs {s['missing_runs']}", False))
    if isinstance(s.get("requirements_verdict"), str):
        out.append((s["requirements_verdict"], bool(s.get("requirements_met"))))
    elif isinstance(s.get("requirements_verdict"), Mapping):  # a fly-off: per controller, "n of m" runs passing
        for ctrl, line in s["requirements_verdict"].items():
            meeting = str((s.get("runs_meeting_requirements") or {}).get(ctrl, ""))
            n, _, m = meeting.partition(" of ")
            out.append((f"{ctrl}: {line}", n == m and n != "" if meeting else ": PASS" in str(line)))
    if isinstance(s.get("verdict_after"), str):  # an FCS design: the tuned controller's verdict, then the start's
        out.append((f"after: {s['verdict_after']}", bool(s.get("requirements_met"))))
        if isinstance(s.get("verdict_before"), str):
            out.append((f"before: {s['verdict_before']}", None))
    if isinstance(s.get("time_margins_verdict"), str):
        rows = s.get("time_margins") or []
        bad = any(r.get("unstable_at_zero") or "differs by" in str(r.get("note", "")) for r in rows)
        out.append((s["time_margins_verdict"], not bad))
    if isinstance(s.get("mission_verdict"), str):  # one run
        out.append((s["mission_verdict"], s.get("mission_success") == 1))
    rel = s.get("reliability")
    if isinstance(rel, Mapping) and rel.get("line"):  # a Monte Carlo
        out += _mission_lines(s.get("mission"), "")
        out.append((str(rel["line"]), bool(rel.get("target_met"))))
    elif isinstance(rel, Mapping):  # a fly-off: per controller
        for ctrl, r in rel.items():
            if isinstance(r, Mapping) and r.get("line"):
                out += _mission_lines((s.get("mission") or {}).get(ctrl), f"{ctrl}: ")
                out.append((f"{ctrl}: {r['line']}", bool(r.get("target_met"))))
    worst = worst_offender(s)
    if worst is not None:
        # highlighted, but not a verdict of its own: the requirement line above is the judgement
        out.append((f"{WORST_PREFIX}{worst.table.replace('_', ' ')}): {worst.line}", None))
    out.append((status, result.status == "complete"))
    batch = loads_verdict(s["loads"]) if isinstance(s.get("loads"), Mapping) else None
    if batch is not None:
        out.append((f"loads: {batch[0]}", batch[1]))
        out += loads_by_choice_lines(s["loads"])
    single = loads_line(s)
    if single is not None:
        out.append((single[0], not single[1]))
    for key, value in s.items():  # any other study's verdict line (flex sweep, FCS design …)
        if key.endswith("verdict") and key not in ("requirements_verdict", "time_margins_verdict", "mission_verdict") \
                and isinstance(value, str):
            out.append((value, None))
    return out


def _mission_lines(mission: Any, prefix: str) -> list[tuple[str, bool | None]]:
    """A batch's mission outcome by class (``montecarlo.analysis.mission_outcomes``): a
    line per class with runs in it (failing when the class counts), or one passing line."""
    if not isinstance(mission, Mapping) or not isinstance(mission.get("by_class"), list):
        return []
    rows = [c for c in mission["by_class"] if c.get("runs")]
    if not rows:
        return [(f"{prefix}mission: no run of {mission.get('runs')} in any failure class", True)]
    return [(f"{prefix}mission {c['label']}: {c['runs']} of {mission.get('runs')} runs (runs {c['run_list']})"
             + ("" if c["counted"] else "; not counted as a failure"), False if c["counted"] else None) for c in rows]


#: How the worst-offender line of :func:`verdicts` starts.
WORST_PREFIX = "worst offender ("


def _verdict_html(lines: list[tuple[str, bool | None]]) -> str:
    cls = {True: "ok", False: "bad", None: "neutral"}
    return "".join(f'<div class="verdict {cls[ok]}{" worst" if text.startswith(WORST_PREFIX) else ""}">'
                   f"{_esc(text)}</div>" for text, ok in lines)


# ------------------------------------------------------------------------------- summary

def _scalars(summary: Mapping[str, Any]) -> str:
    rows = []
    for key, value in summary.items():
        if isinstance(value, (list, dict)) or key in ("status", "message"):
            continue
        name, unit, _ = split_unit(key)
        rows.append([f"<td>{_esc(name)}</td>", _cell(value, key), f"<td>{_esc(unit)}</td>"])
    return _table(("quantity", "value", "unit"), rows) if rows else "<p>No scalar results.</p>"


# -------------------------------------------------------------------------------- events

#: Timeline geometry (SVG user units): width, margins, label font size, the width of one
#: label character (an upper bound for the page's sans-serif at that size), lane height.
TIMELINE_WIDTH, TIMELINE_LEFT, TIMELINE_RIGHT = 1000, 30, 30
LABEL_FONT, LABEL_CHAR_W, LANE_H, LABEL_GAP = 11, 7.0, 16, 8


def timeline_layout(events: Mapping[str, float], t_end: float) -> list[tuple[str, float, float, int, str]]:
    """Where each event label goes: ``(text, x of the mark, x of the label, lane,
    anchor)``, lane 0 next to the axis.

    Labels are horizontal. Each, in time order, takes the lowest lane in which its
    estimated extent (:data:`LABEL_CHAR_W` per character) keeps :data:`LABEL_GAP` from
    every label already there; it starts at its mark, or ends at it (``anchor`` ``end``)
    when it would run past the right edge, so no label overlaps another or leaves the
    drawing."""
    scale = (TIMELINE_WIDTH - TIMELINE_LEFT - TIMELINE_RIGHT) / t_end
    lanes: list[list[tuple[float, float]]] = []
    out = []
    for name, t in sorted(events.items(), key=lambda kv: (kv[1], kv[0])):
        text = f"{name} {t:.2f} s"
        x = TIMELINE_LEFT + t * scale
        w = len(text) * LABEL_CHAR_W
        start, anchor = x + 3, "start"
        if start + w > TIMELINE_WIDTH - 2:
            start, anchor = x - 3 - w, "end"
        span = (start, start + w)
        lane = next((i for i, used in enumerate(lanes)
                     if all(span[1] + LABEL_GAP <= a or span[0] >= b + LABEL_GAP for a, b in used)), len(lanes))
        if lane == len(lanes):
            lanes.append([])
        lanes[lane].append(span)
        out.append((text, x, x + 3 if anchor == "start" else x - 3, lane, anchor))
    return out


def _timeline(events: Mapping[str, float], t_final: float | None) -> str:
    if not events:
        return "<p>No events (a study without a single flight, or a run that stopped before any).</p>"
    t_end = max([*events.values(), t_final or 0.0]) or 1.0
    width, left, right = TIMELINE_WIDTH, TIMELINE_LEFT, TIMELINE_RIGHT
    layout = timeline_layout(events, t_end)
    n_lanes = max(lane for *_, lane, _ in layout) + 1
    axis_y = 20 + n_lanes * LANE_H
    height = axis_y + 44
    scale = (width - left - right) / t_end

    def x(t: float) -> float:
        return left + t * scale

    ticks = []
    step = 10 ** math.floor(math.log10(t_end)) if t_end > 0 else 1.0
    if t_end / step < 4:
        step /= 2
    k = 0.0
    while k <= t_end + 1e-9:
        ticks.append(f'<line x1="{x(k):.1f}" y1="{axis_y}" x2="{x(k):.1f}" y2="{axis_y + 6}" stroke="#6b7a90"/>'
                     f'<text x="{x(k):.1f}" y="{axis_y + 20}" font-size="11" text-anchor="middle" fill="#5a6272">'
                     f"{k:g}</text>")
        k += step
    lines, labels = [], []  # every connector under every label; a white halo keeps a crossed label legible
    for text, xm, xl, lane, anchor in layout:
        y = axis_y - 12 - lane * LANE_H
        lines.append(f'<line x1="{xm:.1f}" y1="{y + 3}" x2="{xm:.1f}" y2="{axis_y}" stroke="#b3261e" '
                     f'stroke-width="{2 if lane == 0 else 1}"/>')
        labels.append(f'<text class="event-label" x="{xl:.1f}" y="{y}" font-size="{LABEL_FONT}" '
                      f'text-anchor="{anchor}" fill="#1d2330" stroke="#fff" stroke-width="3" '
                      f'paint-order="stroke">{_esc(text)}</text>')
    marks = lines + labels
    svg = (f'<svg viewBox="0 0 {width} {height}" width="100%" role="img" aria-label="events timeline">'
           f'<line x1="{left}" y1="{axis_y}" x2="{x(t_end):.1f}" y2="{axis_y}" stroke="#1d2330" stroke-width="1.5"/>'
           f'{"".join(ticks)}{"".join(marks)}<text x="{width - right}" y="{axis_y + 36}" font-size="11" '
           f'text-anchor="end" fill="#5a6272">mission time (s)</text></svg>')
    rows = [[f"<td>{_esc(n)}</td>", f'<td class="num">{float(t):.3f}</td>'] for n, t in events.items()]
    return svg + _table(("event", "time (s)"), rows)


# ------------------------------------------------------------------------------- figures

def _figures(run_dir: Path) -> tuple[str, int]:
    folder = run_dir / "plots"
    pngs = sorted(folder.rglob("*.png")) if folder.is_dir() else []
    if not pngs:
        return "<p>No figures (output.plots=false).</p>", 0
    parts, current = [], None
    for path in pngs:
        group = str(path.parent.relative_to(folder))
        if group != current:
            current = group
            parts.append(f"<h3>{_esc('plots/' if group == '.' else f'plots/{group}/')}</h3>")
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        rel = path.relative_to(run_dir)
        parts.append(f'<figure><img alt="{_esc(rel)}" src="data:image/png;base64,{data}">'
                     f"<figcaption>{_esc(rel)}</figcaption></figure>")
    return "".join(parts), len(pngs)


# -------------------------------------------------------------------------------- config

def _flatten(node: Any, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    if isinstance(node, Mapping):
        for k, v in node.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
        if not node and prefix:
            out[prefix] = {}
    else:
        out[prefix] = node
    return out


def shipped_defaults() -> dict[str, Any]:
    """The flattened configuration ``savant run`` composes with no overrides.

    Composing takes about half a second, so the result is kept as JSON in the numba
    cache folder (:mod:`savant_cli.jit_cache`), keyed by a hash of every file of the
    shipped config tree and the savant version; a changed tree composes anew."""
    import hashlib
    import json
    import os

    from omegaconf import OmegaConf

    from savant_cli.hydra_compose import compose_config, task_config
    from savant_cli.paths import shipped_config_dir
    from savant_cli.version import __version__

    root = shipped_config_dir()
    h = hashlib.sha256(__version__.encode())
    for path in sorted(root.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    folder = os.environ.get("NUMBA_CACHE_DIR")
    cached = Path(folder) / f"shipped_defaults-{h.hexdigest()[:16]}.json" if folder else None
    if cached is not None and cached.is_file():
        try:
            return json.loads(cached.read_text())
        except (OSError, ValueError):
            pass
    flat = _flatten(OmegaConf.to_container(task_config(compose_config([], None)), resolve=True))
    if cached is not None:
        try:
            write_text_atomic(cached, json.dumps(flat))
        except OSError:
            pass  # an unwritable cache only costs the composition next time
    return flat


def config_diff(result: Result) -> list[tuple[str, Any, Any]] | None:
    """``(key, shipped default, this run)`` of every config key that differs from the
    configuration ``savant run`` composes without overrides (a key only one side has:
    the other side ``"—"``); None when the defaults cannot be composed."""
    import json

    from omegaconf import OmegaConf

    try:
        a = shipped_defaults()
    except Exception:  # noqa: BLE001 - the report says so instead of failing
        return None
    # through JSON like the cached defaults, so both sides compare alike
    b = json.loads(json.dumps(_flatten(OmegaConf.to_container(result.config, resolve=True))))
    missing = "—"
    return [(k, a.get(k, missing), b.get(k, missing)) for k in sorted(set(a) | set(b)) if a.get(k, missing) != b.get(k, missing)]


def _config_html(result: Result) -> str:
    diff = config_diff(result)
    if diff is None:
        return "<p>The shipped defaults could not be composed; the full configuration is in <code>.hydra/config.yaml</code>.</p>"
    if not diff:
        return "<p>The shipped defaults, unchanged (<code>savant run</code> with no overrides).</p>"
    rows = [[f"<td><code>{_esc(k)}</code></td>", f"<td>{_esc(d)}</td>", f"<td>{_esc(v)}</td>"] for k, d, v in diff]
    return (f'<p class="sub">{len(diff)} keys differ from the shipped defaults (<code>savant run</code> with no '
            f"overrides); the whole configuration is in <code>.hydra/config.yaml</code> and <code>savant.h5</code>.</p>"
            + _table(("key", "shipped default", "this run"), rows, ["changed"] * len(rows)))


# ---------------------------------------------------------------------------------- page

def render(result: Result) -> str:
    """The page of a loaded study (:func:`savant_cli.result.load`)."""
    lines = verdicts(result)
    figures, n_figures = _figures(result.run_dir)
    t_final = result.summary.get("t_final_s") if isinstance(result.summary.get("t_final_s"), (int, float)) else None
    prov = [[f"<td>{_esc(k)}</td>", f"<td>{_esc(v)}</td>"] for k, v in sorted(result.provenance.items())]
    vehicle = result.config.get("vehicle", {}).get("name", "") if hasattr(result.config, "get") else ""
    title = f"savant {result.study}: {vehicle}".strip(": ")
    ok = all(v is not False for _, v in lines)
    sections = [
        ("verdicts", "Verdicts", _verdict_html(lines)),
        ("summary", "Summary", _scalars(result.summary) + summary_tables(result.summary, worst_offender(result.summary))),
        ("events", "Events", _timeline(result.events, t_final)),
        ("figures", f"Figures ({n_figures})", figures),
        ("config", "Configuration (difference from the shipped defaults)", _config_html(result)),
        ("provenance", "Provenance", _table(("", ""), prov) if prov else "<p>None recorded.</p>"),
    ]
    nav = "".join(f'<a href="#{sid}">{_esc(head)}</a>' for sid, head, _ in sections)
    body = "".join(f'<section id="{sid}"><h2>{_esc(head)}</h2>{content}</section>' for sid, head, content in sections)
    created = result.provenance.get("created_utc", "")
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{_esc(title)}</title><style>{_CSS}</style></head><body><main>"
            f"<h1>{_esc(title)}</h1>"
            f'<p class="sub">{_esc(result.run_dir)} · {_esc(created)} · '
            f'<span style="color:{"#1e7b34" if ok else "#b3261e"}">{"every verdict met" if ok else "a verdict is not met"}'
            f"</span></p><nav>{nav}</nav>{body}</main></body></html>\n")


def write_report(run_dir: Path | str) -> Path:
    """Write ``run_dir/report.html`` (atomically) from the folder's files; returns its path.

    Raises
    ------
    FileNotFoundError
        The folder holds no ``savant.h5`` (``output.hdf5=false``).
    """
    result = load(Path(run_dir).resolve())
    path = result.run_dir / REPORT_FILE
    write_text_atomic(path, render(result))
    return path


def write_report_or_say(folder: Path, console: Console, raise_write_errors: bool = False,
                        say_written: bool = True) -> int:
    """``report.html`` into ``folder`` (:func:`write_report`), or a line on ``console``
    saying why not (and, with ``say_written``, where it was written). What a study's run
    (:func:`savant_cli.runner.run_study`), ``savant report``, ``savant collect`` and
    ``savant rerun`` call.

    Parameters
    ----------
    folder : pathlib.Path
        The run folder.
    console : rich.console.Console
        Where the line goes (stderr in the commands).
    raise_write_errors : bool
        Raise an :class:`~savant_cli.errors.OutputWriteError` instead of saying it.
    say_written : bool
        Say where the page was written.

    Returns
    -------
    int
        1 when the page could not be written (:class:`~savant_cli.errors.OutputWriteError`:
        disk full, folder not writable), else 0: a page that cannot be built leaves the
        exit status alone.
    """
    from savant_cli.errors import OutputWriteError

    try:
        path = write_report(folder)
    except OutputWriteError as exc:
        if raise_write_errors:
            raise
        console.print(f"[red]report.html not written[/red]: {exc}", highlight=False)
        return exc.exit_code
    except FileNotFoundError as exc:
        console.print(f"no report.html: {exc}", highlight=False)
    except Exception as exc:  # noqa: BLE001 - the study's own outputs stand without the page
        console.print(f"[red]report.html not written[/red]: {type(exc).__name__}: {exc}", highlight=False)
    else:
        if say_written:
            console.print(f"report: {path}", highlight=False)
    return 0
