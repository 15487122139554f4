"""A candidate's design points judged on several processes.

The frozen plants of every design point and corner are built once, before the workers
start; the workers are forked (:func:`savant_cli.processes.process_context`), so they
inherit them and a candidate sends only its flight-control tables (a few kB) and the
indices of the points to judge. Each worker judges an interleaved share of the points
(neighbouring points cost alike) and returns their scores, which are the same numbers as
:func:`savant_cli.design.points.point_scores` computes in one process: every judgement
is a pure function of the point and the tables.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import numpy as np

from savant_cli.design.points import DesignPoint, point_scores
from savant_cli.models.fcs import FcsTables
from savant_cli.processes import process_context, terminate_workers, worker_initializer

_POINTS: list[DesignPoint] = []  # the pool's points, inherited by its forked workers


def _scores(indices: list[int], ft: FcsTables, dt: float, axes: tuple[str, ...]) -> np.ndarray:
    return point_scores([_POINTS[i] for i in indices], ft, dt, axes)


class ScorePool:
    """Scores of candidates at ``points`` on ``workers`` processes (1: in this process).

    Use as a context manager; the workers are stopped on exit.
    """

    def __init__(self, points: list[DesignPoint], workers: int):
        global _POINTS
        _POINTS = list(points)
        self._index = {id(p): i for i, p in enumerate(_POINTS)}
        self.workers = max(1, min(workers, len(_POINTS)))
        self._pool = (ProcessPoolExecutor(self.workers, mp_context=process_context(), **worker_initializer())
                      if self.workers > 1 else None)

    def scores(self, points: list[DesignPoint], ft: FcsTables, dt: float, axes: tuple[str, ...]) -> np.ndarray:
        """:func:`~savant_cli.design.points.point_scores` of ``ft`` at ``points`` (each one
        of the pool's)."""
        if self._pool is None:
            return point_scores(points, ft, dt, axes)
        idx = [self._index[id(p)] for p in points]
        out = np.empty(len(idx))
        futures = {k: self._pool.submit(_scores, idx[k::self.workers], ft, dt, axes)
                   for k in range(min(self.workers, len(idx)))}
        for k, fut in futures.items():
            out[k::self.workers] = fut.result()
        return out

    def __enter__(self) -> ScorePool:
        return self

    def __exit__(self, exc_type: type | None, *exc: object) -> None:
        if self._pool is not None:
            if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):
                terminate_workers(self._pool)  # a Ctrl-C: the judgements in flight are abandoned
            self._pool.shutdown(wait=True, cancel_futures=True)
