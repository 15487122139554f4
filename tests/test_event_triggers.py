"""Events from the vehicle's sequence: a condition trigger fires at the first step
boundary at which its condition holds, never a step early or late.

The shipped ares_i's LES jettison is given a condition instead of its 30 s delay (armed at
the J-2X ignition): altitude above 80 km, dynamic pressure below 20 Pa, sensed axial
acceleration above 12 m/s², LOX below 90 t, the CG's radial speed below 600 m/s. The
state at the start of the event's step and of the step before it (before their events:
the run's snapshots) is evaluated by the plant: the condition must hold at the event's
step and not at the one before. The
flight's log at the plant rate shows the jettison itself at that step.
"""

from __future__ import annotations

import numpy as np
import pytest

from savant_cli.config import validate
from savant_cli.datagen.guidance_commands import timed_events
from savant_cli.errors import ConfigError
from savant_cli.hydra_compose import compose_config, task_config
from savant_cli.models import blocks, layout
from savant_cli.sim import engine
from savant_cli.sim.plant import derivative
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare

EVENT = "vehicle.events.les_jettison"


def _prepared(when: dict, *extra: str):
    overrides = ["sim.log_rate_hz=200", "sim.max_time_s=400", f"{EVENT}.delay_s=0.0",
                 *(f"+{EVENT}.when.{k}={v}" for k, v in when.items()), *extra]
    return prepare(validate(task_config(compose_config(overrides, None))))


def _quantity(model, snap, when: dict) -> float:
    """The condition's quantity in a snapshot (the state at the start of its step)."""
    aux, xd = np.zeros(layout.N_AUX), np.zeros(snap.x.size)
    derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, xd)
    field = {"altitude_m": "earth.altitude", "dynamic_pressure_Pa": "aero.dynamic_pressure",
             "axial_acceleration_mps2": "rigid_body.sensed_acceleration"}
    if when["quantity"] == "propellant_kg":
        return float(snap.x[model.layout.tank("lox")])
    if when["quantity"] == "radial_speed_mps":  # r·v/|r| of the CG
        r, v = snap.x[layout.R:layout.R + 3], snap.x[layout.V:layout.V + 3]
        return float(np.dot(r, v) / np.linalg.norm(r))
    return float(aux[blocks.DIAGNOSTICS.field(field[when["quantity"]]).index])


@pytest.mark.parametrize("when", [
    {"quantity": "altitude_m", "above": 80000.0},
    {"quantity": "dynamic_pressure_Pa", "below": 20.0},
    {"quantity": "axial_acceleration_mps2", "above": 12.0},
    {"quantity": "propellant_kg", "of": "lox", "below": 90000.0},
    {"quantity": "radial_speed_mps", "below": 600.0},
])
def test_a_condition_fires_within_one_step(when):
    model = _prepared(when).model
    assert model.sched.rules[engine.EV_LES].when != engine.WHEN_NONE
    result = simulate(model, progress=False)
    t_event = result.events[engine.EV_LES]
    assert result.events[engine.EV_IGNITION] < t_event < result.t_final, result.events
    k = int(round(t_event / model.rates.dt))
    snaps = simulate(model, progress=False, snapshot_steps=(k - 1, k), t_stop=t_event + 1.0).snapshots
    threshold = when.get("above", when.get("below"))
    holds = (lambda v: v > threshold) if "above" in when else (lambda v: v < threshold)
    before, at = _quantity(model, snaps[k - 1], when), _quantity(model, snaps[k], when)
    assert holds(at) and not holds(before), (before, at, threshold)
    # the jettison itself, in the log of every plant step: the mass drops by the LES's 7.06 t
    sig = signals(result, model)
    i = int(np.flatnonzero(sig["time"].data == t_event)[0])
    mass = sig["mass"].data
    burned = mass[i - 2] - mass[i - 1]  # one step's propellant, before the jettison
    assert mass[i - 1] - mass[i] == pytest.approx(7060.0 + burned, abs=0.01)


def test_a_delay_arms_the_condition():
    """Armed 50 s after ignition, an altitude long exceeded fires on the arming step."""
    prep = _prepared({"quantity": "altitude_m", "above": 1000.0}, f"{EVENT}.delay_s=50.0")
    result = simulate(prep.model, progress=False, t_stop=250.0)
    dt = prep.model.rates.dt
    t_armed = result.events[engine.EV_IGNITION] + 50.0
    assert t_armed <= result.events[engine.EV_LES] < t_armed + dt


def test_a_thrust_fraction_triggers_the_separation_only():
    with pytest.raises(ConfigError) as info:
        _prepared({"quantity": "thrust_fraction", "of": "j2x", "below": 0.5})
    assert info.value.key == f"{EVENT}.when.quantity"


def test_the_reference_generator_refuses_a_condition():
    """The command-file generator places events at their delays: it names the event."""
    prep = _prepared({"quantity": "altitude_m", "above": 80000.0})
    with pytest.raises(ConfigError) as info:
        timed_events(prep.vehicle)
    assert info.value.key == f"{EVENT}.when"
