"""Every gain and phase margin of a broken loop, labelled by frequency band, plus disk
margins and the closed-loop bandwidth.

Margins come from :func:`control.stability_margins` on frequency-response data over a
grid that is logarithmic from 0.01 Hz to the Nyquist frequency and refined around every
lightly damped pole of the loop (``± 5ζω`` in 21 points), so crossings of flex and slosh
resonances are resolved; the polynomial method is not used (it is numerically
meaningless for loops of 50–100 states). Crossings at the grid's ends are dropped.

Bands: ``flex`` from 0.7 × the lowest retained bending frequency, ``slosh`` within a
factor 2 of the slosh frequencies, ``rigid/aero`` otherwise. A gain margin below 0 dB is
the gain-reduction (aerodynamic) margin of an unstable vehicle.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

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


def frequency_grid(sys: ct.StateSpace) -> np.ndarray:
    """rad/s grid for a discrete loop: log-spaced, refined around lightly damped poles."""
    w_nyq = np.pi / sys.dt
    w = [np.logspace(np.log10(2 * np.pi * F_MIN_HZ), np.log10(w_nyq), N_BASE)]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(sys.poles().astype(complex)) / sys.dt
    for pole in s:
        wn = abs(pole)
        if not np.isfinite(wn) or wn < 2 * np.pi * F_MIN_HZ or wn >= w_nyq or pole.imag <= 0:
            continue
        zeta = max(-pole.real / wn, 1e-4)
        if zeta < 0.3:
            w.append(wn * (1.0 + np.linspace(-5.0, 5.0, 21) * zeta))
    grid = np.unique(np.concatenate(w))
    return grid[(grid > 0) & (grid < w_nyq)]


def loop_margins(loop: ct.StateSpace, time_s: float, axis: str, bands: Bands) -> list[MarginRow]:
    """All gain and phase crossings of one SISO loop (negative-feedback convention)."""
    w = frequency_grid(loop)
    frd = ct.frd(loop, w)
    gm, pm, _, wg, wp, _ = ct.stability_margins(frd, returnall=True, method="frd")
    rows = []
    w_lo, w_hi = w[0] * 1.0001, w[-1] * 0.9999
    for value, freq in zip(np.atleast_1d(gm), np.atleast_1d(wg)):
        if np.isfinite(value) and value > 0 and w_lo < freq < w_hi:
            f = float(freq) / (2 * np.pi)
            rows.append(MarginRow(time_s, axis, "gain", float(20 * np.log10(value)), f, bands.label(f)))
    for value, freq in zip(np.atleast_1d(pm), np.atleast_1d(wp)):
        if np.isfinite(value) and w_lo < freq < w_hi:
            f = float(freq) / (2 * np.pi)
            rows.append(MarginRow(time_s, axis, "phase", float(value), f, bands.label(f)))
    return sorted(rows, key=lambda r: (r.kind, r.frequency_hz))


def disk_margins(loop: ct.StateSpace) -> dict[str, float]:
    """Balanced (skew 0) disk margin of a SISO or MIMO loop: disk margin α, and the
    simultaneous gain (dB) and phase (deg) variations it guarantees."""
    w = frequency_grid(loop if loop.ninputs == 1 else loop[0, 0])[::4]
    dm, dgm, dpm = ct.disk_margins(loop, w, skew=0.0)
    return {"disk_margin": float(dm), "disk_gain_margin_dB": float(20 * np.log10(dgm)) if dgm > 0 else float("nan"),
            "disk_phase_margin_deg": float(dpm)}


def bandwidth_hz(closed_siso: ct.StateSpace) -> float:
    """−3 dB bandwidth (Hz) of a closed-loop command response, from its frequency
    response (the first frequency where the gain falls 3 dB below its low-frequency
    value); NaN if it never does below the Nyquist frequency. ``control.bandwidth``
    brackets the root from the DC gain and fails on these discrete loops, hence this."""
    w = frequency_grid(closed_siso)
    mag = np.abs(closed_siso.frequency_response(w).complex.ravel())
    ref = mag[0]
    below = np.nonzero(mag < ref * 10 ** (-3 / 20))[0]
    return float(w[below[0]] / (2 * np.pi)) if below.size else float("nan")
