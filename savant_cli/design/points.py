"""The design points of ``study=fcs_design`` and their scores: a frozen operating point
of one uncertainty corner with the requirement set it is judged against
(:class:`DesignPoint`), a candidate controller's verdicts there (:func:`judge_all`) and
the score of each (:func:`point_score`, :func:`point_scores`). The search
(``design/search.py``) and the worker pool (``design/pool.py``) both judge candidates
with these.

The score of a point is its worst check's ratio (:attr:`Check.ratio`: |margin| / required,
attenuation / required; ≥ 1 meets the requirement); a lost closed loop scores
``−1 − 10 σ_max`` (σ_max its largest real part, 1/s), below any kept loop and graded so the
search can climb out of it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from savant_cli.config import RequirementSet
from savant_cli.linear.evaluate import FrozenPoint, judge_controller
from savant_cli.linear.requirements import PointVerdict
from savant_cli.models.fcs import FcsTables


@dataclass
class DesignPoint:
    """A frozen operating point of one uncertainty corner (``""``: the nominal plant) and
    the requirement set it is judged against there (a corner's may be a fraction of the
    nominal's, :func:`savant_cli.linear.requirements.scaled_requirements`)."""

    corner: str
    point: FrozenPoint
    requirements: RequirementSet


def point_score(v: PointVerdict) -> float:
    """The worst check's ratio to its requirement (module notes); a failing check of a
    zero requirement (e.g. a bending peak above 0 dB with no crossing of its own) scores
    v/(1 + |v|) of its value v (dB or deg, negative), in (−1, 0], not the ratio's −∞: graded
    for the search, above any lost closed loop."""
    stability = v.checks[-1]
    if not stability.passed:
        return -1.0 - 10.0 * stability.value
    ratios = [c.ratio if np.isfinite(c.ratio) or c.ratio > 0 else min(c.value, 0.0) / (1.0 + abs(c.value))
              for c in v.checks if c.criterion != "stability"]
    return float(min(ratios)) if ratios else float("inf")


def judge_all(points: list[DesignPoint], ft: FcsTables, dt: float,
              axes: tuple[str, ...] = ("pitch", "yaw")) -> list[PointVerdict]:
    """The verdict of ``ft`` at every point against its own requirement set (loops of
    ``axes`` only).

    Parameters
    ----------
    points : list of DesignPoint
        Where the candidate is judged.
    ft : FcsTables
        The candidate's flight-control tables.
    dt : float
        The flight-control period (s).
    axes : tuple of str
        The loops judged (``"pitch"``, ``"yaw"``).

    Returns
    -------
    list of PointVerdict
        One per point, in order (margins in dB and deg, stability in 1/s).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # python-control notes on unconnected signals
        return [judge_controller(p.point, ft, dt, p.requirements, axes=axes)[2] for p in points]


def point_scores(points: list[DesignPoint], ft: FcsTables, dt: float, axes: tuple[str, ...]) -> np.ndarray:
    """:func:`point_score` of ``ft`` at every point (the parameters as :func:`judge_all`'s:
    ``dt`` in s).

    Returns
    -------
    numpy.ndarray
        One score per point (dimensionless ratio to the requirement; ≥ 1 meets it).
    """
    return np.array([point_score(v) for v in judge_all(points, ft, dt, axes)])
