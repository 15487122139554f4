"""A liquid first stage shut down by an event (its "MECO") before separation
(``vehicle/two_stage.py``, ``models/propulsion.py``, ``sim/engine.py``, ``sim/build.py``).

References: closed forms of a rated burn (the time a tank reaches a level at a constant
flow), the linear shutdown decay's impulse ``k I_sd`` (``T_sd = 2 I_sd / F``), the usable
load of two tanks, and in flight the trigger placed within one plant step of its
condition, the separation exactly its delay after the cutoff, and the engine's
shutdown reported as commanded or, when a tank ran dry first, as depletion.
"""

from __future__ import annotations

import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import compose_config
from savant_cli import constants
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import layout, propulsion
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import build, engine
from savant_cli.sim.build import (
    build_model, event_schedule, first_stage_march, plant_data, predicted_separation_time, rates
)
from savant_cli.sim.plant import pack_tables
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import first_stage_cutoff_keys
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.two_stage import usable_load
from test_vehicle_examples import example_node

SHIPPED = shipped_config_dir() / "vehicle"
EXAMPLE = "a-first-stage-cutoff"
F_RATED, ISP, MR, EXIT_AREA = 14.0e6, 311.0, 2.6, 8.0  # the page's engine
OX, FUEL = 467600.0, 180000.0  # its tanks, kg
I_SD = 2.8e6  # its shutdown impulse, N s
T_SD = 2.0 * I_SD / F_RATED  # its linear decay, s
OX_LEVEL = 5000.0  # the cutoff's oxidizer level, kg
SEP_DELAY = 1.0  # separation after the cutoff, s
FLOW = F_RATED / (constants.G0 * ISP)  # rated mass flow, kg/s


def _node(unthrottled: bool = False, **cutoff) -> dict:
    node = example_node(EXAMPLE)
    if unthrottled:
        del node["stages"]["first_stage"]["engines"]["booster_engine"]["throttle"]
    node["events"]["meco"].update(cutoff)
    node["events"]["meco"] = {k: v for k, v in node["events"]["meco"].items() if v is not None}
    return node


def _vehicle(unthrottled: bool = False, **cutoff):
    return load_vehicle(_node(unthrottled, **cutoff), SHIPPED / "ares_i")


def _march(vehicle):
    cfg = validate(compose_config(["sim.progress=false"]))
    p, tables = plant_data(cfg, vehicle)
    tb = pack_tables(tables)
    return first_stage_march(vehicle, p, tb), predicted_separation_time(vehicle, p, tb)


# ---------------------------------------------------------------- the trace
def test_a_timed_cutoff_decays_linearly_and_delivers_the_shutdown_impulse():
    (time_s, thrust, t_cut), t_sep = _march(_vehicle(unthrottled=True, when=None, delay_s=100.0))
    assert t_cut == 100.0
    after = time_s >= t_cut
    assert np.trapezoid(thrust[after], time_s[after]) == pytest.approx(I_SD, rel=1e-12)
    assert time_s[-1] == pytest.approx(t_cut + T_SD, rel=1e-12) and thrust[-1] == 0.0
    assert t_sep == pytest.approx(t_cut + SEP_DELAY, abs=1e-3)  # armed a delay after the cutoff; no thrust then


def test_a_propellant_cutoff_falls_where_a_rated_burn_leaves_the_level():
    (time_s, thrust, t_cut), _ = _march(_vehicle(unthrottled=True))
    # the oxidizer burns at MR/(1+MR) of the rated flow from liftoff
    assert t_cut == pytest.approx((OX - OX_LEVEL) * (1 + MR) / MR / FLOW, rel=1e-12)
    before = (time_s >= 0.0) & (time_s <= t_cut)
    burned = np.trapezoid(thrust[before], time_s[before]) / (constants.G0 * ISP)
    assert OX - burned * MR / (1 + MR) == pytest.approx(OX_LEVEL, rel=1e-9)


def test_a_tank_that_empties_during_the_decay_ends_the_trace_at_the_usable_load():
    # 100 kg of oxidizer left at the command, where the decay would burn some 660 kg of it
    (time_s, thrust, t_cut), _ = _march(_vehicle(unthrottled=True, when={"quantity": "propellant_kg",
                                                                        "of": "first_stage_lox", "below": 100.0}))
    on = (time_s >= 0.0) & (time_s <= time_s[-2])  # liftoff to the tank's end (the drop after is the table's)
    burned = np.trapezoid(thrust[on], time_s[on]) / (constants.G0 * ISP)
    assert burned == pytest.approx(usable_load(MR, OX, FUEL), rel=1e-9)
    assert time_s[-2] < t_cut + T_SD and thrust[-2] > 0.0


def _les_dropped_in_the_first_stage(cutoff_accel: float) -> dict:
    """The page's vehicle at rated thrust, its LES jettisoned 50 s after liftoff (in the
    first stage's flight: a configuration of the stage and the upper stage, composed from
    their own tables) and its cutoff once the axial acceleration exceeds ``cutoff_accel``."""
    node = _node(unthrottled=True, when={"quantity": "axial_acceleration_mps2", "above": cutoff_accel})
    stack = node["configurations"]["stack"]
    node["configurations"] = {"stack": stack, "stack_bare": {**stack, "parts": ["first_stage", "upper_stage"],
                                                             "mass_table": None},
                              "upper": node["configurations"]["upper"]}
    events = node["events"]
    node["events"] = {"meco": events["meco"], "les_jettison": {"delay_s": 50.0, "jettison": ["les"]},
                      "separation": events["separation"], "upper_stage_ignition": events["upper_stage_ignition"]}
    return node


def test_the_trace_flies_the_items_dropped_in_the_first_stage():
    """A drag-free rated burn to an acceleration: ``F / m = a`` at the mass of the
    configuration flown, the stack less the LES from 50 s (its own mass tables)."""
    accel = 30.0
    vehicle = load_vehicle(_les_dropped_in_the_first_stage(accel), SHIPPED / "ares_i")
    (time_s, thrust, t_cut), _ = _march(vehicle)
    bare = vehicle.configurations["stack_2"].mass
    rated = F_RATED * 1.0  # the start transient's last fraction is 1
    # the propellant left when the bare stack weighs F / a (its mass rises with propellant)
    left = np.interp(rated / accel, bare.mass_kg, bare.propellant_kg)
    expected = (OX + FUEL - left) / FLOW
    assert expected > 50.0  # the cutoff comes after the jettison
    assert abs(t_cut - expected) <= build.TRACE_STEP_S
    les = vehicle.jettisons[0].mass_kg
    stack = vehicle.configurations["stack"].mass
    with_les = (OX + FUEL - np.interp(rated / accel, stack.mass_kg, stack.propellant_kg)) / FLOW
    # the LES kept aboard: the same weight reached once its mass more is burned (the old trace's 1.58 s error)
    assert with_les - expected == pytest.approx(les / FLOW, rel=1e-6)


# ------------------------------------------------------------- refusals
@pytest.mark.parametrize("change, match", [
    (dict(delay_s=0.0), r"meco\.delay_s.*a delay > 0 s"),
    (dict(when={"quantity": "altitude_m", "above": 40000.0}), r"meco\.when\.quantity.*propellant_kg of a first-stage"),
    (dict(when={"quantity": "propellant_kg", "of": "lox", "below": 10.0}), r"meco\.when\.of.*a tank of first_stage"),
    (dict(when={"quantity": "thrust_fraction", "of": "first_stage", "below": 0.5}),
     r"meco\.when\.quantity = 'thrust_fraction'.*propellant_kg of a first-stage tank or axial_acceleration_mps2"),
    (dict(after="separation"), r"events\.meco\.after = 'separation': must name liftoff or an event written before"),
])
def test_a_bad_cutoff_is_refused_naming_its_key(change, match):
    with pytest.raises(ConfigError, match=match):
        _vehicle(**change)


def test_a_solid_motor_cannot_be_shut_down():
    node = OmegaConf.to_container(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle)
    node["events"] = {"meco": {"delay_s": 100.0, "shutdown": ["five_segment_motor"]}, **node["events"]}
    with pytest.raises(ConfigError, match=r"meco\.shutdown.*solid motor, which burns to its end"):
        load_vehicle(node, SHIPPED / "ares_i")


def test_separation_counts_from_liftoff_or_the_cutoff_only():
    node = _node()
    node["events"]["separation"]["after"] = "upper_stage_ignition"
    with pytest.raises(ConfigError, match=r"separation"):
        load_vehicle(node, SHIPPED / "ares_i")
    node = _node()
    node["events"]["separation"].update(after="liftoff", delay_s=0.0)  # on its thrust fraction alone: allowed
    rule = _vehicle_rules(load_vehicle(node, SHIPPED / "ares_i"))[engine.EV_SEPARATION]
    assert (rule.after, rule.delay_s) == (-1, 0.0)


def _vehicle_rules(vehicle):
    cfg = validate(compose_config([]))
    return event_schedule(cfg, vehicle, rates(cfg)).rules


# ---------------------------------------------------------------- flight
def _fly(vehicle):
    cfg = validate(compose_config(["sim.progress=false"]))
    model = build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file))
    result = simulate(model, progress=False)
    return model, result, signals(result, model)


@pytest.fixture(scope="module")
def flight():
    return _fly(_vehicle())


def _oxidizer(total_kg: float) -> float:
    """The oxidizer of a stage holding ``total_kg`` after burning in the mixture ratio."""
    return (total_kg - FUEL + OX / MR) / (1.0 + 1.0 / MR)


def test_the_cutoff_fires_within_one_step_of_its_level_and_separation_its_delay_later(flight):
    model, result, sig = flight
    assert result.status == "complete"
    dt = model.rates.dt
    t_cut, t_sep = result.events[engine.EV_FS_CUTOFF], result.events[engine.EV_SEPARATION]
    assert abs(t_sep - (t_cut + SEP_DELAY)) < 1e-9 * t_sep
    k = sig["throttle"].data[sig["time"].data >= t_cut]
    assert np.all(k == k[0]) and 0.5 <= k[0] < 1.0  # held from the command on
    # the oxidizer at the command: what separation found, plus what the decay burned (k I_sd)
    ox_decay = k[0] * I_SD / (constants.G0 * ISP) * MR / (1 + MR)
    ox_at_cut = _oxidizer(result.d[propulsion.D_FS_PROP_SEP]) + ox_decay
    ox_step = k[0] * FLOW * MR / (1 + MR) * dt  # one plant step's oxidizer
    assert OX_LEVEL - ox_step <= ox_at_cut < OX_LEVEL
    assert first_stage_cutoff_keys(result) == {"time_first_stage_cutoff_s": t_cut, "first_stage_shutdown": "commanded"}
    # the prediction places the cutoff by the drag-free law: late (it throttles sooner), not early
    assert 0.0 <= model.info["predicted_separation_time_s"] - t_sep < 0.5


def test_the_thrust_decays_linearly_from_the_command(flight):
    model, result, sig = flight
    t = sig["time"].data
    t_cut = result.events[engine.EV_FS_CUTOFF]
    decay = (t > t_cut) & (t < result.events[engine.EV_SEPARATION])
    k = sig["throttle"].data[decay]
    vac = k * F_RATED * np.maximum(1.0 - (t[decay] - t_cut) / T_SD, 0.0)
    want = np.maximum(vac - sig["pressure"].data[decay] * EXIT_AREA, 0.0)
    np.testing.assert_allclose(sig["thrust"].data[decay], want, rtol=1e-9, atol=1e-6)
    assert want[0] > 0.0 and want[-1] == 0.0


def test_a_level_never_reached_is_reported_as_a_depletion_shutdown():
    # the fuel's residual at depletion is 153.8 kg: a 100 kg fuel level is never reached
    model, result, sig = _fly(_vehicle(when={"quantity": "propellant_kg", "of": "rp1", "below": 100.0}))
    assert result.status == "complete"
    keys = first_stage_cutoff_keys(result)
    assert keys["first_stage_shutdown"] == "depletion" and result.u[layout.U_FS_T_CUT] == 0.0
    t_cut, t_sep = keys["time_first_stage_cutoff_s"], result.events[engine.EV_SEPARATION]
    assert abs(t_sep - (t_cut + SEP_DELAY)) < 1e-9 * t_sep
    residual = FUEL - usable_load(MR, OX, FUEL) / (1 + MR)
    assert abs(result.d[propulsion.D_FS_PROP_SEP] - residual) < FLOW * model.rates.dt
