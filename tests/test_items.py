"""Jettisoned items in any phase (docs/vehicles.md, "Items in any phase"): several items,
each dropped by its own event in the first stage's burn, the coast or the upper stage's
burn, in the order written.

The invariants: the centre of mass and the linear momentum of the vehicle and the item
are conserved across a jettison (the item leaves with the velocity of its own CG on the
rotating body), the configuration sequence follows the jettisons, a jettison whose
trigger holds early waits for the one written before it, and what the plant flies
cannot be written otherwise (refusals naming the key).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from savant_cli.datagen.guidance_commands import TIMED_SLOTS
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import layout, quaternion as qt
from savant_cli.montecarlo.targets import first_stage_configurations, upper_configurations
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model, event_times
from savant_cli.sim.plant import mass_state
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from test_boosters import _cfg
from test_vehicle_examples import example_node

SHIPPED = shipped_config_dir() / "vehicle"
LES_KG, FAIRINGS_KG = 7060.0, 1200.0  # the shipped LES's and the page's fairings' masses
LES_CG = np.array([3.25, 0.0, 0.0])  # the shipped LES's CG, structure frame (m)
LES_AT_S = 100.0  # the LES's jettison in the first stage's burn (s after liftoff)


def _first_stage_les() -> dict:
    """The page's example with the LES dropped in the first stage's burn, written first:
    the stack, the stack without the LES, the upper stage with its fairings, alone."""
    node = example_node("items-in-any-phase")
    configs = node["configurations"]
    stack, upper_les = configs["stack"], configs["upper_fairings"]
    node["configurations"] = {
        "stack": stack,
        "stack_no_les": {**stack, "parts": ["first_stage", "upper_stage", "sm_fairings"]},
        "upper_fairings": {**upper_les, "parts": ["upper_stage", "sm_fairings"]},
        "upper": configs["upper"]}
    events = node["events"]
    node["events"] = {"les_jettison": {"after": "liftoff", "delay_s": LES_AT_S, "jettison": ["les"]},
                      "separation": events["separation"], "sm_fairing_jettison": events["sm_fairing_jettison"],
                      "upper_stage_ignition": events["upper_stage_ignition"]}
    return node


def _vehicle(node: dict):
    return load_vehicle(node, SHIPPED / "ares_i")


@pytest.fixture(scope="module")
def flight():
    cfg = _cfg()
    vehicle = _vehicle(_first_stage_les())
    model = build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file))
    result = simulate(model, progress=False, t_stop=140.0)
    return model, result


def test_the_configurations_follow_the_written_order():
    v = _vehicle(_first_stage_les())
    assert list(v.configurations) == ["stack", "stack_2", "upper_les", "upper"]
    assert v.first_stage_configurations == 2
    assert first_stage_configurations(v) == ("stack", "stack_2") and upper_configurations(v) == ("upper_les", "upper")
    assert [(j.name, j.kind) for j in v.jettisons] == [("les_jettison", "items"), ("separation", "stage"),
                                                       ("sm_fairing_jettison", "items")]
    les = v.events.trigger(engine.EV_LES)
    sep = v.events.trigger(engine.EV_SEPARATION)
    fairings = v.events.trigger(engine.EV_ITEMS[1])
    assert (les.after, les.delay_s, les.waits_for) == (-1, LES_AT_S, -1)
    assert sep.waits_for == engine.EV_LES and fairings.waits_for == engine.EV_SEPARATION
    mass = {n: c.mass for n, c in v.configurations.items()}
    np.testing.assert_allclose(mass["stack"].mass_kg - mass["stack_2"].mass_kg, LES_KG, atol=1e-6)


@pytest.mark.slow
def test_each_item_leaves_at_its_step_and_the_sequence_follows(flight):
    model, result = flight
    dt = model.rates.dt
    ev = result.events
    assert result.status == "complete"
    assert LES_AT_S <= ev[engine.EV_LES] < LES_AT_S + dt  # the first step boundary from its time on
    t_sep = ev[engine.EV_SEPARATION]
    assert 120.0 < t_sep < 135.0
    assert ev[engine.EV_ITEMS[1]] == pytest.approx(t_sep + 1.0, abs=dt)
    sig = signals(result, model)
    t, config = sig["time"].data, sig["configuration"].data
    for t0, t1, k in ((0.0, ev[engine.EV_LES], 0), (ev[engine.EV_LES], t_sep, 1),
                      (t_sep, ev[engine.EV_ITEMS[1]], 2), (ev[engine.EV_ITEMS[1]], t[-1] + 1.0, 3)):
        assert np.all(config[(t >= t0) & (t < t1)] == k)
    mass = sig["mass"].data
    i = np.searchsorted(t, ev[engine.EV_LES])  # the first sample after the jettison
    burned = (mass[i - 2] - mass[i - 1]) / (t[i - 1] - t[i - 2]) * (t[i] - t[i - 1])  # the flow between them
    assert mass[i - 1] - mass[i] == pytest.approx(LES_KG + burned, rel=1e-3)


@pytest.mark.slow
def test_the_jettison_conserves_the_centre_of_mass_and_the_momentum(flight):
    """Before the step's events: the whole vehicle; after: the rest and the LES, which
    leaves with the velocity of its own CG on the rotating body (ω × r)."""
    model, result = flight
    k = int(round(result.events[engine.EV_LES] / model.rates.dt))
    snap = simulate(model, progress=False, snapshot_steps=(k,), t_stop=(k + 1) * model.rates.dt).snapshots[k]
    x, u, d, ev = snap.x.copy(), snap.u.copy(), snap.d.copy(), snap.events.copy()
    p, tb = model.p, model.packed_tables
    engine.handle_events(snap.t, model.rates.dt, x, u, d, ev, model.sched, p, tb, engine.work_array(x.size))
    assert ev[engine.EV_LES] == snap.t and (snap.u[layout.U_CONFIG], u[layout.U_CONFIG]) == (0, 1)
    m_b, *cg_b = mass_state(snap.x, p, tb, 0, np.zeros(layout.N_AUX))[1]
    m_a = mass_state(x, p, tb, 1, np.zeros(layout.N_AUX))[1][0]
    assert m_b - m_a == pytest.approx(LES_KG, abs=1e-6)
    c_b2i = qt.dcm(snap.x[layout.Q:layout.Q + 4])
    arm = c_b2i @ (np.diag([-1.0, 1.0, -1.0]) @ (LES_CG - np.array(cg_b)))  # CG → the LES's CG, ECI (m)
    w = c_b2i @ snap.x[layout.W:layout.W + 3]  # body rate, ECI axes (rad/s)
    r_b, v_b = snap.x[layout.R:layout.R + 3], snap.x[layout.V:layout.V + 3]
    r_a, v_a = x[layout.R:layout.R + 3], x[layout.V:layout.V + 3]
    # about the old CG: m_a (r_a − r_b) + m_LES arm = 0 (the Earth-sized positions cancel
    # first), to the tables' interpolation: each configuration's CG is interpolated
    # linearly between the rows, a composition's CG is a ratio, so the two tables' CGs
    # disagree by micrometres between rows (a centimetre misplaced would be 1e-2 here)
    scale = LES_KG * np.linalg.norm(arm)
    np.testing.assert_allclose(m_a * (r_a - r_b) + LES_KG * arm, 0.0, atol=1e-5 * scale)
    np.testing.assert_allclose(m_a * (v_a - v_b) + LES_KG * np.cross(w, arm), 0.0,
                               atol=1e-5 * scale * np.linalg.norm(w))
    np.testing.assert_allclose(x[layout.W:layout.W + 3], snap.x[layout.W:layout.W + 3], rtol=0, atol=0)


def test_a_jettison_waits_for_the_one_written_before_it():
    """The fairings' trigger (5 s after liftoff) holds long before the separation written
    before it: they leave at the step after it (items are checked before the separation
    at a step), the separation at its own tail-off."""
    node = _first_stage_les()
    node["events"]["sm_fairing_jettison"] = {"after": "liftoff", "delay_s": 5.0, "jettison": ["sm_fairings"]}
    cfg = _cfg("sim.max_time_s=140")
    vehicle = _vehicle(node)
    model = build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file))
    result = simulate(model, progress=False)
    ev = result.events
    assert ev[engine.EV_ITEMS[1]] == pytest.approx(ev[engine.EV_SEPARATION] + model.rates.dt, abs=1e-9)
    alone = _vehicle(_first_stage_les())
    assert vehicle.events.trigger(engine.EV_SEPARATION) == alone.events.trigger(engine.EV_SEPARATION)


SLOTS = (engine.EV_SEPARATION, engine.EV_BOOSTER_JETTISON, *TIMED_SLOTS)  # the reference's


def test_the_reference_places_each_jettison_at_its_delay():
    v = _vehicle(example_node("items-in-any-phase"))
    times = event_times(v, SLOTS, 126.0, None)
    assert (times[0], times[1], times[engine.EV_ITEMS[0]], times[engine.EV_ITEMS[1]]) == (126.0, 127.5, 127.0, 157.5)
    late = copy.deepcopy(example_node("items-in-any-phase"))
    late["events"]["sm_fairing_jettison"]["delay_s"] = 40.0  # past the LES's, written after it: it waits for it
    late["events"] = {k: late["events"][k] for k in ("separation", "upper_stage_ignition", "les_jettison",
                                                     "sm_fairing_jettison")}
    late["configurations"]["upper_les"]["parts"] = ["upper_stage", "sm_fairings"]
    times = event_times(_vehicle(late), SLOTS, 126.0, None)
    assert (times[engine.EV_ITEMS[0]], times[engine.EV_ITEMS[1]]) == (157.5, 166.0)


def _ignition_with_the_fairings(node: dict) -> None:
    """The fairings' jettison lights the J-2X too (one event of two kinds)."""
    events = node["events"]
    del events["upper_stage_ignition"]
    events["sm_fairing_jettison"]["ignite"] = ["j2x"]
    events["les_jettison"]["after"] = "sm_fairing_jettison"


@pytest.mark.parametrize("change, key, words", [
    (_ignition_with_the_fairings, "vehicle.events.sm_fairing_jettison", "this event is: after separation, ignite"),
    (lambda n: n["configurations"]["stack"].update(mass_table="mass_stack.csv")
     or n["configurations"]["upper_fairings"].update(mass_table="mass_upper_les.csv"),
     "vehicle.items.sm_fairings.mass_kg", "minus"),
])
def test_what_the_plant_cannot_fly_is_refused_naming_the_key(change, key, words):
    node = copy.deepcopy(example_node("items-in-any-phase"))
    change(node)
    with pytest.raises(ConfigError) as info:
        _vehicle(node)
    assert info.value.key.startswith(key) and words in str(info.value)
