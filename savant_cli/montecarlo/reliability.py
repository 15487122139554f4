"""The success probability a Monte Carlo batch demonstrates, by order statistics.

With ``n`` independent runs of which ``f`` fail, the success probability demonstrated at
confidence ``C`` is the one-sided Clopper–Pearson lower bound: the smallest ``p`` for which
``f`` or fewer failures in ``n`` still has probability ``1 − C`` (Hanson and Beard,
"Applying Monte Carlo Simulation to Launch Vehicle Design and Requirements Verification",
NASA/TP-2010-216447). ``scipy.stats.binomtest(...).proportion_ci(method="exact")``
computes it. Examples: 2000 runs, 2 failures, 90 % → 99.734 %; 0 failures → 99.885 %.

The runs a target ``p`` needs at ``C`` (allowing as many failures as the batch had) is the
smallest ``n`` whose bound reaches ``p``; e.g. 852 failure-free runs for 99.73 % at 90 %.

The same binomial argument bounds a quantile by an order statistic
(:func:`lower_quantile_rank`): the flight-performance reserve
(``montecarlo/insertion.py``) is read at the order statistic that lies at or below the
0.135 % quantile of the usable propellant with the confidence of the success line.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

# scipy.stats (about a second to import) is imported where a batch's statistics are
# computed, not by every run that imports this module on its way to report.html


def demonstrated(successes: int, runs: int, confidence: float) -> float:
    """The success probability demonstrated at ``confidence`` by ``successes`` of ``runs``
    (one-sided exact binomial lower bound; 0 with no run)."""
    if runs <= 0:
        return 0.0
    from scipy.stats import binomtest

    ci = binomtest(successes, runs, alternative="greater").proportion_ci(confidence_level=confidence, method="exact")
    return float(ci.low)


def runs_needed(target: float, confidence: float, failures: int = 0) -> int:
    """The fewest runs that demonstrate ``target`` at ``confidence`` with ``failures``
    failed runs among them."""
    def enough(n: int) -> bool:
        return demonstrated(n - failures, n, confidence) >= target

    hi = failures + 1
    while not enough(hi):
        hi *= 2
    lo = hi // 2 if hi > failures + 1 else failures  # enough(lo) is false (or lo has no success)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if enough(mid) else (mid, hi)
    return hi


@dataclass
class Reliability:
    """A batch's demonstrated success (the ``reliability`` block of the Monte Carlo
    summary): a run succeeds when none of its mission failure classes
    (``savant_cli/sim/mission.py``) is among ``failure_classes``."""

    runs: int  # runs counted (every run with a mission outcome: all but "interrupted")
    successes: int
    failures: int
    failure_classes: tuple[str, ...]  # the classes counted as a failed mission
    confidence: float
    demonstrated_probability: float  # at ``confidence``
    target_probability: float
    target_met: bool
    runs_needed_for_target: int  # with this batch's failures

    def line(self) -> str:
        """E.g. ``"success 1998 of 2000 runs: 99.734 % demonstrated at 90 % confidence
        (target 99.73 %: met; 1970 runs needed with 2 failures)"``."""
        return (f"success {self.successes} of {self.runs} runs: {100 * self.demonstrated_probability:.3f} % "
                f"demonstrated at {100 * self.confidence:g} % confidence (target {100 * self.target_probability:g} %: "
                f"{'met' if self.target_met else 'NOT met'}; {self.runs_needed_for_target} runs needed with "
                f"{self.failures} failure{'s' if self.failures != 1 else ''})")

    def as_dict(self) -> dict[str, Any]:
        return {**self.__dict__, "failure_classes": list(self.failure_classes), "line": self.line()}


def reliability(successes: list[bool], failure_classes: tuple[str, ...], confidence: float,
                target: float) -> Reliability:
    """The :class:`Reliability` of the counted runs (one entry each: whether the run
    succeeded under ``failure_classes``)."""
    ok = int(sum(bool(s) for s in successes))
    n = len(successes)
    p = demonstrated(ok, n, confidence)
    return Reliability(n, ok, n - ok, tuple(failure_classes), confidence, p, target, p >= target,
                       runs_needed(target, confidence, n - ok))


def lower_quantile_rank(runs: int, probability: float, confidence: float) -> int | None:
    """The order statistic that bounds a low tail from below at a confidence.

    With ``runs`` independent samples sorted ascending, ``X_(k)`` (1-based) is at or below
    the distribution's ``q = 1 − probability`` quantile with probability
    ``P(Binomial(runs, q) ≥ k)`` (the number of samples below that quantile is binomial;
    Hanson and Beard, NASA/TP-2010-216447, the method of the success line). Returns the
    largest ``k`` for which that probability is at least ``confidence``, or None when even
    the lowest sample does not reach it (too few runs: see :func:`runs_for_quantile`)."""
    q = 1.0 - probability
    k = np.arange(1, runs + 1)
    from scipy.stats import binom

    ok = binom.sf(k - 1, runs, q) >= confidence
    return int(k[ok].max()) if ok.any() else None


def runs_for_quantile(probability: float, confidence: float) -> int:
    """The fewest runs whose lowest sample bounds the ``1 − probability`` quantile at
    ``confidence``: ``1 − probability^n ≥ confidence``, i.e. ``n ≥ ln(1 − C) / ln(p)``."""
    n = int(np.ceil(np.log1p(-confidence) / np.log(probability)))
    while 1.0 - probability ** n < confidence:  # guard the ceiling against round-off
        n += 1
    return n
