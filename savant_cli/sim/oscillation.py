"""Sustained oscillations and slow divergences of one uniformly sampled signal: the signal
analysis behind the flight-health verdicts of :mod:`savant_cli.sim.health`.

**Limit cycle** (:func:`find_limit_cycle`). The class it finds, the detector's definition:
a segment ``y(t) = trend(t) + A·w(2πft + φ) + noise`` where ``w`` is a periodic waveform
of unit amplitude (sine, triangle, any shape whose first harmonic dominates), ``f`` lies
in ``[F_LOW_HZ, f_max]`` (:func:`band_top_hz`), the oscillation lasts at least
``min_periods`` periods, its amplitude (half its peak-to-peak) is at least
``min_amplitude_deg``, its periodic part holds at least ``tonal_fraction`` of the
detrended variance, and its envelope neither decays nor grows as fast as a mode of damping
ratio ``max_damping_ratio``. The trend is whatever a quadratic follows over
``min_periods`` periods (guidance-following motion, trims). docs/outputs.md, *Flight
health*, gives the thresholds' reasons and the measured signal set.

Method: windows sized in periods, not seconds. For a candidate frequency ``f`` every
window holds ``min_periods`` periods (rounded down to whole samples); in each, a linear
least-squares fit of a quadratic trend plus the oscillation at ``f`` gives the
oscillation's share of the detrended variance (its *tonality*) and its amplitude. The
fundamental may vary linearly in amplitude and phase over a window: y1 = (a + a'τ) cos ωτ
+ (b + b'τ) sin ωτ gives the envelope's log rate σ and the phase drift (the frequency
error) at the window's centre.

1. *Screening*: ``f`` on a log grid (:func:`screening_grid`: ratio :data:`GRID_RATIO`,
   :data:`GRID_RATIO_SHORT` where a window holds fewer than :data:`_SHORT` samples and is
   fitted without the drift columns), on block means of at least :data:`_SCREEN_SAMPLES`
   samples per period, windows :data:`_SCREEN_HOP` periods apart. A window is a candidate
   when its tonality and fundamental amplitude reach :data:`_SCREEN` of the verdict's
   thresholds and its tonality exceeds white noise's at :data:`_FALSE_ALARM_SCREEN`
   (capped at :data:`_SCREEN_CAP`). Neighbouring grid frequencies with candidates form a
   cluster; the frequency of its best-fitting window (tonality × amplitude), corrected by
   that window's phase drift, is refined over the cluster's span.
2. *Refinement*, on block means of at least :data:`_REFINE_SAMPLES` samples per period:
   the frequency is corrected by the median phase drift of the best-fitting windows
   until it moves less than 10⁻⁴ of itself (at most :data:`_ITERATIONS` passes); then
   windows 1/:data:`_REFINE_STEPS` period apart are fitted with the trend, the modulated
   fundamental and harmonics 2..:data:`HARMONICS` up to ``f_max``: each gives its periodic
   waveform's amplitude (half its peak-to-peak), its tonality and the damping ratio
   ζ = −σ / (2πf).
3. A window *oscillates* when its tonality ≥ max(``tonal_fraction``, white noise's
   tonality at :data:`FALSE_ALARM`: :func:`chance_tonality`), its amplitude ≥
   ``min_amplitude_deg``, |ζ| < ``max_damping_ratio``, and its first and last periods
   hold the centre's amplitude within what that damping changes over the distance
   (:func:`_ends_hold`: a window across an oscillation's start or end fails). Oscillating
   windows one after another (gaps shorter than a window bridged) make one oscillation,
   from the first window's start to the last one's end, its amplitude the median of its
   windows'.

**Slow divergence** (:func:`find_slow_divergence`): the envelope E(t) (the largest |y|
over the trailing ``1/F_LOW_HZ`` s, one period of the slowest oscillation looked for) has
grown by at least ``growth`` from its smallest value to the end of the segment, ends at
``min_amplitude_deg`` or more, and is still growing there: over the last quarter of the
growth interval E rises by at least an eighth of its total rise (half the mean rate of a
linear growth; an exponential rises faster still at its end, a bounded trend levelling
off rises less). The growth is the ratio E(end) / min E (–).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.special import betainccinv

F_LOW_HZ = 0.05  # Hz, the lowest limit-cycle frequency looked for
GRID_RATIO = 1.15  # ratio of neighbouring screening frequencies
GRID_RATIO_SHORT = 1.03  # the same, for windows of fewer than _SHORT samples
_SHORT = 28  # samples: a shorter window is screened without the drift columns
HARMONICS = 9  # highest harmonic of a waveform's fit (a triangle's peak to 4 %)
_SCREEN = 0.5  # screening thresholds: this fraction of the verdict's
_SCREEN_SAMPLES = 10  # screening: at least this many (block-mean) samples per period
_SCREEN_HOP = 2.0  # screening: periods between windows
_REFINE_STEPS = 40  # verdict windows per period
_ITERATIONS = 8  # at most this many frequency corrections
_REFINE_SAMPLES = 40  # refinement: at least this many (block-mean) samples per period
_PERIOD_SAMPLES = 10  # a period of fewer samples is not fitted on its own (_ends_hold)
_PHASES = 256  # samples of one period of a fitted waveform
#: chance of a window of white noise passing the tonality test (verdict, screening)
FALSE_ALARM = 1e-9
_FALSE_ALARM_SCREEN = 1e-4
_SCREEN_CAP = 0.95  # screening: the chance tonality capped (short windows off the grid still pass)


@lru_cache(maxsize=4096)
def chance_tonality(n: int, p: int, alpha: float) -> float:
    """The tonality that white noise exceeds with probability ``alpha`` in a window of
    ``n`` samples fitted with 3 trend and ``p`` periodic columns: the share of the
    detrended variance that ``p`` of its ``n − 3`` degrees of freedom take is
    Beta(p/2, (n − 3 − p)/2) distributed (Fisher's test for periodicity); ``inf`` when
    the window leaves no degree of freedom."""
    if n - 3 - p <= 0:
        return np.inf
    # Beta(a, b)'s inverse survival function (what scipy.stats.beta.isf evaluates), without
    # importing scipy.stats on every run's path
    return float(betainccinv(0.5 * p, 0.5 * (n - 3 - p), alpha))


@dataclass(frozen=True)
class Oscillation:
    """One sustained oscillation of a signal (deg, Hz, s)."""

    frequency_hz: float
    amplitude_deg: float
    start_s: float
    end_s: float
    damping_ratio: float  # median over its windows; < 0 grows
    tonality: float  # median share of the detrended variance in the periodic part

    @property
    def periods(self) -> float:
        return (self.end_s - self.start_s) * self.frequency_hz


def band_top_hz(fcs_rate_hz: float, log_rate_hz: float, min_periods: float) -> float:
    """The highest limit-cycle frequency (Hz): half the flight-control rate, and below
    the log's Nyquist frequency f_N by what ``min_periods`` periods resolve: a sine at
    f near f_N shows in the samples as an alternation whose envelope beats at f_N − f,
    so its amplitude needs half a beat, 1/(2(f_N − f)) ≤ min_periods/f, i.e.
    f ≤ f_N · 2M/(2M + 1)."""
    f_n = 0.5 * log_rate_hz
    return min(0.5 * fcs_rate_hz, f_n * 2.0 * min_periods / (2.0 * min_periods + 1.0))


def _design(n: int, fs: float, f: float, harmonics: int, modulated: bool) -> np.ndarray:
    """Columns of one window of ``n`` samples: 1, τ, τ² (τ centred, s), then cos and sin
    of the fundamental at ``f`` (with τ·cos and τ·sin when ``modulated``) and of
    harmonics 2..``harmonics``."""
    tau = (np.arange(n) - 0.5 * (n - 1)) / fs
    cols = [np.ones(n), tau, tau**2]
    w = 2.0 * np.pi * f * tau
    cols += [np.cos(w), np.sin(w)]
    if modulated:
        cols += [tau * np.cos(w), tau * np.sin(w)]
    cols += [c for k in range(2, harmonics + 1) for c in (np.cos(k * w), np.sin(k * w))]
    return np.column_stack(cols)


def _fit(windows: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least squares of each row of ``windows`` (2-D) on the columns of ``x``: (coefficients,
    tonality), the tonality being the share of the variance left by the first three
    (trend) columns that the others explain."""
    q, r = np.linalg.qr(x)
    proj = windows @ q  # (windows, columns)
    total = np.einsum("ij,ij->i", windows, windows)
    trend = np.einsum("ij,ij->i", proj[:, :3], proj[:, :3])
    periodic = np.einsum("ij,ij->i", proj[:, 3:], proj[:, 3:])
    rest = total - trend
    with np.errstate(invalid="ignore", divide="ignore"):
        tonal = np.where(rest > 0.0, periodic / rest, 0.0)
    return np.linalg.solve(r, proj.T).T, np.clip(tonal, 0.0, 1.0)


def _windows(y: np.ndarray, n: int, hop: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``n`` samples of ``y`` every ``hop`` samples, and their first indices."""
    view = sliding_window_view(y, n, axis=-1)[..., ::hop, :]
    return view, np.arange(view.shape[-2]) * hop


def screening_grid(fs: float, top_hz: float, min_periods: float) -> np.ndarray:
    """The screening frequencies (Hz): ratio :data:`GRID_RATIO` while a window of
    ``min_periods`` periods holds :data:`_SHORT` samples or more (its fit then follows
    a frequency error by the phase drift), :data:`GRID_RATIO_SHORT` above, up to
    ``top_hz`` included."""
    f_short = min(top_hz, min_periods * fs / _SHORT)
    low = F_LOW_HZ * GRID_RATIO ** np.arange(int(np.ceil(np.log(f_short / F_LOW_HZ) / np.log(GRID_RATIO))))
    low = low[low < f_short]
    high = f_short * GRID_RATIO_SHORT ** np.arange(int(np.ceil(np.log(top_hz / f_short) / np.log(GRID_RATIO_SHORT))) + 1)
    return np.unique(np.r_[low, np.minimum(high, top_hz)])


def _screen(y: np.ndarray, fs: float, grid: np.ndarray, min_periods: float, min_amplitude: float,
            tonal_fraction: float) -> list[list[tuple[float, int, int]]]:
    """Screening (module notes, step 1) of each row of ``y``: per cluster of neighbouring
    grid frequencies with candidate windows, the frequency of the best-fitting one
    (corrected by its phase drift) and the samples the cluster's candidates span. A frequency is screened
    on block means of ``y`` with at least :data:`_SCREEN_SAMPLES` per period (a power of
    two per block), windows :data:`_SCREEN_HOP` periods apart."""
    rows = y.shape[0]
    best = np.zeros((rows, grid.size))  # the best window's tonality × amplitude
    offset = np.zeros((rows, grid.size))  # relative frequency error the drift gives
    spans = np.zeros((rows, grid.size, 2), int)
    blocks: dict[int, np.ndarray] = {}
    for i, f in enumerate(grid):
        d = 1 << max(0, int(np.floor(np.log2(fs / (_SCREEN_SAMPLES * f)))))
        if d not in blocks:
            m = y.shape[1] // d
            blocks[d] = y[:, :m * d].reshape(rows, m, d).mean(axis=2)
        yd, fd = blocks[d], fs / d
        n = int(np.floor(min_periods * fd / f + 1e-9))
        if n > yd.shape[1] or n < 8:
            continue
        win, first = _windows(yd, n, max(1, int(round(_SCREEN_HOP * fd / f))))
        modulated = n >= _SHORT
        coef, tonal = _fit(win.reshape(-1, n), _design(n, fd, f, 1, modulated))
        a, b = coef[:, 3].reshape(rows, -1), coef[:, 4].reshape(rows, -1)
        amp = np.hypot(a, b)
        drift = np.zeros_like(amp)
        if modulated:
            da, db = coef[:, 5].reshape(rows, -1), coef[:, 6].reshape(rows, -1)
            with np.errstate(invalid="ignore", divide="ignore"):
                drift = np.where(amp > 0.0, (b * da - a * db) / amp**2, 0.0)  # rad/s (see _modulated)
        p = 4 if modulated else 2
        least = max(_SCREEN * tonal_fraction, min(chance_tonality(n, p, _FALSE_ALARM_SCREEN), _SCREEN_CAP))
        hit = (tonal.reshape(rows, -1) >= least) & (amp >= _SCREEN * min_amplitude)
        quality = tonal.reshape(rows, -1) * amp
        for r in np.flatnonzero(hit.any(axis=1)):
            on = np.flatnonzero(hit[r])
            w = on[np.argmax(quality[r, on])]
            best[r, i] = quality[r, w]
            offset[r, i] = float(drift[r, w]) / (2.0 * np.pi * f)
            spans[r, i] = (first[on[0]] * d, (first[on[-1]] + n) * d)
    picks: list[list[tuple[float, int, int]]] = []
    for r in range(rows):
        picks.append([])
        i = 0
        while i < grid.size:
            if best[r, i] == 0.0:
                i += 1
                continue
            j = i
            while j + 1 < grid.size and best[r, j + 1] > 0.0:
                j += 1
            # the grid frequency of the best-fitting window (tonality × amplitude: inside
            # the oscillation, not across its ends), corrected by that window's drift
            k = i + int(np.argmax(best[r, i:j + 1]))
            f_pick = float(np.clip(grid[k] * (1.0 + offset[r, k]), grid[0], grid[-1]))
            picks[r].append((f_pick, int(spans[r, i:j + 1, 0].min()),
                             int(spans[r, i:j + 1, 1].max())))
            i = j + 1
    return picks


def _periodic_amplitude(coef: np.ndarray, harmonics: int) -> np.ndarray:
    """Half the peak-to-peak of each window's fitted periodic waveform (fundamental at
    the window centre and its harmonics)."""
    theta = 2.0 * np.pi * np.arange(_PHASES) / _PHASES
    k = np.arange(1, harmonics + 1)
    basis_c, basis_s = np.cos(np.outer(k, theta)), np.sin(np.outer(k, theta))  # (K, P)
    a = np.concatenate([coef[:, 3:4], coef[:, 7::2]], axis=1)[:, :harmonics]
    b = np.concatenate([coef[:, 4:5], coef[:, 8::2]], axis=1)[:, :harmonics]
    wave = a @ basis_c + b @ basis_s
    return 0.5 * (wave.max(axis=1) - wave.min(axis=1))


def _modulated(y: np.ndarray, fs: float, f: float, n: int, hop: int, harmonics: int):
    """Window fits at ``f`` with a modulated fundamental: (first samples, coefficients,
    tonality, d ln A/dt (1/s), phase drift (rad/s))."""
    win, first = _windows(y, n, hop)
    coef, tonal = _fit(win, _design(n, fs, f, harmonics, True))
    a, b, da, db = coef[:, 3], coef[:, 4], coef[:, 5], coef[:, 6]
    amp2 = a * a + b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        # y1 = (a + da τ) cos ωτ + (b + db τ) sin ωτ = A(τ) cos(ωτ + φ(τ)) with
        # a = A cos φ, b = −A sin φ: the envelope's log rate d ln A/dτ and the phase's
        # drift dφ/dτ (the fundamental's angular frequency error) at τ = 0
        sigma = np.where(amp2 > 0.0, (a * da + b * db) / amp2, 0.0)
        drift = np.where(amp2 > 0.0, (b * da - a * db) / amp2, 0.0)
    return first, coef, tonal, sigma, drift


def _ends_hold(y: np.ndarray, fs: float, f: float, n: int, first: np.ndarray, coef: np.ndarray,
               max_damping_ratio: float) -> np.ndarray:
    """Whether each window's first and last periods hold the fundamental's amplitude at
    its centre within what a mode of damping ratio ``max_damping_ratio`` decays or grows
    over the distance: a window across an oscillation's start or end fails (its linear
    envelope cannot see a jump). Each end period, less the window's fitted trend, is
    fitted with a sine and cosine at ``f``. Windows of periods under
    :data:`_PERIOD_SAMPLES` samples are not tested (their edges are a sample or two)."""
    m = int(np.floor(fs / f))
    if m < _PERIOD_SAMPLES:
        return np.ones(first.size, bool)
    one = sliding_window_view(y, m)
    tau = (np.arange(n) - 0.5 * (n - 1)) / fs
    centre = np.hypot(coef[:, 3], coef[:, 4])
    allow = 2.0 * np.pi * max_damping_ratio * f * (n - m) / (2.0 * fs)
    ok = np.ones(first.size, bool)
    for offset in (0, n - m):
        tt = tau[offset:offset + m]
        trend = coef[:, :3] @ np.vstack([np.ones(m), tt, tt**2])
        wave = np.linalg.pinv(np.column_stack([np.cos(2 * np.pi * f * tt), np.sin(2 * np.pi * f * tt)]))
        ab = (one[first + offset] - trend) @ wave.T
        with np.errstate(invalid="ignore", divide="ignore"):
            ok &= np.abs(np.log(np.hypot(ab[:, 0], ab[:, 1]) / centre)) <= allow
    return ok


def _refine(y: np.ndarray, fs: float, f: float, f_max: float, min_periods: float, min_amplitude: float,
            tonal_fraction: float, max_damping_ratio: float) -> list[Oscillation]:
    """Refinement and verdict at one cluster's frequency (module notes, steps 2 and 3);
    times in samples of ``y``. Slow oscillations are refined on block means of ``y``
    holding at least :data:`_REFINE_SAMPLES` per period (a power of two per block)."""
    d = 1 << max(0, int(np.floor(np.log2(fs / (_REFINE_SAMPLES * f * GRID_RATIO**2)))))
    if d > 1:
        m = y.size // d
        found = _refine(y[:m * d].reshape(m, d).mean(axis=1), fs / d, f, f_max, min_periods, min_amplitude,
                        tonal_fraction, max_damping_ratio)
        return [Oscillation(o.frequency_hz, o.amplitude_deg, o.start_s * d, o.end_s * d + d - 1, o.damping_ratio,
                            o.tonality) for o in found]
    f0 = f
    for _ in range(_ITERATIONS):
        n = int(np.floor(min_periods * fs / f + 1e-9))
        if n > y.size:
            return []
        _, coef, tonal, sigma, drift = _modulated(y, fs, f, n, max(1, int(round(fs / f / 2))), 1)
        amp = np.hypot(coef[:, 3], coef[:, 4])
        least = max(tonal_fraction, min(chance_tonality(n, 4, _FALSE_ALARM_SCREEN), _SCREEN_CAP))
        steady = (tonal >= least) & (amp >= _SCREEN * min_amplitude) & (np.abs(sigma) < 0.1 * 2 * np.pi * f)
        if not steady.any():
            return []
        # the windows that fit best: inside the oscillation, not across its ends
        fit = tonal * amp
        steady &= fit >= 0.9 * fit[steady].max()
        f_new = float(np.clip(f + np.median(drift[steady]) / (2.0 * np.pi), f0 / GRID_RATIO**2,
                              min(f0 * GRID_RATIO**2, f_max)))
        done = abs(f_new - f) < 1e-4 * f
        f = f_new
        if done:
            break
    n = int(np.floor(min_periods * fs / f + 1e-9))
    if n > y.size:
        return []
    # harmonics up to the band's top: the log resolves them (band_top_hz)
    harmonics = max(1, min(HARMONICS, int(np.floor(f_max / f * (1.0 + 1e-9))), (n - 5) // 2))
    first, coef, tonal, sigma, _ = _modulated(y, fs, f, n, max(1, int(round(fs / f / _REFINE_STEPS))), harmonics)
    zeta = -sigma / (2.0 * np.pi * f)
    amp = _periodic_amplitude(coef, harmonics)
    least = max(tonal_fraction, chance_tonality(n, 2 + 2 * harmonics, FALSE_ALARM))
    ok = (tonal >= least) & (amp >= min_amplitude) & (np.abs(zeta) < max_damping_ratio)
    ok &= _ends_hold(y, fs, f, n, first, coef, max_damping_ratio)
    found = []
    idx = np.flatnonzero(ok)
    if idx.size:
        # a run of oscillating windows; a gap shorter than a window (noise failing one
        # test in a few windows) does not end it
        gap = max(1, n // max(1, int(first[1] - first[0]) if first.size > 1 else 1))
        for run in np.split(idx, np.flatnonzero(np.diff(idx) > gap) + 1):
            found.append(Oscillation(f, float(np.median(amp[run])), float(first[run[0]]),
                                     float(first[run[-1]] + n - 1), float(np.median(zeta[run])),
                                     float(np.median(tonal[run]))))
    return found


def find_limit_cycle(t: np.ndarray, y_deg: np.ndarray, f_max_hz: float, min_amplitude_deg: float,
                     tonal_fraction: float, min_periods: float, max_damping_ratio: float) -> Oscillation | None:
    """The sustained oscillation of most periods in one signal segment, or None.

    Parameters
    ----------
    t : numpy.ndarray
        Uniform sample times, s.
    y_deg : numpy.ndarray
        The signal, deg (a gimbal angle or an attitude error).
    f_max_hz : float
        The highest frequency looked for (:func:`band_top_hz`), Hz.
    min_amplitude_deg, tonal_fraction, min_periods, max_damping_ratio : float
        The definition's thresholds (module notes; ``sim.health``).

    Returns
    -------
    Oscillation or None
        Frequency (Hz), amplitude (deg, half the peak-to-peak of the periodic waveform),
        start and end (s, in ``t``), median damping ratio and tonality.
    """
    return find_limit_cycles(t, np.asarray(y_deg, float)[None, :], f_max_hz, min_amplitude_deg, tonal_fraction,
                             min_periods, max_damping_ratio)[0]


def find_limit_cycles(t: np.ndarray, y_deg: np.ndarray, f_max_hz: float, min_amplitude_deg: float,
                      tonal_fraction: float, min_periods: float,
                      max_damping_ratio: float) -> list[Oscillation | None]:
    """:func:`find_limit_cycle` of each row of ``y_deg`` (signals × samples of ``t``),
    screened together."""
    y = np.atleast_2d(np.asarray(y_deg, float))
    out: list[Oscillation | None] = [None] * y.shape[0]
    if t.size < 16:
        return out
    fs = 1.0 / float(np.median(np.diff(t)))
    top = min(f_max_hz, 0.5 * fs)
    finite = np.isfinite(y).all(axis=1)
    if top <= F_LOW_HZ or not finite.any():
        return out
    grid = screening_grid(fs, top, min_periods)
    rows = np.flatnonzero(finite)
    for r, picks in zip(rows, _screen(y[rows], fs, grid, min_periods, min_amplitude_deg, tonal_fraction)):
        for f, lo, hi in picks:
            pad = int(round(2.0 * min_periods * fs / f))  # two windows either side of the candidates
            lo, hi = max(0, lo - pad), min(t.size, hi + pad)
            for osc in _refine(y[r, lo:hi], fs, f, top, min_periods, min_amplitude_deg, tonal_fraction,
                               max_damping_ratio):
                osc = Oscillation(osc.frequency_hz, osc.amplitude_deg, float(t[lo + int(osc.start_s)]),
                                  float(t[lo + int(osc.end_s)]), osc.damping_ratio, osc.tonality)
                if out[r] is None or osc.periods > out[r].periods:
                    out[r] = osc
    return out


@dataclass(frozen=True)
class Divergence:
    """A slow divergence of a signal: its envelope's growth (–) and the interval (s)."""

    growth: float
    start_s: float  # where the envelope is smallest
    end_s: float
    start_deg: float
    end_deg: float


def find_slow_divergence(t: np.ndarray, y_deg: np.ndarray, growth: float, min_amplitude_deg: float) -> Divergence | None:
    """A slow divergence of one signal segment (module notes), or None.

    Parameters
    ----------
    t : numpy.ndarray
        Uniform sample times, s.
    y_deg : numpy.ndarray
        The signal, deg (an attitude error).
    growth : float
        The smallest envelope growth, E(end) / min E (–), that is a divergence.
    min_amplitude_deg : float
        The envelope at the end must reach this, deg.
    """
    if t.size < 16 or not np.isfinite(y_deg).all():
        return None
    fs = 1.0 / float(np.median(np.diff(t)))
    span = int(round(fs / F_LOW_HZ))
    if t.size < 4 * span:
        return None
    # trailing maximum over ``span`` samples, valid from the first full span on
    env = sliding_window_view(np.abs(y_deg), span).max(axis=1)
    te = t[span - 1:]
    k0 = int(np.argmin(env))
    e0, e1 = float(env[k0]), float(env[-1])
    if te[-1] - te[k0] < 4.0 / F_LOW_HZ or e1 < min_amplitude_deg:
        return None
    ratio = e1 / e0 if e0 > 0.0 else np.inf
    kq = int(np.searchsorted(te, te[-1] - 0.25 * (te[-1] - te[k0])))
    still_growing = e1 - float(env[kq]) >= 0.125 * (e1 - e0)
    if ratio < growth or not still_growing:
        return None
    return Divergence(float(ratio), float(te[k0]), float(te[-1]), e0, e1)
