"""Signals whose oscillation is known by construction, for the flight-health detectors
(``tests/test_health.py``, ``benchmarks/health_detection_map.py``).

A member of the limit-cycle class (``savant_cli/sim/oscillation.py``, module notes) is

    y(t) = trend(t) + A · w(2π f (t − t_on) + φ) · [t_on ≤ t < t_on + D] + n(t)

on a record of ``D + 2·margin_s`` at ``fs``: ``w`` a sine or a triangle of unit amplitude
(the triangle is a rate-limited oscillation: slope 4Af), the trend guidance-like (a
quadratic over the record plus a 0.3° swing whose period is the longer of 300 s and 20
periods of the oscillation), ``n`` white Gaussian noise of a stated signal-to-noise
ratio (the sine's mean square A²/2 over the noise variance).
"""

from __future__ import annotations

import numpy as np

FS = 50.0  # Hz, the default log rate


def waveform(kind: str, phase: np.ndarray) -> np.ndarray:
    """Unit-amplitude periodic waveform of ``phase`` (rad): ``"sine"`` or ``"triangle"``
    (peaks ±1 at the sine's peaks, straight lines between)."""
    if kind == "sine":
        return np.sin(phase)
    if kind == "triangle":
        return 2.0 / np.pi * np.arcsin(np.sin(phase))
    raise ValueError(kind)


def trend(t: np.ndarray, f_hz: float) -> np.ndarray:
    """The guidance-like slow motion (deg) under an oscillation at ``f_hz``."""
    period = max(300.0, 20.0 / f_hz)
    return 2.0 - 0.01 * t + 1e-4 * t**2 + 0.3 * np.sin(2.0 * np.pi * t / period + 0.7)


def oscillation(f_hz: float, amplitude: float, duration_s: float, kind: str = "sine", *, with_trend: bool = True,
                snr_db: float | None = None, margin_s: float = 20.0, phase: float = 0.3, decay_zeta: float = 0.0,
                seed: int = 0, fs: float = FS) -> tuple[np.ndarray, np.ndarray]:
    """``(t, y)`` (s, deg) of one member of the class (module notes); ``decay_zeta`` > 0
    gives the envelope exp(−ζ 2π f (t − t_on)) of a mode of that damping ratio."""
    t = np.arange(0.0, duration_s + 2.0 * margin_s, 1.0 / fs)
    tau = t - margin_s
    on = (tau >= 0.0) & (tau < duration_s)
    envelope = amplitude * np.exp(-decay_zeta * 2.0 * np.pi * f_hz * tau)
    y = np.where(on, envelope * waveform(kind, 2.0 * np.pi * f_hz * tau + phase), 0.0)
    if with_trend:
        y = y + trend(t, f_hz)
    if snr_db is not None:
        sigma = amplitude / np.sqrt(2.0) * 10.0 ** (-snr_db / 20.0)
        y = y + sigma * np.random.default_rng(seed).normal(size=t.size)
    return t, y


def sweep_frequencies(top_hz: float, n: int = 200) -> np.ndarray:
    """``n`` log-spaced frequencies from 0.05 Hz to ``top_hz``, plus the frequencies the
    issue-12 detector missed (issue 26: 0.174–0.177, 0.224–0.226, 0.274–0.276,
    0.324–0.325 Hz), sorted."""
    holes = [0.174, 0.175, 0.176, 0.177, 0.224, 0.225, 0.226, 0.274, 0.275, 0.276, 0.324, 0.325]
    return np.unique(np.r_[np.geomspace(0.05, top_hz, n), holes])
