"""A diverging run reports the time at which it diverged, with every model switched on.

Regression test for issue 11: the engine's step counter was reused by the slosh-wall
loop, so a run diverging with slosh on reported the time of the second step of its
chunk (0.010 s instead of 8.78 s). The reference here is the logged history itself:
logged at the plant rate, the first sample whose body-rate magnitude exceeds the
divergence limit is the reported divergence time, and none before it does.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare


@pytest.mark.parametrize("fidelity", [["slosh=off"], ["slosh=on"], ["slosh=on", "flex=on", "flex.n_modes=2",
                                                                    "actuator=simplex"]])
def test_reported_divergence_time_is_the_first_sample_past_the_limit(fidelity):
    limit_deg_s = 1.0
    cfg = validate(compose_config([*fidelity, f"sim.max_body_rate_deg_s={limit_deg_s}", "sim.log_rate_hz=200",
                                   "sim.max_time_s=30", "sim.chunk_s=4.0"]))
    model = prepare(cfg).model
    result = simulate(model, progress=False, chunk_s=cfg.sim.chunk_s)
    assert result.status == "diverged"
    sig = signals(result, model)
    t = sig["time"].data
    rate = np.degrees(np.linalg.norm(sig["body_rate"].data, axis=1))
    first = int(np.argmax(rate > limit_deg_s))
    assert rate[first] > limit_deg_s and np.all(rate[:first] <= limit_deg_s)
    assert result.t_final == pytest.approx(t[first], abs=1e-9)
    assert result.t_final > cfg.sim.chunk_s  # past the first chunk: the old counter gave 0.010 s
    assert f"diverged at t = {t[first]:.3f} s" in result.message
