"""The demonstrated success probability (montecarlo/reliability.py) against closed forms
and the binomial distribution's own definition."""

from __future__ import annotations

import math

import pytest
from scipy.stats import binom

from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.montecarlo.reliability import demonstrated, reliability, runs_needed

from conftest import compose_config


@pytest.mark.parametrize("n", [1, 10, 852, 2000])
def test_no_failure_bound_is_the_closed_form(n):
    """0 failures in n: p_L^n = 1 − C."""
    assert demonstrated(n, n, 0.9) == pytest.approx(0.1 ** (1.0 / n), rel=1e-10)


@pytest.mark.parametrize("n, failures, confidence", [(2000, 2, 0.9), (500, 5, 0.95), (100, 1, 0.5)])
def test_bound_makes_the_observed_failures_a_1_minus_c_event(n, failures, confidence):
    """At the lower bound p_L, P(f or fewer failures in n) = 1 − C (Clopper–Pearson)."""
    p = demonstrated(n - failures, n, confidence)
    assert binom.cdf(failures, n, 1.0 - p) == pytest.approx(1.0 - confidence, rel=1e-6)


def test_the_issues_figures():
    """2 losses in 2000 runs demonstrate 99.73 % at 90 % (Hanson & Beard's example);
    failure-free, 99.73 % needs ceil(ln 0.1 / ln 0.9973) = 852 runs."""
    assert demonstrated(1998, 2000, 0.9) >= 0.9973 > demonstrated(1997, 2000, 0.9)
    assert runs_needed(0.9973, 0.9, 0) == math.ceil(math.log(0.1) / math.log(0.9973)) == 852


@pytest.mark.parametrize("failures", [0, 1, 2, 7])
def test_runs_needed_is_the_fewest(failures):
    n = runs_needed(0.999, 0.9, failures)
    assert demonstrated(n - failures, n, 0.9) >= 0.999 > demonstrated(n - 1 - failures, n - 1, 0.9)


def test_interrupted_runs_are_not_counted_and_losses_are():
    r = reliability(["complete"] * 97 + ["limit_cycle", "diverged", "failed", "interrupted"],
                    ("complete", "limit_cycle", "saturated"), 0.9, 0.99)
    assert (r.runs, r.successes, r.failures) == (100, 98, 2)
    assert r.demonstrated_probability == pytest.approx(demonstrated(98, 100, 0.9)) and not r.target_met
    assert "success 98 of 100 runs" in r.line() and "NOT met" in r.line()


@pytest.mark.parametrize("override, key", [
    ("study.reliability.confidence=1.0", "study.reliability.confidence"),
    ("study.reliability.target_probability=0", "study.reliability.target_probability"),
    ("study.reliability.success_statuses=[complete,interrupted]", "study.reliability.success_statuses[1]"),
    ("study.reliability.success_statuses=[]", "study.reliability.success_statuses"),
])
def test_bad_reliability_settings_are_refused(override, key):
    with pytest.raises(ConfigError) as err:
        validate(compose_config(["study=montecarlo", override]))
    assert err.value.key == key
