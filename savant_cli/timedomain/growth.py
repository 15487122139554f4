"""Whether a response grows: amplitude growth over successive periods.

The response is the difference between two runs of the same perturbed loop, one with
an excitation doublet and one without (``timedomain/search.py``), so what is left is the
loop's own transient: it decays when the loop is stable and grows when it is not,
whatever the trajectory does meanwhile. From the end of a settling time onwards:

1. The oscillation frequency is read from the zero crossings of the response (half a
   period between neighbours); with fewer than three crossings the response is taken as
   non-oscillatory (a divergence, or a decay without overshoot).
2. The analysed span is cut, from its end backwards, into segments one period long
   (non-oscillatory: a quarter of the span), at least :data:`MIN_SEGMENTS` of them; each
   segment's amplitude is its largest absolute value, the envelope sampled once a period.
3. The growth rate σ (1/s) is the least-squares slope of the logarithm of the last
   :data:`FIT_SEGMENTS` amplitudes against time: the early segments carry the decay of the
   faster modes the excitation also started.

The response is unstable when σ > 0 (the envelope grows from period to period), or when
the run itself diverged. No fixed amplitude threshold decides it; the amplitudes only
have to stand above numerical noise (:data:`NOISE_FLOOR` of the largest).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_SEGMENTS = 3
FIT_SEGMENTS = 4
NOISE_FLOOR = 1e-9


@dataclass(frozen=True)
class Growth:
    """The growth of one response.

    Attributes
    ----------
    unstable : bool
        The envelope grows (σ > 0) or the run diverged.
    rate_per_s : float
        Envelope growth rate σ, 1/s (amplitude ∝ exp(σ t); NaN if it could not be fitted).
    frequency_hz : float
        Oscillation frequency from the zero crossings, Hz (0: non-oscillatory).
    amplitude : float
        Largest absolute value of the analysed response (its units).
    reason : str
        What decided it, in words.
    """

    unstable: bool
    rate_per_s: float
    frequency_hz: float
    amplitude: float
    reason: str


def oscillation_frequency(t: np.ndarray, y: np.ndarray) -> float:
    """Frequency (Hz) from the zero crossings of ``y`` (linear between samples); 0 with
    fewer than three crossings."""
    s = np.signbit(y)
    i = np.flatnonzero(s[1:] != s[:-1])
    if i.size < 3:
        return 0.0
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return float((tc.size - 1) / (2.0 * (tc[-1] - tc[0])))


def assess(t: np.ndarray, y: np.ndarray, settle_s: float, diverged: bool = False) -> Growth:
    """The growth of the response ``y`` sampled at ``t`` (s), from ``t[0] + settle_s`` on.

    Parameters
    ----------
    t : ndarray
        Sample times, s, increasing and uniform.
    y : ndarray
        The response (any unit): excited minus unexcited run.
    settle_s : float
        Time from the start left out (the excitation itself), s.
    diverged : bool
        The run stopped on a divergence: unstable whatever the envelope.
    """
    keep = t >= t[0] + settle_s
    tt, yy = t[keep], y[keep]
    amp = float(np.max(np.abs(yy))) if yy.size else 0.0
    if diverged:
        return Growth(True, float("nan"), oscillation_frequency(tt, yy) if yy.size else 0.0, amp,
                      "the run diverged")
    span = float(tt[-1] - tt[0]) if tt.size > 1 else 0.0
    if span <= 0.0 or amp == 0.0:
        return Growth(False, float("nan"), 0.0, amp, "no response to analyse")
    f = oscillation_frequency(tt, yy)
    seg = 1.0 / f if f > 0.0 else span / 4.0
    seg = min(seg, span / MIN_SEGMENTS)
    n_seg = int(span // seg)
    edges = tt[-1] - seg * np.arange(n_seg, -1, -1)
    a = np.array([np.max(np.abs(yy[(tt >= lo) & (tt <= hi)]), initial=0.0) for lo, hi in zip(edges[:-1], edges[1:])])
    centres = 0.5 * (edges[:-1] + edges[1:])
    a, centres = a[-FIT_SEGMENTS:], centres[-FIT_SEGMENTS:]
    floor = NOISE_FLOOR * amp
    if np.all(a <= floor):
        return Growth(False, float("-inf"), f, amp, "the response died out")
    rate = float(np.polyfit(centres, np.log(np.maximum(a, floor)), 1)[0])
    grows = rate > 0.0
    per_period = np.exp(rate * seg)
    return Growth(grows, rate, f, amp, f"envelope {'grows' if grows else 'decays'} x{per_period:.3f} per "
                  f"{'period' if f > 0 else 'segment'} ({seg:.2f} s)")
