"""Flight health of one run: time on the actuator limits, per-stage peak rates, a
limit-cycle detector, a slow-divergence detector and the loss-of-control bounds (issue 12
item 8, issue 26 item 4).

:func:`assess` reads a flown run's history (the log at ``sim.log_rate_hz``) and returns
the health keys of its summary. A run that flew to its end but is unhealthy gets, instead
of ``complete``, the first of the statuses ``loss_of_control``, ``limit_cycle``,
``slow_divergence``, ``saturated`` that applies (``savant_cli/io/record.py``), with the
numbers behind the verdict in its message and summary. A run that did not fly to its end
(``diverged`` …) keeps its status; its health keys are still computed.

Limits, per stage (first stage before separation, upper stage from it on), by the log's
sample spacing as ``rcs_on_time_s``:

* *time at the rate limit*: the actuator's rate state on its stop (the third-order
  nozzle rate, the simplex spool flow) in either axis;
* *time at the gimbal stop*: either nozzle angle on its stop;
* *peak gimbal rate*: the largest nozzle rate |δ̇| of either axis (deg/s), and the
  largest body-rate magnitude |ω| over the flight.

Limit cycle: a sustained oscillation of a gimbal angle (every channel of the history's
``gimbal_angle``: each engine's pitch and yaw, and each gimbaled booster's, so that a
cluster's differential-gimbal roll loop is watched too) or an attitude error (pitch, yaw)
by :func:`savant_cli.sim.oscillation.find_limit_cycle` (its definition and method are in
that module's notes), in each stage's history less ``event_quiet_s`` after each event
(liftoff, separation, upper-stage ignition, LES jettison), from 0.05 Hz to
:func:`~savant_cli.sim.oscillation.band_top_hz` (half the flight-control rate, below the
log's Nyquist frequency). The one of most periods is reported.

Slow divergence: the pitch or yaw attitude error's envelope grows by
``divergence_growth`` or more to the end of a stage's quiet stretch and is still growing
there (:func:`savant_cli.sim.oscillation.find_slow_divergence`). The attitude error is the
regulated quantity, which a controlled flight keeps bounded; a gimbal angle is not
tested, its trim legitimately follows the centre-of-gravity travel and the thrust
misalignment. The largest growth is reported.

Loss of control: the pitch/yaw attitude-error magnitude √(e_θ² + e_ψ²) exceeds
``max_attitude_error_deg`` anywhere in the flown history, or (when ``max_alpha_deg`` is
set) the total angle of attack α_t (cos α_t = cos α cos β) exceeds it while the dynamic
pressure is at least ``alpha_min_dynamic_pressure_Pa``. The first exceedance is reported.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from savant_cli.io.record import Signal
from savant_cli.models import actuator, layout
from savant_cli.models.configurations import ENGINE_FIRST
from savant_cli.sim import engine
from savant_cli.sim.build import SimModel
from savant_cli.sim.oscillation import band_top_hz, find_limit_cycles, find_slow_divergence
from savant_cli.sim.run import SimResult, channel_columns
from savant_cli.sim.summary import total_alpha_deg

STAGES = ("first_stage", "upper_stage")
_ON_STOP = 1.0 - 1e-9  # a state within this fraction of its limit is on the stop
#: the attitude errors searched for a limit cycle and a slow divergence: name → (signal, column)
ATTITUDE_SIGNALS = {"attitude_error_pitch": ("attitude_error", 1), "attitude_error_yaw": ("attitude_error", 2)}


@dataclass
class LimitCycle:
    """The sustained oscillation of most periods found in a run."""

    signal: str  # e.g. "gimbal_angle_pitch"
    stage: str
    frequency_hz: float
    amplitude_deg: float
    start_s: float
    end_s: float

    @property
    def periods(self) -> float:
        return (self.end_s - self.start_s) * self.frequency_hz


@dataclass
class SlowDivergence:
    """The largest slow divergence found in a run (growth –, envelope deg, times s)."""

    signal: str
    stage: str
    growth: float
    start_s: float
    end_s: float
    start_deg: float
    end_deg: float


@dataclass
class LossOfControl:
    """The first exceedance of a loss-of-control bound."""

    time_s: float
    reason: str


def _limits(model: SimModel, stage: int) -> tuple[np.ndarray, np.ndarray]:
    """Each gimbal channel's (rate limit rad/s, gimbal limit rad) while a stage flies (0
    first, 1 upper): the stage's, and on the first stage the gimbaled boosters' own on
    their channels."""
    n = len(model.layout.channels)
    rate, gimbal = (np.full(n, v) for v in actuator.limits(model.p, ENGINE_FIRST if stage == 0 else
                                                             layout.ENGINE_UPPER))
    first_booster = int(model.p[actuator.P_BOOSTER_CHANNEL])
    if stage == 0 and first_booster >= 0:
        rate[first_booster:], gimbal[first_booster:] = actuator.booster_limits(model.p)
    return rate, gimbal


def _stage_masks(t: np.ndarray, result: SimResult) -> list[np.ndarray]:
    t_sep = result.events[engine.EV_SEPARATION]
    first = t < t_sep if np.isfinite(t_sep) else np.ones(t.size, bool)
    return [first, ~first]


def _quiet_pieces(t: np.ndarray, result: SimResult, quiet_s: float) -> list[tuple[str, np.ndarray]]:
    """(stage, sample indices) of each contiguous stretch of a stage that lies outside
    the ``quiet_s`` after liftoff, the boosters' jettison, a liquid first stage's cutoff,
    separation, upper-stage ignition, each item's jettison and a restarting upper stage's
    first cutoff and restart."""
    starts = [float(t[0]), *(result.events[k] for k in (engine.EV_BOOSTER_JETTISON, engine.EV_FS_CUTOFF,
                                                         engine.EV_SEPARATION, engine.EV_IGNITION, *engine.EV_ITEMS,
                                                         engine.EV_US_CUTOFF, engine.EV_RESTART))]
    quiet = np.ones(t.size, bool)
    for te in starts:
        if np.isfinite(te):
            quiet &= ~((t >= te) & (t < te + quiet_s))
    out = []
    for stage, mask in zip(STAGES, _stage_masks(t, result)):
        idx = np.flatnonzero(mask & quiet)
        if idx.size >= 16:
            out += [(stage, piece) for piece in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if piece.size >= 16]
    return out


def cycle_signals(sig: dict[str, Signal]) -> dict[str, tuple[str, int]]:
    """The signals searched for a limit cycle, name → (signal, column): each column of
    ``gimbal_angle`` (``gimbal_angle_pitch``, ``gimbal_angle_yaw``, then
    ``gimbal_angle_pitch2`` … of a cluster's further engines and the gimbaled boosters),
    then the pitch and yaw attitude errors."""
    columns = channel_columns(sig["gimbal_angle"].data.shape[1])
    gimbal = {f"gimbal_angle_{c}": ("gimbal_angle", k) for k, c in enumerate(columns)}
    return {**gimbal, **ATTITUDE_SIGNALS}


def _signal_deg(sig: dict[str, Signal], where: tuple[str, int]) -> np.ndarray:
    signal, column = where
    return np.degrees(sig[signal].data[:, column])


def limit_cycle(t: np.ndarray, sig: dict[str, Signal], result: SimResult, model: SimModel, cfg) -> LimitCycle | None:
    """The limit cycle of most periods over every gimbal channel's angle and the attitude
    errors (pitch, yaw) of both stages (module notes), or None. ``cfg`` is
    ``sim.health``."""
    fs_fcs = 1.0 / (model.rates.n_fcs * model.rates.dt)
    fs_log = 1.0 / float(np.median(np.diff(t)))
    top = band_top_hz(fs_fcs, fs_log, cfg.min_periods)
    best = None
    signals = cycle_signals(sig)
    names = list(signals)
    for stage, piece in _quiet_pieces(t, result, cfg.event_quiet_s):
        rows = np.stack([_signal_deg(sig, signals[name])[piece] for name in names])
        for name, found in zip(names, find_limit_cycles(t[piece], rows, top, cfg.min_amplitude_deg,
                                                         cfg.tonal_fraction, cfg.min_periods, cfg.max_damping_ratio)):
            if found and (best is None or found.periods > best.periods):
                best = LimitCycle(name, stage, found.frequency_hz, found.amplitude_deg, found.start_s, found.end_s)
    return best


def slow_divergence(t: np.ndarray, sig: dict[str, Signal], result: SimResult, cfg) -> SlowDivergence | None:
    """The largest slow divergence of the pitch and yaw attitude errors of both stages
    (module notes), or None."""
    best = None
    for stage, piece in _quiet_pieces(t, result, cfg.event_quiet_s):
        for name, where in ATTITUDE_SIGNALS.items():
            found = find_slow_divergence(t[piece], _signal_deg(sig, where)[piece], cfg.divergence_growth,
                                         cfg.divergence_min_amplitude_deg)
            if found and (best is None or found.growth > best.growth):
                best = SlowDivergence(name, stage, found.growth, found.start_s, found.end_s, found.start_deg,
                                      found.end_deg)
    return best


def loss_of_control(t: np.ndarray, sig: dict[str, Signal], cfg) -> LossOfControl | None:
    """The first exceedance of the attitude-error bound or the α bound (module notes)."""
    err = np.degrees(np.hypot(sig["attitude_error"].data[:, 1], sig["attitude_error"].data[:, 2]))
    found = []
    over = np.flatnonzero(err > cfg.max_attitude_error_deg)
    if over.size:
        k = int(over[0])
        found.append(LossOfControl(float(t[k]), f"attitude error {err[k]:.1f} deg > {cfg.max_attitude_error_deg:g} deg "
                                                f"at {t[k]:.1f} s"))
    if cfg.max_alpha_deg is not None:
        alpha_total = total_alpha_deg(sig["alpha"].data, sig["beta"].data)
        q = sig["dynamic_pressure"].data
        over = np.flatnonzero((alpha_total > cfg.max_alpha_deg) & (q >= cfg.alpha_min_dynamic_pressure_Pa))
        if over.size:
            k = int(over[0])
            found.append(LossOfControl(float(t[k]), f"total angle of attack {alpha_total[k]:.1f} deg > "
                                                    f"{cfg.max_alpha_deg:g} deg at {t[k]:.1f} s "
                                                    f"(dynamic pressure {q[k]:,.0f} Pa)"))
    return min(found, key=lambda x: x.time_s) if found else None


def assess(result: SimResult, sig: dict[str, Signal], model: SimModel, cfg) -> dict[str, Any]:
    """Health keys of a flown run (see the module notes); sets ``result.status`` and
    ``result.message`` to ``loss_of_control``, ``limit_cycle``, ``slow_divergence`` or
    ``saturated`` (the first that applies) for a run that flew to its end but is
    unhealthy. ``cfg`` is the ``sim.health`` config."""
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
        at_rate = mask & np.any(np.abs(rate_state) >= _ON_STOP * rate_limit[:rate_state.shape[1]], axis=1)
        at_stop = mask & np.any(np.abs(angles) >= _ON_STOP * gimbal_limit[:angles.shape[1]], axis=1)
        out[f"time_at_rate_limit_{name}_s"] = float(dt[at_rate].sum())
        out[f"time_at_gimbal_stop_{name}_s"] = float(dt[at_stop].sum())
        out[f"max_gimbal_rate_{name}_deg_s"] = float(np.degrees(np.abs(rates[mask]).max())) if mask.any() else 0.0
        for what, held in (("rate limit", at_rate), ("gimbal stop", at_stop)):
            if dt[held].sum() > longest_hold[1]:
                longest_hold = (f"{name.replace('_', ' ')} {what}", float(dt[held].sum()))
    out["max_body_rate_deg_s"] = float(np.degrees(np.linalg.norm(sig["body_rate"].data, axis=1)).max())
    cycle = limit_cycle(t, sig, result, model, cfg)
    out["limit_cycle"] = cycle is not None
    out["limit_cycle_signal"] = cycle.signal if cycle else ""
    out["limit_cycle_frequency_hz"] = cycle.frequency_hz if cycle else None
    out["limit_cycle_amplitude_deg"] = cycle.amplitude_deg if cycle else None
    out["limit_cycle_start_s"] = cycle.start_s if cycle else None
    out["limit_cycle_end_s"] = cycle.end_s if cycle else None
    div = slow_divergence(t, sig, result, cfg)
    out["slow_divergence"] = div is not None
    out["slow_divergence_signal"] = div.signal if div else ""
    out["slow_divergence_growth"] = div.growth if div else None
    loc = loss_of_control(t, sig, cfg)
    out["loss_of_control"] = loc is not None
    out["loss_of_control_time_s"] = loc.time_s if loc else None
    out["loss_of_control_reason"] = loc.reason if loc else ""
    saturated = longest_hold[1] > cfg.max_saturation_s
    flags = [name for name, on in (("loss_of_control", loc), ("limit_cycle", cycle), ("slow_divergence", div),
                                   ("saturated", saturated)) if on]
    out["health_flags"] = ",".join(flags)
    if result.status == "complete" and flags:
        result.status = flags[0]
        if loc:
            result.message = f"loss of control: {loc.reason} ({result.message})"
        elif cycle:
            result.message = (f"limit cycle: {cycle.signal} {cycle.amplitude_deg:.3g} deg at "
                              f"{cycle.frequency_hz:.3g} Hz, {cycle.start_s:.1f}–{cycle.end_s:.1f} s "
                              f"({result.message})")
        elif div:
            result.message = (f"slow divergence: {div.signal} envelope grew ×{div.growth:.3g}, "
                              f"{div.start_deg:.3g} deg at {div.start_s:.1f} s to {div.end_deg:.3g} deg at "
                              f"{div.end_s:.1f} s ({result.message})")
        else:
            result.message = (f"saturated: {longest_hold[1]:.2f} s on the {longest_hold[0]} "
                              f"(more than sim.health.max_saturation_s = {cfg.max_saturation_s} s; {result.message})")
    return out
