"""``savant compare RUN_DIR REFERENCE --map MAP.yaml``: a run against another
simulation's time history.

The mapping file (YAML) names the reference's time column and, per compared signal, the
savant signal (``name`` or ``name[column]``), the reference column, the conversion of
the reference into savant's SI units (``value × scale + offset``) and the tolerances::

    reference:
      time: {column: sim_time_s, scale: 1.0, offset: 0.0}
      window_s: [0.0, 120.0]        # optional: compare only inside this window
    signals:
      altitude:
        savant: altitude
        reference: altitude_ft
        scale: 0.3048
        tolerance: {max_abs: 50.0, rms: 20.0, max_rel: 0.01}   # any of the three

The reference (CSV with a header row and ``#`` comments, or HDF5 with one 1-D dataset per
column, at the root or under ``reference.group``) is interpolated linearly onto the
run's log times inside the overlap of the two time axes. Per signal: max and RMS
difference (savant − reference), max difference relative to the run's peak |value|,
and pass/fail against each tolerance given. Outputs in ``RUN_DIR/compare_<ref stem>/``
(or ``--out``): ``compare.csv``, ``compare.json``, and per signal an overlay and
difference plot. Exit status 0 when every signal passes, 1 otherwise, 2 for bad input.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_json_atomic, write_text_atomic
from savant_cli.io.hdf5 import read_run
from savant_cli.io.table_order import require_increasing

TOLERANCES = ("max_abs", "rms", "max_rel")
_SIGNAL_RE = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(\w+)\])?$")


@dataclass(frozen=True)
class Mapped:
    """One compared signal of the mapping file."""

    name: str
    savant: str
    reference: str
    scale: float
    offset: float
    units: str
    tolerance: dict[str, float]


def _number(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(key, value, "must be a finite number")
    return float(value)


def read_mapping(path: Path) -> tuple[dict[str, Any], list[Mapped]]:
    """The mapping file: the reference's time spec and the compared signals."""
    if not path.is_file():
        raise ConfigError("--map", str(path), "no such mapping file")
    try:
        doc = OmegaConf.to_container(OmegaConf.load(path), resolve=True)
    except (OmegaConfBaseException, ValueError, TypeError) as exc:
        raise ConfigError("--map", str(path), f"is not a valid YAML mapping ({exc})") from None
    except Exception as exc:  # noqa: BLE001 - the YAML parser's own errors
        raise ConfigError("--map", str(path), f"is not valid YAML ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("signals"), dict) or not doc["signals"]:
        raise ConfigError("--map", str(path), "must have `reference: {time: {column: …}}` and a non-empty `signals:`")
    ref = doc.get("reference") or {}
    time = ref.get("time") or {}
    if not isinstance(time, dict) or not time.get("column"):
        raise ConfigError("reference.time.column", time, "must name the reference's time column")
    spec = {"time": str(time["column"]), "time_scale": _number("reference.time.scale", time.get("scale", 1.0)),
            "time_offset": _number("reference.time.offset", time.get("offset", 0.0)),
            "group": str(ref.get("group", "")), "window": (-math.inf, math.inf)}
    if ref.get("window_s") is not None:
        w = ref["window_s"]
        if not isinstance(w, list) or len(w) != 2 or _number("reference.window_s[0]", w[0]) >= _number(
                "reference.window_s[1]", w[1]):
            raise ConfigError("reference.window_s", w, "must be [start, end] in s with start < end")
        spec["window"] = (float(w[0]), float(w[1]))
    out = []
    for name, s in doc["signals"].items():
        key = f"signals.{name}"
        if not isinstance(s, dict) or "savant" not in s or "reference" not in s:
            raise ConfigError(key, s, "must give `savant:` (signal) and `reference:` (column)")
        tol = s.get("tolerance") or {}
        for k in tol:
            if k not in TOLERANCES:
                raise ConfigError(f"{key}.tolerance.{k}", tol[k], f"unknown tolerance; allowed: {', '.join(TOLERANCES)}")
            if _number(f"{key}.tolerance.{k}", tol[k]) < 0:
                raise ConfigError(f"{key}.tolerance.{k}", tol[k], "must be zero or positive")
        out.append(Mapped(str(name), str(s["savant"]), str(s["reference"]), _number(f"{key}.scale", s.get("scale", 1.0)),
                          _number(f"{key}.offset", s.get("offset", 0.0)), str(s.get("units", "")),
                          {k: float(v) for k, v in tol.items()}))
    return spec, out


def read_reference(path: Path, group: str = "") -> dict[str, np.ndarray]:
    """Columns of a CSV (header row, ``#`` comments) or an HDF5 file (1-D datasets)."""
    if not path.is_file():
        raise ConfigError("REFERENCE", str(path), "no such file")
    if path.suffix.lower() in (".h5", ".hdf5"):
        with h5py.File(path, "r") as f:
            g = f[group] if group else f
            return {k: np.asarray(v[()], dtype=float).ravel() for k, v in g.items() if isinstance(v, h5py.Dataset)}
    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if len(lines) < 3:
        raise ConfigError("REFERENCE", str(path), "needs a header row and at least two data rows")
    rows = list(csv.reader(lines))
    header = [h.strip() for h in rows[0]]
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:]])
    except ValueError as exc:
        raise ConfigError("REFERENCE", str(path), f"non-numeric entry ({exc})") from None
    if data.shape[1] != len(header):
        raise ConfigError("REFERENCE", str(path), "every row needs one value per header column")
    return {h: data[:, i] for i, h in enumerate(header)}


def _savant_signal(signals: dict, spec: str, key: str) -> np.ndarray:
    m = _SIGNAL_RE.match(spec)
    if not m or m.group(1) not in signals:
        raise ConfigError(key, spec, "no such savant signal; known: " + ", ".join(k for k in signals if k != "time"))
    sig = signals[m.group(1)]
    data = np.asarray(sig.data, dtype=float)
    if m.group(2) is None:
        if data.ndim != 1:
            raise ConfigError(key, spec, f"is a vector signal: name a column, e.g. {m.group(1)}[{sig.columns[0]}]")
        return data
    col = m.group(2)
    idx = int(col) if col.isdigit() else (list(sig.columns).index(col) if col in sig.columns else -1)
    if data.ndim != 2 or not 0 <= idx < data.shape[1]:
        raise ConfigError(key, spec, f"no such column; {m.group(1)} has {', '.join(sig.columns) or 'none'}")
    return data[:, idx]


def compare(run_dir: Path, reference: Path, mapping: Path, out_dir: Path | None = None,
            plots: bool = True, console: Console | None = None) -> int:
    """Compare, write the outputs, print the table; the exit status (0 pass, 1 fail)."""
    console = console or Console()
    spec, mapped = read_mapping(mapping)
    ref = read_reference(reference, spec["group"])
    for name in [spec["time"]] + [m.reference for m in mapped]:
        if name not in ref:
            key = "reference.time.column" if name == spec["time"] else \
                f"signals.{next(m.name for m in mapped if m.reference == name)}.reference"
            raise ConfigError(key, name, f"no such column in {reference.name}; it has {', '.join(ref)}")
    run = read_run(run_dir / "savant.h5")
    t_run = np.asarray(run.signals["time"].data, dtype=float)
    t_ref = ref[spec["time"]] * spec["time_scale"] + spec["time_offset"]
    require_increasing(f"{reference.name}:{spec['time']}", ref[spec["time"]], what="the reference's time axis")
    lo, hi = max(t_run[0], t_ref[0], spec["window"][0]), min(t_run[-1], t_ref[-1], spec["window"][1])
    if not hi > lo:
        raise ConfigError("REFERENCE", str(reference), f"its time axis [{t_ref[0]:g}, {t_ref[-1]:g}] s does not overlap "
                          f"the run's [{t_run[0]:g}, {t_run[-1]:g}] s (within reference.window_s)")
    sel = (t_run >= lo) & (t_run <= hi)
    t = t_run[sel]
    rows, traces = [], {}
    for m in mapped:
        y = _savant_signal(run.signals, m.savant, f"signals.{m.name}.savant")[sel]
        r = np.interp(t, t_ref, ref[m.reference] * m.scale + m.offset)
        d = y - r
        peak = float(np.max(np.abs(y))) or 1.0
        stats = {"max_abs": float(np.max(np.abs(d))), "rms": float(np.sqrt(np.mean(d * d))),
                 "max_rel": float(np.max(np.abs(d))) / peak}
        checks = {k: stats[k] <= v for k, v in m.tolerance.items()}
        rows.append({"signal": m.name, "savant": m.savant, "reference": m.reference, "units": m.units,
                     "max_abs_difference": stats["max_abs"], "rms_difference": stats["rms"],
                     "max_relative_difference": stats["max_rel"],
                     **{f"tolerance_{k}": m.tolerance.get(k, "") for k in TOLERANCES},
                     "passed": all(checks.values()) if checks else ""})
        traces[m.name] = (y, r, m.units)
    out = out_dir or run_dir / f"compare_{reference.stem}"
    out.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_text_atomic(out / "compare.csv", buf.getvalue())
    write_json_atomic(out / "compare.json", {"run": str(run_dir), "reference": str(reference),
                                             "mapping": str(mapping), "window_s": [float(lo), float(hi)],
                                             "samples": int(t.size), "signals": rows,
                                             "passed": all(r["passed"] is not False for r in rows)})
    if plots:
        from savant_cli.plots.compare import plot_comparison

        for name, (y, r, units) in traces.items():
            plot_comparison(t, y, r, name, units, out / f"compare_{name}.png")
    table = Table(title=f"{run_dir.name} vs {reference.name}: {t[0]:.1f}–{t[-1]:.1f} s, {t.size} samples")
    for c in ("signal", "max |Δ|", "RMS Δ", "max |Δ| / peak", "result"):
        table.add_column(c, justify="left" if c == "signal" else "right")
    for r in rows:
        result = {True: "pass", False: "[red]FAIL[/red]", "": "–"}[r["passed"]]
        table.add_row(escape(f"{r['signal']} [{r['units']}]"), f"{r['max_abs_difference']:.4g}", f"{r['rms_difference']:.4g}",
                      f"{r['max_relative_difference']:.3g}", result)
    console.print(table)
    console.print(f"outputs: {out}")
    return 0 if all(r["passed"] is not False for r in rows) else 1
