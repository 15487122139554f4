"""The solid motor's dispersions conserve what physics conserves, and separation is
decided on board from the flown motor (issue 26 item 2).

Every figure is read from the flown history at the plant rate (``sim.log_rate_hz`` =
``sim.plant_rate_hz``) and compared with closed forms: the delivered vacuum impulse
``g0 Isp M`` of a load ``M`` burned at ``Isp``, the load itself, and the burn-rate
scaling ``t_sep,k = t_sep,0 / k`` of a motor whose thrust is ``k F0(k t)``.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import propulsion
from savant_cli.montecarlo.targets import Target, apply_samples, build_dispersed
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim import engine
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare

RATE = ["sim.log_rate_hz=200", "sim.progress=false", "winds=none"]
TOL = 1e-3  # the 0.1 %


@pytest.fixture(scope="module")
def base():
    cfg = validate(compose_config(["phase=first_stage", *RATE]))
    prep = prepare(cfg, hydra_search_dirs())
    return cfg, prep.vehicle, read_guidance(prep.command_file)


def _model(base, **factors):
    """The model of a motor dispersed by ``burn_rate``, ``load`` (table targets) and
    ``isp`` (a scale of vehicle.first_stage.isp_vac_s), through the Monte Carlo's own path."""
    cfg, vehicle, guidance = base
    items = []
    if "burn_rate" in factors:
        items.append((Target("tables.first_stage.burn_rate", "tables"), "scale", factors["burn_rate"]))
    if "load" in factors:
        items.append((Target("tables.first_stage.propellant_load", "tables"), "scale", factors["load"]))
    if "isp" in factors:
        items.append((Target("vehicle.first_stage.isp_vac_s", "vehicle", ("first_stage", "isp_vac_s"),
                             vehicle.first_stage.isp_vac_s), "scale", factors["isp"]))
    applied = apply_samples(cfg, vehicle, items, {})
    return applied, build_dispersed(applied, guidance)


def _whole_burn(base, **factors):
    """Fly the stack without separating (fraction 0) past the end of the dispersed trace;
    return the vehicle, times (s), flown vacuum thrust (N) and first-stage propellant (kg)."""
    applied, model = _model(base, **factors)
    rules = list(model.sched.rules)  # a thrust never below 0 % of its peak: no separation
    rules[engine.EV_SEPARATION] = rules[engine.EV_SEPARATION]._replace(threshold=0.0)
    model.sched = model.sched._replace(rules=tuple(rules))
    t_end = applied.vehicle.first_stage.thrust_time_s[-1]
    res = simulate(model, progress=False, t_stop=t_end + 2.0)
    assert np.isnan(res.events[engine.EV_SEPARATION])
    log = res.log
    t = log[:, 0]
    f_vac = log[:, 1 + model.layout.n + propulsion.A_THRUST_VAC]
    prop = log[:, 1 + model.layout.tank("grain")]
    return applied.vehicle, t, f_vac, prop


@pytest.fixture(scope="module")
def nominal_burn(base):
    return _whole_burn(base)


def _impulse(t, f):
    return float(np.trapezoid(f, t))


def test_nominal_motor_delivers_g0_isp_load_and_burns_its_load(base, nominal_burn):
    vehicle, t, f, prop = nominal_burn
    fs = vehicle.first_stage
    assert _impulse(t, f) == pytest.approx(constants.G0 * fs.isp_vac_s * fs.propellant_kg, rel=TOL)
    assert prop[0] - prop[-1] == pytest.approx(fs.propellant_kg, rel=TOL)
    assert prop[-1] < TOL * fs.propellant_kg  # nothing left when the trace ends
    assert np.all(f[t > fs.thrust_time_s[-1]] == 0.0)  # and no thrust after it


@pytest.mark.parametrize("k", [0.97, 1.03])
def test_burn_rate_conserves_load_and_total_impulse(base, nominal_burn, k):
    _, t0, f0, prop0 = nominal_burn
    vehicle, t, f, prop = _whole_burn(base, burn_rate=k)
    fs = vehicle.first_stage
    assert _impulse(t, f) == pytest.approx(_impulse(t0, f0), rel=TOL)
    assert prop[0] - prop[-1] == pytest.approx(prop0[0] - prop0[-1], rel=TOL)
    assert prop[-1] < TOL * fs.propellant_kg
    # the burn ends when the propellant does: the last thrust sample is within the trace
    t_last = t[np.nonzero(f > 0.0)[0][-1]]
    assert t_last == pytest.approx(t0[np.nonzero(f0 > 0.0)[0][-1]] / k, abs=0.02)
    # thrust × k on a time axis ÷ k: the peak is k times the nominal's
    assert f.max() == pytest.approx(k * f0.max(), rel=TOL)


def test_isp_scales_thrust_at_the_same_mass_flow(base, nominal_burn):
    _, t0, f0, prop0 = nominal_burn
    _, t, f, prop = _whole_burn(base, isp=1.01)
    np.testing.assert_allclose(prop, prop0, rtol=0, atol=1e-6 * prop0[0])  # same mass flow
    np.testing.assert_allclose(f, 1.01 * f0, rtol=1e-9, atol=1e-3)


def test_load_scales_flow_and_thrust_at_the_same_burn_time(base, nominal_burn):
    _, t0, f0, prop0 = nominal_burn
    vehicle, t, f, prop = _whole_burn(base, load=1.003)
    assert vehicle.first_stage.propellant_kg == pytest.approx(1.003 * 647600.0)
    assert prop[0] - prop[-1] == pytest.approx(1.003 * (prop0[0] - prop0[-1]), rel=TOL)
    np.testing.assert_allclose(f, 1.003 * f0, rtol=1e-9, atol=1e-3)
    assert prop[-1] < TOL * vehicle.first_stage.propellant_kg
    stack = vehicle.configurations["stack"].mass
    assert stack.mass_kg[-1] - stack.mass_kg[0] == pytest.approx(1.003 * 647600.0, abs=1.0)


def _separation(base, **factors):
    applied, model = _model(base, **factors)
    res = simulate(model, progress=False)
    assert res.stop_code == engine.STOP_SEPARATION
    return applied, model, res


@pytest.fixture(scope="module")
def nominal_separation(base):
    return _separation(base)


def _flown_thrust(vehicle, t):
    """The motor's vacuum thrust from its data alone (numpy): load in the table's shape at Isp."""
    fs = vehicle.first_stage
    mdot = fs.propellant_kg * np.interp(t, fs.thrust_time_s, fs.thrust_vac_N) / np.trapezoid(fs.thrust_vac_N,
                                                                                              fs.thrust_time_s)
    return constants.G0 * fs.isp_vac_s * mdot


def test_separation_is_the_first_step_below_the_fraction_of_the_flown_peak(nominal_separation):
    applied, model, res = nominal_separation
    frac = applied.vehicle.events.separation_thrust_fraction
    t = res.log[:, 0]
    f = res.log[:, 1 + model.layout.n + propulsion.A_THRUST_VAC]
    t_sep = res.events[engine.EV_SEPARATION]
    before = t < t_sep - 0.5 * model.rates.dt
    t, f = t[before], f[before]
    np.testing.assert_allclose(np.diff(t), model.rates.dt, rtol=1e-9)  # every step up to separation
    assert t[-1] == pytest.approx(t_sep - model.rates.dt)
    peak = np.maximum.accumulate(f)
    assert np.all(f >= frac * peak)  # no earlier step met the rule
    f_sep = _flown_thrust(applied.vehicle, t_sep)
    assert f_sep < frac * peak[-1]  # the separation step does
    np.testing.assert_allclose(f, _flown_thrust(applied.vehicle, t), rtol=1e-9)  # the flown motor is its data


def test_faster_burning_motor_separates_earlier_by_the_burn_rate_scaling(base, nominal_separation):
    dt = nominal_separation[1].rates.dt
    t0 = nominal_separation[2].events[engine.EV_SEPARATION]
    for k in (1.03, 0.97):
        t_k = _separation(base, burn_rate=k)[2].events[engine.EV_SEPARATION]
        assert t_k == pytest.approx(t0 / k, abs=2 * dt)
    assert t0 / 1.03 < t0 - 3.0  # the check is not trivial: ~3.8 s earlier


def test_summary_impulse_and_propellant_at_separation(nominal_separation):
    """The summary's first-stage figures against the flown history and the closed form."""
    from savant_cli.sim.summary import propulsion_keys

    applied, model, res = nominal_separation
    keys = propulsion_keys(res, model.p)
    fs = applied.vehicle.first_stage
    t = res.log[:, 0]
    f = res.log[:, 1 + model.layout.n + propulsion.A_THRUST_VAC]
    t_sep = res.events[engine.EV_SEPARATION]
    before = t < t_sep - 0.5 * model.rates.dt
    flown = _impulse(np.append(t[before], t_sep), np.append(f[before], _flown_thrust(applied.vehicle, t_sep)))
    assert keys["first_stage_total_impulse_Ns"] == pytest.approx(flown, rel=1e-6)
    left = keys["first_stage_propellant_at_separation_kg"]
    assert 0.0 < left < 0.001 * fs.propellant_kg  # the 2 % cue leaves ~0.02 % of the load
    # what the motor delivered is g0 Isp times what it burned
    assert keys["first_stage_total_impulse_Ns"] == pytest.approx(constants.G0 * fs.isp_vac_s * (fs.propellant_kg - left),
                                                                 rel=1e-5)
