"""Every gain and phase margin of a broken loop, labelled by frequency band, plus disk
margins and the closed-loop bandwidth.

Crossings are bracketed on a grid that is logarithmic from 0.01 Hz to the Nyquist
frequency and refined around every lightly damped pole of the loop (``± 5ζω`` in 21
points), so crossings of flex and slosh resonances are resolved, then refined by Brent's
method on the exact response (:mod:`savant_cli.linear.response`). This is
:func:`control.stability_margins`' FRD method with exact evaluation in place of its
spline (which evaluates point by point and took 0.1 s per loop); the polynomial method is
not used (it is numerically meaningless for loops of 50–100 states). The tests check
both against ``control``'s routines.

Labels: the studies name each crossing by the mode that makes it
(:mod:`savant_cli.linear.modes`); without a labeler, :class:`Bands` gives the band by
frequency (``flex`` from 0.7 × the lowest retained bending frequency, ``slosh`` within a
factor 2 of the slosh frequencies, ``rigid/aero`` otherwise). A gain margin below 0 dB is
a gain-reduction margin.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np
from scipy.optimize import brentq
from slycot import ab13md

from savant_cli.linear.response import FastResponse

F_MIN_HZ = 0.01
N_BASE = 700


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
        ``"gain"`` (read at a phase crossover) or ``"phase"`` (read at a gain crossover).
    value : float
        Gain margin in dB (negative: the gain-reduction margin of an aerodynamically
        unstable vehicle) or phase margin in deg.
    frequency_hz : float
        Crossover frequency (Hz).
    band : str
        The requirement band: ``"rigid/aero"``, ``"slosh"`` or ``"flex"``.
    mode : str
        The open-loop mode that makes the crossing (``rigid``, ``aero``, ``integrator``,
        ``slosh_<tank>``, ``flex_<n>``; :mod:`savant_cli.linear.modes`), or
        ``""`` when labelled by frequency band alone.
    meets_requirement : bool or None
        Its verdict against the requirement set (:mod:`savant_cli.linear.requirements`),
        ``None`` when not judged.
    """

    time_s: float
    axis: str
    kind: str
    value: float
    frequency_hz: float
    band: str
    mode: str = ""
    meets_requirement: bool | None = None

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


@dataclass(frozen=True)
class Bands:
    """Frequency bands of the point (Hz); ``None`` when the model is off."""

    flex_from_hz: float | None = None
    slosh_hz: tuple[float, float] | None = None

    def label(self, f_hz: float) -> str:
        if self.flex_from_hz is not None and f_hz >= self.flex_from_hz:
            return "flex"
        if self.slosh_hz is not None and self.slosh_hz[0] / 2.0 <= f_hz <= self.slosh_hz[1] * 2.0:
            return "slosh"
        return "rigid/aero"


def frequency_grid(sys: ct.StateSpace, poles: np.ndarray | None = None) -> np.ndarray:
    """rad/s grid for a discrete loop: log-spaced, refined around lightly damped poles
    (``poles``: the eigenvalues of ``sys.A`` when already at hand)."""
    w_nyq = np.pi / sys.dt
    w = [np.logspace(np.log10(2 * np.pi * F_MIN_HZ), np.log10(w_nyq), N_BASE)]
    z = sys.poles() if poles is None else poles
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(np.asarray(z, dtype=complex)) / sys.dt
    for pole in s:
        wn = abs(pole)
        if not np.isfinite(wn) or wn < 2 * np.pi * F_MIN_HZ or wn >= w_nyq or pole.imag <= 0:
            continue
        zeta = max(-pole.real / wn, 1e-4)
        if zeta < 0.3:
            w.append(wn * (1.0 + np.linspace(-5.0, 5.0, 21) * zeta))
    grid = np.unique(np.concatenate(w))
    return grid[(grid > 0) & (grid < w_nyq)]


def _grid_and_response(sys: ct.StateSpace, response: FastResponse | None) -> tuple[np.ndarray, FastResponse]:
    fr = FastResponse(sys) if response is None else response
    return frequency_grid(sys, fr.poles), fr


def _roots(fun, w: np.ndarray, values: np.ndarray) -> list[float]:
    """Every root of ``fun`` bracketed by a sign change of ``values`` on the grid ``w``."""
    positive = values >= 0.0
    roots = []
    for i in np.nonzero(positive[1:] != positive[:-1])[0]:
        fa, fb = fun(w[i]), fun(w[i + 1])
        if fa * fb > 0.0:  # a grazing crossing lost in round-off: the nearer grid point
            roots.append(float(w[i] if abs(fa) < abs(fb) else w[i + 1]))
        else:
            roots.append(brentq(fun, w[i], w[i + 1], xtol=1e-12 * w[i], rtol=4 * np.finfo(float).eps))
    return roots


def loop_margins(loop: ct.StateSpace, time_s: float, axis: str, bands: Bands | None = None,
                 response: FastResponse | None = None, labeler=None) -> list[MarginRow]:
    """All gain and phase crossings of one SISO loop (negative-feedback convention).

    Crossings are bracketed on :func:`frequency_grid` and refined by Brent's method on
    the exact response; gain margin ``1/|L|`` where ``L`` crosses the negative real
    axis, phase margin ``∠L mod 360° − 180°`` where ``|L| = 1`` (the definitions of
    :func:`control.stability_margins`, against which the tests check these).
    ``response``: the loop's :class:`FastResponse` when already built; ``labeler``: a
    :class:`savant_cli.linear.modes.MarginLabeler` of the loop, which names each
    crossing's mode and band (else ``bands``, default ``Bands()``, gives the band by
    frequency)."""
    bands = bands or Bands()
    w, fr = _grid_and_response(loop, response)
    h = fr.siso(w)
    rows = []

    def row(kind: str, value: float, f: float) -> MarginRow:
        if labeler is None:
            return MarginRow(time_s, axis, kind, value, f, bands.label(f))
        mode, band = labeler.label(f, kind, value)
        return MarginRow(time_s, axis, kind, value, f, band, mode)

    for wp in _roots(lambda x: float(fr.siso(x)[0].imag), w, h.imag):
        hp = fr.siso(wp)[0]
        if hp.real < 0.0:
            f = wp / (2 * np.pi)
            rows.append(row("gain", float(-20 * np.log10(abs(hp))), f))
    for wg in _roots(lambda x: float(abs(fr.siso(x)[0]) - 1.0), w, np.abs(h) - 1.0):
        pm = float(np.remainder(np.angle(fr.siso(wg)[0], deg=True), 360.0) - 180.0)
        f = wg / (2 * np.pi)
        rows.append(row("phase", pm, f))
    return sorted(rows, key=lambda r: (r.kind, r.frequency_hz))


def _disk_values(alpha: float) -> dict[str, float]:
    """Balanced (skew 0) disk: its gain and phase variations from the disk margin α."""
    if alpha >= 2.0:
        return {"disk_margin": alpha, "disk_gain_margin_dB": float("inf"), "disk_phase_margin_deg": 90.0}
    g_min, g_max = (1.0 - alpha / 2.0) / (1.0 + alpha / 2.0), (1.0 + alpha / 2.0) / (1.0 - alpha / 2.0)
    return {"disk_margin": alpha, "disk_gain_margin_dB": float(20 * np.log10(g_max)),
            "disk_phase_margin_deg": float(np.degrees(np.arccos((1.0 + g_min * g_max) / (g_min + g_max))))}


def disk_margins(loop: ct.StateSpace, response: FastResponse | None = None) -> dict[str, float]:
    """Balanced (skew 0) disk margin of a SISO or MIMO loop: disk margin α, and the
    simultaneous gain (dB) and phase (deg) variations it guarantees.

    α = 1 / max_ω μ(S − I/2), S = (I + L)⁻¹, on :func:`frequency_grid`, with μ the
    structured singular value for one independent complex gain per loop: |S − ½| for a
    SISO loop, the upper bound of slycot ``ab13md`` (as :func:`control.disk_margins`)
    for a MIMO one. As μ ≤ σ̄, frequencies are taken in falling order of σ̄(S − I/2) and
    the search stops once σ̄ is below the largest μ found, which gives the whole grid's
    maximum with a handful of ``ab13md`` calls. ``response``: the loop's
    :class:`FastResponse` when already built."""
    w, fr = _grid_and_response(loop, response)
    n = loop.ninputs
    h = np.moveaxis(fr(w), 2, 0)  # (n_w, n, n)
    st = np.linalg.inv(np.eye(n) + h) - 0.5 * np.eye(n)
    sigma = np.linalg.svd(st, compute_uv=False)[:, 0]
    if n == 1:
        return _disk_values(float(1.0 / sigma.max()))
    mu_max = 0.0
    for k in np.argsort(sigma)[::-1]:
        if sigma[k] <= mu_max:
            break
        mu_max = max(mu_max, float(ab13md(st[k], np.ones(n, dtype=int), np.full(n, 2, dtype=int))[0]))
    return _disk_values(1.0 / mu_max)


def bandwidth_hz(closed_siso: ct.StateSpace) -> float:
    """−3 dB bandwidth (Hz) of a closed-loop command response, from its frequency
    response (the first frequency where the gain falls 3 dB below its low-frequency
    value); NaN if it never does below the Nyquist frequency. ``control.bandwidth``
    brackets the root from the DC gain and fails on these discrete loops, hence this."""
    w, fr = _grid_and_response(closed_siso, None)
    mag = np.abs(fr.siso(w))
    ref = mag[0]
    below = np.nonzero(mag < ref * 10 ** (-3 / 20))[0]
    return float(w[below[0]] / (2 * np.pi)) if below.size else float("nan")
