"""Writing the linear models of a study (``savant.h5`` group ``linear``, a MATLAB
``.mat`` file, ``margins.csv``) and reloading any point as a python-control system.

HDF5 layout: ``linear/<point>/<system>/{A, B, C, D}`` with attributes ``dt`` (s; 0 for
continuous), ``states``, ``inputs``, ``outputs`` (names), ``time_s``; ``<point>`` is
``t<time in ms>`` (e.g. ``t055000``); systems: ``plant_continuous``, ``plant`` (discrete,
with the gyro dynamics), ``controller``, ``open_pitch`` and ``open_yaw`` (loop at a time,
the other axis closed), ``open_pitch_only`` and ``open_yaw_only`` (other axis open),
``open_mimo`` (2x2), ``closed_loop``. ``linear/margins`` is the margin table (with each
row's ``meets_requirement``), with the band requirements the charts mark as attribute
``requirements`` (JSON: band → [gain dB, phase deg]) and the chart option
``exclusion_zones``; ``linear/requirements`` holds the requirement set and every check of
every point (:func:`write_checks`).

Chart data (:mod:`savant_cli.linear.charts`) of a point, when the study drew or was asked
to keep its charts, sits in ``linear/<point>/charts``: ``loop_<axis>/{f_hz, response,
mag_db, phase_deg}``, ``root_locus_<axis>/{gains, branches, poles, zeros}`` (attribute
``dt``), ``pzmap/{poles, zeros}`` (attribute ``dt``) and ``responses/{time_s, step,
impulse, ramp}`` (attributes ``commands``, ``outputs``). Complex arrays are HDF5
compound (r, i) datasets, which h5py reads back as complex. ``savant report`` redraws the
charts from there.
"""

from __future__ import annotations

import json
from pathlib import Path

import control as ct
import h5py
import numpy as np
from omegaconf import OmegaConf

from savant_cli.config import RequirementSet
from savant_cli.linear.charts import CommandResponses, LoopResponse, PointCharts, PoleZeroMap, RootLocus
from savant_cli.linear.loops import LinearPoint
from savant_cli.linear.margins import MarginRow
from savant_cli.linear.requirements import PointVerdict, verdict_line

_STR = h5py.string_dtype()
MARGIN_COLUMNS = ("time_s", "axis", "kind", "value", "frequency_hz", "band", "mode")
CHECK_COLUMNS = ("time_s", "axis", "mode", "criterion", "value", "required", "unit", "frequency_hz", "passed")


def point_key(time_s: float) -> str:
    return f"t{int(round(time_s * 1000)):06d}"


def point_keys(g: h5py.Group) -> list[str]:
    """The operating points' group names in a ``linear`` group (``margins`` and
    ``requirements`` aside)."""
    return [k for k in g if "time_s" in g[k].attrs and k not in ("margins", "requirements")]


def systems(pt: LinearPoint) -> dict[str, ct.StateSpace]:
    """The systems stored per point, by name."""
    out = {"plant_continuous": pt.plant_continuous, "plant": pt.plant, "controller": pt.controller}
    for axis, sys in pt.loops.items():
        out[f"open_{axis}"] = sys
    for axis, sys in pt.loops_open.items():
        out[f"open_{axis}_only"] = sys
    out["open_mimo"] = pt.mimo
    out["closed_loop"] = pt.closed
    return out


def _names(labels) -> np.ndarray:
    return np.array([str(s) for s in labels], dtype=object)


def write_linear_group(f: h5py.File, points: list[LinearPoint], rows: list[MarginRow],
                       charts: dict[float, PointCharts] | None = None, requirements: RequirementSet | None = None,
                       exclusion_zones: bool = True, verdicts: list[PointVerdict] | None = None,
                       judged: list[bool] | None = None, verdict_text: str | None = None) -> None:
    """Write every point's systems, chart data, the margin table and the requirement
    checks into ``f["linear"]``.

    Parameters
    ----------
    f : h5py.File
        The run file, open for writing.
    points : list of LinearPoint
        The operating points' systems.
    rows : list of MarginRow
        The margin table of all points.
    charts : dict of float to PointCharts, optional
        Chart data by point time (s); points without an entry get no ``charts`` group.
    requirements : RequirementSet, optional
        The requirement set (its band values are what the charts mark).
    exclusion_zones : bool
        Whether the Nichols charts draw the exclusion zones.
    verdicts : list of PointVerdict, optional
        The points' requirement verdicts: group ``linear/requirements``
        (:func:`write_checks`).
    judged : list of bool, optional
        Whether each verdict counts in the study's verdict (False: a point of the
        first-stage tail-off window, reported but not judged); default all.
    verdict_text : str, optional
        The study's verdict line; default the line of the judged verdicts.
    """
    g = f.create_group("linear", track_order=True)
    g.attrs["note"] = "roll (on/off jets) is not part of the linear analysis"
    charts = charts or {}
    for pt in points:
        pg = g.create_group(point_key(pt.time_s), track_order=True)
        pg.attrs["time_s"] = pt.time_s
        pg.attrs["phase"] = pt.phase
        if pt.time_s in charts:
            write_charts(pg.create_group("charts", track_order=True), charts[pt.time_s])
        for name, sys in systems(pt).items():
            sg = pg.create_group(name)
            for m in ("A", "B", "C", "D"):
                sg.create_dataset(m, data=np.asarray(getattr(sys, m), dtype=np.float64))
            sg.attrs["dt"] = 0.0 if sys.dt in (None, 0) else float(sys.dt)
            for attr, labels in (("states", sys.state_labels), ("inputs", sys.input_labels),
                                 ("outputs", sys.output_labels)):
                sg.create_dataset(attr, data=_names(labels), dtype=_STR)
    write_margin_table(g.create_group("margins"), rows, requirements, exclusion_zones)
    if verdicts is not None:
        write_checks(g.create_group("requirements", track_order=True), verdicts, requirements, judged, verdict_text)


def write_margin_table(mg: h5py.Group, rows: list[MarginRow], requirements: RequirementSet | None,
                       exclusion_zones: bool) -> None:
    """The margin rows (:data:`MARGIN_COLUMNS`, and ``meets_requirement`` when the rows
    were judged) into ``mg``, with the attributes ``requirements`` (JSON: band → [gain dB,
    phase deg], what the charts mark) and ``exclusion_zones``."""
    mg.attrs["exclusion_zones"] = bool(exclusion_zones)
    bands = requirements.by_band() if requirements is not None else {}
    mg.attrs["requirements"] = json.dumps({band: list(req) for band, req in bands.items()})
    for col in MARGIN_COLUMNS:
        vals = [getattr(r, col) for r in rows]
        if col in ("axis", "kind", "band", "mode"):
            mg.create_dataset(col, data=_names(vals), dtype=_STR)
        else:
            mg.create_dataset(col, data=np.asarray(vals, dtype=np.float64))
    if rows and all(r.meets_requirement is not None for r in rows):
        mg.create_dataset("meets_requirement", data=np.array([r.meets_requirement for r in rows], bool))


def write_checks(g: h5py.Group, verdicts: list[PointVerdict], requirements: RequirementSet | None,
                 judged: list[bool] | None = None, verdict_text: str | None = None) -> None:
    """The requirement verdicts into ``g``: attributes ``set`` (the requirement set as
    JSON), ``verdict`` (the one-line verdict, ``verdict_text`` when given) and ``passed``
    (every judged point passes); ``points/{time_s, stage, passed, judged}`` and
    ``checks/<column>`` (:data:`CHECK_COLUMNS`, every check of every point, judged or not).
    ``judged``: whether each point counts in the verdict (default all)."""
    judged = [True] * len(verdicts) if judged is None else list(judged)
    counted = [v for v, j in zip(verdicts, judged) if j]
    if requirements is not None:
        g.attrs["set"] = json.dumps(OmegaConf.to_container(OmegaConf.structured(requirements)))
        g.attrs["verdict"] = verdict_text or verdict_line([("", [v]) for v in counted], requirements.name)
    g.attrs["passed"] = all(v.passed for v in counted)
    pg = g.create_group("points", track_order=True)
    pg.create_dataset("time_s", data=np.array([v.time_s for v in verdicts], float))
    pg.create_dataset("stage", data=_names([v.stage for v in verdicts]), dtype=_STR)
    pg.create_dataset("passed", data=np.array([v.passed for v in verdicts], bool))
    pg.create_dataset("judged", data=np.array(judged, bool))
    checks = [c for v in verdicts for c in v.checks]
    cg = g.create_group("checks", track_order=True)
    for col in CHECK_COLUMNS:
        vals = [getattr(c, col) for c in checks]
        if col in ("axis", "mode", "criterion", "unit"):
            cg.create_dataset(col, data=_names(vals), dtype=_STR)
        else:
            cg.create_dataset(col, data=np.asarray(vals, dtype=bool if col == "passed" else np.float64))


def write_checks_csv(path: Path, verdicts: list[PointVerdict]) -> None:
    """``requirements.csv``: every requirement check of every point
    (:data:`CHECK_COLUMNS`, with the point's stage; ``passed`` yes/no)."""
    from savant_cli.io.atomic import write_text_atomic

    lines = [",".join(("stage",) + CHECK_COLUMNS)]
    for v in verdicts:
        for c in v.checks:
            lines.append(f"{v.stage},{c.time_s:.3f},{c.axis},{c.mode},{c.criterion},{c.value:.6g},{c.required:g},"
                         f"{c.unit},{c.frequency_hz:.9g},{'yes' if c.passed else 'no'}")
    write_text_atomic(path, "\n".join(lines) + "\n")


def write_loop_response(g: h5py.Group, lp: LoopResponse) -> None:
    """One loop's frequency response into group ``g`` (attribute ``label``)."""
    g.attrs["label"] = lp.label
    for name in ("f_hz", "response", "mag_db", "phase_deg"):
        g.create_dataset(name, data=getattr(lp, name))


def read_loop_response(g: h5py.Group) -> LoopResponse:
    """The frequency response written by :func:`write_loop_response`."""
    return LoopResponse(str(g.attrs["label"]), *(g[n][()] for n in ("f_hz", "response", "mag_db", "phase_deg")))


def write_charts(g: h5py.Group, charts: PointCharts) -> None:
    """Write one point's chart data into group ``g`` (layout in the module notes)."""
    g.attrs["time_s"] = charts.time_s
    for lp in charts.loops:
        write_loop_response(g.create_group(f"loop_{lp.label}"), lp)
    for rl in charts.root_loci:
        rg = g.create_group(f"root_locus_{rl.label}")
        rg.attrs["dt"] = 0.0 if rl.dt is None else rl.dt
        for name in ("gains", "branches", "poles", "zeros"):
            rg.create_dataset(name, data=getattr(rl, name))
    pz = g.create_group("pzmap")
    pz.attrs["dt"] = 0.0 if charts.pzmap.dt is None else charts.pzmap.dt
    pz.create_dataset("poles", data=charts.pzmap.poles)
    pz.create_dataset("zeros", data=charts.pzmap.zeros)
    rs = charts.responses
    tg = g.create_group("responses")
    tg.attrs["commands"] = list(rs.commands)
    tg.attrs["outputs"] = list(rs.outputs)
    for name in ("time_s", "step", "impulse", "ramp"):
        tg.create_dataset(name, data=getattr(rs, name))


def _strs(values) -> tuple[str, ...]:
    return tuple(v.decode() if isinstance(v, bytes) else str(v) for v in values)


def _dt(attr: float) -> float | None:
    return float(attr) if attr > 0 else None


def read_charts(g: h5py.Group) -> PointCharts:
    """The chart data written by :func:`write_charts`."""
    labels = [k.removeprefix("loop_") for k in g if k.startswith("loop_")]
    loops = tuple(read_loop_response(g[f"loop_{a}"]) for a in labels)
    loci = tuple(RootLocus(a, *(g[f"root_locus_{a}/{n}"][()] for n in ("gains", "branches", "poles", "zeros")),
                           _dt(g[f"root_locus_{a}"].attrs["dt"])) for a in labels)
    pz = PoleZeroMap(g["pzmap/poles"][()], g["pzmap/zeros"][()], _dt(g["pzmap"].attrs["dt"]))
    tg = g["responses"]
    rs = CommandResponses(tg["time_s"][()], _strs(tg.attrs["commands"]), _strs(tg.attrs["outputs"]),
                          tg["step"][()], tg["impulse"][()], tg["ramp"][()])
    return PointCharts(float(g.attrs["time_s"]), loops, loci, pz, rs)


def read_margins(g: h5py.Group) -> tuple[list[MarginRow], dict[str, tuple[float, float]], bool]:
    """The margin table of a ``linear`` (or flex-sweep case) group, its requirement set
    (band → gain dB, phase deg) and its ``exclusion_zones`` option."""
    mg = g["margins"]
    names = [c for c in MARGIN_COLUMNS if c in mg]  # files before issue 12 have no mode
    cols = {c: (mg[c].asstr()[()] if c in ("axis", "kind", "band", "mode") else mg[c][()]) for c in names}
    n = len(cols["time_s"])
    modes = cols.get("mode", [""] * n)
    meets = [bool(ok) for ok in mg["meets_requirement"][()]] if "meets_requirement" in mg else [None] * n
    rows = [MarginRow(float(t), str(a), str(k), float(v), float(fz), str(b), str(m), ok)
            for t, a, k, v, fz, b, m, ok in zip(cols["time_s"], cols["axis"], cols["kind"], cols["value"],
                                                cols["frequency_hz"], cols["band"], modes, meets)]
    req = {band: (float(v[0]), float(v[1])) for band, v in json.loads(mg.attrs.get("requirements", "{}")).items()}
    return rows, req, bool(mg.attrs.get("exclusion_zones", True))


def point_verdicts(g: h5py.Group) -> dict[float, tuple[bool, bool]]:
    """Each point's requirement verdict in a ``linear`` group, time (s) → (passed,
    judged); empty without a requirement set (files before issue 13: all judged)."""
    if "requirements/points" not in g:
        return {}
    pts = g["requirements/points"]
    judged = pts["judged"][()] if "judged" in pts else np.ones(pts["passed"].shape, bool)
    return {float(t): (bool(ok), bool(j)) for t, ok, j in zip(pts["time_s"][()], pts["passed"][()], judged)}


def read_linear_group(path: Path | str) -> tuple[list[PointCharts], list[MarginRow], dict[str, tuple[float, float]],
                                                 bool, list[float]]:
    """What ``savant report`` draws of a linear study: the chart data of every point that
    has it (in time order), the margin table, the requirements, ``exclusion_zones`` and
    the times of the judged points that fail their requirement set."""
    with h5py.File(path, "r") as f:
        g = f["linear"]
        charts = [read_charts(g[k]["charts"]) for k in point_keys(g) if "charts" in g[k]]
        rows, req, zones = read_margins(g)
        failed = [t for t, (ok, judged) in point_verdicts(g).items() if judged and not ok]
    return sorted(charts, key=lambda c: c.time_s), rows, req, zones, failed


def load_point(path: Path | str, time_s: float, system: str = "open_pitch") -> ct.StateSpace:
    """Reload one stored linear system as a python-control ``StateSpace``.

    Parameters
    ----------
    path : path of a ``study=linear`` run's ``savant.h5``.
    time_s : flight time of the point (s), as requested in ``study.times``.
    system : one of the names of :func:`systems` (``open_pitch``, ``closed_loop`` ...).
    """
    with h5py.File(path, "r") as f:
        g = f["linear"]
        key = point_key(time_s)
        if key not in g:
            have = sorted(float(g[k].attrs["time_s"]) for k in point_keys(g))
            raise KeyError(f"no linear point at t = {time_s} s; stored: {have}")
        return read_system(g[key], system)


def read_system(pg: h5py.Group, system: str) -> ct.StateSpace:
    """One stored system of a point's group as a python-control ``StateSpace`` (named
    ``<system>_<point key>``, with its state, input and output labels)."""
    sg = pg[system]
    dt = float(sg.attrs["dt"])
    return ct.ss(sg["A"][()], sg["B"][()], sg["C"][()], sg["D"][()], dt if dt > 0 else 0,
                 states=list(_strs(sg["states"][()])) or None, inputs=list(_strs(sg["inputs"][()])),
                 outputs=list(_strs(sg["outputs"][()])),
                 name=f"{system}_{point_key(float(pg.attrs['time_s']))}")


def system_names(pg: h5py.Group) -> list[str]:
    """The names of the systems stored in a point's group (:func:`systems`)."""
    return [k for k in pg if isinstance(pg[k], h5py.Group) and "A" in pg[k]]


def write_mat(path: Path, points: list[LinearPoint]) -> None:
    """MATLAB file: one struct per point (``t055000``) holding each system's A, B, C, D,
    Ts and name lists (``ss(A, B, C, D, Ts)`` in MATLAB)."""
    from scipy.io import savemat

    from savant_cli.io.atomic import atomic_path

    data = {}
    for pt in points:
        entry = {"time_s": pt.time_s}
        for name, sys in systems(pt).items():
            entry[name] = {"A": sys.A, "B": sys.B, "C": sys.C, "D": sys.D,
                           "Ts": 0.0 if sys.dt in (None, 0) else float(sys.dt),
                           "StateName": np.array(sys.state_labels, dtype=object),
                           "InputName": np.array(sys.input_labels, dtype=object),
                           "OutputName": np.array(sys.output_labels, dtype=object)}
        data[point_key(pt.time_s)] = entry
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            savemat(fh, data, do_compression=True)


def write_margins_csv(path: Path, rows: list[MarginRow]) -> None:
    """``margins.csv``: one row per crossing (:data:`MARGIN_COLUMNS`), plus the column
    ``meets_requirement`` (yes/no) when the rows were judged."""
    from savant_cli.io.atomic import write_text_atomic

    judged = bool(rows) and all(r.meets_requirement is not None for r in rows)
    header = list(MARGIN_COLUMNS) + (["meets_requirement"] if judged else [])
    lines = [",".join(header)]  # value: gain margin in dB or phase margin in deg
    for r in rows:  # frequencies to 1e-8 relative: a crossing on a 1e-4-damped resonance
        line = f"{r.time_s:.3f},{r.axis},{r.kind},{r.value:.4f},{r.frequency_hz:.9g},{r.band},{r.mode}"
        if judged:
            line += ",yes" if r.meets_requirement else ",no"
        lines.append(line)
    write_text_atomic(path, "\n".join(lines) + "\n")
