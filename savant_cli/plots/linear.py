"""Charts of the frequency-domain stability study (the analogues of the Simulink Control
Design / Control System Toolbox charts of NASA's SAVANT tool).

The study linearizes the vehicle at a set of flight times and hands this module, per
operating point, python-control objects and a margin table; this module only draws.
Every control computation is python-control's: frequency responses
(:func:`control.frequency_response`), poles and zeros (``sys.poles()``, ``sys.zeros()``),
closed loops (:func:`control.feedback`) and time responses (:func:`control.step_response`,
:func:`control.impulse_response`, :func:`control.forced_response`).

Figures are drawn with matplotlib's object-oriented API on the Agg canvas
(``matplotlib.figure.Figure`` + ``FigureCanvasAgg``): no pyplot, no GUI backend, no global
state. Each figure is written atomically as a 120-dpi PNG (:func:`savant_cli.io.atomic.atomic_path`).

Files of one operating point (``tNNNN.N`` is the flight time, ``f"t{time_s:06.1f}"``):

- ``bode_tNNNN.N.png``: magnitude (dB) and phase (deg) of each axis's open loop L vs
  frequency (Hz), crossover frequencies of the margin table marked;
- ``nichols_tNNNN.N.png``: gain (dB) vs phase (deg) of L, critical points, margins
  annotated, optional exclusion zones;
- ``nyquist_tNNNN.N.png``: L in the complex plane, around the critical point and on a
  compressed radius;
- ``rootlocus_tNNNN.N.png``: closed-loop poles of 1 + k L = 0 for k in
  :data:`ROOT_LOCUS_GAINS`, z-plane and a zoom near z = 1;
- ``pzmap_tNNNN.N.png``: poles and zeros of the closed loop, z-plane and equivalent s-plane;
- ``response_tNNNN.N.png``: closed-loop step, impulse and ramp responses.

Conventions
-----------
*Open loop.* ``L`` is the SISO loop broken at one axis's actuator command with the other
axis closed; the closed loop is ``L / (1 + L)`` (negative unity feedback), so the critical
point is L = −1: 0 dB and −180° (mod 360°).

*Frequency grid.* From :data:`F_MIN_HZ` to the Nyquist frequency ``1 / (2 dt)`` (25 Hz at
50 Hz; :data:`F_MAX_CONTINUOUS_HZ` for a continuous loop): :data:`N_FREQUENCIES` log-spaced
points, plus :data:`N_RESONANCE` points spread over ±8 half-power half-widths around the
damped frequency of every pole and zero of L with damping ratio below
:data:`RESONANCE_DAMPING` (a 0.5 % damped flex mode is 1 % wide; the log grid alone is
0.4 % per point), plus the exact frequencies of the margin table, so the markers sit on
the curves.

*Phase.* The phase is unwrapped along the grid (continuous curve, no ±180° jumps), then
shifted by a whole number of turns so that at the lowest-frequency gain crossover
(|L| = 0 dB, the rigid-body crossover; the lowest grid frequency when |L| never crosses
0 dB) it lies in (−360°, 0°]. The rigid-body phase margin is then the distance to the
critical point drawn at −180°; the other critical points −180° ± k·360° inside the plot
are drawn too (a flex-mode loop excursion may encircle one of them). Bode and Nichols use
the same phase.

*Nyquist.* L(e^{jωT}) for ω > 0 (solid) and its mirror image for ω < 0 (dashed), without
the indentation at ω = 0. Left: linear axes limited to the critical region
(:data:`NYQUIST_WINDOW`). Right: the whole curve on a compressed radius
r → log10(1 + r) at the true angle, which keeps the encirclements of −1 (drawn at radius
log10 2) while a low-frequency magnitude of 10⁴ stays on the page.

*Root locus.* The closed-loop poles for each gain k are ``control.feedback(k * L, 1).poles()``
(eigenvalues of the state-space closed loop), joined into branches by nearest
assignment between successive gains. :func:`control.root_locus_map` is not used: it roots
the transfer-function polynomial of L, whose coefficients cannot represent the 20–80
poles clustered near z = 1 of a 50-Hz loop (on a 58-state test loop it put closed-loop
poles at |z| = 2.1 for k = 1 when the eigenvalues are all inside |z| < 0.9997).

*Time responses.* Commands in rad and outputs in rad; drawn in deg per deg of command
(the system is linear). The discrete impulse is python-control's unit-area pulse (one
sample of 1/dt); the ramp is u = t.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import control as ct
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Rectangle
from matplotlib.ticker import MultipleLocator
from scipy.optimize import linear_sum_assignment

from savant_cli.io.atomic import atomic_path

__all__ = ["MarginRow", "plot_linear_point", "plot_margin_envelope", "point_tag"]

DPI = 120
_PNG_LEVEL = 3  # zlib level of the PNGs, as in plots/ascent.py

#: Lowest plotted frequency (Hz).
F_MIN_HZ = 0.01
#: Highest plotted frequency of a continuous-time loop (Hz); a discrete loop stops at 1/(2 dt).
F_MAX_CONTINUOUS_HZ = 25.0
#: Log-spaced points of the base frequency grid.
N_FREQUENCIES = 1500
#: Extra points around each lightly damped pole or zero of the loop.
N_RESONANCE = 25
#: Poles and zeros with a damping ratio below this get the extra points.
RESONANCE_DAMPING = 0.1
#: Gains k of the root locus 1 + k L = 0 (k = 1 is the nominal loop and is always included).
ROOT_LOCUS_GAINS = np.unique(np.concatenate([np.logspace(-2.0, 1.0, 49), [1.0]]))
#: Launch-vehicle rigid/aero exclusion zone around each critical point: ±dB, ±deg.
EXCLUSION_GAIN_DB = 6.0
EXCLUSION_PHASE_DEG = 30.0
#: (xmin, xmax, ymin, ymax) of the linear Nyquist panel.
NYQUIST_WINDOW = (-3.0, 1.5, -2.25, 2.25)
#: Magnitude range drawn on Bode and Nichols charts (dB); the rest is clipped.
DB_LIMITS = (-80.0, 80.0)
#: Duration of the closed-loop time responses (s).
RESPONSE_DURATION_S = 10.0

_AXIS_ORDER = ("pitch", "yaw")
_AXIS_COLORS = {"pitch": "C0", "yaw": "C1"}
_BAND_COLORS = {"rigid/aero": "C0", "slosh": "C2", "flex": "C3"}
_AXIS_MARKERS = {"pitch": "o", "yaw": "^"}
_GAIN_COLOR = "C3"   # phase crossover (where the gain margin is read)
_PHASE_COLOR = "C2"  # gain crossover (where the phase margin is read)
_CRITICAL_COLOR = "red"


@dataclass(frozen=True)
class MarginRow:
    """One stability margin of one loop at one operating point.

    Attributes
    ----------
    time_s : float
        Flight time of the operating point (s).
    axis : str
        Loop: ``"pitch"`` or ``"yaw"``.
    kind : str
        ``"gain"`` (gain margin, read at a phase crossover) or ``"phase"`` (phase margin,
        read at a gain crossover).
    value : float
        Gain margin in dB (negative: gain-reduction margin, as at the low-frequency
        crossover of an aerodynamically unstable vehicle) or phase margin in deg.
    frequency_hz : float
        Crossover frequency (Hz).
    band : str
        ``"rigid/aero"``, ``"slosh"`` or ``"flex"``.
    """

    time_s: float
    axis: str
    kind: str
    value: float
    frequency_hz: float
    band: str

    def __post_init__(self) -> None:
        if self.kind not in ("gain", "phase"):
            raise ValueError(f"MarginRow.kind must be 'gain' or 'phase', not {self.kind!r}")

    @property
    def unit(self) -> str:
        """``"dB"`` for a gain margin, ``"deg"`` for a phase margin."""
        return "dB" if self.kind == "gain" else "deg"

    def label(self) -> str:
        """Short text of the margin, e.g. ``"pitch GM -8.5 dB @ 0.125 Hz"``."""
        name = "GM" if self.kind == "gain" else "PM"
        unit = " dB" if self.kind == "gain" else "°"
        return f"{self.axis} {name} {self.value:.1f}{unit} @ {self.frequency_hz:.3g} Hz"


def point_tag(time_s: float) -> str:
    """File-name tag of an operating point: ``t055.0`` for 55 s, ``t123.4`` for 123.4 s."""
    return f"t{time_s:06.1f}"


# --------------------------------------------------------------------------- computation


@dataclass(frozen=True)
class _Loop:
    """Frequency response of one open loop on its grid."""

    axis: str
    f_hz: np.ndarray
    response: np.ndarray  # complex L(e^{jωT})
    mag_db: np.ndarray
    phase_deg: np.ndarray  # unwrapped and shifted (see module notes)


def _sorted_axes(names: Iterable[str]) -> list[str]:
    names = list(names)
    return [a for a in _AXIS_ORDER if a in names] + sorted(a for a in names if a not in _AXIS_ORDER)


def _color(axis: str, k: int) -> str:
    return _AXIS_COLORS.get(axis, f"C{k + 2}")


def _sample_time(sys: ct.LTI) -> float | None:
    """dt of a discrete system with a numeric sample time, else None."""
    dt = sys.dt
    if dt is None or dt is True or dt is False or not sys.isdtime():
        return None
    return float(dt)


def _f_max(sys: ct.LTI) -> float:
    dt = _sample_time(sys)
    return 0.5 / dt if dt else F_MAX_CONTINUOUS_HZ


def _s_plane(roots: np.ndarray, dt: float | None) -> np.ndarray:
    """Equivalent s-plane roots ln(z)/dt (1/s) of z-plane roots; roots at z = 0 become NaN."""
    roots = np.asarray(roots, dtype=complex)
    if dt is None:
        return roots
    out = np.full(roots.shape, np.nan + 0j)
    ok = np.isfinite(roots) & (np.abs(roots) > 1e-9)
    out[ok] = np.log(roots[ok]) / dt
    return out


def _frequency_grid(sys: ct.LTI, extra_hz: Iterable[float] = ()) -> np.ndarray:
    """Log grid from F_MIN_HZ to the Nyquist frequency, refined at resonances (Hz)."""
    f_hi = _f_max(sys)
    parts = [np.geomspace(F_MIN_HZ, f_hi, N_FREQUENCIES)]
    s = _s_plane(np.concatenate([sys.poles(), sys.zeros()]), _sample_time(sys))
    s = s[np.isfinite(s) & (np.abs(s.imag) > 0)]
    wn = np.abs(s)
    zeta = -s.real / np.maximum(wn, 1e-300)
    light = np.abs(zeta) < RESONANCE_DAMPING
    # sinh spacing: dense at the peak, reaching ±8 half-widths (ζ f_n) on either side
    u = np.sinh(np.linspace(-np.arcsinh(8.0), np.arcsinh(8.0), N_RESONANCE))
    for w, z, wd in zip(wn[light], zeta[light], np.abs(s.imag[light])):
        fd, half = wd / (2 * np.pi), max(abs(z), 1e-4) * w / (2 * np.pi)
        parts.append(fd + half * u)
    parts.append(np.asarray([f for f in extra_hz if np.isfinite(f)], dtype=float))
    f = np.concatenate(parts)
    f = np.clip(f, F_MIN_HZ, f_hi)
    return np.unique(f)


def _loop_response(axis: str, sys: ct.LTI, rows: Sequence[MarginRow]) -> _Loop:
    if not sys.issiso():
        raise ValueError(f"loop {axis!r} must be SISO, got {sys.ninputs} inputs and {sys.noutputs} outputs")
    f = _frequency_grid(sys, (r.frequency_hz for r in rows if r.axis == axis))
    resp = ct.frequency_response(sys, 2 * np.pi * f)
    f = np.asarray(resp.omega, dtype=float) / (2 * np.pi)
    h = np.asarray(resp.complex, dtype=complex).reshape(-1)
    with np.errstate(divide="ignore"):
        mag_db = 20.0 * np.log10(np.abs(h))
    phase = np.degrees(np.unwrap(np.angle(h)))
    sign = np.signbit(mag_db)
    cross = np.flatnonzero(sign[1:] != sign[:-1])
    anchor = int(cross[0]) if cross.size else 0
    # the whole number of turns putting the anchor phase in (−360°, 0°]
    phase = phase - 360.0 * math.ceil(phase[anchor] / 360.0)
    return _Loop(axis, f, h, mag_db, phase)


def _root_locus(sys: ct.LTI, gains: np.ndarray) -> np.ndarray:
    """Closed-loop poles of 1 + k L = 0, shape (gains, n), columns continuous branches."""
    loci = np.empty((len(gains), sys.nstates), dtype=complex)
    for i, k in enumerate(gains):
        p = np.asarray(ct.feedback(float(k) * sys, 1).poles(), dtype=complex)
        if i == 0:
            loci[0] = np.sort_complex(p)
            continue
        prev = loci[i - 1]
        _, col = linear_sum_assignment(np.abs(prev[:, None] - p[None, :]))
        loci[i] = p[col]
    return loci


def _margin_index(loop: _Loop, freq_hz: float) -> int | None:
    if not np.isfinite(freq_hz):
        return None
    return int(np.argmin(np.abs(loop.f_hz - np.clip(freq_hz, loop.f_hz[0], loop.f_hz[-1]))))


# --------------------------------------------------------------------------- drawing helpers


def _figure(width: float, height: float, left: float = 0.8, right: float = 0.25, bottom: float = 0.55,
            top: float = 0.6, wspace: float = 0.25, hspace: float = 0.2) -> Figure:
    """A figure on the Agg canvas with fixed margins in inches (no layout engine)."""
    fig = Figure(figsize=(width, height), dpi=DPI)
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=left / width, right=1.0 - right / width, bottom=bottom / height,
                        top=1.0 - top / height, wspace=wspace, hspace=hspace)
    return fig


def _title(fig: Figure, text: str, time_s: float | None, height: float) -> None:
    full = text if time_s is None else f"{text} at t = {time_s:.1f} s"
    fig.suptitle(full, fontsize=11, y=1.0 - 0.15 / height, va="top")


def _grid(ax) -> None:
    ax.grid(True, lw=0.4, alpha=0.6)


def _unit_circle(ax, radius: float = 1.0, label: str | None = "unit circle") -> None:
    ax.add_patch(Circle((0.0, 0.0), radius, fill=False, lw=0.8, ls="--", color="0.4", label=label))


def _save(fig: Figure, path: Path) -> Path:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI, pil_kwargs={"compress_level": _PNG_LEVEL})
    return path


def _critical_phases(lo: float, hi: float) -> list[float]:
    """Phases −180° + k·360° inside [lo, hi] (deg)."""
    k0, k1 = math.ceil((lo + 180.0) / 360.0), math.floor((hi + 180.0) / 360.0)
    return [-180.0 + 360.0 * k for k in range(k0, k1 + 1)]


def _db_limits(loops: Sequence[_Loop]) -> tuple[float, float]:
    finite = np.concatenate([lp.mag_db[np.isfinite(lp.mag_db)] for lp in loops] or [np.zeros(1)])
    lo = max(float(finite.min()), DB_LIMITS[0]) if finite.size else -20.0
    hi = min(float(finite.max()), DB_LIMITS[1]) if finite.size else 20.0
    lo, hi = min(lo, -EXCLUSION_GAIN_DB - 4.0), max(hi, EXCLUSION_GAIN_DB + 4.0)
    pad = 0.04 * (hi - lo)
    return lo - pad, hi + pad


def _phase_locator(span: float) -> MultipleLocator:
    return MultipleLocator(45.0 if span <= 450 else 90.0 if span <= 1080 else 180.0 if span <= 2160 else 360.0)


# --------------------------------------------------------------------------- figures


def _bode_figure(time_s: float, loops: Sequence[_Loop], margins: Sequence[MarginRow]) -> Figure:
    n = len(loops)
    width, height = 4.6 * n + 0.6, 6.2
    fig = _figure(width, height, left=0.85, bottom=0.95, top=0.55, wspace=0.28, hspace=0.08)
    axes = fig.subplots(2, n, sharex=True, squeeze=False)
    ylim_db = _db_limits(loops)
    for j, loop in enumerate(loops):
        ax_m, ax_p = axes[0, j], axes[1, j]
        color = _color(loop.axis, j)
        ax_m.semilogx(loop.f_hz, loop.mag_db, color=color, lw=1.0, label=f"{loop.axis} loop |L|")
        ax_p.semilogx(loop.f_hz, loop.phase_deg, color=color, lw=1.0, label=f"{loop.axis} loop ∠L")
        ax_m.axhline(0.0, color="0.3", lw=0.7)
        ax_m.set_ylim(*ylim_db)
        plo, phi = float(np.min(loop.phase_deg)), float(np.max(loop.phase_deg))
        pad = 0.05 * max(phi - plo, 90.0)
        ax_p.set_ylim(plo - pad, phi + pad)
        for c in _critical_phases(plo - pad, phi + pad):
            ax_p.axhline(c, color=_CRITICAL_COLOR, lw=0.7, ls="-", alpha=0.7)
        ax_p.yaxis.set_major_locator(_phase_locator(phi - plo))
        for row in margins:
            if row.axis != loop.axis or not np.isfinite(row.frequency_hz) or row.frequency_hz <= 0:
                continue
            style = dict(color=_GAIN_COLOR, ls="--") if row.kind == "gain" else dict(color=_PHASE_COLOR, ls=":")
            for ax in (ax_m, ax_p):
                ax.axvline(row.frequency_hz, lw=0.9, **style)
        ax_m.set_title(f"{loop.axis} loop (broken at the {loop.axis} actuator command)", fontsize=9)
        ax_m.set_ylabel("magnitude |L| (dB)", fontsize=9)
        ax_p.set_ylabel("phase ∠L (deg)", fontsize=9)
        ax_p.set_xlabel("frequency (Hz)", fontsize=9)
        ax_p.set_xlim(loop.f_hz[0], loop.f_hz[-1])
        for ax in (ax_m, ax_p):
            _grid(ax)
            ax.tick_params(labelsize=8)
    handles = [Line2D([], [], color=_color(lp.axis, j), lw=1.0, label=f"{lp.axis} open loop L") for j, lp in enumerate(loops)]
    handles += [Line2D([], [], color=_GAIN_COLOR, ls="--", lw=0.9, label="phase crossover (gain margin)"),
                Line2D([], [], color=_PHASE_COLOR, ls=":", lw=0.9, label="gain crossover (phase margin)"),
                Line2D([], [], color=_CRITICAL_COLOR, lw=0.7, label="−180° (mod 360°)")]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    _title(fig, "Open-loop Bode diagrams", time_s, height)
    return fig


def _nichols_figure(time_s: float, loops: Sequence[_Loop], margins: Sequence[MarginRow],
                    exclusion_zones: bool = True) -> Figure:
    width, height = 8.4, 6.6
    fig = _figure(width, height, left=0.8, bottom=0.6, top=0.55)
    ax = fig.add_subplot(1, 1, 1)
    ylo, yhi = _db_limits(loops)
    # phase range: the part of each curve inside the drawn magnitudes, and (−360°, 0°]
    xs = [-360.0, 0.0]
    for lp in loops:
        inside = (lp.mag_db >= ylo) & (lp.mag_db <= yhi)
        if inside.any():
            xs += [float(lp.phase_deg[inside].min()), float(lp.phase_deg[inside].max())]
    xlo, xhi = min(xs), max(xs)
    pad = 0.03 * (xhi - xlo)
    xlo, xhi = xlo - pad, xhi + pad
    for j, lp in enumerate(loops):
        ax.plot(lp.phase_deg, lp.mag_db, color=_color(lp.axis, j), lw=1.0, label=f"{lp.axis} open loop L")
    crit = _critical_phases(xlo, xhi)
    ax.plot(crit, np.zeros(len(crit)), ls="none", marker="P", ms=9, color=_CRITICAL_COLOR,
            label="critical point L = −1 (0 dB, −180° mod 360°)", zorder=5)
    if exclusion_zones:
        for k, c in enumerate(crit):
            ax.add_patch(Rectangle((c - EXCLUSION_PHASE_DEG, -EXCLUSION_GAIN_DB), 2 * EXCLUSION_PHASE_DEG,
                                   2 * EXCLUSION_GAIN_DB, facecolor=_CRITICAL_COLOR, alpha=0.12,
                                   edgecolor=_CRITICAL_COLOR, lw=0.8, zorder=1,
                                   label=(f"rigid/aero exclusion zone ±{EXCLUSION_GAIN_DB:g} dB, "
                                          f"±{EXCLUSION_PHASE_DEG:g}°") if k == 0 else None))
    by_axis = {lp.axis: lp for lp in loops}
    offsets = ((14, 16), (14, -22), (-120, 16), (-120, -22), (20, 34), (-130, -40))
    count = 0
    for row in margins:
        lp = by_axis.get(row.axis)
        i = None if lp is None else _margin_index(lp, row.frequency_hz)
        if i is None or not np.isfinite(row.value):
            continue
        x, y = float(lp.phase_deg[i]), float(np.clip(lp.mag_db[i], ylo, yhi))
        is_gain = row.kind == "gain"
        ax.plot([x], [y], ls="none", marker="s" if is_gain else "D", ms=5, mfc="none",
                mec=_GAIN_COLOR if is_gain else _PHASE_COLOR, mew=1.2, zorder=6)
        ax.annotate(row.label(), (x, y), xytext=offsets[count % len(offsets)], textcoords="offset points",
                    fontsize=7, color="0.1",
                    bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.7", "pad": 1.0, "lw": 0.5},
                    arrowprops={"arrowstyle": "-", "lw": 0.6, "color": "0.4"}, annotation_clip=False, zorder=7)
        count += 1
    handles, _ = ax.get_legend_handles_labels()
    handles += [Line2D([], [], ls="none", marker="s", mfc="none", mec=_GAIN_COLOR, mew=1.2,
                       label="gain margin (at phase crossover)"),
                Line2D([], [], ls="none", marker="D", mfc="none", mec=_PHASE_COLOR, mew=1.2,
                       label="phase margin (at gain crossover)")]
    ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlim(xlo, xhi)
    ax.set_ylim(ylo, yhi)
    ax.xaxis.set_major_locator(_phase_locator(xhi - xlo))
    ax.set_xlabel("open-loop phase ∠L (deg; unwrapped, critical point of the rigid-body crossover at −180°)",
                  fontsize=9)
    ax.set_ylabel("open-loop gain |L| (dB)", fontsize=9)
    ax.tick_params(labelsize=8)
    _grid(ax)
    _title(fig, "Nichols chart", time_s, height)
    return fig


def _nyquist_figure(time_s: float, loops: Sequence[_Loop]) -> Figure:
    width, height = 11.0, 5.9
    fig = _figure(width, height, left=0.75, bottom=0.6, top=0.6, wspace=0.22)
    ax_lin, ax_log = fig.subplots(1, 2)
    for j, lp in enumerate(loops):
        color = _color(lp.axis, j)
        h = lp.response
        ax_lin.plot(h.real, h.imag, color=color, lw=1.0, label=f"{lp.axis} L, ω > 0")
        ax_lin.plot(h.real, -h.imag, color=color, lw=0.6, ls="--", label=f"{lp.axis} L, ω < 0")
        r = np.log10(1.0 + np.abs(h))
        ang = np.angle(h)
        ax_log.plot(r * np.cos(ang), r * np.sin(ang), color=color, lw=1.0, label=f"{lp.axis} L, ω > 0")
        ax_log.plot(r * np.cos(ang), -r * np.sin(ang), color=color, lw=0.6, ls="--", label=f"{lp.axis} L, ω < 0")
        # direction of increasing frequency
        k = int(np.searchsorted(lp.f_hz, 0.3 * lp.f_hz[-1]))
        k = min(max(k, 1), len(h) - 1)
        ax_log.annotate("", xy=(r[k] * np.cos(ang[k]), r[k] * np.sin(ang[k])),
                        xytext=(r[k - 1] * np.cos(ang[k - 1]), r[k - 1] * np.sin(ang[k - 1])),
                        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.0})
    x0, x1, y0, y1 = NYQUIST_WINDOW
    _unit_circle(ax_lin)
    ax_lin.plot([-1.0], [0.0], ls="none", marker="P", ms=9, color=_CRITICAL_COLOR, label="critical point −1", zorder=5)
    ax_lin.set_xlim(x0, x1)
    ax_lin.set_ylim(y0, y1)
    ax_lin.set_title("critical region (linear axes)", fontsize=9)
    ax_lin.set_xlabel("Re L (–)", fontsize=9)
    ax_lin.set_ylabel("Im L (–)", fontsize=9)
    rmax = max([float(np.log10(1.0 + np.max(np.abs(lp.response)))) for lp in loops] + [1.0])
    for decade in range(0, int(math.ceil(rmax)) + 1):
        rr = math.log10(1.0 + 10.0 ** decade)
        if rr <= rmax * 1.05:
            ax_log.add_patch(Circle((0.0, 0.0), rr, fill=False, lw=0.5, ls=":", color="0.6"))
            ax_log.text(rr * 0.707, rr * 0.707, f"|L|={10 ** decade:g}", fontsize=6, color="0.45")
    _unit_circle(ax_log, math.log10(2.0), label="|L| = 1")
    ax_log.plot([-math.log10(2.0)], [0.0], ls="none", marker="P", ms=9, color=_CRITICAL_COLOR,
                label="critical point −1", zorder=5)
    lim = 1.08 * rmax
    ax_log.set_xlim(-lim, lim)
    ax_log.set_ylim(-lim, lim)
    ax_log.set_title("whole curve, compressed radius log10(1 + |L|)", fontsize=9)
    ax_log.set_xlabel("log10(1 + |L|) · cos ∠L (–)", fontsize=9)
    ax_log.set_ylabel("log10(1 + |L|) · sin ∠L (–)", fontsize=9)
    for ax in (ax_lin, ax_log):
        ax.set_aspect("equal", adjustable="box")
        ax.axhline(0.0, color="0.3", lw=0.5)
        ax.axvline(0.0, color="0.3", lw=0.5)
        ax.tick_params(labelsize=8)
        _grid(ax)
    ax_lin.legend(loc="upper left", fontsize=7, framealpha=0.85)
    _title(fig, "Nyquist diagrams of the open loops", time_s, height)
    return fig


def _root_locus_figure(time_s: float, systems: Mapping[str, ct.LTI], gains: np.ndarray = ROOT_LOCUS_GAINS) -> Figure:
    names = _sorted_axes(systems)
    n = len(names)
    width, height = 4.3 * n + 0.6, 9.0
    fig = _figure(width, height, left=0.8, bottom=0.95, top=0.6, wspace=0.3, hspace=0.28)
    axes = fig.subplots(2, n, squeeze=False)
    gains = np.asarray(gains, dtype=float)
    k1 = int(np.argmin(np.abs(gains - 1.0)))
    for j, name in enumerate(names):
        sys = systems[name]
        discrete = _sample_time(sys) is not None
        loci = _root_locus(sys, gains)
        poles, zeros = sys.poles(), sys.zeros()
        closed = loci[k1]
        for row, ax in enumerate(axes[:, j]):
            ax.plot(loci.real, loci.imag, color="0.55", lw=0.6)
            ax.plot(poles.real, poles.imag, ls="none", marker="x", ms=6, mew=1.2, color="C0", label="open-loop poles")
            ax.plot(zeros.real, zeros.imag, ls="none", marker="o", ms=5, mfc="none", mew=1.0, color="C2",
                    label="open-loop zeros")
            ax.plot(closed.real, closed.imag, ls="none", marker="s", ms=4, color=_CRITICAL_COLOR,
                    label="closed-loop poles, k = 1")
            ax.axhline(0.0, color="0.3", lw=0.5)
            ax.axvline(0.0, color="0.3", lw=0.5)
            if discrete:
                _unit_circle(ax)
            ax.set_aspect("equal", adjustable="datalim" if row else "box")
            ax.tick_params(labelsize=8)
            _grid(ax)
            ax.set_xlabel("Re z (–)" if discrete else "Re s (1/s)", fontsize=9)
            ax.set_ylabel("Im z (–)" if discrete else "Im s (rad/s)", fontsize=9)
        top, zoom = axes[0, j], axes[1, j]
        if discrete:
            top.set_xlim(-1.35, 1.35)
            top.set_ylim(-1.35, 1.35)
            zoom.set_xlim(0.84, 1.06)
            zoom.set_ylim(-0.13, 0.13)
            zoom.set_title(f"{name}: zoom near z = 1 (modes below ≈ 1 Hz)", fontsize=9)
        else:
            finite = np.concatenate([poles, closed])
            finite = finite[np.isfinite(finite)]
            span = max(float(np.max(np.abs(finite))) if finite.size else 1.0, 1.0)
            top.set_xlim(-1.1 * span, 0.3 * span)
            top.set_ylim(-1.1 * span, 1.1 * span)
            zoom.set_xlim(-5.0, 2.0)
            zoom.set_ylim(-7.0, 7.0)
            zoom.set_title(f"{name}: zoom near s = 0", fontsize=9)
        top.set_title(f"{name} loop, 1 + k L = 0, k = {gains[0]:.3g} … {gains[-1]:.3g}", fontsize=9)
    handles, _ = axes[0, 0].get_legend_handles_labels()
    handles.insert(0, Line2D([], [], color="0.55", lw=0.6, label="root locus branches"))
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    _title(fig, "Root locus" + (" in the z-plane" if all(_sample_time(s) for s in systems.values()) else ""),
           time_s, height)
    return fig


def _closed_zeros(closed: ct.StateSpace, outputs: Sequence[str], inputs: Sequence[str]) -> tuple[np.ndarray, str]:
    """Transmission zeros of the square block commands → attitudes (python-control without
    slycot has no zeros of a non-square system)."""
    oi = [closed.find_output(o) for o in outputs]
    ii = [closed.find_input(i) for i in inputs]
    oi, ii = [k for k in oi if k is not None], [k for k in ii if k is not None]
    if oi and len(oi) == len(ii):
        try:
            z = np.asarray(closed[oi, ii].zeros(), dtype=complex)
            names = ", ".join(closed.input_labels[k] for k in ii)
            return z[np.isfinite(z)], f"transmission zeros ({names} → attitudes)"
        except (NotImplementedError, ValueError, np.linalg.LinAlgError):
            pass
    try:
        z = np.asarray(closed.zeros(), dtype=complex)
        return z[np.isfinite(z)], "transmission zeros"
    except (NotImplementedError, ValueError, np.linalg.LinAlgError):
        return np.zeros(0, dtype=complex), "zeros (not computed)"


def _pzmap_figure(time_s: float, closed: ct.StateSpace) -> Figure:
    width, height = 11.0, 5.9
    fig = _figure(width, height, left=0.75, bottom=0.95, top=0.6, wspace=0.25)
    ax_z, ax_s = fig.subplots(1, 2)
    dt = _sample_time(closed)
    poles = np.asarray(closed.poles(), dtype=complex)
    commands = [c for c in ("pitch_command", "yaw_command") if c in closed.input_labels] or list(closed.input_labels)
    attitudes = [c.replace("_command", "_attitude") for c in commands]
    zeros, zlabel = _closed_zeros(closed, attitudes, commands)
    unstable = np.abs(poles) >= 1.0 if dt else poles.real >= 0.0
    if dt:
        sp, sz = _s_plane(poles, dt), _s_plane(zeros, dt)
        ax_z.plot(zeros.real, zeros.imag, ls="none", marker="o", ms=5, mfc="none", color="C2", label=zlabel)
        ax_z.plot(poles[~unstable].real, poles[~unstable].imag, ls="none", marker="x", ms=6, mew=1.2, color="C0",
                  label="poles, |z| < 1")
        ax_z.plot(poles[unstable].real, poles[unstable].imag, ls="none", marker="x", ms=7, mew=1.6,
                  color=_CRITICAL_COLOR, label="poles, |z| ≥ 1 (unstable)")
        _unit_circle(ax_z)
        ax_z.set_xlim(-1.35, 1.35)
        ax_z.set_ylim(-1.35, 1.35)
        ax_z.set_aspect("equal", adjustable="box")
        ax_z.set_xlabel("Re z (–)", fontsize=9)
        ax_z.set_ylabel("Im z (–)", fontsize=9)
        ax_z.set_title(f"z-plane (dt = {dt:g} s)", fontsize=9)
    else:
        sp, sz = poles, zeros
        ax_z.set_visible(False)
    at_origin = int(np.count_nonzero(~np.isfinite(sp)))
    ok_p, ok_z = np.isfinite(sp), np.isfinite(sz)
    ax_s.plot(sz[ok_z].real, sz[ok_z].imag / (2 * np.pi), ls="none", marker="o", ms=5, mfc="none", color="C2",
              label=zlabel)
    ax_s.plot(sp[ok_p & ~unstable].real, sp[ok_p & ~unstable].imag / (2 * np.pi), ls="none", marker="x", ms=6,
              mew=1.2, color="C0", label="poles, stable" + (f" ({at_origin} at z = 0 not shown)" if at_origin else ""))
    ax_s.plot(sp[ok_p & unstable].real, sp[ok_p & unstable].imag / (2 * np.pi), ls="none", marker="x", ms=7,
              mew=1.6, color=_CRITICAL_COLOR, label="poles, unstable")
    ax_s.axvline(0.0, color="0.3", lw=0.6)
    ax_s.axhline(0.0, color="0.3", lw=0.5)
    ax_s.set_xscale("symlog", linthresh=1.0)
    if dt:
        ny = 0.5 / dt
        ax_s.set_ylim(-1.05 * ny, 1.05 * ny)
        for y in (-ny, ny):
            ax_s.axhline(y, color="0.5", lw=0.6, ls="--")
    ax_s.set_xlabel("Re s (1/s, symmetric log scale)", fontsize=9)
    ax_s.set_ylabel("Im s / 2π (Hz)", fontsize=9)
    ax_s.set_title("equivalent s-plane, s = ln(z)/dt" if dt else "s-plane", fontsize=9)
    for ax in (ax_z, ax_s):
        ax.tick_params(labelsize=8)
        _grid(ax)
    handles, _ = ax_s.get_legend_handles_labels()
    handles.append(Line2D([], [], color="0.4", ls="--", lw=0.8, label="unit circle / Nyquist frequency"))
    fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=8, frameon=False)
    _title(fig, "Closed-loop poles and zeros", time_s, height)
    return fig


def _response_figure(time_s: float, closed: ct.StateSpace, duration_s: float = RESPONSE_DURATION_S) -> Figure:
    dt = _sample_time(closed)
    step_t = dt if dt else duration_s / 1000.0
    t = np.arange(0.0, duration_s + 0.5 * step_t, step_t)
    commands = [c for c in ("pitch_command", "yaw_command") if c in closed.input_labels] or list(closed.input_labels)
    cmd_idx = [closed.find_input(c) for c in commands]
    wanted = [o for o in ("pitch_attitude", "pitch_gimbal", "yaw_attitude", "yaw_gimbal") if o in closed.output_labels]
    outputs = wanted or list(closed.output_labels)
    out_idx = [closed.find_output(o) for o in outputs]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        step = np.asarray(ct.step_response(closed, t).outputs).reshape(closed.noutputs, closed.ninputs, -1)
        impulse = np.asarray(ct.impulse_response(closed, t).outputs).reshape(closed.noutputs, closed.ninputs, -1)
        ramp = np.empty((closed.noutputs, closed.ninputs, t.size))
        for i in cmd_idx:
            u = np.zeros((closed.ninputs, t.size))
            u[i] = t
            ramp[:, i, :] = np.asarray(ct.forced_response(closed, t, u).outputs).reshape(closed.noutputs, -1)
    kinds = (("step", step, "response to a 1° step (deg)", np.ones_like(t)),
             ("impulse", impulse, "response to a unit-area\n1°·s pulse (deg)", None),
             ("ramp", ramp, "response to a 1°/s ramp (deg)", t))
    n = len(commands)
    width, height = 4.6 * n + 0.7, 8.2
    fig = _figure(width, height, left=1.05, bottom=1.05, top=0.6, wspace=0.25, hspace=0.12)
    axes = fig.subplots(3, n, sharex=True, squeeze=False)
    for col, (cmd, i) in enumerate(zip(commands, cmd_idx)):
        own = cmd.removesuffix("_command")
        for row, (kind, data, ylabel, reference) in enumerate(kinds):
            ax = axes[row, col]
            if reference is not None:
                ax.plot(t, reference, color="0.5", lw=0.8, ls="--", label="command")
            for name, k in zip(outputs, out_idx):
                axis, _, what = name.partition("_")
                mine = axis == own
                color = {("attitude", True): "C0", ("gimbal", True): "C1",
                         ("attitude", False): "C2", ("gimbal", False): "C3"}.get((what, mine), "C4")
                ax.plot(t, data[k, i], lw=1.1 if mine else 0.7, ls="-" if mine else ":", color=color,
                        label=f"{'own' if mine else 'cross'}-axis {what}" if wanted else name)
            ax.axhline(0.0, color="0.3", lw=0.5)
            _grid(ax)
            ax.tick_params(labelsize=8)
            if col == 0:
                ax.set_ylabel(ylabel, fontsize=9)
            if row == 0:
                ax.set_title(f"to {cmd.replace('_', ' ')}", fontsize=9)
            ax.text(0.01, 0.96, kind, transform=ax.transAxes, fontsize=8, va="top", ha="left", color="0.3")
        axes[-1, col].set_xlabel("time after the command (s)", fontsize=9)
        axes[-1, col].set_xlim(0.0, duration_s)
    handles, _ = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 5), fontsize=8, frameon=False)
    _title(fig, "Closed-loop attitude and gimbal responses", time_s, height)
    return fig


def _envelope_figure(rows: Sequence[MarginRow], requirements: Mapping[str, tuple[float, float]] | None) -> Figure:
    width, height = 9.0, 7.2
    fig = _figure(width, height, left=0.85, right=2.3, bottom=0.6, top=0.55, hspace=0.1)
    ax_g, ax_p = fig.subplots(2, 1, sharex=True)
    requirements = dict(requirements or {})
    axes_names = _sorted_axes({r.axis for r in rows})
    bands = list(_BAND_COLORS) + sorted({r.band for r in rows} - set(_BAND_COLORS))
    handles: list[Line2D] = []
    violating = False
    for band in bands:
        color = _BAND_COLORS.get(band, f"C{4 + bands.index(band)}")
        for axis in axes_names:
            sel = [r for r in rows if r.band == band and r.axis == axis and np.isfinite(r.value)]
            if not sel:
                continue
            marker = _AXIS_MARKERS.get(axis, "s")
            for ax, kind in ((ax_g, "gain"), (ax_p, "phase")):
                pts = [r for r in sel if r.kind == kind]
                if not pts:
                    continue
                req = requirements.get(band)
                bad = np.zeros(len(pts), dtype=bool)
                if req is not None:
                    v = np.array([r.value for r in pts])
                    bad = np.abs(v) < req[0] if kind == "gain" else v < req[1]
                violating |= bool(bad.any())
                ax.scatter([r.time_s for r in pts], [r.value for r in pts], s=22, marker=marker, color=color,
                           edgecolors=np.where(bad, _CRITICAL_COLOR, color), linewidths=np.where(bad, 1.4, 0.5),
                           zorder=3)
            handles.append(Line2D([], [], ls="none", marker=marker, color=color, label=f"{band}, {axis}"))
    # requirement lines, one per distinct (gain, phase) pair
    groups: dict[tuple[float, float], list[str]] = {}
    for band, req in requirements.items():
        groups.setdefault((float(req[0]), float(req[1])), []).append(band)
    for k, ((g, p), names) in enumerate(groups.items()):
        color = "0.15" if len(groups) == 1 else _BAND_COLORS.get(names[0], f"C{4 + k}")
        ls = ("--", "-.", ":", (0, (5, 1, 1, 1)))[k % 4]
        ax_g.axhline(g, color=color, lw=1.0, ls=ls)
        ax_g.axhline(-g, color=color, lw=1.0, ls=ls)
        ax_p.axhline(p, color=color, lw=1.0, ls=ls)
        handles.append(Line2D([], [], color=color, lw=1.0, ls=ls,
                              label=f"requirement {', '.join(names)}: ±{g:g} dB, {p:g}°"))
    if violating:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="white", mec=_CRITICAL_COLOR, mew=1.4,
                              label="below requirement"))
    ax_g.axhline(0.0, color="0.3", lw=0.6)
    ax_p.axhline(0.0, color="0.3", lw=0.6)
    ax_g.set_ylabel("gain margin (dB)\n(negative: gain reduction)", fontsize=9)
    ax_p.set_ylabel("phase margin (deg)", fontsize=9)
    ax_p.set_xlabel("flight time of the operating point (s)", fontsize=9)
    for ax in (ax_g, ax_p):
        _grid(ax)
        ax.tick_params(labelsize=8)
    fig.legend(handles=handles, loc="center right", fontsize=8, frameon=False)
    times = [r.time_s for r in rows]
    span = f" ({min(times):.1f}–{max(times):.1f} s)" if times else ""
    _title(fig, f"Stability margins vs flight time{span}", None, height)
    return fig


# --------------------------------------------------------------------------- public API


def plot_linear_point(time_s: float, loops: dict[str, ct.StateSpace], closed: ct.StateSpace,
                      margins: list[MarginRow], out_dir: Path, exclusion_zones: bool = True) -> list[Path]:
    """Draw the six frequency- and time-domain charts of one operating point.

    Parameters
    ----------
    time_s : float
        Flight time of the operating point (s); in the titles and, as ``f"t{time_s:06.1f}"``,
        in the file names.
    loops : dict of str to control.StateSpace
        SISO open loop of each axis (``"pitch"``, ``"yaw"``), broken at that axis's actuator
        command (rad → rad) with the other axis closed, sign such that the closed loop is
        L / (1 + L). Normally discrete (dt = 0.02 s); a continuous loop is drawn to
        :data:`F_MAX_CONTINUOUS_HZ`.
    closed : control.StateSpace
        Closed loop with inputs ``pitch_command``, ``yaw_command`` (attitude commands, rad)
        and outputs including ``pitch_attitude``, ``yaw_attitude``, ``pitch_gimbal``,
        ``yaw_gimbal`` (rad); missing names are skipped.
    margins : list of MarginRow
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
        If ``loops`` is empty or a loop is not SISO.

    Notes
    -----
    Frequencies in Hz, magnitudes in dB, phases in deg (unwrapped; the shift convention
    is in the module notes), time in s. See the module docstring for the frequency grid,
    the Nyquist radius compression and the root-locus method.
    """
    if not loops:
        raise ValueError("plot_linear_point needs at least one loop")
    out_dir = Path(out_dir)
    tag = point_tag(time_s)
    names = _sorted_axes(loops)
    responses = [_loop_response(a, loops[a], margins) for a in names]
    figures = (
        (f"bode_{tag}.png", lambda: _bode_figure(time_s, responses, margins)),
        (f"nichols_{tag}.png", lambda: _nichols_figure(time_s, responses, margins, exclusion_zones)),
        (f"nyquist_{tag}.png", lambda: _nyquist_figure(time_s, responses)),
        (f"rootlocus_{tag}.png", lambda: _root_locus_figure(time_s, {a: loops[a] for a in names})),
        (f"pzmap_{tag}.png", lambda: _pzmap_figure(time_s, closed)),
        (f"response_{tag}.png", lambda: _response_figure(time_s, closed)),
    )
    return [_save(build(), out_dir / filename) for filename, build in figures]


def plot_margin_envelope(rows: list[MarginRow], out_path: Path,
                         requirements: dict[str, tuple[float, float]] | None = None) -> Path:
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
        ±gain (a gain-reduction margin must be below −gain) and at +phase; points of a band
        inside its requirement get a red edge.

    Returns
    -------
    pathlib.Path
        ``out_path``.

    Notes
    -----
    Top panel: gain margins (dB); bottom panel: phase margins (deg); colour = band
    (rigid/aero, slosh, flex), marker = axis (pitch ○, yaw △).
    """
    return _save(_envelope_figure(rows, requirements), Path(out_path))
