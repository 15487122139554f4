"""The search for a time-domain margin: from the stored state just before the window,
the same perturbed loop is flown with and without an excitation doublet; their
difference is the loop's transient, judged by :func:`savant_cli.timedomain.growth.assess`
against the stated decay per period (``Search.min_damping_ratio``). A coarse scan from no
change to the search bound finds the first change that is not stable, and bisection
between it and the last stable change narrows the margin to the tolerance (a scan first, so that a stable band above an unstable one, as in a
conditionally stable loop, cannot hide the smallest margin).

Kinds and their search variable:

* ``gain_high``: the loop-gain multiplier above 1, in dB (0 … ``bound``);
* ``gain_low``: the multiplier below 1, in dB of reduction (0 … ``bound``, reported
  negative, as ``study=linear`` reports a gain-reduction margin);
* ``delay``: the inserted pure delay, in ms (0 … ``bound``).

Every trial is a pure function of the model, the snapshot and the search, so the searches
run on forked worker processes (:func:`run_searches`) with the same results as in one.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from savant_cli import lifecycle
from savant_cli.models import actuator, layout
from savant_cli.processes import process_context, terminate_workers, worker_initializer
from savant_cli.sim import loop_perturbation
from savant_cli.sim.build import SimModel
from savant_cli.sim.run import Snapshot, simulate
from savant_cli.timedomain.growth import Growth, assess

UNITS = {"gain_high": "dB", "gain_low": "dB", "delay": "ms"}


@dataclass(frozen=True)
class Search:
    """One margin search.

    Attributes
    ----------
    time_s : float
        The point (s).
    axis, kind : str
        ``pitch`` | ``yaw``; one of :class:`savant_cli.config.MarginKind`.
    snapshot : int
        Index of the stored state the trials start from (at ``start_s``).
    start_s, end_s : float
        The perturbation window (mission time, s).
    bound, tolerance : float
        Search bound and bisection tolerance (dB or ms).
    scan_points : int
        Coarse-scan points between 0 and ``bound``.
    pulse_rad, pulse_s : float
        Excitation doublet amplitude (rad) and duration (s).
    settle_s : float
        Time after the window starts left out of the growth analysis (s).
    min_damping_ratio : float
        ζ_min: a trial is stable only when its response decays per period at least as
        fast as a mode of this damping ratio (``study.min_damping_ratio``).
    max_saturation_s : float
        Either run longer than this on its rate limit or gimbal stop after the settling
        time is in a saturated oscillation: not stable (``sim.health.max_saturation_s``).
    """

    time_s: float
    axis: str
    kind: str
    snapshot: int
    start_s: float
    end_s: float
    bound: float
    tolerance: float
    scan_points: int
    pulse_rad: float
    pulse_s: float
    settle_s: float
    min_damping_ratio: float
    max_saturation_s: float = 1.0


@dataclass
class Trial:
    """One judged change: its value (dB or ms) and growth."""

    value: float
    growth: Growth
    saturated_s: float  # time on the rate limit or the gimbal stop in the excited run after the settling time, s


@dataclass
class SearchResult:
    """A finished search.

    ``margin`` is NaN when every change up to the bound was stable (``unstable_at_zero``: the
    unperturbed loop is already not stable). ``last_stable`` and ``first_unstable`` are the
    responses ``(t s, gimbal deg)`` bracketing the margin."""

    search: Search
    margin: float
    frequency_hz: float
    trials: list[Trial] = field(default_factory=list)
    last_stable: tuple[np.ndarray, np.ndarray] | None = None
    first_unstable: tuple[np.ndarray, np.ndarray] | None = None
    unstable_at_zero: bool = False
    bracket: tuple[float, float] = (float("nan"), float("nan"))  # last stable, first unstable change

    @property
    def saturated_s(self) -> float:
        """Saturated time of the first unstable trial (s; 0 if none)."""
        bad = [tr for tr in self.trials if tr.growth.unstable and self.first_unstable is not None
               and tr.value == self.bracket[1]]
        return bad[0].saturated_s if bad else 0.0


def perturbation_of(s: Search, value: float, dt: float, excited: bool) -> np.ndarray:
    """The inserted perturbation of ``s`` at ``value`` (dB or ms)."""
    gain, delay = 1.0, 0.0
    if s.kind == "gain_high":
        gain = 10.0 ** (value / 20.0)
    elif s.kind == "gain_low":
        gain = 10.0 ** (-value / 20.0)
    else:
        delay = value / 1000.0
    return loop_perturbation.perturbation(s.axis, s.start_s, s.end_s, gain, delay, s.pulse_rad if excited else 0.0, s.pulse_s, dt)


def _saturated_s(log: np.ndarray, model: SimModel, engine: int, axis: int, after_s: float) -> float:
    """Time (s) the axis's actuator spends on its rate limit or gimbal stop in ``log``
    from mission time ``after_s`` on (``engine``: the engine phase, which sets the
    stage's limits)."""
    lay = model.layout
    rate_limit, gimbal_limit = actuator.limits(model.p, engine)
    k = lay.channel(axis)
    rate_col = 1 + (lay.valve + layout.N_VALVE_PER_CHANNEL * axis if lay.simplex else k + 1)
    on = (np.abs(log[:, 1 + k]) >= 0.999 * gimbal_limit) | (np.abs(log[:, rate_col]) >= 0.999 * rate_limit)
    on &= log[:, 0] >= after_s
    dt_log = float(np.median(np.diff(log[:, 0]))) if log.shape[0] > 1 else 0.0
    return float(on.sum() * dt_log)


def response(model: SimModel, snap: Snapshot, s: Search, value: float
             ) -> tuple[np.ndarray, np.ndarray, bool, float, float]:
    """The loop's transient at ``value``: times (s), excited minus unexcited gimbal angle
    of the axis (deg), whether either run diverged, and the excited and the unexcited
    runs' saturated times after the settling time (s; the doublet itself may touch a
    limit)."""
    dt = model.rates.dt
    runs = [simulate(model, progress=False, start=snap, t_stop=s.end_s,
                     perturbation=perturbation_of(s, value, dt, excited)) for excited in (True, False)]
    n = min(r.log.shape[0] for r in runs)
    axis = loop_perturbation.AXES.index(s.axis)
    col = 1 + model.layout.n + actuator.A_ANGLES + axis
    y = np.degrees(runs[0].log[:n, col] - runs[1].log[:n, col])
    diverged = any(r.status not in ("complete",) for r in runs)
    engine = int(snap.u[layout.U_ENGINE])
    after = s.start_s + s.settle_s
    return (runs[0].log[:n, 0], y, diverged, _saturated_s(runs[0].log[:n], model, engine, axis, after),
            _saturated_s(runs[1].log[:n], model, engine, axis, after))


def find_margin(model: SimModel, snap: Snapshot, s: Search) -> SearchResult:
    """Scan, then bisect, for the smallest change of ``s`` whose response is not stable."""
    out = SearchResult(s, float("nan"), float("nan"))
    cache: dict[float, tuple] = {}

    def judge(value: float) -> bool:
        t, y, diverged, sat, sat_unexcited = response(model, snap, s, value)
        g = assess(t, y, s.settle_s, s.min_damping_ratio, diverged)
        if not g.unstable:  # a saturated oscillation is at or beyond the margin, whatever the difference shows
            if sat > s.max_saturation_s:
                g = replace(g, unstable=True, reason=f"the excited run rides the actuator limits for {sat:.2f} s "
                            f"after the settling time (a saturated oscillation; {g.reason})")
            elif sat_unexcited > s.max_saturation_s:  # both runs in the same limit cycle
                g = replace(g, unstable=True, reason=f"the unexcited run rides the actuator limits for "
                            f"{sat_unexcited:.2f} s (a saturated limit cycle; {g.reason})")
        out.trials.append(Trial(float(value), g, sat))
        cache[value] = (t, y)
        return g.unstable

    if judge(0.0):
        out.unstable_at_zero = True
        out.margin = 0.0
        out.first_unstable = cache[0.0]
        out.bracket = (0.0, 0.0)
        out.frequency_hz = out.trials[-1].growth.frequency_hz
        return out
    lo, hi = 0.0, None
    for v in np.linspace(0.0, s.bound, max(2, s.scan_points) + 1)[1:]:
        if judge(float(v)):
            hi = float(v)
            break
        lo = float(v)
    if hi is None:
        out.last_stable = cache[lo]
        return out
    while hi - lo > s.tolerance:
        mid = 0.5 * (lo + hi)
        if judge(mid):
            hi = mid
        else:
            lo = mid
    out.margin = 0.5 * (lo + hi)  # the boundary, to within half the tolerance
    out.frequency_hz = next(tr.growth.frequency_hz for tr in out.trials if tr.value == hi)
    out.last_stable, out.first_unstable = cache[lo], cache[hi]
    out.bracket = (lo, hi)
    return out


_MODEL: SimModel | None = None
_SNAPS: list[Snapshot] = []


def _one(s: Search) -> SearchResult:
    return find_margin(_MODEL, _SNAPS[s.snapshot], s)


def run_searches(model: SimModel, snaps: list[Snapshot], searches: list[Search], workers: int,
                 progress=None) -> list[SearchResult]:
    """Every search, on ``workers`` forked processes (1: in this one); ``progress()`` is
    called as each finishes. Results in the order of ``searches``."""
    global _MODEL, _SNAPS
    _MODEL, _SNAPS = model, list(snaps)
    workers = max(1, min(workers, len(searches)))
    if workers == 1:
        results = []
        for s in searches:
            results.append(_one(s))
            if progress:
                progress()
        return results
    with ProcessPoolExecutor(workers, mp_context=process_context(), **worker_initializer()) as pool:
        try:
            futures = [pool.submit(_one, s) for s in searches]
            results = []
            for fut in futures:
                results.append(fut.result())
                if progress:
                    progress()
                lifecycle.stage("searches")  # after each search (where a test may interrupt it)
        except KeyboardInterrupt:
            terminate_workers(pool)  # a Ctrl-C: the searches in flight are abandoned
            raise
    return results
