"""Bounds on everything that sizes work or memory (issue 27, item 6): refused at
validation with the key, the value and the allowed range, each just inside and just
outside its bound; a summary with an infinite number says why in the run's message."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli import config
from savant_cli.config import validate
from savant_cli.errors import ConfigError


def _refused(overrides: list[str]) -> ConfigError:
    with pytest.raises(ConfigError) as err:
        validate(compose_config(overrides))
    return err.value


@pytest.mark.parametrize("inside, outside, key, allowed", [
    (["study=montecarlo", f"study.n_runs={config.MAX_N_RUNS}", "study.histories.signals=[]"],
     ["study=montecarlo", f"study.n_runs={config.MAX_N_RUNS + 1}", "study.histories.signals=[]"], "study.n_runs", "1,000,000"),
    (["study=montecarlo", "study.n_runs=20000", f"study.shards={config.MAX_SHARDS}", "study.histories.signals=[]"],
     ["study=montecarlo", "study.n_runs=20000", f"study.shards={config.MAX_SHARDS + 1}"], "study.shards", "10,000"),
    (["study=montecarlo", f"study.workers={config.MAX_WORKERS}"], ["study=montecarlo", f"study.workers={config.MAX_WORKERS + 1}"],
     "study.workers", "256"),
    (["study=time_margins", f"study.workers={config.MAX_WORKERS}"],
     ["study=time_margins", f"study.workers={config.MAX_WORKERS + 1}"], "study.workers", "256"),
    ([f"winds.scale={config.MAX_WINDS_SCALE}"], [f"winds.scale={config.MAX_WINDS_SCALE * 1.001}"], "winds.scale", "0 and 5"),
    (["sim.plant_rate_hz=1000", "sim.sensor_rate_hz=1000", "sim.log_rate_hz=500", "sim.max_time_s=1000"],
     ["sim.plant_rate_hz=1000", "sim.sensor_rate_hz=1000", "sim.log_rate_hz=500", "sim.max_time_s=1001"],
     "sim.log_rate_hz", "at most 500,000"),
    (["study=linear", "study.times=[799]"], ["study=linear", "study.times=[55,800]"], "study.times[1]", "800 s"),
    (["study=mode_retention", "study.times=[55]", "sim.max_time_s=60"],
     ["study=mode_retention", "study.times=[55]", "sim.max_time_s=50"], "study.times[0]", "50 s"),
    (["study=montecarlo", "study.linear_times=[55]", "sim.max_time_s=60"],
     ["study=montecarlo", "study.linear_times=[55]", "sim.max_time_s=55"], "study.linear_times[0]", "55 s"),
    (["study=linear", "study.every=0.02"], ["study=linear", "study.every=0.019"], "study.every", "0.02 s"),
    (["study=montecarlo", "study.n_runs=62500", "study.histories.signals=[alpha]"],
     ["study=montecarlo", "study.n_runs=62501", "study.histories.signals=[alpha]"], "study.histories.rate_hz", "2.5e+08"),
    (["study=montecarlo", "study.histories.signals=[alpha]", "study.histories.rate_hz=50"],
     ["study=montecarlo", "study.histories.signals=[alpha]", "study.histories.rate_hz=51"],
     "study.histories.rate_hz", "50 Hz"),
])
def test_bound_just_inside_and_outside(inside, outside, key, allowed):
    validate(compose_config(inside))
    err = _refused(outside)
    assert err.key == key and allowed in err.allowed, str(err)


def test_the_issue_values_are_refused_at_once():
    """The values of the issue: refused in validation before anything is sized by them
    (a trillion runs used to grow memory at 120 MB/s until killed): the validation's
    peak of Python allocations stays under 64 MB, a bound the old growth passed within
    a second and that does not depend on how loaded the machine is."""
    import tracemalloc

    for overrides, key in ((["study=montecarlo", "study.n_runs=1000000000000"], "study.n_runs"),
                           (["winds.scale=1e6"], "winds.scale"),
                           (["study=linear", "study.times=[700]", "sim.max_time_s=600"], "study.times[0]"),
                           (["study=linear", "study.every=1e-9"], "study.every")):
        cfg = compose_config(overrides)
        tracemalloc.start()
        try:
            with pytest.raises(ConfigError) as err:
                validate(cfg)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert peak < 64 * 2**20, (overrides, peak)
        assert err.value.key == key


def test_histories_bound_ignores_a_batch_without_histories():
    validate(compose_config(["study=montecarlo", f"study.n_runs={config.MAX_N_RUNS}", "study.histories.signals=[]"]))


def test_nonfinite_summary_says_why():
    from savant_cli.sim.run_summary import nonfinite_note

    assert nonfinite_note({"apogee_altitude_km": 185.0, "time_separation_s": None, "status": "complete"},
                          "complete") == ""
    open_orbit = nonfinite_note({"apogee_altitude_km": np.inf, "perigee_altitude_km": 50.0}, "complete")
    assert "apogee_altitude_km = inf" in open_orbit and "open" in open_orbit and "null in summary.json" in open_orbit
    diverged = nonfinite_note({"apogee_altitude_km": np.inf, "max_alpha_deg": np.nan}, "diverged")
    assert "max_alpha_deg = nan" in diverged and "diverged" in diverged
