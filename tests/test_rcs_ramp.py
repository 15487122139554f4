"""Roll jets with a ramp time of 0 open and shut at once (issue 12 item 10): the flight
completes (the thrust-fraction rate used to be ±inf, and the run "diverged" at the first
firing), and the roll torque takes only the values 0 and ±n·F_jet·l, with
F_jet = F_vac(h) − p_amb·A_exit from the vehicle's own table."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare


def _fly(*overrides: str):
    cfg = validate(compose_config(["phase=first_stage", "sim.max_time_s=40", *overrides]))
    prep = prepare(cfg, hydra_search_dirs())
    res = simulate(prep.model, progress=False)
    return prep, res, signals(res, prep.model)


def test_zero_ramp_is_an_instantaneous_step():
    prep, res, sig = _fly("vehicle.stages.upper_stage.roll_jets.ramp_up_s=0", "vehicle.stages.upper_stage.roll_jets.ramp_down_s=0")
    assert res.status == "complete", res.message
    rcs = prep.vehicle.rcs
    alt = sig["altitude"].data
    pres = sig["pressure"].data
    f_jet = np.maximum(np.interp(alt, rcs.altitude_m, rcs.thrust_vac_N) - pres * rcs.exit_area_m2, 0.0)
    full = rcs.jets_per_direction * f_jet * rcs.moment_arm_m
    torque = sig["rcs_torque"].data
    on = np.abs(torque) > 0.0
    assert on.sum() > 10  # the jets fired
    np.testing.assert_allclose(np.abs(torque[on]), full[on], rtol=1e-9)
    # with the shipped 20/30 ms ramps the same flight logs partly open jets
    _, res_ramped, sig_ramped = _fly()
    ramped = np.abs(sig_ramped["rcs_torque"].data)
    full_r = np.interp(sig_ramped["time"].data, sig["time"].data, full)
    partial = (ramped > 1e-6 * full_r) & (ramped < (1.0 - 1e-6) * full_r)
    assert res_ramped.status == "complete" and partial.any()


def test_negative_ramp_is_refused():
    from savant_cli.errors import ConfigError

    with pytest.raises(ConfigError, match="ramp_up_s"):
        _fly("vehicle.stages.upper_stage.roll_jets.ramp_up_s=-0.01")
