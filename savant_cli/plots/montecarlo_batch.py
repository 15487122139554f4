"""A batch's figures: histograms of the summary scalars and the dispersions, envelopes
of the decimated histories (read from ``savant.h5`` one signal at a time) and the
margin spread; drawn when the batch is written and redrawn from ``savant.h5`` alone
(``savant report``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from savant_cli.io.console import split_unit
from savant_cli.montecarlo.batch import AXIS_CODES, BAND_CODES, KIND_CODES
from savant_cli.montecarlo.results import Tables
from savant_cli.montecarlo.storage import read_tables
from savant_cli.plots import montecarlo as mcp


def redraw(out_dir: Path) -> list[Path]:
    """Redraw a batch's plots into ``out_dir/plots`` from its ``savant.h5`` alone
    (:func:`draw_figures`); returns the PNG files written."""
    with h5py.File(out_dir / "savant.h5", "r") as f:
        g = f["montecarlo"]
        tb = read_tables(g)
        dispersions = [{"name": k, "units": str(ds.attrs.get("units", ""))} for k, ds in g["dispersions"].items()]
        requirements = {b: (float(r[0]), float(r[1])) for b, r in json.loads(g.attrs.get("requirements", "{}")).items()}
    return draw_figures(out_dir, tb, dispersions, requirements or None)


def draw_figures(out_dir: Path, tb: Tables, dispersions: list[dict[str, Any]],
                 requirements: dict[str, tuple[float, float]] | None) -> list[Path]:
    """Draw a batch's figures into ``out_dir/plots``.

    Parameters
    ----------
    out_dir : Path
        The batch's folder; its ``savant.h5`` must already hold the histories of
        ``tb.history_names`` (group ``montecarlo/histories``).
    tb : Tables
        The batch's scalar tables.
    dispersions : list of dict
        One row per dispersion, in the column order of ``tb.values``: ``name`` and
        ``units`` (the unit of its histogram's axis; ``"1"`` for a scale factor).
    requirements : dict or None
        Band → (gain margin dB, phase margin deg) marked on the margin-spread plot;
        None: no marks.

    Returns
    -------
    list of Path
        The PNG files written: histograms of the summary scalars (the nominal run's
        value marked) and of the dispersions, an envelope per history signal, and the
        margin spread when the runs have margins.
    """
    folder = out_dir / "plots"
    paths = []
    ok = tb.ok
    nominal_row = np.nonzero(tb.runs == 0)[0]
    values = {k: tb.summary[ok, j] for j, k in enumerate(tb.summary_keys)}
    units = {k: split_unit(k)[1] for k in tb.summary_keys}
    nominal = {k: float(tb.summary[nominal_row[0], j]) for j, k in enumerate(tb.summary_keys)} if nominal_row.size else None
    paths += mcp.plot_histograms(values, folder, units=units, nominal=nominal)
    disp = {d["name"]: tb.values[tb.runs > 0, j] for j, d in enumerate(dispersions)}
    if disp:
        paths += mcp.plot_histograms(disp, folder / "dispersions",
                                     units={d["name"]: d.get("units", "") for d in dispersions})
    if tb.history_names:
        with h5py.File(out_dir / "savant.h5", "r") as f:
            hg = f["montecarlo/histories"]
            t = hg["time"][()]
            for name in tb.history_names:  # one signal in memory at a time
                paths += mcp.plot_envelopes(t, {name: hg[name][()]}, folder, units=None)
    if tb.margins.size:
        m = tb.margins
        table = {"run": m[:, 0].astype(int), "time_s": m[:, 1],
                 "axis": np.array([AXIS_CODES[int(c)] for c in m[:, 2]]),
                 "kind": np.array([KIND_CODES[int(c)] for c in m[:, 3]]),
                 "band": np.array([BAND_CODES[int(c)] for c in m[:, 4]]), "value": m[:, 5], "frequency_hz": m[:, 6]}
        paths.append(mcp.plot_margin_spread(table, folder / "margin_spread.png", requirements=requirements))
    return paths
