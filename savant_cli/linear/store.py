"""Writing the linear models of a study (``savant.h5`` group ``linear``, a MATLAB
``.mat`` file, ``margins.csv``) and reloading any point as a python-control system.

HDF5 layout: ``linear/<point>/<system>/{A, B, C, D}`` with attributes ``dt`` (s; 0 for
continuous), ``states``, ``inputs``, ``outputs`` (names), ``time_s``; ``<point>`` is
``t<time in ms>`` (e.g. ``t055000``); systems: ``plant_continuous``, ``plant`` (discrete,
with the gyro dynamics), ``controller``, ``open_pitch`` and ``open_yaw`` (loop at a time,
the other axis closed), ``open_pitch_only`` and ``open_yaw_only`` (other axis open),
``open_mimo`` (2x2), ``closed_loop``. ``linear/margins`` is the margin table.
"""

from __future__ import annotations

from pathlib import Path

import control as ct
import h5py
import numpy as np

from savant_cli.linear.loops import LinearPoint
from savant_cli.linear.margins import MarginRow

_STR = h5py.string_dtype()
MARGIN_COLUMNS = ("time_s", "axis", "kind", "value", "frequency_hz", "band")


def point_key(time_s: float) -> str:
    return f"t{int(round(time_s * 1000)):06d}"


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


def write_linear_group(f: h5py.File, points: list[LinearPoint], rows: list[MarginRow]) -> None:
    """Write every point's systems and the margin table into ``f["linear"]``."""
    g = f.create_group("linear", track_order=True)
    g.attrs["note"] = "roll (on/off jets) is not part of the linear analysis"
    for pt in points:
        pg = g.create_group(point_key(pt.time_s), track_order=True)
        pg.attrs["time_s"] = pt.time_s
        pg.attrs["phase"] = pt.phase
        for name, sys in systems(pt).items():
            sg = pg.create_group(name)
            for m in ("A", "B", "C", "D"):
                sg.create_dataset(m, data=np.asarray(getattr(sys, m), dtype=np.float64))
            sg.attrs["dt"] = 0.0 if sys.dt in (None, 0) else float(sys.dt)
            for attr, labels in (("states", sys.state_labels), ("inputs", sys.input_labels),
                                 ("outputs", sys.output_labels)):
                sg.create_dataset(attr, data=_names(labels), dtype=_STR)
    mg = g.create_group("margins")
    for col in MARGIN_COLUMNS:
        vals = [getattr(r, col) for r in rows]
        if col in ("axis", "kind", "band"):
            mg.create_dataset(col, data=_names(vals), dtype=_STR)
        else:
            mg.create_dataset(col, data=np.asarray(vals, dtype=np.float64))


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
            have = sorted(float(g[k].attrs["time_s"]) for k in g if k != "margins")
            raise KeyError(f"no linear point at t = {time_s} s; stored: {have}")
        sg = g[key][system]
        dec = lambda ds: [s.decode() if isinstance(s, bytes) else str(s) for s in ds[()]]  # noqa: E731
        dt = float(sg.attrs["dt"])
        return ct.ss(sg["A"][()], sg["B"][()], sg["C"][()], sg["D"][()], dt if dt > 0 else 0,
                     states=dec(sg["states"]) or None, inputs=dec(sg["inputs"]), outputs=dec(sg["outputs"]),
                     name=f"{system}_{key}")


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
    from savant_cli.io.atomic import write_text_atomic

    lines = [",".join(MARGIN_COLUMNS)]  # value: gain margin in dB or phase margin in deg
    for r in rows:
        lines.append(f"{r.time_s:.3f},{r.axis},{r.kind},{r.value:.4f},{r.frequency_hz:.5f},{r.band}")
    write_text_atomic(path, "\n".join(lines) + "\n")
