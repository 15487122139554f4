"""Slosh on any tank (docs/vehicles.md, "Slosh on any stage"): the tanks of a liquid
first stage slosh beside the upper stage's, by the vehicle file's names.

References: a tank's liquid level is its propellant over ``ρ π R²`` (closed form); a
jettisoned tank's slosh mass leaves the vehicle (its states held, its level, frequency
and force zero); the linear plant's lightly damped pairs at the slosh frequency number
two per tank aboard (a pitch-plane and a yaw-plane pendulum each), each between the
frequency the plant computes in closed form, ``ω = ω_table(level) √(a / a_ref)``, and
that frequency raised by the mass's coupling to a free rigid body,
``ω √(1 + m_s (1/m_r + d²/I))`` (a pendulum of mass ``m_s`` at ``d`` from the CG of a
body of mass ``m_r`` and pitch inertia ``I``); the refusals name their keys.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.flex_slosh import load_flex, load_slosh, point_keys
from savant_cli.io.guidance_file import read_guidance
from savant_cli.linear.modes import plant_group
from savant_cli.linear.plant import linear_states, linearize_plant
from savant_cli.models import layout, slosh
from savant_cli.models.flex import N_POINTS, PT_GIMBAL_FS, PT_GYRO_FS, PT_SLOSH
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import derivative, mass_state
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from test_vehicle_examples import example_node

SHIPPED = shipped_config_dir() / "vehicle"
TANKS = ("first_stage_lox", "rp1", "lox", "lh2")
#: the example's first-stage tanks: radius m, density kg/m³
GEOMETRY = {"first_stage_lox": (2.75, 1141.0), "rp1": (2.75, 820.0)}


def _vehicle():
    return load_vehicle(example_node("first-stage-slosh"), SHIPPED / "ares_i")


def test_every_sloshing_tank_in_the_order_of_the_propellant_states():
    vehicle = _vehicle()
    assert tuple(vehicle.slosh_spec) == TANKS == vehicle.tanks
    data = load_slosh(vehicle, validate(compose_config(["slosh=on"])).slosh)
    # the first stage's tanks are aboard in the stack only; the upper stage's in all three
    assert [(t.name, t.configurations) for t in data.tanks] == [
        ("first_stage_lox", 1), ("rp1", 1), ("lox", 3), ("lh2", 3)]
    assert [t.reference_accel_mps2 for t in data.tanks] == [9.80665] * 4


def test_a_solid_grain_does_not_slosh():
    node = example_node("first-stage-slosh")
    node["stages"]["first_stage"] = example_node("jettison-on-a-condition")["stages"]["first_stage"]
    node["stages"]["first_stage"]["tanks"]["grain"]["slosh"] = node["stages"]["upper_stage"]["tanks"]["lox"]["slosh"]
    node["configurations"]["stack"]["mass_tanks"] = ["grain"]
    node["events"]["separation"]["when"]["of"] = "five_segment_motor"
    with pytest.raises(ConfigError, match="solid motor's grain does not slosh") as info:
        load_vehicle(node, SHIPPED / "ares_i")
    assert info.value.key == "vehicle.stages.first_stage.tanks.grain.slosh"


def test_more_sloshing_tanks_than_the_plant_holds_are_refused(monkeypatch):
    from savant_cli.vehicle import two_stage

    monkeypatch.setattr(two_stage, "MAX_SLOSH_TANKS", 3)
    with pytest.raises(ConfigError, match="at most 3 tanks with a slosh section") as info:
        _vehicle()
    assert info.value.key == "vehicle.stages.upper_stage.tanks.lh2.slosh"


def test_a_tanks_states_name_its_group():
    assert plant_group("slosh_first_stage_lox_y_dot") == "slosh_first_stage_lox"
    assert plant_group("slosh_rp1_z") == "slosh_rp1"
    assert plant_group("slosh_lox_y") == "slosh_lox"


@pytest.fixture(scope="module")
def flight():
    vehicle = _vehicle()
    cfg = validate(compose_config(["sim.progress=false", "slosh=on"]))
    shipped = validate(compose_config(["sim.progress=false"]))
    guidance = read_guidance(prepare(shipped, hydra_search_dirs()).command_file)
    model = build_model(cfg, vehicle, guidance)
    steps = tuple(int(round(t / model.rates.dt)) for t in (60.0, 250.0))
    result = simulate(model, progress=False, snapshot_steps=steps)
    return model, result, signals(result, model), steps


@pytest.mark.slow
def test_first_stage_slosh_flies_and_leaves_with_its_stage(flight):
    model, result, sig, _ = flight
    assert result.status == "complete", result.message
    assert sig["liquid_level"].columns == TANKS and sig["slosh_frequency"].columns == TANKS
    assert sig["slosh_position"].columns[:4] == ("first_stage_lox_y", "first_stage_lox_z", "rp1_y", "rp1_z")
    t = sig["time"].data
    t_sep = result.events[engine.EV_SEPARATION]
    before, after = t < t_sep - 0.5, t > t_sep + 0.5
    prop = sig["propellant_remaining"].data
    for j, tank in enumerate(GEOMETRY):
        radius, density = GEOMETRY[tank]
        level = sig["liquid_level"].data[:, j]
        expected = np.maximum(prop[:, model.layout.tanks.index(tank)], 0.0) / (density * np.pi * radius**2)
        np.testing.assert_allclose(level[before], expected[before], rtol=1e-12)
        assert np.all(level[after] == 0.0) and np.all(sig["slosh_frequency"].data[after, j] == 0.0)
        assert np.all(sig["slosh_force"].data[after, 3 * j:3 * j + 3] == 0.0)
        pos = sig["slosh_position"].data[:, 2 * j:2 * j + 2]
        assert np.ptp(pos[before], axis=0).min() > 1e-6  # it sloshed while aboard
        assert np.all(pos[after] == pos[after][0])  # held once its stage is gone
    # the upper stage's tanks slosh on after the separation
    assert np.ptp(sig["slosh_position"].data[after, 4:], axis=0).min() > 1e-6


@pytest.mark.slow
def test_the_linear_plant_has_two_slosh_pairs_per_tank_aboard(flight):
    """At 60 s (stack: four tanks) and 250 s (upper stage: two), the linear plant's
    lightly damped pairs (ζ < 0.1) in the tanks' bands, from 0.95 ω to 1.05 times the
    coupled bound (module docstring), number two per tank aboard, and the first stage's
    tanks' states are gone at 250 s."""
    model, result, _, steps = flight
    for step, aboard in zip(steps, (TANKS, TANKS[2:])):
        snap = result.snapshots[step]
        config = int(snap.u[layout.U_CONFIG])
        aux = np.zeros(layout.N_AUX)
        derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, np.zeros(snap.x.size))
        rigid = mass_state(snap.x, model.p, model.packed_tables, config, aux)[2]
        m_r, cg_x, iyy = rigid[0], rigid[1], rigid[5]
        bands = []
        for j, tank in enumerate(TANKS):
            w = aux[slosh.A_FREQUENCY + j]
            m_s, station = (aux[slosh.A_MODE + j * slosh.N_MODE + k] for k in (slosh.M_MASS, slosh.M_STATION))
            assert (w > 0.0) == (tank in aboard)
            if tank in aboard:
                bands.append((0.95 * w, 1.05 * w * np.sqrt(1.0 + m_s * (1.0 / m_r + (station - cg_x) ** 2 / iyy))))
        names, _ = linear_states(model, config)
        assert {plant_group(n) for n in names if n.startswith("slosh_")} == {f"slosh_{t}" for t in aboard}
        eig = np.linalg.eigvals(linearize_plant(model, snap).sys.A)
        in_band = [any(lo < abs(e) < hi for lo, hi in bands) for e in eig]
        pairs = eig[(eig.imag > 0) & np.array(in_band) & (-eig.real / np.abs(eig) < 0.1)]
        assert pairs.size == 2 * len(aboard), (snap.t, np.sort(np.abs(pairs)), bands)


def test_flex_loads_a_first_stage_tank_on_the_first_stage_sets_only():
    """Each sloshing tank is a flex point, ``flex.nodes.slosh_<tank>`` (missing: refused,
    naming the key); a first-stage tank's shapes are the nodes' on the first stage's sets
    and zero on the upper stage's, as the first stage's gimbal's are."""
    cfg = validate(compose_config(["flex=on"]))
    node = example_node("first-stage-slosh")
    with pytest.raises(ConfigError) as info:
        load_flex(load_vehicle(node, SHIPPED / "ares_i"), cfg.flex, cfg.sim.plant_rate_hz)
    assert info.value.key == "vehicle.flex.nodes.slosh_first_stage_lox"
    nodes = node["flex"]["nodes"]
    nodes["slosh_first_stage_lox"], nodes["slosh_rp1"] = nodes["gimbal_first_stage"], nodes["rate_gyro_first_stage"]
    vehicle = load_vehicle(node, SHIPPED / "ares_i")
    assert point_keys(vehicle)[N_POINTS:] == tuple(f"slosh_{t}" for t in TANKS)
    shapes = load_flex(vehicle, cfg.flex, cfg.sim.plant_rate_hz).shapes  # (set, mode, point, 6)
    lox_fs, rp1 = PT_SLOSH, PT_SLOSH + 1
    np.testing.assert_array_equal(shapes[:2, :, lox_fs], shapes[:2, :, PT_GIMBAL_FS])
    np.testing.assert_array_equal(shapes[:2, :, rp1], shapes[:2, :, PT_GYRO_FS])
    assert np.all(shapes[2:, :, [lox_fs, rp1, PT_GIMBAL_FS]] == 0.0)
    assert np.all(np.abs(shapes[2:, :, PT_SLOSH + 2]).max(axis=-1) > 0.0)  # the upper stage's LOX tank
