"""The demonstrated success probability (montecarlo/reliability.py) against closed forms
and the binomial distribution's own definition."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binom

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.montecarlo.reliability import (
    demonstrated, lower_quantile_rank, reliability, runs_for_quantile, runs_needed
)


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


def test_successes_are_counted_and_the_line_says_so():
    r = reliability([True] * 98 + [False] * 2, ("loss_of_control",), 0.9, 0.99)
    assert (r.runs, r.successes, r.failures) == (100, 98, 2)
    assert r.demonstrated_probability == pytest.approx(demonstrated(98, 100, 0.9)) and not r.target_met
    assert "success 98 of 100 runs" in r.line() and "NOT met" in r.line()
    assert r.as_dict()["failure_classes"] == ["loss_of_control"]


@pytest.mark.parametrize("n", [10, 500, 1704, 1705, 2000, 5000, 20000])
@pytest.mark.parametrize("probability, confidence", [(0.99865, 0.9), (0.99, 0.95), (0.9, 0.5)])
def test_order_statistic_bounds_the_low_quantile_by_the_beta_law(n, probability, confidence):
    """The k-th smallest of n uniform samples is Beta(k, n − k + 1): it lies at or below the
    (1 − P) quantile with probability I_q(k, n − k + 1) (the regularized incomplete beta
    function, an identity independent of the binomial sum the code uses). The rank chosen
    reaches C and the next one does not."""
    from scipy.special import betainc

    q = 1.0 - probability
    k = lower_quantile_rank(n, probability, confidence)
    if k is None:
        assert betainc(1, n, q) < confidence  # not even the lowest sample
        assert n < runs_for_quantile(probability, confidence)
        return
    assert betainc(k, n - k + 1, q) >= confidence
    assert k == n or betainc(k + 1, n - k, q) < confidence


def test_the_issues_reserve_figures():
    """99.865 % at 90 %: 1 − 0.99865^n ≥ 0.9 first at n = ceil(ln 0.1 / ln 0.99865) = 1705;
    2000 runs give the lowest run (1 − 0.99865^2000 = 0.933), 500 runs none."""
    assert runs_for_quantile(0.99865, 0.9) == math.ceil(math.log(0.1) / math.log(0.99865)) == 1705
    assert lower_quantile_rank(2000, 0.99865, 0.9) == 1 and 1 - 0.99865 ** 2000 == pytest.approx(0.9330, abs=1e-4)
    assert lower_quantile_rank(500, 0.99865, 0.9) is None


def test_order_statistic_coverage_by_simulation():
    """Sampling check of the bound: over 4000 batches of 3000 standard normal runs, the
    chosen order statistic lies at or below the true 0.135 % quantile (−3σ) in at least
    90 % of the batches (within the sampling error)."""
    from scipy.stats import norm

    rng = np.random.default_rng(26)
    n, batches = 3000, 4000
    k = lower_quantile_rank(n, 0.99865, 0.9)
    x = np.partition(rng.standard_normal((batches, n)), k - 1, axis=1)[:, k - 1]
    covered = np.mean(x <= norm.ppf(0.00135))
    expected = float(binom.sf(k - 1, n, 0.00135))
    assert expected >= 0.9 and covered == pytest.approx(expected, abs=3 * np.sqrt(expected * (1 - expected) / batches))


@pytest.mark.parametrize("override, key", [
    ("study.reliability.confidence=1.0", "study.reliability.confidence"),
    ("study.reliability.target_probability=0", "study.reliability.target_probability"),
    ("study.reliability.reserve_probability=0", "study.reliability.reserve_probability"),
])
def test_bad_reliability_settings_are_refused(override, key):
    with pytest.raises(ConfigError) as err:
        validate(compose_config(["study=montecarlo", override]))
    assert err.value.key == key
