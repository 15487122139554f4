"""PEG across two burns (``guidance.peg.first_stage_burn``, ``models/peg.py``,
``sim/engine.py``): a liquid first stage's burn guided to its own cutoff state, the
attitude held through staging, then the upper stage's burn guided to the insertion orbit.

References: the cutoff lands on the plant step nearest PEG's predicted time (half a
step); the stage's state at the end of its thrust against the target within what a
fraction of a guidance cycle's flight changes; the held command constant; a stage 3 %
low in thrust still cut off on target (PEG senses the acceleration), later;
the kernel's two-burn mission in vacuum is in ``tests/test_peg.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import peg
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import summarize
from savant_cli.vehicle import load_vehicle
from test_boosters import _cfg
from test_vehicle_examples import example_node

FOLDER = shipped_config_dir() / "vehicle" / "ares_i"
#: The page's guided burn (docs/models.md, "Two burns"): engaged at 120 s, in the
#: vehicle's own plane, to the state the unguided stage passes at 180 s.
BURN = dict(start_s=120.0, isp_vac_s=311.0, shutdown_impulse_time_s=0.2, perigee_altitude_km=-6014.0,
            apogee_altitude_km=81.8, cutoff_altitude_km=64.0, plane="engagement")
LIMIT = 20.0  # m/s²: the page's first-stage throttle limit, which lengthens the burn past 180 s


def _override(**changes) -> str:
    burn = {**BURN, **changes}
    return "+guidance.peg.first_stage_burn={" + ",".join(f"{k}:{v}" for k, v in burn.items()) + "}"


def _node(thrust_scale: float = 1.0) -> dict:
    node = example_node("a-first-stage-cutoff")
    engine_node = node["stages"]["first_stage"]["engines"]["booster_engine"]
    engine_node["throttle"].update(minimum=0.3, axial_acceleration_limit_mps2=LIMIT)
    engine_node["thrust_vac_N"] *= thrust_scale
    return node


def _fly(thrust_scale: float = 1.0):
    cfg = _cfg(_override())
    command_file = prepare(_cfg(), hydra_search_dirs()).command_file  # the shipped vehicle's profile
    model = build_model(cfg, load_vehicle(_node(thrust_scale), FOLDER), read_guidance(command_file))
    result = simulate(model, progress=False)
    sig = signals(result, model)
    return model, result, sig, summarize(result, sig, target=peg.insertion_target(cfg.guidance), p=model.p)


@pytest.fixture(scope="module")
def flights():
    return _fly(), _fly(thrust_scale=0.97)


def _at(sig, t: float) -> int:
    return int(np.searchsorted(sig["time"].data, t - 1e-9))


@pytest.mark.slow
def test_peg_cuts_the_first_stage_off_on_its_target_then_flies_the_upper_stage(flights):
    """The first stage's cutoff is PEG's (``first_stage_shutdown: guidance``), on the plant
    step nearest its predicted time; at the end of the thrust the radius is within what
    0.5 s of climb changes, the speed within 0.1 s of the thrust acceleration, the
    flight-path angle within 0.1 deg of the target; the upper stage's PEG engages afresh
    after ignition and inserts within the target's tolerance."""
    model, result, sig, summary = flights[0]
    dt = model.rates.dt
    assert result.status == "complete" and summary["first_stage_shutdown"] == "guidance"
    t_cut = result.events[engine.EV_FS_CUTOFF]
    predicted = sig["peg_cutoff_time"].data[_at(sig, t_cut) - 1]  # the latest cycle's, before the step
    assert abs(t_cut - predicted) <= 0.5 * dt + 1e-9
    i = _at(sig, t_cut)
    r, v = sig["position_eci"].data[i], sig["velocity_eci"].data[i]
    climb = np.dot(r, v) / np.linalg.norm(r)  # m/s
    assert abs(summary["first_stage_burn_radius_error_m"]) < 0.5 * climb
    assert abs(summary["first_stage_burn_speed_error_mps"]) < 0.1 * LIMIT
    assert abs(summary["first_stage_burn_flight_path_angle_error_deg"]) < 0.1
    assert summary["peg_engage_time_s"] > result.events[engine.EV_IGNITION]
    target = peg.insertion_target(_cfg().guidance)
    assert abs(summary["perigee_altitude_km"] - target.apsis_altitudes_km[0]) < 1.0
    assert abs(summary["apogee_altitude_km"] - target.apsis_altitudes_km[1]) < 1.0


@pytest.mark.slow
def test_the_attitude_is_held_from_the_cutoff_until_the_upper_stage_steers(flights):
    """From the first guidance cycle after the first stage's cutoff until the upper
    stage's PEG engages, the raw guidance command is one attitude at zero rate."""
    model, result, sig, summary = flights[0]
    t = sig["time"].data
    held = (t >= np.ceil(result.events[engine.EV_FS_CUTOFF]) + 0.01) & (t < summary["peg_engage_time_s"])
    q = sig["quaternion_guidance"].data[held]
    assert held.sum() > 100 and np.abs(q - q[0]).max() == 0.0


@pytest.mark.slow
def test_a_low_thrust_stage_burns_longer_and_still_cuts_off_on_target(flights):
    """The stage's rated thrust 3 % low (guidance is not told): the stage climbs slower
    before its throttle reaches the limit; PEG senses the acceleration, cuts the stage
    off later, on its target within the same bounds."""
    (_, nominal, _, _), (_, result, sig, summary) = flights
    assert summary["first_stage_shutdown"] == "guidance"
    assert result.events[engine.EV_FS_CUTOFF] > nominal.events[engine.EV_FS_CUTOFF] + 0.5
    assert abs(summary["first_stage_burn_speed_error_mps"]) < 0.1 * LIMIT
    assert abs(summary["first_stage_burn_flight_path_angle_error_deg"]) < 0.1


def test_in_the_target_plane_the_short_stage_fails_at_engagement():
    """``plane: target``: the example's stage is 111 m/s and 5.6 km out of the target plane
    at 120 s, which 60 s of burn cannot take out; PEG does not converge at engagement and
    the run says so (the reason for ``plane: engagement``)."""
    cfg = _cfg(_override(plane="target"))
    command_file = prepare(_cfg(), hydra_search_dirs()).command_file
    model = build_model(cfg, load_vehicle(_node(), FOLDER), read_guidance(command_file))
    result = simulate(model, progress=False, t_stop=130.0)
    assert result.status == "guidance_failed" and "did not converge at engagement" in result.message
    assert result.t_final == pytest.approx(BURN["start_s"], abs=1e-6)
    sig = signals(result, model)
    i = _at(sig, BURN["start_s"])
    normal = -model.p[peg.P_IY:peg.P_IY + 3]
    assert abs(sig["velocity_eci"].data[i] @ normal) > 100.0 and abs(sig["position_eci"].data[i] @ normal) > 5e3


def test_a_solid_first_stage_refuses_a_guided_burn():
    """The shipped ares_i's solid motor burns to its end: the key is named."""
    cfg = _cfg(_override())
    with pytest.raises(ConfigError) as info:
        prepare(cfg, hydra_search_dirs())
    assert info.value.key == "guidance.peg.first_stage_burn"


@pytest.mark.parametrize("changes, key", [
    (dict(plane="other"), "plane"),
    (dict(perigee_altitude_km=-6400.0), "perigee_altitude_km"),
    (dict(apogee_altitude_km=-6100.0), "apogee_altitude_km"),
    (dict(cutoff_altitude_km=90.0), "cutoff_altitude_km"),
    (dict(cutoff_altitude_km=0.0), "cutoff_altitude_km"),
    (dict(start_s=0.0), "start_s"),
])
def test_a_bad_first_stage_burn_is_refused_naming_its_key(changes, key):
    with pytest.raises(ConfigError) as info:
        validate(compose_config([_override(**changes)]))
    assert info.value.key == f"guidance.peg.first_stage_burn.{key}"


@pytest.mark.slow
def test_a_target_beyond_the_stage_fails_the_run_as_guidance_failed():
    """A cutoff orbit far beyond the stage (apogee 300 km; its unguided burnout coasts to under 90 km):
    PEG's time to go stops converging, and the run says so in its status and message,
    with the time, and keeps what it flew (its history up to then, its summary)."""
    cfg = _cfg(_override(apogee_altitude_km=300.0))
    command_file = prepare(_cfg(), hydra_search_dirs()).command_file
    model = build_model(cfg, load_vehicle(_node(), FOLDER), read_guidance(command_file))
    result = simulate(model, progress=False)
    sig = signals(result, model)
    summary = summarize(result, sig, p=model.p)
    assert result.status == "guidance_failed" and "PEG" in result.message
    assert BURN["start_s"] <= result.t_final < 190.6  # engaged, failed before the stage's own burnout
    assert summary["status"] == "guidance_failed" and sig["time"].data[-1] == pytest.approx(result.t_final, abs=0.1)
    assert summary["first_stage_shutdown"] is None and summary["first_stage_burn_speed_error_mps"] is None
