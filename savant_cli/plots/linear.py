"""Charts of the frequency-domain stability study (the analogues of the Simulink Control
Design / Control System Toolbox charts of NASA's SAVANT tool).

This module only draws. The study computes, per operating point, the chart data of
:mod:`savant_cli.linear.charts` (frequency responses, root loci, poles and zeros, time
responses; the control computations and their conventions are documented there) and
stores it in ``savant.h5``; these functions draw that data, whether it was just computed
or read back by ``savant report``.

Figures are drawn with matplotlib's object-oriented API on the Agg canvas
(``matplotlib.figure.Figure`` + ``FigureCanvasAgg``): no pyplot, no GUI backend. Each
figure is made and written by the drawing base, :mod:`savant_cli.plots.figure`.

Files of one operating point (``tNNNN.N`` is ``f"t{time_s:06.1f}"``, e.g. ``t0055.0``):

- ``bode_tNNNN.N.png``: magnitude (dB) and phase (deg) of the open loops L vs frequency
  (Hz), pitch and yaw overlaid; the crossover frequencies of the margin table marked
  (dashed: phase crossover, where a gain margin is read; dotted: gain crossover);
- ``nichols_tNNNN.N.png``: gain (dB) vs phase (deg) of L, critical points, every margin
  marked and annotated with its value and frequency, optional exclusion zones;
- ``nyquist_tNNNN.N.png``: L in the complex plane on a radius compressed beyond |L| = 1;
- ``rootlocus_tNNNN.N.png``: closed-loop poles of 1 + k L = 0 over the gains of the data,
  whole z-plane and a zoom near z = 1, the poles at k = 1 marked;
- ``pzmap_tNNNN.N.png``: poles and zeros of the closed loop, z-plane and equivalent s-plane
  (σ in 1/s, frequency in Hz), stable / neutral / unstable poles coloured;
- ``response_tNNNN.N.png``: closed-loop step, impulse and ramp responses of attitude
  (left axis) and gimbal (right axis) to each attitude command, in deg per deg.

Drawing conventions
-------------------
*Phase.* Bode and Nichols draw the same unwrapped, shifted phase of the data; the
critical points −180° ± k·360° inside the plot are drawn (a flex-mode loop excursion may
encircle one of them).

*Nyquist.* L(e^{jωT}) for ω > 0 (solid) and its mirror image for ω < 0 (dashed), without
the indentation at ω = 0, drawn at radius ρ = |L| inside the unit circle and
ρ = 1 + log10 |L| outside it (true angle). The map is continuous and monotonic, so the
encirclements of −1 are those of L, the critical region keeps its linear shape, and a
low-frequency magnitude of 10⁴ stays on the page (ρ = 5); dotted rings mark |L| = 10^k
and the ±6 dB rings |L| = 1/2 and 2.

*Pole-zero map.* Poles with |σ| ≤ :data:`NEUTRAL_RATE` (σ = ln|z| / dt) are drawn as
neutral: the rigid-body and drift integrators of a linearized vehicle sit at z = 1 ± 1e-5.

Speed
-----
The six charts of a point take 0.75–1.0 s with the study's 85-state loops on a 2-core
machine (median of 18 points; matplotlib 3.11). What it takes: short labels and few
ticks (text and ticks are most of the drawing time); one artist per kind of marker;
each chart's figure kept per thread from one point to the next with its axes and ticks
(:func:`savant_cli.plots.figure.sheet`: 40 % less drawing); text drawn unhinted (``text.hinting = "none"``
during the draw only: 15–20 % less); PNG compression on a worker thread while the next
chart is drawn.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Rectangle
from matplotlib.ticker import FormatStrFormatter, LogLocator, MaxNLocator, MultipleLocator, NullLocator

from savant_cli.linear.charts import CommandResponses, LoopResponse, PointCharts, PoleZeroMap, RootLocus, sorted_axes
from savant_cli.linear.margins import MarginRow
from savant_cli.plots.figure import fresh_sheets, new_figure, render, save_rendered, sheet, style_axes, write_png

__all__ = ["MarginRow", "plot_linear_point", "plot_margin_envelope", "plot_nichols_overlay", "point_tag"]

#: Launch-vehicle rigid/aero exclusion zone around each critical point: ±dB, ±deg.
EXCLUSION_GAIN_DB = 6.0
EXCLUSION_PHASE_DEG = 30.0
#: Magnitude range drawn on Bode and Nichols charts (dB); the rest is clipped.
DB_LIMITS = (-80.0, 80.0)
#: Poles with |Re s| at most this (1/s: doubling or halving in more than 690 s) are drawn as
#: neutral: rigid-body and drift integrators of a linearized vehicle sit at z = 1 ± 1e-5.
NEUTRAL_RATE = 1e-3

_AXIS_COLORS = {"pitch": "C0", "yaw": "C1", "roll": "C2"}
_BAND_COLORS = {"rigid/aero": "C0", "slosh": "C2", "flex": "C3"}
_AXIS_MARKERS = {"pitch": "o", "yaw": "^", "roll": "s"}
_GAIN_COLOR = "C3"   # phase crossover (where the gain margin is read)
_PHASE_COLOR = "C2"  # gain crossover (where the phase margin is read)
_CRITICAL_COLOR = "red"


def point_tag(time_s: float) -> str:
    """File-name tag of an operating point, ``f"t{time_s:06.1f}"``: ``t0055.0`` for 55 s,
    ``t0123.4`` for 123.4 s (six characters: the point counts)."""
    return f"t{time_s:06.1f}"


# --------------------------------------------------------------------------- helpers


def _color(axis: str, k: int) -> str:
    return _AXIS_COLORS.get(axis, f"C{k + 2}")


def _margin_index(loop: LoopResponse, freq_hz: float) -> int | None:
    if not np.isfinite(freq_hz):
        return None
    return int(np.argmin(np.abs(loop.f_hz - np.clip(freq_hz, loop.f_hz[0], loop.f_hz[-1]))))


# --------------------------------------------------------------------------- drawing helpers
#
# Drawing on the Agg canvas costs mostly text (about 0.5 ms per text object plus 0.1 ms
# per character with matplotlib 3.11 on the study machine), tick machinery (about 1 ms per
# tick, created per axes) and axes set-up. So: labels are short, ticks few, markers of one
# kind are one artist, axes titles sit at a fixed height (an automatic one measures the
# tick labels), and each chart's figure is kept from one operating point to the next
# (see :func:`savant_cli.plots.figure.sheet`).


def _title(fig: Figure, text: str, time_s: float | None) -> None:
    full = text if time_s is None else f"{text}, t = {time_s:.1f} s"
    fig.suptitle(full, fontsize=11, y=1.0 - 0.1 / fig.get_figheight(), va="top")


def _axes_title(ax, text: str) -> None:
    ax.set_title(text, fontsize=9, y=1.0, pad=3.0)


def _style(ax, nbins_x: int | None = 4, nbins_y: int | None = 4) -> None:
    style_axes(ax, nbins_x, nbins_y, labelsize=8)


def _log_x(ax) -> None:
    ax.set_xscale("log")
    ax.xaxis.set_major_locator(LogLocator(base=10.0, numticks=12))
    ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))  # plain numbers: no mathtext parsing
    ax.xaxis.set_minor_locator(NullLocator())


def _unit_circle(ax, radius: float = 1.0) -> None:
    ax.add_patch(Circle((0.0, 0.0), radius, fill=False, lw=0.8, ls="--", color="0.4"))


def _cross_hairs(ax) -> None:
    ax.axhline(0.0, color="0.3", lw=0.5)
    ax.axvline(0.0, color="0.3", lw=0.5)


def _critical_phases(lo: float, hi: float) -> list[float]:
    """Phases −180° + k·360° inside [lo, hi] (deg)."""
    k0, k1 = math.ceil((lo + 180.0) / 360.0), math.floor((hi + 180.0) / 360.0)
    return [-180.0 + 360.0 * k for k in range(k0, k1 + 1)]


def _db_limits(loops: Sequence[LoopResponse]) -> tuple[float, float]:
    finite = np.concatenate([lp.mag_db[np.isfinite(lp.mag_db)] for lp in loops])
    lo = max(float(finite.min()), DB_LIMITS[0]) if finite.size else -20.0
    hi = min(float(finite.max()), DB_LIMITS[1]) if finite.size else 20.0
    lo, hi = min(lo, -EXCLUSION_GAIN_DB - 4.0), max(hi, EXCLUSION_GAIN_DB + 4.0)
    pad = 0.04 * (hi - lo)
    return lo - pad, hi + pad


def _phase_locator(span: float) -> MultipleLocator:
    """Phase ticks every 45°…360°, always through −180°."""
    step = 45.0 if span <= 270 else 90.0 if span <= 720 else 180.0 if span <= 1440 else 360.0
    return MultipleLocator(step, offset=180.0 if step == 360.0 else 0.0)


def _label(row) -> str:
    """Full text of a margin, e.g. ``"pitch GM -8.5 dB @ 0.125 Hz"``. The charts read only
    the six fields of a row (``time_s``, ``axis``, ``kind``, ``value``, ``frequency_hz``,
    ``band``)."""
    name = "GM" if row.kind == "gain" else "PM"
    unit = " dB" if row.kind == "gain" else "°"
    return f"{row.axis} {name} {row.value:.1f}{unit} @ {row.frequency_hz:.3g} Hz"


def _short(row) -> str:
    """Annotation of a margin on the Nichols chart (the axis is the text colour)."""
    unit = " dB" if row.kind == "gain" else "°"
    return f"{row.value:.1f}{unit}, {row.frequency_hz:.3g} Hz"


def _vertical_lines(ax, x: Sequence[float], **kw) -> None:
    """Full-height vertical lines at ``x`` as one artist (NaN-separated, axes-fraction y)."""
    if len(x):
        ax.plot(np.repeat(np.asarray(x, dtype=float), 3), np.tile([0.0, 1.0, np.nan], len(x)),
                transform=ax.get_xaxis_transform(), **kw)


# --------------------------------------------------------------------------- figures
#
# Each chart is a layout function (the static part, run once per thread) and a drawing
# function that fills the sheet with one operating point and returns the figure.


def _bode_layout() -> tuple[Figure, list]:
    fig = new_figure(8.0, 5.8, left=0.75, bottom=0.95, hspace=0.07)
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    for ax in (ax_m, ax_p):
        _log_x(ax)
    _style(ax_m, None, 4)
    _style(ax_p, None, None)
    ax_m.set_ylabel("magnitude |L| (dB)", fontsize=9)
    ax_p.set_ylabel("phase ∠L (deg)", fontsize=9)
    ax_p.set_xlabel("frequency (Hz)", fontsize=9)
    return fig, [ax_m, ax_p]


def _bode_figure(time_s: float, loops: Sequence[LoopResponse], margins: Sequence[MarginRow]) -> Figure:
    """Magnitude and phase of the loops, overlaid; crossovers of the margin table marked."""
    fig, (ax_m, ax_p) = sheet(("bode",), _bode_layout)
    plo, phi = np.inf, -np.inf
    for j, lp in enumerate(loops):
        color = _color(lp.axis, j)
        ax_m.plot(lp.f_hz, lp.mag_db, color=color, lw=1.0)
        ax_p.plot(lp.f_hz, lp.phase_deg, color=color, lw=1.0)
        plo, phi = min(plo, float(np.min(lp.phase_deg))), max(phi, float(np.max(lp.phase_deg)))
        for kind, ls in (("gain", "--"), ("phase", ":")):
            f = [r.frequency_hz for r in margins if r.axis == lp.axis and r.kind == kind
                 and np.isfinite(r.frequency_hz) and r.frequency_hz > 0]
            for ax in (ax_m, ax_p):
                _vertical_lines(ax, f, color=color, lw=0.8, ls=ls)
    ax_m.axhline(0.0, color=_CRITICAL_COLOR, lw=0.7)
    ax_m.set_ylim(*_db_limits(loops))
    pad = 0.05 * max(phi - plo, 90.0)
    ax_p.set_ylim(plo - pad, phi + pad)
    for c in _critical_phases(plo - pad, phi + pad):
        ax_p.axhline(c, color=_CRITICAL_COLOR, lw=0.7)
    ax_p.yaxis.set_major_locator(_phase_locator(phi - plo))
    ax_p.set_xlim(min(lp.f_hz[0] for lp in loops), max(lp.f_hz[-1] for lp in loops))
    handles = [Line2D([], [], color=_color(lp.axis, j), lw=1.0, label=f"{lp.axis} L") for j, lp in enumerate(loops)]
    handles += [Line2D([], [], color="0.2", ls="--", lw=0.8, label="phase crossover (GM)"),
                Line2D([], [], color="0.2", ls=":", lw=0.8, label="gain crossover (PM)"),
                Line2D([], [], color=_CRITICAL_COLOR, lw=0.7, label="0 dB, −180°")]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8, frameon=False,
               handlelength=1.8, columnspacing=1.2)
    _title(fig, "Open-loop Bode diagram", time_s)
    return fig


_OFFSETS = ((5, 3, "left", "bottom"), (-5, 3, "right", "bottom"), (5, -3, "left", "top"), (-5, -3, "right", "top"))


def _nichols_layout() -> tuple[Figure, list]:
    fig = new_figure(8.0, 6.0, left=0.75, bottom=0.5)
    ax = fig.add_subplot(1, 1, 1)
    _style(ax, None, 6)
    ax.set_xlabel("open-loop phase ∠L (deg, unwrapped)", fontsize=9)
    ax.set_ylabel("open-loop gain |L| (dB)", fontsize=9)
    return fig, [ax]


def _nichols_figure(time_s: float, loops: Sequence[LoopResponse], margins: Sequence[MarginRow],
                    exclusion_zones: bool = True) -> Figure:
    """Gain vs unwrapped phase of the loops, critical points, exclusion zones, margins."""
    fig, (ax,) = sheet(("nichols",), _nichols_layout)
    ylo, yhi = _db_limits(loops)
    # phase range: the part of each curve inside the drawn magnitudes, and [−360°, 0°]
    xs = [-360.0, 0.0]
    for lp in loops:
        inside = (lp.mag_db >= ylo) & (lp.mag_db <= yhi)
        if inside.any():
            xs += [float(lp.phase_deg[inside].min()), float(lp.phase_deg[inside].max())]
    pad = 0.03 * (max(xs) - min(xs))
    xlo, xhi = min(xs) - pad, max(xs) + pad
    handles = []
    for j, lp in enumerate(loops):
        handles += ax.plot(lp.phase_deg, lp.mag_db, color=_color(lp.axis, j), lw=1.0, label=f"{lp.axis} L")
    crit = _critical_phases(xlo, xhi)
    handles += ax.plot(crit, np.zeros(len(crit)), ls="none", marker="P", ms=9, color=_CRITICAL_COLOR,
                       label="critical point", zorder=5)
    if exclusion_zones:
        for c in crit:
            ax.add_patch(Rectangle((c - EXCLUSION_PHASE_DEG, -EXCLUSION_GAIN_DB), 2 * EXCLUSION_PHASE_DEG,
                                   2 * EXCLUSION_GAIN_DB, facecolor=_CRITICAL_COLOR, alpha=0.12,
                                   edgecolor=_CRITICAL_COLOR, lw=0.8, zorder=1))
        handles.append(Rectangle((0, 0), 1, 1, facecolor=_CRITICAL_COLOR, alpha=0.12, edgecolor=_CRITICAL_COLOR,
                                 lw=0.8, label=f"exclusion ±{EXCLUSION_GAIN_DB:g} dB, ±{EXCLUSION_PHASE_DEG:g}°"))
    by_axis = {lp.axis: (j, lp) for j, lp in enumerate(loops)}
    outside: list[str] = []
    marks: dict[bool, list[tuple[float, float]]] = {True: [], False: []}
    # a margin that every loop has alike (a symmetric vehicle's pitch and yaw) is written once, in black
    shared: dict[str, set[str]] = {}
    for row in margins:
        shared.setdefault(f"{row.kind}|{_short(row)}", set()).add(row.axis)
    written: set[str] = set()
    for row in margins:
        j, lp = by_axis.get(row.axis, (0, None))
        i = None if lp is None else _margin_index(lp, row.frequency_hz)
        if not np.isfinite(row.value):
            continue  # an infinite margin: nothing to mark
        if i is None or not (xlo <= lp.phase_deg[i] <= xhi and ylo <= lp.mag_db[i] <= yhi):
            outside.append(_label(row))
            continue
        x, y = float(lp.phase_deg[i]), float(lp.mag_db[i])
        is_gain = row.kind == "gain"
        marks[is_gain].append((x, y))
        key = f"{row.kind}|{_short(row)}"
        common = len(loops) > 1 and shared[key] >= set(by_axis)
        if common and key in written:
            continue
        written.add(key)
        dx, dy, ha, va = _OFFSETS[len(written) % len(_OFFSETS)]
        ax.annotate(_short(row), (x, y), xytext=(dx, dy), textcoords="offset points", fontsize=6.5, ha=ha, va=va,
                    color="0.15" if common else _color(row.axis, j), annotation_clip=False, zorder=7)
    for is_gain, pts in marks.items():
        if pts:
            x, y = np.array(pts).T
            ax.plot(x, y, ls="none", marker="s" if is_gain else "D", ms=5, mfc="none",
                    mec=_GAIN_COLOR if is_gain else _PHASE_COLOR, mew=1.2, zorder=6)
    if outside:
        ax.text(0.99, 0.01, "off the chart:\n" + "\n".join(outside), transform=ax.transAxes, fontsize=6.5,
                ha="right", va="bottom", bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "0.7", "lw": 0.5})
    handles += [Line2D([], [], ls="none", marker="s", mfc="none", mec=_GAIN_COLOR, mew=1.2, label="gain margin"),
                Line2D([], [], ls="none", marker="D", mfc="none", mec=_PHASE_COLOR, mew=1.2, label="phase margin")]
    ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlim(xlo, xhi)
    ax.set_ylim(ylo, yhi)
    ax.xaxis.set_major_locator(_phase_locator(xhi - xlo))
    _title(fig, "Nichols chart", time_s)
    return fig


def _compress(h: np.ndarray) -> np.ndarray:
    """Nyquist-plane point of L drawn at radius ρ(|L|) = |L| for |L| ≤ 1 and 1 + log10 |L|
    beyond, at its true angle (continuous and monotonic: encirclements are kept)."""
    r = np.abs(h)
    with np.errstate(divide="ignore"):
        rho = np.where(r <= 1.0, r, 1.0 + np.log10(np.maximum(r, 1.0)))
    return rho * np.exp(1j * np.angle(h))


def _nyquist_layout() -> tuple[Figure, list]:
    fig = new_figure(7.0, 6.4, left=0.75, bottom=0.85, top=0.5)
    ax = fig.add_subplot(1, 1, 1)
    ax.set_aspect("equal", adjustable="box")
    _style(ax)
    ax.set_xlabel("Re L (–), radius 1 + log10|L| beyond |L| = 1", fontsize=9)
    ax.set_ylabel("Im L (–), same scale", fontsize=9)
    return fig, [ax]


def _nyquist_figure(time_s: float, loops: Sequence[LoopResponse]) -> Figure:
    """L in the complex plane, radius compressed beyond the unit circle."""
    fig, (ax,) = sheet(("nyquist",), _nyquist_layout)
    handles = []
    rmax = 1.5
    for j, lp in enumerate(loops):
        color = _color(lp.axis, j)
        c = _compress(lp.response)
        rmax = max(rmax, float(np.max(np.abs(c))))
        handles += ax.plot(c.real, c.imag, color=color, lw=1.0, label=f"{lp.axis} L, ω > 0")
        ax.plot(c.real, -c.imag, color=color, lw=0.6, ls="--")  # ω < 0: mirror image
        k = min(max(int(np.searchsorted(lp.f_hz, 0.1)), 1), len(c) - 1)  # direction of increasing ω
        ax.annotate("", xy=(c[k].real, c[k].imag), xytext=(c[k - 1].real, c[k - 1].imag),
                    arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.0})
    handles.append(Line2D([], [], color="0.3", lw=0.6, ls="--", label="ω < 0"))
    # rings: |L| = 1/2 and 2 (∓6 dB, dotted red), 1 (dashed), 10^k (dotted grey)
    for r_ring, ls, color in ((0.5, ":", _CRITICAL_COLOR), (2.0, ":", _CRITICAL_COLOR), (1.0, "--", "0.4")):
        ax.add_patch(Circle((0.0, 0.0), abs(_compress(np.array([r_ring]))[0]), fill=False, lw=0.8, ls=ls, color=color))
    decade = 1
    while 1.0 + decade <= rmax * 1.02 and decade <= 12:
        ax.add_patch(Circle((0.0, 0.0), 1.0 + decade, fill=False, lw=0.5, ls=":", color="0.55"))
        ax.text(0.0, -(1.0 + decade), f"{10 ** decade:g}", fontsize=6.5, color="0.4", ha="left", va="bottom")
        decade += 1
    handles += ax.plot([-1.0], [0.0], ls="none", marker="P", ms=9, color=_CRITICAL_COLOR, label="−1", zorder=5)
    handles += [Line2D([], [], color="0.4", lw=0.8, ls="--", label="|L| = 1"),
                Line2D([], [], color=_CRITICAL_COLOR, lw=0.8, ls=":", label="|L| = 0.5, 2 (±6 dB)")]
    lim = 1.05 * rmax
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    _cross_hairs(ax)
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    _title(fig, "Nyquist diagram", time_s)
    return fig


def _root_locus_layout(discrete: bool) -> tuple[Figure, list]:
    fig = new_figure(9.6, 5.3, left=0.7, bottom=0.85, wspace=0.22)
    ax_all, ax_zoom = fig.subplots(1, 2)
    for ax in (ax_all, ax_zoom):
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("Re z (–)" if discrete else "Re s (1/s)", fontsize=9)
        ax.set_ylabel("Im z (–)" if discrete else "Im s (rad/s)", fontsize=9)
        _style(ax)
    _axes_title(ax_all, "z-plane" if discrete else "s-plane")
    _axes_title(ax_zoom, "near z = 1 (modes below ≈ 1 Hz)" if discrete else "near s = 0")
    return fig, [ax_all, ax_zoom]


def _root_locus_figure(time_s: float, loci: Sequence[RootLocus]) -> Figure:
    """Root loci of 1 + k L = 0 of all loops, overlaid: whole plane and a zoom near z = 1 (s = 0)."""
    discrete = all(rl.dt is not None for rl in loci)
    fig, (ax_all, ax_zoom) = sheet(("rootlocus", discrete), lambda: _root_locus_layout(discrete))
    gains = loci[0].gains
    handles = []
    extent = 1.0
    for j, rl in enumerate(loci):
        color = _color(rl.label, j)
        branches, poles, zeros, closed = rl.branches, rl.poles, rl.zeros, rl.nominal
        finite = np.concatenate([poles, closed])
        finite = finite[np.isfinite(finite)]
        if finite.size:
            extent = max(extent, float(np.max(np.abs(finite))))
        # all branches as one NaN-separated line (one artist instead of one per state)
        joined = np.vstack([branches, np.full((1, branches.shape[1]), np.nan)]).T.reshape(-1)
        for ax in (ax_all, ax_zoom):
            ax.plot(joined.real, joined.imag, color=color, lw=0.6, alpha=0.55)
            ax.plot(poles.real, poles.imag, ls="none", marker="x", ms=6, mew=1.2, color=color)
            ax.plot(zeros.real, zeros.imag, ls="none", marker="o", ms=5, mfc="none", mew=1.0, color=color)
            ax.plot(closed.real, closed.imag, ls="none", marker="s", ms=4, color=color, mec="k", mew=0.6)
        handles.append(Line2D([], [], color=color, lw=1.0, label=f"{rl.label}"))
    handles += [Line2D([], [], ls="none", marker="x", ms=6, mew=1.2, color="0.3", label="open-loop poles"),
                Line2D([], [], ls="none", marker="o", ms=5, mfc="none", color="0.3", label="zeros"),
                Line2D([], [], ls="none", marker="s", ms=4, color="0.5", mec="k", mew=0.6, label="k = 1 poles")]
    for ax in (ax_all, ax_zoom):
        _cross_hairs(ax)
    if discrete:
        for ax in (ax_all, ax_zoom):
            _unit_circle(ax)
        ax_all.set_xlim(-1.3, 1.3)
        ax_all.set_ylim(-1.3, 1.3)
        ax_zoom.set_xlim(0.84, 1.06)
        ax_zoom.set_ylim(-0.11, 0.11)
        handles.append(Line2D([], [], color="0.4", ls="--", lw=0.8, label="unit circle"))
    else:
        ax_all.set_xlim(-1.1 * extent, 0.3 * extent)
        ax_all.set_ylim(-1.1 * extent, 1.1 * extent)
        ax_zoom.set_xlim(-5.0, 2.0)
        ax_zoom.set_ylim(-3.5, 3.5)
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8, frameon=False,
               handlelength=1.5, columnspacing=1.0)
    _title(fig, f"Root locus of 1 + kL, k = {gains[0]:.2g}…{gains[-1]:.2g}", time_s)
    return fig


def _pzmap_layout(discrete: bool) -> tuple[Figure, list]:
    fig = new_figure(9.6, 5.0, left=0.65, bottom=0.85, wspace=0.25)
    ax_z, ax_s = fig.subplots(1, 2)
    if discrete:
        ax_z.set_aspect("equal", adjustable="box")
        ax_z.set_xlabel("Re z (–)", fontsize=9)
        ax_z.set_ylabel("Im z (–)", fontsize=9)
        _style(ax_z)
    else:
        ax_z.set_visible(False)
    ax_s.set_xscale("symlog", linthresh=1.0)
    ax_s.xaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax_s.xaxis.set_minor_locator(NullLocator())
    ax_s.set_xlabel("Re s = σ (1/s, symlog)", fontsize=9)
    ax_s.set_ylabel("Im s / 2π (Hz)", fontsize=9)
    _axes_title(ax_s, "s = ln(z)/dt" if discrete else "s-plane")
    _style(ax_s, None, 4)
    return fig, [ax_z, ax_s]


def _pzmap_figure(time_s: float, pz: PoleZeroMap) -> Figure:
    """Closed-loop poles and zeros: z-plane and the equivalent s-plane (Hz)."""
    dt = pz.dt
    fig, (ax_z, ax_s) = sheet(("pzmap", dt is not None), lambda: _pzmap_layout(dt is not None))
    poles, zeros, sp, sz = pz.poles, pz.zeros, pz.s_poles, pz.s_zeros
    at_origin = int(np.count_nonzero(~np.isfinite(sp)))
    sigma = np.where(np.isfinite(sp), sp.real, -np.inf)
    groups = ((sigma < -NEUTRAL_RATE, "C0", "stable poles" + (f", {at_origin} at z = 0" if at_origin else "")),
              (np.abs(sigma) <= NEUTRAL_RATE, "C1", f"neutral, |σ| ≤ {NEUTRAL_RATE:g} 1/s"),
              (sigma > NEUTRAL_RATE, _CRITICAL_COLOR, "unstable"))

    def draw(ax, p, z, scale: float) -> None:
        okz = np.isfinite(z)
        ax.plot(z[okz].real, z[okz].imag / scale, ls="none", marker="o", ms=5, mfc="none", color="C2")
        for sel, color, _ in groups:
            sel = sel & np.isfinite(p)
            if sel.any():
                ax.plot(p[sel].real, p[sel].imag / scale, ls="none", marker="x", ms=6, mew=1.3, color=color)
        _cross_hairs(ax)

    if dt:
        draw(ax_z, poles, zeros, 1.0)
        _unit_circle(ax_z)
        ax_z.set_xlim(-1.3, 1.3)
        ax_z.set_ylim(-1.3, 1.3)
        _axes_title(ax_z, f"z-plane, dt = {dt:g} s")
        ny = 0.5 / dt
        ax_s.axhline(ny, color="0.4", lw=0.7, ls="--")
        ax_s.axhline(-ny, color="0.4", lw=0.7, ls="--")
    draw(ax_s, sp, sz, 2 * np.pi)
    if dt:
        ax_s.set_ylim(-1.05 * ny, 1.05 * ny)
    handles = [Line2D([], [], ls="none", marker="x", ms=6, mew=1.3, color=color, label=f"{label} ({int(sel.sum())})")
               for sel, color, label in groups]
    handles.append(Line2D([], [], ls="none", marker="o", ms=5, mfc="none", color="C2", label="zeros, cmd → attitude"))
    if dt:
        handles.append(Line2D([], [], color="0.4", ls="--", lw=0.8, label="|z| = 1, Nyquist"))
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    _title(fig, "Closed-loop poles and zeros", time_s)
    return fig


_RESPONSE_ROWS = (("step", "1° step"), ("impulse", "1°·s pulse"), ("ramp", "1°/s ramp"))


def _response_layout(named: bool, gimbal: bool) -> tuple[Figure, list]:
    fig = new_figure(9.0, 6.8, left=0.8, right=0.8, bottom=0.85, hspace=0.1)
    axes = list(fig.subplots(len(_RESPONSE_ROWS), 1, sharex=True))
    twins = []
    for ax, (kind, what) in zip(axes, _RESPONSE_ROWS):
        _style(ax, 5, 4)
        ax.set_ylabel(f"{kind}: attitude (deg)\nper {what}" if named else f"{kind} (per {what})", fontsize=8.5)
        if gimbal:
            right = ax.twinx()
            right.yaxis.set_major_locator(MaxNLocator(4))
            right.tick_params(labelsize=8)
            right.set_ylabel("gimbal (deg)", fontsize=8.5)
            twins.append(right)
    axes[-1].set_xlabel("time after the command (s)", fontsize=9)
    return fig, axes + twins


def _response_figure(time_s: float, data: CommandResponses) -> Figure:
    """Step, impulse and ramp responses (rows) to each command: attitude on the left axis,
    gimbal on the right one (a gimbal pulse is tens of times the attitude's)."""
    t, commands, outputs = data.time_s, list(data.commands), list(data.outputs)
    duration_s = float(t[-1])
    named = any(o.endswith(("_attitude", "_gimbal")) for o in outputs)
    gimbal = any(o.endswith("_gimbal") for o in outputs)
    fig, axes = sheet(("response", named, gimbal), lambda: _response_layout(named, gimbal))
    rows = len(_RESPONSE_ROWS)
    lefts, rights = axes[:rows], (axes[rows:] if gimbal else [None] * rows)
    references = {"step": np.ones_like(t), "ramp": t}
    handles: dict[str, Line2D] = {}
    for ax, right, (kind, _) in zip(lefts, rights, _RESPONSE_ROWS):
        y = data.of(kind)
        if kind in references:
            handles.setdefault("command", ax.plot(t, references[kind], color="0.5", lw=0.8, ls="--")[0])
        for i, cmd in enumerate(commands):
            axis = cmd.removesuffix("_command")
            color = _color(axis, i)
            for k, name in enumerate(outputs):
                if not named:  # no recognised output names: every output on the left axis
                    handles.setdefault(f"{cmd} → {name}", ax.plot(t, y[k, i], color=f"C{k}", lw=1.0,
                                                                  ls=("-", "--", ":")[i % 3])[0])
                    continue
                is_gimbal = name.endswith("_gimbal")
                target = right if is_gimbal else ax
                quantity = "gimbal" if is_gimbal else "attitude"
                if name.startswith(axis + "_"):
                    label = f"{axis} {quantity}" + (" (right)" if is_gimbal else "")
                    handles.setdefault(label, target.plot(t, y[k, i], color=color, lw=0.9 if is_gimbal else 1.1,
                                                          ls="--" if is_gimbal else "-")[0])
                else:  # cross-coupling: drawn when it is more than 1 % of the own-axis response
                    own = f"{axis}_{quantity}"
                    scale = float(np.max(np.abs(y[outputs.index(own), i]))) if own in outputs else 0.0
                    if np.max(np.abs(y[k, i])) > 1e-2 * max(scale, 1e-12):
                        handles.setdefault("other axis", target.plot(t, y[k, i], color=color, lw=0.7, ls=":")[0])
    lefts[-1].set_xlim(0.0, duration_s)
    fig.legend(handles=list(handles.values()), labels=list(handles), loc="lower center", ncol=3,
               fontsize=8, frameon=False, handlelength=1.8, columnspacing=1.2)
    _title(fig, "Closed-loop responses to attitude commands", time_s)
    return fig


def _envelope_figure(rows: Sequence[MarginRow], requirements: Mapping[str, tuple[float, float]] | None,
                     failed_times: Sequence[float] = (),
                     failed_label: str = "point fails its\nrequirement set") -> Figure:
    """Gain and phase margins vs flight time, by band (colour) and axis (marker); the
    points failing their requirement set marked by a red line across both panels."""
    fig = new_figure(9.0, 7.0, left=0.85, right=2.2, bottom=0.6, top=0.5, hspace=0.08)
    ax_g, ax_p = fig.subplots(2, 1, sharex=True)
    requirements = dict(requirements or {})
    axes_names = sorted_axes({r.axis for r in rows})
    bands = list(_BAND_COLORS) + sorted({r.band for r in rows} - set(_BAND_COLORS))
    handles: list = []
    violating = False
    for b, band in enumerate(bands):
        color = _BAND_COLORS.get(band, f"C{4 + b}")
        for axis in axes_names:
            sel = [r for r in rows if r.band == band and r.axis == axis and np.isfinite(r.value)]
            if not sel:
                continue
            marker = _AXIS_MARKERS.get(axis, "s")
            for ax, kind in ((ax_g, "gain"), (ax_p, "phase")):
                pts = [r for r in sel if r.kind == kind]
                if not pts:
                    continue
                v = np.array([r.value for r in pts])
                req = requirements.get(band)
                bad = np.zeros(v.size, dtype=bool)
                if all(r.meets_requirement is not None for r in pts):  # judged by the requirement set
                    bad = np.array([not r.meets_requirement for r in pts])
                elif req is not None:  # by the band's requirement alone
                    bad = np.abs(v) < (req[0] if kind == "gain" else req[1])
                violating |= bool(bad.any())
                ax.scatter([r.time_s for r in pts], v, s=22, marker=marker, color=color,
                           edgecolors=np.where(bad, "k", color), linewidths=np.where(bad, 1.4, 0.5), zorder=3)
            handles.append(Line2D([], [], ls="none", marker=marker, color=color, label=f"{band}, {axis}"))
    # requirement lines, one style per distinct (gain, phase) pair
    groups: dict[tuple[float, float], list[str]] = {}
    for band, req in requirements.items():
        groups.setdefault((float(req[0]), float(req[1])), []).append(band)
    for k, ((g, p), names) in enumerate(groups.items()):
        color = "0.15" if len(groups) == 1 else _BAND_COLORS.get(names[0], f"C{4 + k}")
        ls = ("--", "-.", ":", (0, (5, 1, 1, 1)))[k % 4]
        ax_g.axhline(g, color=color, lw=1.0, ls=ls)
        ax_g.axhline(-g, color=color, lw=1.0, ls=ls)
        ax_p.axhline(p, color=color, lw=1.0, ls=ls)
        who = "all bands" if len(groups) == 1 and len(names) > 1 else ", ".join(names)
        handles.append(Line2D([], [], color=color, lw=1.0, ls=ls, label=f"requirement ({who}):\n±{g:g} dB, {p:g}°"))
    if violating:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="white", mec="k", mew=1.4,
                              label="inside requirement\n(black edge)"))
    for t in failed_times:
        for ax in (ax_g, ax_p):
            ax.axvline(t, color="tab:red", lw=2.5, alpha=0.25, zorder=1)
    if len(failed_times):
        handles.append(Line2D([], [], color="tab:red", lw=2.5, alpha=0.25, label=failed_label))
    ax_g.axhline(0.0, color="0.3", lw=0.6)
    ax_p.axhline(0.0, color="0.3", lw=0.6)
    ax_g.set_ylabel("gain margin (dB)\nnegative: gain reduction", fontsize=9)
    ax_p.set_ylabel("phase margin (deg)", fontsize=9)
    ax_p.set_xlabel("flight time (s)", fontsize=9)
    for ax in (ax_g, ax_p):
        _style(ax, None, 6)
    fig.legend(handles=handles, loc="center right", fontsize=8, frameon=False)
    times = [r.time_s for r in rows]
    span = f", {min(times):.1f}–{max(times):.1f} s" if times else ""
    _title(fig, f"Stability margins vs flight time{span}", None)
    return fig


# --------------------------------------------------------------------------- public API


def plot_linear_point(charts: PointCharts, margins: Sequence[MarginRow], out_dir: Path,
                      exclusion_zones: bool = True) -> list[Path]:
    """Draw the six frequency- and time-domain charts of one operating point.

    Parameters
    ----------
    charts : savant_cli.linear.charts.PointCharts
        The point's chart data (:func:`savant_cli.linear.charts.point_charts`, or read back
        from ``savant.h5`` by :func:`savant_cli.linear.store.read_charts`): open-loop
        frequency responses, root loci, closed-loop poles and zeros, time responses.
        Its time (s) is in the titles and, as ``f"t{time_s:06.1f}"``, in the file names.
    margins : sequence of MarginRow
        The margins of this operating point (both axes); each finite one is marked on the
        Bode and Nichols charts at its frequency.
    out_dir : pathlib.Path
        Folder of the PNGs (created if missing).
    exclusion_zones : bool, optional
        Draw the rigid/aero exclusion zone (±6 dB, ±30°) around each critical point of the
        Nichols chart.

    Returns
    -------
    list of pathlib.Path
        ``bode``, ``nichols``, ``nyquist``, ``rootlocus``, ``pzmap`` and ``response`` PNGs,
        in that order.

    Raises
    ------
    ValueError
        If ``charts`` holds no loop.

    Notes
    -----
    Frequencies in Hz, magnitudes in dB, phases in deg (unwrapped; the shift convention
    is in :mod:`savant_cli.linear.charts`), time in s.

    Each chart's figure is kept per calling thread and reused by the next call (module
    notes, *Speed*); matplotlib's ``text.hinting`` is set to ``"none"`` during each draw
    and restored. Both are invisible to a caller that does not draw with matplotlib on
    another thread at the same time.
    """
    if not charts.loops:
        raise ValueError("plot_linear_point needs at least one loop")
    out_dir = Path(out_dir)
    time_s = charts.time_s
    tag = point_tag(time_s)
    # PNG compression on a worker thread (Pillow releases the GIL) while the next figure is
    # drawn. Nothing else runs there: Python-level work on a second thread slows the
    # drawing thread by more than it saves, through the GIL.
    with ThreadPoolExecutor(max_workers=1) as worker:
        figures = (
            (f"bode_{tag}.png", lambda: _bode_figure(time_s, charts.loops, margins)),
            (f"nichols_{tag}.png", lambda: _nichols_figure(time_s, charts.loops, margins, exclusion_zones)),
            (f"nyquist_{tag}.png", lambda: _nyquist_figure(time_s, charts.loops)),
            (f"rootlocus_{tag}.png", lambda: _root_locus_figure(time_s, charts.root_loci)),
            (f"pzmap_{tag}.png", lambda: _pzmap_figure(time_s, charts.pzmap)),
            (f"response_{tag}.png", lambda: _response_figure(time_s, charts.responses)),
        )
        jobs = [worker.submit(write_png, render(build()), out_dir / filename) for filename, build in figures]
        return [job.result() for job in jobs]


def chart_figure(name: str, charts: PointCharts, margins: Sequence[MarginRow], exclusion_zones: bool = True) -> Figure:
    """One of :func:`plot_linear_point`'s charts as a new figure the caller keeps (not a
    reused sheet): ``name`` one of ``bode``, ``nichols``, ``nyquist``, ``rootlocus``,
    ``pzmap``, ``response`` (what ``savant_cli.Result.plot`` draws)."""
    t = charts.time_s
    builders = {"bode": lambda: _bode_figure(t, charts.loops, margins),
                "nichols": lambda: _nichols_figure(t, charts.loops, margins, exclusion_zones),
                "nyquist": lambda: _nyquist_figure(t, charts.loops),
                "rootlocus": lambda: _root_locus_figure(t, charts.root_loci),
                "pzmap": lambda: _pzmap_figure(t, charts.pzmap),
                "response": lambda: _response_figure(t, charts.responses)}
    if name not in builders:
        raise KeyError(f"no linear chart {name!r}; known: {', '.join(builders)}")
    with fresh_sheets():
        return builders[name]()


def envelope_figure(rows: list[MarginRow], requirements: dict[str, tuple[float, float]] | None = None,
                    failed_times: Sequence[float] = ()) -> Figure:
    """:func:`plot_margin_envelope`'s figure, returned instead of written."""
    return _envelope_figure(rows, requirements, failed_times)


def plot_margin_envelope(rows: list[MarginRow], out_path: Path,
                         requirements: dict[str, tuple[float, float]] | None = None,
                         failed_times: Sequence[float] = (),
                         failed_label: str = "point fails its\nrequirement set") -> Path:
    """Draw the stability margins of a study against flight time.

    Parameters
    ----------
    rows : list of MarginRow
        Margins of all operating points; non-finite values (infinite margins) are left out.
    out_path : pathlib.Path
        PNG file to write (its folder is created if missing).
    requirements : dict of str to (float, float), optional
        Band → (gain margin in dB, phase margin in deg), e.g.
        ``{"rigid/aero": (6, 30), "slosh": (6, 30), "flex": (6, 30)}``. Drawn as lines at
        ±gain (a gain-reduction margin must be below −gain) and at +phase. A margin
        that misses its requirement gets a black edge: by its own verdict
        (``MarginRow.meets_requirement``) when the rows were judged, else by its band's
        values here.
    failed_times : sequence of float
        Flight times (s) of the points that fail their requirement set (a margin, a
        bending mode's attenuation or closed-loop stability), marked by a red line.
    failed_label : str
        The legend entry of those lines.

    Returns
    -------
    pathlib.Path
        ``out_path``.

    Notes
    -----
    Top panel: gain margins (dB); bottom panel: phase margins (deg); colour = band
    (rigid/aero, slosh, flex), marker = axis (pitch ○, yaw △).
    """
    return save_rendered(_envelope_figure(rows, requirements, failed_times, failed_label), Path(out_path))


def plot_nichols_overlay(time_s: float, loops: Sequence[LoopResponse], out_path: Path, title: str = "Nichols chart",
                         exclusion_zones: bool = True) -> Path:
    """Overlay the Nichols curves of several variants of one loop (a parameter study).

    Parameters
    ----------
    time_s : float
        Flight time of the operating point (s), shown in the title.
    loops : sequence of LoopResponse
        One frequency response per variant (:func:`savant_cli.linear.charts.loop_response`),
        its label the legend entry.
    out_path : pathlib.Path
        PNG file to write.
    title : str
        Figure title (the time is appended).
    exclusion_zones : bool
        Draw the launch-vehicle exclusion zones around the critical points.

    Returns
    -------
    pathlib.Path
        ``out_path``.
    """
    fig = _nichols_figure(time_s, list(loops), [], exclusion_zones)
    _title(fig, title, time_s)
    return save_rendered(fig, Path(out_path))
