"""The vehicle tree (savant_cli/vehicle/): the event sequence walked and checked, the
configurations it reaches derived, and the two-stage records the plant flies.

Each refusal is provoked by one edit of the shipped ares_i vehicle and must name the key
that is wrong; each accepted edit must change what the walk derives the way the physics
says (a stage takes what is mounted on it along).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from omegaconf import OmegaConf

from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.schema import read_tree
from savant_cli.vehicle.tree import LIFTOFF

VEHICLES = shipped_config_dir() / "vehicle"
DATA = VEHICLES / "ares_i"
NODE = OmegaConf.to_container(OmegaConf.load(VEHICLES / "ares_i.yaml").vehicle, resolve=True)


@pytest.fixture
def node() -> dict:
    return copy.deepcopy(NODE)


def _refused(node: dict, key: str, match: str = "") -> ConfigError:
    with pytest.raises(ConfigError) as info:
        load_vehicle(node, DATA)
    assert info.value.key == key, info.value
    assert match in str(info.value), info.value
    return info.value


def test_the_shipped_sequence_reaches_its_three_configurations(node):
    tree = read_tree(node, DATA)
    assert tree.sequence == ((LIFTOFF, "stack"), ("separation", "upper_les"), ("les_jettison", "upper"))
    assert tree.configurations["upper_les"].parts == {"upper_stage", "les"}
    assert tree.ignited_later() == {"j2x"}  # the motor burns from liftoff
    assert [p.name for p in tree.stages()] == ["first_stage", "upper_stage"]
    assert tree.engines["five_segment_motor"].source == "trace" and tree.engines["j2x"].source == "liquid"


def test_a_stage_takes_what_is_mounted_on_it_along(node):
    """An interstage mounted on the first stage leaves with it at separation: the walk
    derives {upper_stage, les} after it, so upper_les (which does not list it) follows."""
    node["items"] = {"interstage": {"mass_kg": 5900.0, "attached_to": "first_stage"}, **node["items"]}
    node["configurations"]["stack"]["parts"].append("interstage")
    tree = read_tree(node, DATA)
    assert tree.sequence[1] == ("separation", "upper_les")
    node["configurations"]["upper_les"]["parts"].append("interstage")  # a configuration the walk never reaches
    with pytest.raises(ConfigError) as info:
        read_tree(node, DATA)
    assert info.value.key == "vehicle.events.separation.jettison"  # what flies after separation has no configuration


def test_nothing_is_jettisoned_twice(node):
    node["events"]["again"] = {"after": "les_jettison", "delay_s": 5.0, "jettison": ["les"]}
    _refused(node, "vehicle.events.again.jettison", "no longer attached")


def test_an_item_goes_with_its_stage(node):
    node["items"]["les"]["attached_to"] = "first_stage"  # gone at separation: its own jettison comes too late
    _refused(node, "vehicle.events.les_jettison.jettison", "no longer attached")


def test_an_engine_is_not_ignited_after_its_stage_is_gone(node):
    node["events"]["upper_stage_ignition"]["ignite"] = ["j2x", "five_segment_motor"]
    _refused(node, "vehicle.events.upper_stage_ignition.ignite", "jettisoned")


def test_a_burning_engine_is_not_ignited_again(node):
    node["events"]["relight"] = {"after": "upper_stage_ignition", "delay_s": 1.0, "ignite": ["j2x"]}
    _refused(node, "vehicle.events.relight.ignite", "already burning")
    del node["events"]["relight"]
    node["events"]["first_cutoff"] = {"after": "upper_stage_ignition", "delay_s": 100.0, "shutdown": ["j2x"]}
    node["events"]["restart"] = {"after": "first_cutoff", "delay_s": 60.0, "ignite": ["j2x"]}  # a second burn
    assert list(read_tree(node, DATA).events)[-2:] == ["first_cutoff", "restart"]


def test_only_a_burning_engine_is_shut_down(node):
    node["events"]["separation"]["shutdown"] = ["j2x"]  # not ignited until the next event
    _refused(node, "vehicle.events.separation.shutdown", "not burning")


def test_a_trigger_counts_from_an_earlier_event(node):
    node["events"]["upper_stage_ignition"]["after"] = "les_jettison"
    _refused(node, "vehicle.events.upper_stage_ignition.after", "written before this one")


def test_names_are_unique_across_the_vehicle(node):
    node["items"] = {"lox": {"mass_kg": 10.0}}  # a tank's name
    _refused(node, "vehicle.items.lox", "unique")


@pytest.mark.parametrize("when, key, match", [
    ({"quantity": "thrust_fraction", "of": "rs68", "below": 0.02}, "of", "needs the engine or part"),
    ({"quantity": "thrust_fraction", "of": "five_segment_motor", "below": 1.0}, "below", "within (0, 1)"),
    ({"quantity": "altitude_m", "of": "grain", "above": 1000.0}, "of", "leave 'of' out"),
    ({"quantity": "mach", "above": 1.0}, "quantity", "must be one of"),
])
def test_a_condition_names_what_it_watches(node, when, key, match):
    node["events"]["separation"]["when"] = when
    _refused(node, f"vehicle.events.separation.when.{key}", match)


def test_a_condition_gives_one_threshold(node):
    node["events"]["separation"]["when"]["above"] = 0.5
    _refused(node, "vehicle.events.separation.when", "exactly one of below, above")


def test_a_tank_of_an_engine_is_its_own_part(node):
    node["stages"]["upper_stage"]["engines"]["j2x"]["tanks"] = ["lox", "grain"]
    _refused(node, "vehicle.stages.upper_stage.engines.j2x.tanks", "own part")


def test_a_fixed_nozzle_needs_no_gimbal_data_and_a_gimbaled_one_does(node):
    motor = node["stages"]["first_stage"]["engines"]["five_segment_motor"]
    del motor["moving_mass"]
    _refused(node, "vehicle.stages.first_stage.engines.five_segment_motor.moving_mass", "gimbaled engine needs it")
    motor["gimbal_axes"] = []
    del motor["gimbal_limit_deg"]
    tree = read_tree(node, DATA)
    assert tree.engines["five_segment_motor"].moving_mass is None
    assert tree.engines["five_segment_motor"].gimbal_limit_rad == 0.0


@pytest.mark.parametrize("edit, key", [
    (lambda n: n["stages"].update(third_stage=copy.deepcopy(n["stages"]["upper_stage"])), "vehicle.stages"),
    (lambda n: n["stages"]["first_stage"]["engines"]["five_segment_motor"].update(gimbal_axes=["pitch"]),
     "vehicle.stages.first_stage.engines.five_segment_motor.gimbal_axes"),
    (lambda n: n["stages"]["first_stage"]["engines"]["five_segment_motor"].update(gimbal_axes=["pitch"]),
     "vehicle.stages.first_stage.engines.five_segment_motor.gimbal_axes"),
])
def test_a_shape_the_plant_does_not_fly_yet_is_refused_by_name(node, edit, key):
    """Read as a tree, refused by the two-stage records with the key that leaves the shape
    (a third stage copies the upper stage's names, so its names clash first: renamed)."""
    edit(node)
    third = node["stages"].get("third_stage")
    if third is not None:  # unique names for the copied stage
        third["tanks"] = {f"{k}3": v for k, v in third["tanks"].items()}
        third["engines"] = {"j2x3": {**third["engines"]["j2x"], "tanks": ["lox3", "lh23"]}}
        del third["roll_jets"]
        node["configurations"]["upper_les"]["parts"].append("third_stage")
        node["configurations"]["upper"]["parts"].append("third_stage")
        node["configurations"]["stack"]["parts"].append("third_stage")
    read_tree(node, DATA)  # a valid tree
    _refused(node, key, "the plant flies one vehicle shape today")


def test_the_records_are_the_trees_numbers():
    vehicle = load_vehicle(NODE, DATA)
    tree = vehicle.tree
    assert vehicle.first_stage.propellant_kg == tree.tanks["grain"].propellant_kg == 647600.0
    assert vehicle.upper_stage.lox_kg + vehicle.upper_stage.lh2_kg == pytest.approx(135100.0)
    assert vehicle.first_stage.jettison_mass_kg == 91400.0 and vehicle.upper_stage.les_mass_kg == 7060.0
    assert vehicle.events.separation_thrust_fraction == 0.02
    assert (vehicle.events.ignition_delay_s, vehicle.events.les_jettison_delay_s) == (1.5, 30.0)
    np.testing.assert_array_equal(vehicle.upper_stage.gimbal_m, [35.1, 0.0, 0.0])
    assert vehicle.configurations["upper"].aero is tree.configurations["upper"].aero


def test_the_mass_check_names_the_tank(node):
    node["stages"]["first_stage"]["tanks"]["grain"]["propellant_kg"] += 1000.0
    _refused(node, "vehicle.stages.first_stage.tanks.grain.propellant_kg", "mass_first_stage.csv")
