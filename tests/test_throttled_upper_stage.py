"""A throttled upper stage (``models/throttle.py``, ``models/propulsion.py``,
``models/peg.py``): docs/vehicles.md's example, the J-2X held to 25 m/s².

References: the rocket equation's mass flow at the rated Isp for a throttled thrust
(closed form); the throttle's acceleration limit itself; the target orbit's insertion
state; PEG's own constant-thrust mode as the comparison its constant-acceleration mode
must beat (the thrust integrals against quadrature are ``tests/test_peg.py``'s).
"""

from __future__ import annotations

import numpy as np
import pytest

from savant_cli import constants
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import layout, peg, propulsion, throttle
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import derivative
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import summarize
from savant_cli.vehicle import load_vehicle
from test_boosters import _cfg
from test_vehicle_examples import example_node

EXAMPLE = "a-throttled-upper-stage"
LIMIT = 25.0  # the page's acceleration limit, m/s²
FOLDER = shipped_config_dir() / "vehicle" / "ares_i"


def _model(node: dict | None = None):
    cfg = _cfg()
    vehicle = load_vehicle(node or example_node(EXAMPLE), FOLDER)
    return cfg, build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file)), vehicle


def test_the_upper_stage_burns_its_setting_of_rated_thrust_at_the_rated_isp():
    """At a setting of 0.8, 20 s after ignition (the start transient over): the vacuum
    thrust is 0.8 of rated and the propellant flow ``F/(g0 Isp)``, split at the mixture
    ratio (1e-12)."""
    _, model, vehicle = _model()
    assert model.p[throttle.P_US_ON] == 1.0 and model.p[peg.P_ACCEL_LIMIT] == LIMIT
    us = vehicle.upper_stage
    x, u = model.x0.copy(), model.u0.copy()
    t = 200.0
    u[layout.U_CONFIG], u[layout.U_ENGINE], u[layout.U_T_IGN] = 2, layout.ENGINE_UPPER, t - 20.0
    u[layout.U_US_THROTTLE] = 0.8
    aux, xd = np.zeros(layout.N_AUX), np.zeros_like(x)
    derivative(t, x, u, model.p, model.packed_tables, aux, xd)
    assert aux[propulsion.A_THRUST_VAC] == pytest.approx(0.8 * us.thrust_vac_N, rel=1e-12)
    assert aux[throttle.A_US_SETTING] == 0.8
    flow = 0.8 * us.thrust_vac_N / (constants.G0 * us.isp_vac_s)
    lox, lh2 = xd[model.layout.tank("lox")], xd[model.layout.tank("lh2")]
    assert lox + lh2 == pytest.approx(-flow, rel=1e-12)
    assert lox / lh2 == pytest.approx(us.mixture_ratio, rel=1e-12)


@pytest.mark.parametrize("keep_limit", [True, False])
def test_an_upper_stage_throttle_with_a_schedule_is_refused_naming_it(tmp_path, keep_limit):
    """A schedule on the upper stage (with or without a limit) is refused at the engine's
    ``throttle``: PEG models a constant-thrust then constant-acceleration burn only."""
    folder = tmp_path / "ares_i"
    folder.mkdir()
    for f in FOLDER.iterdir():
        (folder / f.name).symlink_to(f)
    (folder / "upper_throttle.csv").write_text("time_s,throttle\n0.0,1.0\n600.0,0.8\n")
    node = example_node(EXAMPLE)
    section = node["stages"]["upper_stage"]["engines"]["j2x"]["throttle"]
    section["table"] = "upper_throttle.csv"
    if not keep_limit:
        del section["axial_acceleration_limit_mps2"]
    with pytest.raises(ConfigError) as exc:
        load_vehicle(node, folder)
    assert exc.value.key.endswith("j2x.throttle") and "axial_acceleration_limit_mps2" in str(exc.value)


@pytest.fixture(scope="module")
def flights():
    """The example flown, and flown again with PEG modelling constant thrust."""
    cfg, model, _ = _model()
    out = []
    for limit in (LIMIT, 0.0):
        model.p[peg.P_ACCEL_LIMIT] = limit
        result = simulate(model, progress=False)
        sig = signals(result, model)
        out.append((result, sig, summarize(result, sig, target=peg.insertion_target(cfg.guidance), p=model.p)))
    model.p[peg.P_ACCEL_LIMIT] = LIMIT
    return out


@pytest.mark.slow
def test_the_throttle_holds_the_limit_and_peg_flies_to_the_target(flights):
    """The sensed acceleration never exceeds the limit by more than 0.1 % and sits on it
    (within 0.1 %) while the throttle is below 1; PEG cuts off on target (radius within
    50 m, velocity within 0.1 m/s), its engagement prediction of the cutoff within 1.5 s,
    where its constant-thrust mode was more than 2 s early and inserted further off."""
    (result, sig, summary), (result_ct, sig_ct, summary_ct) = flights
    assert result.status == "complete" and summary["peg_converged_at_cutoff"] == 1
    t = sig["time"].data
    burning = (t > result.events[engine.EV_IGNITION] + 5.0) & (t < result.events[engine.EV_CUTOFF])
    accel = np.linalg.norm(sig["sensed_acceleration"].data, axis=1)
    setting = sig["upper_stage_throttle"].data
    assert np.max(accel[burning]) <= LIMIT * 1.001
    limited = burning & (setting < 1.0)
    assert limited.sum() > 10 and np.max(np.abs(accel[limited] - LIMIT)) < 1e-3 * LIMIT
    assert abs(summary["insertion_radius_error_m"]) < 50.0 and summary["insertion_velocity_error_mps"] < 0.1

    def engagement_error(result, sig):
        k = int(np.argmax(sig["peg_active"].data > 0))
        return sig["time"].data[k] + sig["peg_time_to_go"].data[k] - result.events[engine.EV_CUTOFF]

    assert abs(engagement_error(result, sig)) < 1.5
    assert engagement_error(result_ct, sig_ct) < -2.0
    assert abs(summary_ct["insertion_radius_error_m"]) > abs(summary["insertion_radius_error_m"])
