"""Whether a response is stable: its envelope must decay by a stated ratio per period.

The response is the difference between two runs of the same perturbed loop, one with
an excitation doublet and one without (``timedomain/search.py``), so what is left is the
loop's own transient: it decays when the loop is stable and grows when it is not,
whatever the trajectory does meanwhile. From the end of a settling time onwards:

1. The oscillation frequency f is read from the zero crossings of the response (half a
   period between neighbours); with fewer than three crossings the response is taken as
   non-oscillatory (a divergence, or a decay without overshoot).
2. The analysed span is cut, from its end backwards, into segments one period T = 1/f
   long when it holds at least :data:`MIN_SEGMENTS` periods, else half a period long
   (|y| of any oscillation repeats every half period, so each segment still holds one
   peak of a constant-amplitude sine or triangle); non-oscillatory: a quarter of the
   span. Each segment's amplitude is its largest absolute value: the envelope sampled
   at its peaks.
3. The envelope rate σ (1/s) is the least-squares slope of the logarithm of the last
   :data:`FIT_SEGMENTS` amplitudes against time (the early segments carry the decay of
   the faster modes the excitation also started), and the decay per period is
   ρ = exp(σ T) (non-oscillatory: per segment).

The response is **stable** only when ρ ≤ ρ_max = exp(−2π ζ_min / √(1 − ζ_min²)), the
decay per period of a second-order mode of damping ratio ζ_min (``study.min_damping_ratio``,
docs/design_studies.md). A constant-amplitude oscillation (ρ = 1, whatever its
waveform or frequency, to within the envelope's sampling error, far below 1 − ρ_max)
is therefore "not stable": at or beyond the margin. So is a diverged run.

A response whose last segment has fallen to :data:`DEAD_FLOOR` (−60 dB) of its largest
value or below has died out: stable. At the threshold damping a mode needs
ln(1000)/(2π ζ_min) ≈ 110 periods to lose 60 dB, far more than any window holds, so only
a response that decayed much faster than the threshold gets there; what is left is the
small trajectory difference the doublet leaves between the two runs (not an
oscillation of the loop), whose zero crossings would otherwise set a meaningless
period. The limit this sets: a neutral mode excited to less than 1e-3 of the
response's peak is not seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_SEGMENTS = 3
FIT_SEGMENTS = 6
NOISE_FLOOR = 1e-9
DEAD_FLOOR = 1e-3


def decay_threshold(min_damping_ratio: float) -> float:
    """ρ_max: the envelope ratio per damped period of a mode of damping ratio ζ
    (``exp(−2π ζ / √(1 − ζ²))``, 0 ≤ ζ < 1); a stable response decays at least this much."""
    z = float(min_damping_ratio)
    return float(np.exp(-2.0 * np.pi * z / np.sqrt(1.0 - z * z)))


@dataclass(frozen=True)
class Growth:
    """The verdict on one response.

    Attributes
    ----------
    unstable : bool
        Not stable: the envelope decays less than the threshold per period (a growing,
        constant-amplitude or too lightly damped response), or the run diverged. The
        change that produced it is at or beyond the margin.
    rate_per_s : float
        Envelope rate σ, 1/s (amplitude ∝ exp(σ t); NaN if it could not be fitted).
    frequency_hz : float
        Oscillation frequency from the zero crossings, Hz (0: non-oscillatory).
    amplitude : float
        Largest absolute value of the analysed response (its units).
    reason : str
        What decided it, in words.
    decay_per_period : float
        Envelope ratio per period ρ = exp(σ T) (per segment when non-oscillatory; NaN
        when not fitted).
    """

    unstable: bool
    rate_per_s: float
    frequency_hz: float
    amplitude: float
    reason: str
    decay_per_period: float = float("nan")


def oscillation_frequency(t: np.ndarray, y: np.ndarray) -> float:
    """Frequency (Hz) from the zero crossings of ``y`` (linear between samples); 0 with
    fewer than three crossings."""
    s = np.signbit(y)
    i = np.flatnonzero(s[1:] != s[:-1])
    if i.size < 3:
        return 0.0
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return float((tc.size - 1) / (2.0 * (tc[-1] - tc[0])))


def envelope(t: np.ndarray, y: np.ndarray, f_hz: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The envelope of ``y`` sampled once a segment, from the end of ``t`` backwards:
    ``(segment centres s, amplitudes, segment length s)`` (step 2 of the module's
    procedure; ``f_hz`` 0: quarter-span segments)."""
    span = float(t[-1] - t[0])
    if f_hz > 0.0:
        period = 1.0 / f_hz
        seg = period if span >= MIN_SEGMENTS * period else 0.5 * period
    else:
        seg = span / 4.0
    n_seg = max(int(span // seg), 1)
    edges = t[-1] - seg * np.arange(n_seg, -1, -1)
    amp = np.array([np.max(np.abs(y[(t >= lo) & (t <= hi)]), initial=0.0) for lo, hi in zip(edges[:-1], edges[1:])])
    return 0.5 * (edges[:-1] + edges[1:]), amp, seg


def assess(t: np.ndarray, y: np.ndarray, settle_s: float, min_damping_ratio: float,
           diverged: bool = False) -> Growth:
    """The verdict on the response ``y`` sampled at ``t`` (s), from ``t[0] + settle_s`` on.

    Parameters
    ----------
    t : ndarray
        Sample times, s, increasing and uniform.
    y : ndarray
        The response (any unit): excited minus unexcited run.
    settle_s : float
        Time from the start left out (the excitation itself), s.
    min_damping_ratio : float
        ζ_min: stable only when the envelope decays at least as fast per period as a
        mode of this damping ratio (0 ≤ ζ_min < 1).
    diverged : bool
        The run stopped on a divergence: not stable whatever the envelope.
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
    centres, a, seg = envelope(tt, yy, f)
    a, centres = a[-FIT_SEGMENTS:], centres[-FIT_SEGMENTS:]
    floor = NOISE_FLOOR * amp
    if np.all(a <= floor):
        return Growth(False, float("-inf"), f, amp, "the response died out", 0.0)
    if a[-1] <= DEAD_FLOOR * amp:
        return Growth(False, float("nan"), f, amp, f"the response died out: its last segment is "
                      f"{a[-1] / amp:.1e} of its peak (at most {DEAD_FLOOR:g})")
    if a.size < 2:
        return Growth(True, float("nan"), f, amp, "too short a span to see the envelope decay")
    rate = float(np.polyfit(centres, np.log(np.maximum(a, floor)), 1)[0])
    per = 1.0 / f if f > 0.0 else seg
    rho = float(np.exp(rate * per))
    rho_max = decay_threshold(min_damping_ratio)
    stable = rho <= rho_max
    unit = "period" if f > 0.0 else "segment"
    return Growth(not stable, rate, f, amp,
                  f"envelope x{rho:.3f} per {unit} ({per:.2f} s; stable needs <= x{rho_max:.3f}, "
                  f"damping ratio {min_damping_ratio:g})", rho)
