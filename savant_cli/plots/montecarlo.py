"""Figures of a Monte Carlo dispersion study: histograms of scalar results, envelopes of
time histories and the spread of the stability margins over the runs.

Figures are drawn with matplotlib's object-oriented API on the Agg canvas
(``matplotlib.figure.Figure`` + ``FigureCanvasAgg``): no pyplot, no GUI backend, no
global state. Each figure is made and written through the drawing base
(:mod:`savant_cli.plots.figure`: a 120-dpi PNG, written atomically) and cleared once written.

Files (in the folder given):

- ``histograms_01.png``, ``histograms_02.png``, …: one small histogram per scalar result,
  ``per_page`` per page (:func:`plot_histograms`);
- ``envelope_<name>.png``: the runs of one time history with their min/max envelope,
  0.135–99.865 percentile band, median and nominal run (:func:`plot_envelopes`);
- ``margin_spread.png``: gain and phase margins of every run vs linearization time, per
  axis and frequency band (:func:`plot_margin_spread`).

Conventions
-----------
Run 0 is the nominal (undispersed) run. NaN marks a missing value (a failed run, or the
samples after a run ended) and is ignored by every statistic. The dashed percentile lines
and the shaded band are the 0.135 and 99.865 percentiles (±3σ of a normal distribution),
:data:`P_LOW` and :data:`P_HIGH`, with numpy's default (linear) interpolation.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from savant_cli.plots.figure import bin_count, file_stem, new_figure, save_figure, style_axes

__all__ = ["P_HIGH", "P_LOW", "plot_envelopes", "plot_histograms", "plot_margin_spread", "plot_montecarlo"]

#: Lower and upper percentiles (%) of the dispersion lines and bands (±3σ of a normal law).
P_LOW, P_HIGH = 0.135, 99.865
#: Columns of the histogram grid.
HIST_COLUMNS = 4
#: Most samples per individual run line of an envelope figure (longer runs are strided;
#: the envelope, band, median and nominal lines are never strided).
MAX_RUN_POINTS = 2000

_AXES = ("pitch", "yaw")
_KINDS = (("gain", "gain margin (dB)\nnegative: gain reduction"), ("phase", "phase margin (deg)"))
_BAND_COLORS = {"rigid/aero": "C0", "slosh": "C2", "flex": "C3"}
_MARGIN_COLUMNS = ("run", "time_s", "axis", "kind", "band", "value")
_NOMINAL_COLOR = "C3"


# --------------------------------------------------------------------------- helpers


def _label(name: str, units: Mapping[str, str] | None) -> str:
    """``name [unit]``, or ``name`` alone when the unit is unknown or empty."""
    unit = (units or {}).get(name, "")
    return f"{name} [{unit}]" if unit else name


# --------------------------------------------------------------------------- histograms


def _histogram_panel(ax, name: str, values: np.ndarray, units: Mapping[str, str] | None,
                     nominal: float | None) -> None:
    x = np.asarray(values, dtype=np.float64).ravel()
    x = x[np.isfinite(x)]
    ax.set_title(_label(name, units), fontsize=8, pad=3.0)
    style_axes(ax, 4, 4)
    if x.size:
        lo, hi = float(x.min()), float(x.max())
        half = 0.0 if hi > lo else 0.01 * abs(lo) if lo != 0.0 else 0.5  # no spread: one bar 2 % wide
        counts, edges = np.histogram(x, bins=bin_count(x), range=(lo - half, hi + half))
        ax.stairs(counts, edges, fill=True, color="C0", alpha=0.75, gid="histogram")  # one artist: fast
        if x.size >= 2:
            for p in np.percentile(x, [P_LOW, P_HIGH]):
                ax.axvline(float(p), color="0.25", lw=0.9, ls="--", gid="percentile")
    if nominal is not None and np.isfinite(nominal):
        ax.axvline(float(nominal), color=_NOMINAL_COLOR, lw=1.4, gid="nominal")
    if not x.size:
        ax.text(0.5, 0.5, "no finite values", transform=ax.transAxes, ha="center", va="center", fontsize=8,
                color="0.4")
        return
    sigma = f"{np.std(x, ddof=1):.3g}" if x.size >= 2 else "–"
    ax.text(0.97, 0.95, f"mean {np.mean(x):.4g}\nσ {sigma}\nN {x.size}", transform=ax.transAxes, ha="right",
            va="top", fontsize=6.5, bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "none", "pad": 1.0})


def _histogram_page(names: list[str], values: Mapping[str, np.ndarray], units: Mapping[str, str] | None,
                    nominal: Mapping[str, float] | None, page: int, pages: int, ncols: int = HIST_COLUMNS) -> Figure:
    """One page of ``ncols`` columns (every page of a set as wide), as many rows as needed."""
    ncols = max(1, min(ncols, len(names)))
    nrows = -(-len(names) // ncols)
    width, height = max(2.4 * ncols + 0.3, 5.0), 2.0 * nrows + 0.95
    fig = new_figure(width, height, left=0.45, right=0.15, bottom=0.6, top=0.4, wspace=0.3, hspace=0.45)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax, name in zip(axes, names):
        _histogram_panel(ax, name, values[name], units, (nominal or {}).get(name))
    for ax in axes[len(names):]:
        ax.remove()
    handles = [Line2D([], [], color=_NOMINAL_COLOR, lw=1.4, label="nominal (run 0)"),
               Line2D([], [], color="0.25", lw=0.9, ls="--", label=f"{P_LOW:g} / {P_HIGH:g} percentiles")]
    fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle(f"Monte Carlo dispersions ({page}/{pages})", fontsize=11, y=1.0 - 0.08 / height, va="top")
    return fig


def plot_histograms(values: dict[str, np.ndarray], folder: Path, *, units: dict[str, str] | None = None,
                    nominal: dict[str, float] | None = None, per_page: int = 12) -> list[Path]:
    """Draw one histogram per scalar result, ``per_page`` per PNG.

    Parameters
    ----------
    values : dict of str to numpy.ndarray
        Name → 1-D array of the result over the runs, in the unit of ``units[name]``
        (NaN entries are ignored).
    folder : pathlib.Path
        Folder for ``histograms_01.png``, ``histograms_02.png``, … (created if missing).
    units : dict of str to str, optional
        Name → unit, shown in the panel titles as ``name [unit]``.
    nominal : dict of str to float, optional
        Name → value of the nominal run (run 0), drawn as a solid vertical line.
    per_page : int, optional
        Panels per page (12: a 4 × 3 grid).

    Returns
    -------
    list of pathlib.Path
        The pages written, ``ceil(len(values) / per_page)`` of them.

    Raises
    ------
    ValueError
        If ``per_page`` is less than 1.

    Notes
    -----
    Each panel shows the histogram (numpy's ``'auto'`` bin count, at most
    :data:`savant_cli.plots.figure.MAX_BINS`), dashed lines at the :data:`P_LOW` and :data:`P_HIGH` percentiles,
    and the mean, sample standard deviation σ (``ddof=1``) and number N of finite values.
    A result with one finite value or no spread is one bar; with none, the panel says so.
    """
    if per_page < 1:
        raise ValueError(f"per_page must be at least 1, got {per_page}")
    names = list(values)
    pages = -(-len(names) // per_page)
    written = []
    ncols = min(HIST_COLUMNS, per_page)
    for k in range(pages):
        fig = _histogram_page(names[k * per_page:(k + 1) * per_page], values, units, nominal, k + 1, pages, ncols)
        written.append(save_figure(fig, Path(folder) / f"histograms_{k + 1:02d}.png"))
    return written


# --------------------------------------------------------------------------- envelopes


@dataclass(frozen=True)
class _Envelope:
    """Statistics over the runs at each time sample (arrays of shape (n_t,)); NaN where
    too few runs have data (1 for count, minimum, maximum, median; 2 for low, high)."""

    count: np.ndarray  # runs with a finite value
    minimum: np.ndarray
    maximum: np.ndarray
    low: np.ndarray  # P_LOW percentile
    median: np.ndarray
    high: np.ndarray  # P_HIGH percentile


def _envelope_stats(runs: np.ndarray) -> _Envelope:
    """Nan-aware envelope statistics of ``runs`` (n_runs, n_t) along the runs."""
    data = np.atleast_2d(np.asarray(runs, dtype=np.float64))
    finite = np.isfinite(data)
    data = np.where(finite, data, np.nan)
    count = finite.sum(axis=0)
    stats = {key: np.full(data.shape[1], np.nan) for key in ("minimum", "maximum", "low", "median", "high")}
    one, two = count >= 1, count >= 2
    if one.any():
        stats["minimum"][one] = np.nanmin(data[:, one], axis=0)
        stats["maximum"][one] = np.nanmax(data[:, one], axis=0)
        stats["median"][one] = np.nanmedian(data[:, one], axis=0)
    if two.any():
        stats["low"][two], stats["high"][two] = np.nanpercentile(data[:, two], [P_LOW, P_HIGH], axis=0)
    return _Envelope(count=count, **stats)


def _run_rows(n_runs: int, max_lines: int) -> np.ndarray:
    """At most ``max_lines`` run indices evenly spread over ``range(n_runs)``."""
    if max_lines <= 0 or n_runs == 0:
        return np.zeros(0, dtype=int)
    if n_runs <= max_lines:
        return np.arange(n_runs)
    return np.unique(np.round(np.linspace(0.0, n_runs - 1, max_lines)).astype(int))


def _envelope_figure(time_s: np.ndarray, runs: np.ndarray, name: str, units: Mapping[str, str] | None,
                     max_lines: int) -> Figure:
    t = np.asarray(time_s, dtype=np.float64)
    data = np.atleast_2d(np.asarray(runs, dtype=np.float64))
    if t.ndim != 1 or data.ndim != 2 or data.shape[1] != t.size:
        raise ValueError(f"history {name!r}: shape {np.shape(runs)} does not match time_s of shape {t.shape} "
                         "(expected (n_runs, n_t))")
    env = _envelope_stats(data)
    fig = new_figure(9.0, 4.6, left=0.85, right=2.3, bottom=0.6, top=0.45)
    ax = fig.subplots()
    rows = _run_rows(data.shape[0], max_lines)
    if rows.size:  # all runs as one line, separated by NaN (fast to draw, gaps respected)
        step = max(1, -(-t.size // MAX_RUN_POINTS))
        tt, yy = t[::step], data[rows, ::step]
        x = np.hstack([np.broadcast_to(tt, yy.shape), np.full((rows.size, 1), np.nan)]).ravel()
        y = np.hstack([yy, np.full((rows.size, 1), np.nan)]).ravel()
        ax.plot(x, y, color="0.65", lw=0.4, alpha=0.5, gid="runs", label=f"runs ({rows.size} of {data.shape[0]})")
    ax.fill_between(t, env.low, env.high, color="C0", alpha=0.25, lw=0, gid="band",
                    label=f"{P_LOW:g}–{P_HIGH:g} percentiles")
    ax.plot(t, env.minimum, color="C0", lw=0.9, ls="--", gid="minimum", label="min / max")
    ax.plot(t, env.maximum, color="C0", lw=0.9, ls="--", gid="maximum")
    ax.plot(t, env.median, color="C0", lw=1.3, gid="median", label="median")
    ax.plot(t, data[0], color=_NOMINAL_COLOR, lw=1.6, gid="nominal", label="nominal (run 0)")
    if not env.count.any():
        ax.text(0.5, 0.5, "no data", transform=ax.transAxes, ha="center", va="center", fontsize=10, color="0.4")
    if t.size and t[-1] > t[0]:
        ax.set_xlim(float(t[0]), float(t[-1]))
    ax.set_xlabel("time (s)", fontsize=9)
    ax.set_ylabel(_label(name, units), fontsize=9)
    style_axes(ax)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False, borderaxespad=0.0)
    fig.suptitle(f"Monte Carlo envelope: {name}", fontsize=11, y=1.0 - 0.08 / 4.6, va="top")
    return fig


def plot_envelopes(time_s: np.ndarray, histories: dict[str, np.ndarray], folder: Path, *,
                   units: dict[str, str] | None = None, max_lines: int = 200) -> list[Path]:
    """Draw the time histories of all runs of each signal with their dispersion envelope.

    Parameters
    ----------
    time_s : numpy.ndarray
        Common time grid, shape (n_t,), in s.
    histories : dict of str to numpy.ndarray
        Signal name → values, shape (n_runs, n_t), in the unit of ``units[name]``. Row 0 is
        the nominal run; NaN after a run ended and for missing samples.
    folder : pathlib.Path
        Folder for the ``envelope_<name>.png`` files (created if missing); characters of the
        name other than letters, digits, ``.``, ``_`` and ``-`` become ``_``.
    units : dict of str to str, optional
        Signal name → unit, shown in the y label as ``name [unit]``.
    max_lines : int, optional
        Most individual runs drawn (thin grey lines), chosen evenly over the runs.

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of ``histories``.

    Raises
    ------
    ValueError
        If a history's shape is not (n_runs, n_t).

    Notes
    -----
    At each time sample: the min/max envelope (dashed) and the median over the runs with
    data, the :data:`P_LOW`–:data:`P_HIGH` percentile band where at least 2 runs have data,
    and the nominal run in red. Statistics ignore NaN. Individual run lines longer than
    :data:`MAX_RUN_POINTS` samples are strided; the statistics are not.
    """
    written = []
    for name, runs in histories.items():
        fig = _envelope_figure(time_s, runs, name, units, max_lines)
        written.append(save_figure(fig, Path(folder) / f"envelope_{file_stem(name)}.png"))
    return written


# --------------------------------------------------------------------------- margins


def _margin_table(margins: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The columns of the margin table as arrays, rows with a non-finite value removed."""
    missing = [c for c in _MARGIN_COLUMNS if c not in margins]
    if missing:
        raise ValueError(f"margin table lacks column(s) {missing}")
    lengths = {len(np.asarray(margins[c]).reshape(-1)) for c in _MARGIN_COLUMNS}
    if len(lengths) > 1:
        raise ValueError(f"margin table columns have different lengths {sorted(lengths)}")
    table = {c: np.asarray(margins[c]).reshape(-1) for c in _MARGIN_COLUMNS}
    table["time_s"] = table["time_s"].astype(np.float64)
    table["value"] = table["value"].astype(np.float64)
    for c in ("axis", "kind", "band"):
        table[c] = table[c].astype(str)
    keep = np.isfinite(table["value"]) & np.isfinite(table["time_s"])
    return {c: v[keep] for c, v in table.items()}


def _requirement_lines(axes: np.ndarray, requirements: Mapping[str, tuple[float, float]]) -> list[Line2D]:
    """Lines at ±gain (gain row) and +phase (phase row), one style per distinct pair."""
    groups: dict[tuple[float, float], list[str]] = {}
    for band, req in requirements.items():
        groups.setdefault((float(req[0]), float(req[1])), []).append(band)
    handles = []
    for k, ((g, p), names) in enumerate(groups.items()):
        color = "0.15" if len(groups) == 1 else _BAND_COLORS.get(names[0], f"C{4 + k}")
        ls = ("--", "-.", ":", (0, (5, 1, 1, 1)))[k % 4]
        for ax in axes[0]:
            ax.axhline(g, color=color, lw=1.0, ls=ls, gid="requirement")
            ax.axhline(-g, color=color, lw=1.0, ls=ls, gid="requirement")
        for ax in axes[1]:
            ax.axhline(p, color=color, lw=1.0, ls=ls, gid="requirement")
        who = "all bands" if len(groups) == 1 and len(names) > 1 else ", ".join(names)
        handles.append(Line2D([], [], color=color, lw=1.0, ls=ls, label=f"requirement ({who}):\n±{g:g} dB, {p:g}°"))
    return handles


def _margin_figure(margins: Mapping[str, np.ndarray],
                   requirements: Mapping[str, tuple[float, float]] | None) -> Figure:
    """Gain (top) and phase (bottom) margins vs time, pitch (left) and yaw (right)."""
    tab = _margin_table(margins)
    fig = new_figure(11.0, 7.0, left=0.95, right=2.3, bottom=0.6, top=0.6, wspace=0.08, hspace=0.1)
    axes = fig.subplots(2, 2, sharex=True, sharey="row", squeeze=False)
    bands = [b for b in _BAND_COLORS if b in tab["band"]] + sorted(set(tab["band"]) - set(_BAND_COLORS))
    times = np.unique(tab["time_s"])
    step = float(np.min(np.diff(times))) if times.size > 1 else 1.0
    slot = 0.7 * step / max(len(bands), 1)  # width of one band's column at a time
    rng = np.random.default_rng(0)  # jitter: the same picture every time
    handles: list[Line2D] = []
    for b, band in enumerate(bands):
        color = _BAND_COLORS.get(band, f"C{4 + b}")
        offset = (b - 0.5 * (len(bands) - 1)) * slot
        for r, (kind, _) in enumerate(_KINDS):
            for c, axis in enumerate(_AXES):
                sel = (tab["kind"] == kind) & (tab["axis"] == axis) & (tab["band"] == band)
                if not sel.any():
                    continue
                ax, t, v, run = axes[r, c], tab["time_s"][sel], tab["value"][sel], tab["run"][sel]
                # one bar per time; gain margins split by sign (gain reduction / increase)
                sign = (v < 0.0) if kind == "gain" else np.zeros(v.size, dtype=bool)
                keys, inv = np.unique(np.column_stack([t, sign]), axis=0, return_inverse=True)
                inv = inv.reshape(-1)
                lo, hi = np.full(len(keys), np.inf), np.full(len(keys), -np.inf)
                np.minimum.at(lo, inv, v)
                np.maximum.at(hi, inv, v)
                ax.vlines(keys[:, 0] + offset, lo, hi, color=color, lw=3.0, alpha=0.35, gid=f"range/{band}")
                x = t + offset + rng.uniform(-0.3, 0.3, t.size) * slot
                ax.scatter(x, v, s=7, color=color, alpha=0.6, lw=0, zorder=3, gid=f"points/{band}")
                nom = run == 0
                if nom.any():
                    ax.scatter(t[nom] + offset, v[nom], s=36, marker="D", color=color, edgecolors="k",
                               linewidths=1.0, zorder=4, gid=f"nominal/{band}")
        handles.append(Line2D([], [], ls="none", marker="o", color=color, label=band))
    handles.append(Line2D([], [], ls="none", marker="D", mfc="white", mec="k", mew=1.0, label="nominal (run 0)"))
    handles.append(Line2D([], [], color="0.5", lw=3.0, alpha=0.5, label="min–max over runs"))
    handles += _requirement_lines(axes, dict(requirements or {}))
    for r, (kind, ylabel) in enumerate(_KINDS):
        axes[r, 0].set_ylabel(ylabel, fontsize=9)
        for c, axis in enumerate(_AXES):
            ax = axes[r, c]
            ax.axhline(0.0, color="0.3", lw=0.6)
            style_axes(ax)
            if r == 0:
                ax.set_title(axis, fontsize=10, pad=3.0)
            else:
                ax.set_xlabel("flight time (s)", fontsize=9)
            if not ((tab["kind"] == kind) & (tab["axis"] == axis)).any():
                ax.text(0.5, 0.5, "no crossings", transform=ax.transAxes, ha="center", va="center",
                        fontsize=10, color="0.4")
    fig.legend(handles=handles, loc="center right", fontsize=8, frameon=False)
    n_runs = np.unique(tab["run"]).size
    fig.suptitle(f"Stability margins over {n_runs} Monte Carlo run(s)", fontsize=11, y=1.0 - 0.1 / 7.0, va="top")
    return fig


def plot_margin_spread(margins: dict[str, np.ndarray], out_path: Path, *,
                       requirements: dict[str, tuple[float, float]] | None = None) -> Path:
    """Draw the spread over the runs of the stability margins at each linearization time.

    Parameters
    ----------
    margins : dict of str to numpy.ndarray
        Column table, equal-length arrays: ``run`` (int, 0 = nominal), ``time_s`` (float,
        s), ``axis`` (``"pitch"``/``"yaw"``), ``kind`` (``"gain"``/``"phase"``), ``band``
        (``"rigid/aero"``, ``"slosh"``, ``"flex"``), ``value`` (gain margin in dB, negative
        for the low-frequency aerodynamic gain-reduction margin, or phase margin in deg)
        and ``frequency_hz`` (Hz, not drawn). Rows with a non-finite value are left out.
    out_path : pathlib.Path
        PNG file to write (its folder is created if missing).
    requirements : dict of str to (float, float), optional
        Band → (gain margin in dB, phase margin in deg), drawn as horizontal lines at
        ±gain on the gain panels and +phase on the phase panels.

    Returns
    -------
    pathlib.Path
        ``out_path``.

    Raises
    ------
    ValueError
        If a column is missing or the columns differ in length.

    Notes
    -----
    2 × 2 panels: gain (dB) / phase (deg) by pitch / yaw. At each linearization time every
    band has its own slot (colour): a translucent bar from the smallest to the largest
    margin over the runs (for gain margins, one bar for the negative gain-reduction margins
    and one for the positive ones), the margins of the individual runs as dots jittered within the
    slot, and the nominal run's as black-edged diamonds. A panel without margins says
    "no crossings".
    """
    return save_figure(_margin_figure(margins, requirements), Path(out_path))


# --------------------------------------------------------------------------- all


def plot_montecarlo(folder: Path, *, values: dict[str, np.ndarray], time_s: np.ndarray | None,
                    histories: dict[str, np.ndarray] | None, margins: dict[str, np.ndarray] | None,
                    units: dict[str, str] | None = None, nominal: dict[str, float] | None = None,
                    requirements: dict[str, tuple[float, float]] | None = None) -> list[Path]:
    """Draw every figure of a Monte Carlo study into ``folder``.

    Parameters
    ----------
    folder : pathlib.Path
        Output folder (created if missing).
    values : dict of str to numpy.ndarray
        Scalar results over the runs, see :func:`plot_histograms`.
    time_s : numpy.ndarray or None
        Common time grid of ``histories`` (s), shape (n_t,).
    histories : dict of str to numpy.ndarray or None
        Time histories, see :func:`plot_envelopes`; skipped when None or empty.
    margins : dict of str to numpy.ndarray or None
        Margin table, see :func:`plot_margin_spread`, written as ``margin_spread.png``;
        skipped when None, empty or without rows.
    units : dict of str to str, optional
        Name → unit, for ``values`` and ``histories``.
    nominal : dict of str to float, optional
        Name → nominal value of the scalar results.
    requirements : dict of str to (float, float), optional
        Band → (gain margin in dB, phase margin in deg).

    Returns
    -------
    list of pathlib.Path
        Histogram pages, then envelope figures, then the margin figure.

    Raises
    ------
    ValueError
        If ``histories`` is given without ``time_s``, or on a bad shape or table.
    """
    folder = Path(folder)
    written = plot_histograms(values, folder, units=units, nominal=nominal)
    if histories:
        if time_s is None:
            raise ValueError("histories given without time_s")
        written += plot_envelopes(time_s, histories, folder, units=units)
    if margins and np.size(margins.get("value", [None])) > 0:  # no "value" column: the call raises
        written.append(plot_margin_spread(margins, folder / "margin_spread.png", requirements=requirements))
    return written
