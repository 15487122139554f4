"""Flight health of one run: time on the actuator limits, per-stage peak rates, and a
limit-cycle detector (issue 12 item 8).

:func:`assess` reads a flown run's history (the log at ``sim.log_rate_hz``) and returns
the health keys of its summary; a run that flew to its end but limit-cycled, or sat on an
actuator limit longer than allowed, gets the status ``limit_cycle`` or ``saturated``
instead of ``complete`` (``savant_cli/io/record.py``), with the numbers behind the
verdict in its message and summary.

Limits, per stage (first stage before separation, upper stage from it on), by the log's
sample spacing as ``rcs_on_time_s``:

* *time at the rate limit*: the actuator's rate state on its stop (the third-order
  nozzle rate, the simplex spool flow) in either axis;
* *time at the gimbal stop*: either nozzle angle on its stop;
* *peak gimbal rate*: the largest nozzle rate |δ̇| of either axis (deg/s), and the
  largest body-rate magnitude |ω| over the flight.

Limit cycle: a sustained periodic oscillation of a gimbal angle or an attitude error
(pitch, yaw). Each stage's history (less ``window_s`` after each event, where transients
are expected) is cut into windows of ``window_s`` with half-window steps; each window is
detrended (a cubic: the guidance-following motion) and its periodogram (Hann window,
:func:`scipy.signal.periodogram`) gives the peak frequency f, the fraction of the
window's variance within ±15 % of f (*tonality*) and the amplitude of that narrow-band
part, √2 × its RMS (the density integrated over the band). A window oscillates when its tonality is at least
``tonal_fraction``, its amplitude at least ``min_amplitude_deg`` and it holds three
periods. A limit cycle is a run of at least three consecutive oscillating windows (two window
lengths) at one frequency (within ±15 % of their median) spanning at least
``min_periods`` periods whose amplitude holds (the last window's at least half the first's: a decaying transient is not a limit
cycle). The largest is reported: signal, frequency, amplitude, start and end.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.signal import periodogram

from savant_cli.io.record import Signal
from savant_cli.models import actuator
from savant_cli.models.configurations import ENGINE_FIRST
from savant_cli.sim import engine as E
from savant_cli.sim import layout as L
from savant_cli.sim.build import SimModel
from savant_cli.sim.run import SimResult

STAGES = ("first_stage", "upper_stage")
_BAND = 0.15  # ± relative half-width of a tonal peak and of one frequency across windows
_ON_STOP = 1.0 - 1e-9  # a state within this fraction of its limit is on the stop
_MIN_WINDOWS = 3  # consecutive oscillating windows (two window lengths) for a limit cycle


@dataclass
class LimitCycle:
    """The strongest sustained oscillation found in a run."""

    signal: str  # e.g. "gimbal_angle_pitch"
    stage: str
    frequency_hz: float
    amplitude_deg: float
    start_s: float
    end_s: float

    @property
    def periods(self) -> float:
        return (self.end_s - self.start_s) * self.frequency_hz


def _limits(model: SimModel, stage: int) -> tuple[float, float]:
    """(rate limit rad/s, gimbal limit rad) of a stage (0 first, 1 upper)."""
    return actuator.limits(model.p, ENGINE_FIRST if stage == 0 else L.ENGINE_UPPER)


def _stage_masks(t: np.ndarray, result: SimResult) -> list[np.ndarray]:
    t_sep = result.events[E.EV_SEPARATION]
    first = t < t_sep if np.isfinite(t_sep) else np.ones(t.size, bool)
    return [first, ~first]


def _window_peaks(y: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Peak frequency (Hz), tonality and narrow-band amplitude of each row of ``y`` (one
    window per row, uniformly sampled at ``fs``), all windows at once: each row less its
    least-squares cubic, then its Hann-windowed periodogram."""
    n = y.shape[1]
    tau = np.arange(n) / fs
    basis = np.vander(tau - tau.mean(), 4)
    y = y - (y @ np.linalg.pinv(basis).T) @ basis.T
    f, pxx = periodogram(y, fs=fs, window="hann", detrend=False, scaling="density", axis=-1)
    df = f[1] - f[0]
    k = 1 + np.argmax(pxx[:, 1:], axis=1)
    fk = f[k]
    band = (f[None, :] >= (1 - _BAND) * fk[:, None]) & (f[None, :] <= (1 + _BAND) * fk[:, None])
    # a density integrates to the mean square (the Hann window's noise bandwidth is in
    # the scaling), so the band's share is its variance: a sine of amplitude A gives A²/2
    power = (pxx * band).sum(axis=1) * df
    total = pxx[:, 1:].sum(axis=1) * df
    with np.errstate(invalid="ignore", divide="ignore"):
        tonal = np.where(total > 0.0, power / total, 0.0)
    return fk, tonal, np.sqrt(2.0 * power)


def detect_limit_cycle(t: np.ndarray, y_deg: np.ndarray, window_s: float, min_amplitude_deg: float,
                       tonal_fraction: float, min_periods: float) -> tuple[float, float, float, float] | None:
    """The longest sustained oscillation of one signal segment (deg): ``(frequency Hz,
    amplitude deg, start s, end s)``, or None (method in the module notes)."""
    if t.size < 8 or not np.isfinite(y_deg).all():
        return None
    fs = 1.0 / float(np.median(np.diff(t)))
    n = int(round(window_s * fs))
    if n < 16 or t.size < n:
        return None
    starts = np.arange(0, t.size - n + 1, n // 2)
    f, tonal, amp = _window_peaks(y_deg[starts[:, None] + np.arange(n)[None, :]], fs)
    ok = (tonal >= tonal_fraction) & (amp >= min_amplitude_deg) & (f * window_s >= 3.0)
    hits = [(bool(ok[w]), float(f[w]), float(amp[w]), float(t[s0]), float(t[s0 + n - 1]))
            for w, s0 in enumerate(starts)]
    best = None
    i = 0
    while i < len(hits):
        if not hits[i][0]:
            i += 1
            continue
        j = i
        while j + 1 < len(hits) and hits[j + 1][0]:
            j += 1
        run = hits[i:j + 1]
        f_med = float(np.median([h[1] for h in run]))
        run = [h for h in run if abs(h[1] - f_med) <= _BAND * f_med]
        if len(run) >= _MIN_WINDOWS:
            start, end = run[0][3], run[-1][4]
            holds = run[-1][2] >= 0.5 * run[0][2]
            if holds and (end - start) * f_med >= min_periods:
                amplitude = float(np.median([h[2] for h in run]))
                if best is None or (end - start) > best[3] - best[2]:
                    best = (f_med, amplitude, start, end)
        i = j + 1
    return best


def assess(result: SimResult, sig: dict[str, Signal], model: SimModel, cfg) -> dict[str, Any]:
    """Health keys of a flown run (see the module notes); sets ``result.status`` and
    ``result.message`` to ``limit_cycle`` or ``saturated`` for a run that flew to its end
    but is unhealthy. ``cfg`` is the ``sim.health`` config."""
    t = sig["time"].data
    out: dict[str, Any] = {}
    if t.size < 2:
        return out
    dt = np.diff(t, append=t[-1])
    rates = sig["gimbal_rate"].data
    angles = sig["gimbal_angle"].data
    vo = int(model.p[actuator.P_VALVE_OFFSET])
    rate_state = sig["actuator_valve_flow"].data if vo >= 0 else rates
    longest_hold = ("", 0.0)
    for s, (name, mask) in enumerate(zip(STAGES, _stage_masks(t, result))):
        rate_limit, gimbal_limit = _limits(model, s)
        at_rate = mask & np.any(np.abs(rate_state) >= _ON_STOP * rate_limit, axis=1)
        at_stop = mask & np.any(np.abs(angles) >= _ON_STOP * gimbal_limit, axis=1)
        out[f"time_at_rate_limit_{name}_s"] = float(dt[at_rate].sum())
        out[f"time_at_gimbal_stop_{name}_s"] = float(dt[at_stop].sum())
        out[f"max_gimbal_rate_{name}_deg_s"] = float(np.degrees(np.abs(rates[mask]).max())) if mask.any() else 0.0
        for what, held in (("rate limit", at_rate), ("gimbal stop", at_stop)):
            if dt[held].sum() > longest_hold[1]:
                longest_hold = (f"{name.replace('_', ' ')} {what}", float(dt[held].sum()))
    out["max_body_rate_deg_s"] = float(np.degrees(np.linalg.norm(sig["body_rate"].data, axis=1)).max())
    cycle = _limit_cycle(t, sig, result, cfg)
    out["limit_cycle"] = cycle is not None
    out["limit_cycle_signal"] = cycle.signal if cycle else ""
    out["limit_cycle_frequency_hz"] = cycle.frequency_hz if cycle else None
    out["limit_cycle_amplitude_deg"] = cycle.amplitude_deg if cycle else None
    out["limit_cycle_start_s"] = cycle.start_s if cycle else None
    out["limit_cycle_end_s"] = cycle.end_s if cycle else None
    flags = (["limit_cycle"] if cycle else []) + (["saturated"] if longest_hold[1] > cfg.max_saturation_s else [])
    out["health_flags"] = ",".join(flags)
    if result.status == "complete" and flags:
        if cycle:
            result.status = "limit_cycle"
            result.message = (f"limit cycle: {cycle.signal} {cycle.amplitude_deg:.3g} deg at "
                              f"{cycle.frequency_hz:.3g} Hz, {cycle.start_s:.1f}–{cycle.end_s:.1f} s "
                              f"({result.message})")
        else:
            result.status = "saturated"
            result.message = (f"saturated: {longest_hold[1]:.2f} s on the {longest_hold[0]} "
                              f"(more than sim.health.max_saturation_s = {cfg.max_saturation_s} s; {result.message})")
    return out


def _limit_cycle(t: np.ndarray, sig: dict[str, Signal], result: SimResult, cfg) -> LimitCycle | None:
    """The longest limit cycle over the gimbal angles and attitude errors (pitch, yaw) of
    both stages, each stage less ``window_s`` after its start events."""
    starts = [0.0, result.events[E.EV_SEPARATION], result.events[E.EV_IGNITION], result.events[E.EV_LES]]
    quiet = np.ones(t.size, bool)
    for te in starts:
        if np.isfinite(te):
            quiet &= ~((t >= te) & (t < te + cfg.window_s))
    candidates = {"gimbal_angle_pitch": sig["gimbal_angle"].data[:, 0], "gimbal_angle_yaw": sig["gimbal_angle"].data[:, 1],
                  "attitude_error_pitch": sig["attitude_error"].data[:, 1],
                  "attitude_error_yaw": sig["attitude_error"].data[:, 2]}
    best = None
    for stage, mask in zip(STAGES, _stage_masks(t, result)):
        m = mask & quiet
        if m.sum() < 16:
            continue
        # the longest contiguous quiet stretch of the stage
        idx = np.flatnonzero(m)
        breaks = np.flatnonzero(np.diff(idx) > 1)
        pieces = np.split(idx, breaks + 1)
        for piece in pieces:
            for name, y in candidates.items():
                found = detect_limit_cycle(t[piece], np.degrees(y[piece]), cfg.window_s, cfg.min_amplitude_deg,
                                           cfg.tonal_fraction, cfg.min_periods)
                if found and (best is None or (found[3] - found[2]) * found[0] > best.periods):
                    best = LimitCycle(name, stage, found[0], found[1], found[2], found[3])
    return best
