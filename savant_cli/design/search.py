"""The search of the flight-control design: every candidate judged on frozen operating
points of the nominal flight and the uncertainty corners, the smallest margin-to-requirement
ratio maximized with ``scipy.optimize.minimize``.

The score of a point is its worst check's ratio (``design/points.py``). A candidate's objective (:func:`objective`) is its smallest
point score when every point meets the requirement, and otherwise minus the sum of the
points' shortfalls ``Σ max(0, 1 − score)`` (goal attainment): a point no candidate can
fix does not stop the search from fixing the others, as a bare max-min would.

Two methods (``study.optimizer.method``):

- ``nelder_mead``: maximize :func:`objective`, bounded simplex search on the normalized
  parameters;
- ``cobyla``: the margins as constraints: maximize ``t`` subject to every point's ratio
  ``≥ t`` (the epigraph form), a linear-approximation trust region.

A converged search restarts from the best point found with a fresh simplex (trust radius)
up to ``restarts`` times while the evaluation budget lasts and a restart improves.

Both are derivative-free: margins are piecewise smooth (crossings appear and vanish as the
loop changes). The plant of each point is linearized once (:func:`savant_cli.linear.
evaluate.freeze`); a candidate costs its controller, the loop assembly and the margins.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import NonlinearConstraint, minimize

from savant_cli.config import DesignOptimizer
from savant_cli.design.parameters import FreeParameter
from savant_cli.design.points import DesignPoint, point_scores
from savant_cli.design.pool import ScorePool
from savant_cli.models.fcs import FcsTables


def objective(scores: np.ndarray) -> float:
    """The smallest score if all are ≥ 1, else minus the total shortfall below 1."""
    shortfall = np.maximum(0.0, 1.0 - scores).sum()
    return float(scores.min()) if shortfall == 0.0 else -float(shortfall)


@dataclass
class SearchResult:
    """A schedule's search: the best parameters, their scores, and every evaluation."""

    values: dict[tuple[str, str], float]
    score: float  # objective of the best candidate (the smallest ratio when all points pass)
    initial_score: float
    evaluations: int
    wall_s: float
    history: list[float] = field(default_factory=list)  # score of each evaluation, in order
    message: str = ""


def search(params: list[FreeParameter], tables_of: Callable[[dict[tuple[str, str], float]], FcsTables],
           points: list[DesignPoint], dt: float, opt: DesignOptimizer,
           axes: tuple[str, ...], progress: Callable[[int, float], None] | None = None,
           pool: ScorePool | None = None) -> SearchResult:
    """Maximize :func:`objective` over the candidates ``tables_of(values)``.

    Parameters
    ----------
    params : list of FreeParameter
        The tuned parameters (one schedule's).
    tables_of : callable
        Parameter values → the candidate's flight-control tables.
    points : list of DesignPoint
        Where candidates are judged, each against its requirement set.
    dt : float
        Control period (s).
    opt : DesignOptimizer
        Method, evaluation budget, tolerance, initial step, early stop.
    axes : tuple of str
        Loops judged.
    progress : callable, optional
        Called with (evaluations so far, best score so far) after each evaluation.
    pool : ScorePool, optional
        Judges each candidate's points on its worker processes (the same scores as in
        this process, :mod:`savant_cli.design.pool`); None: in this process.
    """
    t0 = time.perf_counter()
    cache: dict[bytes, np.ndarray] = {}
    history: list[float] = []
    best = [-np.inf, None]

    def values_of(u: np.ndarray) -> dict[tuple[str, str], float]:
        u = np.clip(u, 0.0, 1.0)
        return {(p.schedule, p.name): p.physical(float(x)) for p, x in zip(params, u)}

    def scores(u: np.ndarray) -> np.ndarray:
        key = np.clip(u, 0.0, 1.0).tobytes()
        if key not in cache:
            ft = tables_of(values_of(u))
            cache[key] = pool.scores(points, ft, dt, axes) if pool is not None else point_scores(points, ft, dt, axes)
            s = objective(cache[key])
            history.append(s)
            if s > best[0]:
                best[0], best[1] = s, np.clip(u, 0.0, 1.0).copy()
            if progress is not None:
                progress(len(history), best[0])
            if opt.stop_ratio > 0 and best[0] >= opt.stop_ratio:
                raise _Enough
        return cache[key]

    u0 = np.array([p.normalized(p.initial) for p in params])
    initial = objective(scores(u0))
    bounds = [(0.0, 1.0)] * len(params)
    messages = []
    try:
        for attempt in range(1 + opt.restarts):  # each restart from the best point so far
            left = opt.max_evaluations - len(history)
            if left <= len(params) + 1:
                break
            start, before = best[1].copy(), best[0]
            if opt.method == "nelder_mead":
                simplex = [start] + [np.clip(start + opt.initial_step * np.eye(len(params))[i]
                                             * (1.0 if start[i] + opt.initial_step <= 1.0 else -1.0), 0.0, 1.0)
                                     for i in range(len(params))]
                res = minimize(lambda u: -objective(scores(u)), start, method="Nelder-Mead", bounds=bounds,
                               options={"maxfev": left, "xatol": opt.tolerance, "fatol": opt.tolerance,
                                        "initial_simplex": np.array(simplex)})
            else:  # epigraph: z = (u, t), maximize t with every point's score >= t
                cons = NonlinearConstraint(lambda z: scores(z[:-1]) - z[-1], 0.0, np.inf)
                res = minimize(lambda z: -z[-1], np.append(start, float(scores(start).min())), method="COBYLA",
                               constraints=[cons],
                               bounds=bounds + [(None, None)],
                               options={"maxiter": left, "rhobeg": opt.initial_step, "tol": opt.tolerance})
            messages.append(str(res.message))
            if attempt and best[0] - before <= opt.tolerance:
                break  # a restart that found nothing better
    except _Enough:
        messages.append(f"every point reached the stop ratio {opt.stop_ratio}")
    message = "; ".join(messages)
    return SearchResult(values_of(best[1]), float(best[0]), initial, len(history), time.perf_counter() - t0,
                        history, message)


class _Enough(Exception):
    """Raised inside the objective to end a search at ``stop_ratio``."""
