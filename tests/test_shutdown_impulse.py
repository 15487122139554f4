"""The J-2X shutdown impulse (issue 26 item 2): after the cutoff command the engine's
thrust decays and delivers the configured impulse, the insertion state is taken after
the decay, and guidance's anticipation of the nominal impulse keeps the nominal flight
on its target. The flown impulse is integrated from the plant-rate history."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.models import propulsion
from savant_cli.models.peg import insertion_target
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim import engine
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import propulsion_keys, summarize

BASE = ["phase=upper_stage", "sim.log_rate_hz=200", "sim.progress=false"]


def _fly(overrides):
    cfg = validate(compose_config([*BASE, *overrides]))
    prep = prepare(cfg, hydra_search_dirs())
    res = simulate(prep.model, progress=False)
    assert res.stop_code == engine.STOP_GUIDANCE_CUTOFF, res.message
    summ = summarize(res, signals(res, prep.model), target=insertion_target(cfg.guidance), p=prep.model.p)
    return prep, res, summ


@pytest.fixture(scope="module")
def nominal():
    return _fly([])


def _flown_shutdown_impulse(prep, res) -> tuple[float, float]:
    """Impulse after the cutoff command (N·s), trapezoid of the logged vacuum thrust, and
    the time from the command to the end of the run (s)."""
    model = prep.model
    t = res.log[:, 0]
    f = res.log[:, 1 + model.layout.n + propulsion.A_THRUST_VAC]
    t_cut = res.events[engine.EV_CUTOFF]
    after = t >= t_cut - 1e-9
    tt, ff = t[after], f[after]
    if tt[-1] < res.t_final - 1e-9:  # the decay ends at the stop: thrust zero there
        tt, ff = np.append(tt, res.t_final), np.append(ff, 0.0)
    return float(np.trapezoid(ff, tt)), float(res.t_final - t_cut)


def test_flown_shutdown_impulse_is_the_configured_one(nominal):
    prep, res, summ = nominal
    us = prep.vehicle.upper_stage
    flown, duration = _flown_shutdown_impulse(prep, res)
    assert flown == pytest.approx(us.shutdown_impulse_Ns, rel=2e-3)
    assert summ["shutdown_impulse_Ns"] == pytest.approx(us.shutdown_impulse_Ns, rel=2e-3)
    # the decay lasts 2 I / F and the run ends with it
    assert duration == pytest.approx(2.0 * us.shutdown_impulse_Ns / us.thrust_vac_N, abs=prep.model.rates.dt)


def test_dispersed_shutdown_impulse_is_flown():
    prep, res, summ = _fly(["vehicle.stages.upper_stage.engines.j2x.shutdown_impulse_Ns=300000.0"])
    flown, _ = _flown_shutdown_impulse(prep, res)
    assert flown == pytest.approx(300000.0, rel=2e-3)
    assert summ["shutdown_impulse_Ns"] == pytest.approx(300000.0, rel=2e-3)


def test_guidance_anticipates_the_nominal_shutdown_impulse(nominal):
    """PEG cuts off early by the tail-off's thrust-equivalent time, so the nominal flight
    inserts on target; without the anticipation it overshoots by the tail-off's Δv."""
    prep, res, summ = nominal
    m_cut = summ["cutoff_mass_kg"]
    dv_tail = prep.vehicle.upper_stage.shutdown_impulse_Ns / m_cut  # ≈ 6 m/s
    assert dv_tail > 5.0
    assert abs(summ["insertion_speed_error_mps"]) < 0.1 * dv_tail
    assert abs(summ["insertion_apogee_error_km"]) < 1.0 and abs(summ["insertion_perigee_error_km"]) < 1.0
    _, _, late = _fly(["guidance.peg.shutdown_impulse_time_s=0.0"])
    assert late["insertion_speed_error_mps"] == pytest.approx(dv_tail, rel=0.15)
