"""A batch's files: the journal streamed into the tables and the decimated histories of
``savant.h5`` (:func:`write_tables`), the ``montecarlo`` group written
(:func:`write_group`, :func:`write_checks`) and read back (:func:`read_tables`), and the
CSV tables (:func:`write_csv`).

Runs are streamed file by file into preallocated tables; the decimated histories go
row by row into HDF5, so memory does not grow with the number of runs beyond the scalar
tables.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from omegaconf import OmegaConf

from savant_cli.config import RequirementSet
from savant_cli.io.atomic import write_text_atomic
from savant_cli.linear.requirements import (
    CHECK_ARRAY_COLUMNS, CRITERIA, DEFAULT_SLOSH_TANKS, STAGES, mode_code, mode_name
)
from savant_cli.montecarlo.analysis import PERCENTILES, Analysis
from savant_cli.montecarlo.batch import AXIS_CODES, BAND_CODES, KIND_CODES, MARGIN_ARRAY_COLUMNS, read_outcome
from savant_cli.montecarlo.inventory import Inventory, ranges_text
from savant_cli.montecarlo.results import N_CHECK, N_MARGIN, Tables
from savant_cli.sim.engine import EVENT_NAMES


def write_tables(h5: h5py.Group | None, inv: Inventory, runs: list[int], history_names: list[str],
                 history_time: np.ndarray) -> Tables:
    """Stream the journal entries of ``runs`` into the scalar tables, and their decimated
    histories into ``h5``.

    Parameters
    ----------
    h5 : h5py.Group or None
        The batch's ``montecarlo`` group; its ``histories`` group is created here
        (``time`` in s, one float32 dataset per signal, a row per run, NaN where a run
        ended early). None: the tables only.
    inv : Inventory
        The batch's journal files.
    runs : list of int
        The run numbers to read, in row order (each one of ``inv.files``).
    history_names : list of str
        The decimated history columns the journal entries carry, in their order.
    history_time : numpy.ndarray
        The histories' common time grid (s).

    Returns
    -------
    Tables
        One row per run of ``runs``.
    """
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
                  np.vstack(checks) if checks else np.zeros((0, N_CHECK)),
                  tuple(inv.manifest.get("slosh_tanks", DEFAULT_SLOSH_TANKS)))


def _strings(items: list[str]) -> np.ndarray:
    return np.array(items, dtype=h5py.string_dtype())


def write_group(g: h5py.Group, tb: Tables, an: Analysis, inv: Inventory, expected: list[int],
                dispersions: list[dict[str, Any]], config_yaml: str, provenance: dict[str, str],
                requirements: RequirementSet | None) -> None:
    """Group ``montecarlo``'s attributes and datasets beside the histories.

    Parameters
    ----------
    g : h5py.Group
        The batch's ``montecarlo`` group.
    tb : Tables
        The batch's scalar tables: datasets ``runs/*`` (``t_final_s``, ``wall_time_s``
        in s), ``events/<event>_s`` (s), ``dispersions/<name>`` (in each dispersion's
        ``units``), ``summary/<key>`` (units in the key's suffix) and ``margins/*`` (gain dB,
        phase deg, frequency Hz; axis, kind, band and mode as names).
    an : Analysis
        What the tables say: the attributes ``mission``, ``reliability``, ``insertion``,
        ``loads`` (JSON) and the ``requirements`` group (:func:`write_checks`).
    inv : Inventory
        The batch's journal (its manifest's ``seed``).
    expected : list of int
        The run numbers the batch should hold.
    dispersions : list of dict
        One row per dispersion, in the column order of ``tb.values``; every key but
        ``name`` becomes an attribute of its dataset.
    config_yaml : str
        The batch's composed configuration (attribute ``config_yaml``).
    provenance : dict of str to str
        Attributes ``provenance_<key>``.
    requirements : RequirementSet or None
        The set the runs' margins were judged against (attribute ``requirements``: band →
        [gain dB, phase deg]).
    """
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
        # lists as JSON; the choices (apply, dist: StrEnum) as plain str, which h5py takes
        ds.attrs.update({k: json.dumps(v) if isinstance(v, (list, tuple)) else str(v) if isinstance(v, str) else v
                         for k, v in d.items() if k != "name"})
    sg = g.create_group("summary", track_order=True)
    for j, k in enumerate(tb.summary_keys):
        sg.create_dataset(k, data=tb.summary[:, j])
    mg = g.create_group("margins")
    if tb.slosh_tanks != DEFAULT_SLOSH_TANKS:  # the tanks the slosh modes' codes name
        mg.attrs["slosh_tanks"] = list(tb.slosh_tanks)
    for j, col in enumerate(("run",) + MARGIN_ARRAY_COLUMNS):
        data = tb.margins[:, j]
        if col in ("axis", "kind", "band"):
            codes = {"axis": AXIS_CODES, "kind": KIND_CODES, "band": BAND_CODES}[col]
            mg.create_dataset(col, data=_strings([codes[int(c)] for c in data]))
        elif col == "mode":
            mg.create_dataset(col, data=_strings([mode_name(int(c), tb.slosh_tanks) for c in data]))
        else:
            mg.create_dataset(col, data=data.astype(int) if col == "run" else data.astype(bool)
                              if col == "meets_requirement" else data)
    write_checks(g.create_group("requirements", track_order=True), tb.checks, an.verdict, requirements,
                 tb.slosh_tanks)


def write_checks(g: h5py.Group, checks: np.ndarray, verdict: dict[str, Any],
                 requirements: RequirementSet | None, slosh_tanks: tuple[str, ...] = DEFAULT_SLOSH_TANKS) -> None:
    """Group ``montecarlo/requirements``: attributes ``set`` (JSON), ``verdict`` (the one
    line), ``passed``; ``checks/<column>`` (every check of every run: ``run`` and
    ``linear/requirements.py::CHECK_ARRAY_COLUMNS``, names for the codes) and
    ``failed_runs/{run, points_failed, worst}``.

    Parameters
    ----------
    g : h5py.Group
        The new group ``montecarlo/requirements``.
    checks : numpy.ndarray
        Every check of every run, (n, 1 + len(CHECK_ARRAY_COLUMNS)): the run, then the
        check's columns (values in their check's unit: dB, deg, 1/s).
    verdict : dict
        The batch's verdict (``montecarlo/analysis.py::requirement_verdicts``).
    requirements : RequirementSet or None
        The set the checks were judged against; None: no ``set`` attribute.
    slosh_tanks : tuple of str
        The tanks the checks' slosh mode codes name.
    """
    if requirements is not None:
        g.attrs["set"] = json.dumps(OmegaConf.to_container(OmegaConf.structured(requirements)))
    g.attrs["verdict"] = verdict["line"]
    g.attrs["passed"] = bool(verdict["passed"])
    cg = g.create_group("checks", track_order=True)
    names = {"axis": lambda c: AXIS_CODES[int(c)] if c >= 0 else "", "mode": lambda c: mode_name(int(c), slosh_tanks),
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
    """The scalar tables of a batch's ``montecarlo`` group (as
    :func:`~savant_cli.montecarlo.outputs.write_outputs` wrote them; margins re-coded)."""
    summary_keys = list(g["summary"])
    runs = g["runs/run"][()]
    m = g["margins"]
    tanks = tuple(str(t) for t in m.attrs.get("slosh_tanks", DEFAULT_SLOSH_TANKS))
    margins = np.zeros((0, N_MARGIN))
    if m["run"].size:
        codes = {col: np.array([names.index(s) for s in m[col].asstr()[()]], dtype=float)
                 for col, names in (("axis", AXIS_CODES), ("kind", KIND_CODES), ("band", BAND_CODES))}
        codes["mode"] = np.array([mode_code(s, tanks) for s in m["mode"].asstr()[()]], dtype=float)
        margins = np.column_stack([m["run"][()]] + [codes[c] if c in codes else m[c][()].astype(float)
                                                    for c in MARGIN_ARRAY_COLUMNS])
    return Tables(runs, list(g["runs/status"].asstr()[()]), list(g["runs/message"].asstr()[()]),
                  g["runs/t_final_s"][()], g["runs/wall_time_s"][()],
                  np.column_stack([ds[()] for ds in g["dispersions"].values()]) if len(g["dispersions"])
                  else np.zeros((runs.size, 0)),
                  summary_keys, np.column_stack([g["summary"][k][()] for k in summary_keys]) if summary_keys
                  else np.zeros((runs.size, 0)),
                  np.column_stack([g["events"][f"{n}_s"][()] if f"{n}_s" in g["events"] else np.full(runs.size, np.nan)
                                   for n in EVENT_NAMES]),  # (a file written before a later event's slot: NaN)
                  margins, [k for k in g["histories"] if k != "time"] if "histories" in g else [])


def write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    """Write ``rows`` as a CSV table, atomically.

    Parameters
    ----------
    path : Path
        The CSV file.
    rows : list of dict
        One dict per row, the first row's keys as the header (units in the keys' names);
        floats written to 10 significant digits. No rows: an empty file.
    """
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    write_text_atomic(path, buf.getvalue())
