"""The success probability a Monte Carlo batch demonstrates, by order statistics.

With ``n`` independent runs of which ``f`` fail, the success probability demonstrated at
confidence ``C`` is the one-sided Clopper–Pearson lower bound: the smallest ``p`` for which
``f`` or fewer failures in ``n`` still has probability ``1 − C`` (Hanson and Beard,
"Applying Monte Carlo Simulation to Launch Vehicle Design and Requirements Verification",
NASA/TP-2010-216447). ``scipy.stats.binomtest(...).proportion_ci(method="exact")``
computes it. Examples: 2000 runs, 2 failures, 90 % → 99.734 %; 0 failures → 99.885 %.

The runs a target ``p`` needs at ``C`` (allowing as many failures as the batch had) is the
smallest ``n`` whose bound reaches ``p``; e.g. 852 failure-free runs for 99.73 % at 90 %.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from scipy.stats import binomtest


def demonstrated(successes: int, runs: int, confidence: float) -> float:
    """The success probability demonstrated at ``confidence`` by ``successes`` of ``runs``
    (one-sided exact binomial lower bound; 0 with no run)."""
    if runs <= 0:
        return 0.0
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
    summary)."""

    runs: int  # runs counted (flown to a verdict: every status but "interrupted")
    successes: int
    failures: int
    success_statuses: tuple[str, ...]
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
        return {**self.__dict__, "success_statuses": list(self.success_statuses), "line": self.line()}


def reliability(statuses: list[str], success_statuses: tuple[str, ...], confidence: float,
                target: float) -> Reliability:
    """The :class:`Reliability` of runs with ``statuses`` (``"interrupted"`` runs not
    counted), a run succeeding when its status is one of ``success_statuses``."""
    counted = [s for s in statuses if s != "interrupted"]
    ok = sum(s in success_statuses for s in counted)
    p = demonstrated(ok, len(counted), confidence)
    failures = len(counted) - ok
    return Reliability(len(counted), ok, failures, tuple(success_statuses), confidence, p, target, p >= target,
                       runs_needed(target, confidence, failures))
