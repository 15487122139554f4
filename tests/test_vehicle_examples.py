"""The worked examples of docs/vehicles.md, read from the page: each ``yaml`` block that
starts with ``# example: <name>`` is merged over the shipped ares_i vehicle, loaded, and
checked for what the page says it does. A new example on the page without a check here
fails, as does a check whose example left the page.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from savant_cli.config import validate
from savant_cli.hydra_compose import compose_config, task_config
from savant_cli.models import cluster, layout
from savant_cli.paths import shipped_config_dir
from savant_cli.sim import build, engine
from savant_cli.vehicle import load_vehicle

PAGE = Path(__file__).resolve().parents[1] / "docs" / "vehicles.md"
SHIPPED = shipped_config_dir() / "vehicle"
BLOCK = re.compile(r"```yaml\n# example: (\S+)\n(.*?)```", re.S)


def examples() -> dict[str, str]:
    return {name: body for name, body in BLOCK.findall(PAGE.read_text(encoding="utf-8"))}


def example_node(name: str) -> dict:
    """The page's example ``name`` written over the vehicle it :data:`BUILDS_ON` (the
    shipped ares_i node, or another example's), the sections it :data:`REPLACES` emptied
    first, in place: the stages and the events keep their order."""
    builds_on = BUILDS_ON.get(name)
    base = OmegaConf.create(example_node(builds_on)) if builds_on else OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle
    for key in REPLACES.get(name, ()):
        OmegaConf.update(base, key, {}, merge=False)
    return OmegaConf.to_container(OmegaConf.merge(base, OmegaConf.create(examples()[name])), resolve=True)


def _loaded(name: str):
    return load_vehicle(example_node(name), SHIPPED / "ares_i")


def _rule(vehicle, slot: int) -> engine.EventRule:
    cfg = validate(task_config(compose_config([], None)))
    return build.event_schedule(cfg, vehicle, build.rates(cfg)).rules[slot]


def check_jettison_on_a_condition(vehicle):
    rule = _rule(vehicle, engine.EV_LES)
    assert (rule.when, rule.above, rule.threshold, rule.delay_s) == (engine.WHEN_DYNAMIC_PRESSURE, False, 50.0, 0.0)
    assert rule.after == engine.EV_IGNITION


def check_a_delay_arms_a_condition(vehicle):
    rule = _rule(vehicle, engine.EV_LES)
    assert (rule.when, rule.above, rule.threshold, rule.delay_s) == (engine.WHEN_ALTITUDE, True, 100000.0, 20.0)


def check_composed_mass_properties(vehicle):
    shipped = load_vehicle(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle, SHIPPED / "ares_i")
    for name, c in vehicle.configurations.items():
        assert vehicle.tree.configurations[name].mass_file.endswith("(composed from its parts)")
        np.testing.assert_allclose(c.mass.mass_kg, shipped.configurations[name].mass.mass_kg, rtol=1e-9)
        np.testing.assert_allclose(c.mass.inertia_kgm2, shipped.configurations[name].mass.inertia_kgm2, rtol=1e-6,
                                   atol=1.0)


def check_items_in_any_phase(vehicle):
    assert list(vehicle.configurations) == ["stack", "upper_les", "upper_les_2", "upper"]
    assert [j.kind for j in vehicle.jettisons] == ["stage", "items", "items"]
    assert [j.mass_kg for j in vehicle.jettisons[1:]] == [1200.0, 7060.0]
    fairings, les = (_rule(vehicle, slot) for slot in engine.EV_ITEMS[:2])
    assert (fairings.after, fairings.delay_s, fairings.waits_for) == (engine.EV_SEPARATION, 1.0, engine.EV_SEPARATION)
    assert (les.after, les.delay_s, les.waits_for) == (engine.EV_IGNITION, 30.0, engine.EV_ITEMS[0])
    mass = {n: c.mass for n, c in vehicle.configurations.items()}  # each drop is the items' mass at every level
    np.testing.assert_allclose(mass["upper_les"].mass_kg - mass["upper_les_2"].mass_kg, 1200.0, atol=1e-6)
    np.testing.assert_allclose(mass["upper_les_2"].mass_kg - mass["upper"].mass_kg, 7060.0, atol=1e-6)


def check_ignition_on_a_tank(vehicle):
    rule = _rule(vehicle, engine.EV_IGNITION)
    # the tanks' states follow the rigid body's in the vehicle's order
    lox_state = layout.N_STATE + vehicle.tanks.index("lox")
    assert (rule.when, rule.of, rule.above) == (engine.WHEN_PROPELLANT, lox_state, True)


def check_a_two_engine_cluster(vehicle):
    shipped = load_vehicle(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle, SHIPPED / "ares_i").upper_stage
    us = vehicle.upper_stage
    # the stage's record is the engines' sums and mean: the shipped J-2X's (1 ulp: 3.65 + 3.65 is 7.3 exactly)
    for name in ("thrust_vac_N", "nozzle_exit_area_m2", "shutdown_impulse_Ns", "isp_vac_s", "mixture_ratio"):
        assert getattr(us, name) == getattr(shipped, name), name
    np.testing.assert_array_equal(us.gimbal_m, shipped.gimbal_m)
    assert [m.name for m in us.mounts] == ["j2x", "j2x_b"]
    np.testing.assert_array_equal([m.offset_m for m in us.mounts], [[0.0, 1.2, 0.0], [0.0, -1.2, 0.0]])
    assert (us.engine.mass_kg, us.engine.inertia_about_gimbal_kgm2) == (1250.0, 4062.5)  # each engine's


def check_a_given_mixing_matrix(vehicle):
    given = [[1.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    rows = cluster.mount_table(vehicle)  # checks the matrix against the allocation's moments
    np.testing.assert_array_equal(rows[-2:, cluster.M_PITCH_ROLL:cluster.M_BOOSTER], np.reshape(given, (2, 6)))
    # the mixer's own allocation, to roundoff: the page's "this one is the mixer's own"
    own = cluster.mount_table(dataclasses.replace(
        vehicle, upper_stage=dataclasses.replace(vehicle.upper_stage, mixing_matrix=None)))
    np.testing.assert_allclose(own[-2:, cluster.M_PITCH_ROLL:cluster.M_BOOSTER], np.reshape(given, (2, 6)), atol=1e-12)


def check_a_liquid_first_stage(vehicle):
    fs = vehicle.first_stage
    assert vehicle.tanks == ("first_stage_lox", "rp1", "lox", "lh2")
    assert fs.liquid is not None and fs.propellant_kg == 647600.0  # the stack mass table's full load, unchanged
    assert (fs.liquid.thrust_vac_N, fs.liquid.mixture_ratio, fs.liquid.throttle.axial_acceleration_limit_mps2) == (
        14.0e6, 2.6, 39.2)
    # "the oxidizer runs out first and leaves 153.8 kg of RP-1"
    burned = min(fs.oxidizer_kg, 2.6 * fs.fuel_kg) * (1 + 1 / 2.6)
    assert fs.fuel_kg - burned / 3.6 == pytest.approx(153.846, abs=1e-3)
    rule = _rule(vehicle, engine.EV_SEPARATION)
    assert (rule.when, rule.threshold) == (engine.WHEN_THRUST_FRACTION, 0.02)


def check_a_first_stage_cutoff(vehicle):
    assert vehicle.first_stage.liquid.shutdown_impulse_Ns == 2.8e6
    cut, sep = _rule(vehicle, engine.EV_FS_CUTOFF), _rule(vehicle, engine.EV_SEPARATION)
    oxidizer_state = layout.N_STATE + vehicle.tanks.index("first_stage_lox")
    assert (cut.after, cut.delay_s, cut.when, cut.of, cut.above, cut.threshold) == (
        -1, 60.0, engine.WHEN_PROPELLANT, oxidizer_state, False, 5000.0)
    assert (sep.after, sep.delay_s, sep.when, sep.threshold) == (engine.EV_FS_CUTOFF, 1.0, engine.WHEN_THRUST_FRACTION,
                                                                 0.02)
    assert vehicle.events.names == ("separation", "upper_stage_ignition", "les_jettison", "", "meco", "", "", "", "",
                                    "", "")


def check_strap_on_boosters(vehicle):
    b = vehicle.boosters
    assert b.names == ("booster_left", "booster_right") and b.engines == ("booster_left_motor", "booster_right_motor")
    np.testing.assert_array_equal(b.nozzle_m, [[91.5, -2.755, 0.0], [91.5, 2.755, 0.0]])
    np.testing.assert_array_equal(b.cant_rad, 0.0)
    assert (b.propellant_kg, b.inert_mass_kg, b.isp_vac_s, b.nozzle_exit_area_m2) == (44200.0, 5100.0, 279.0, 2.0)
    drop = _rule(vehicle, engine.EV_BOOSTER_JETTISON)
    assert (drop.after, drop.delay_s, drop.when, drop.of, drop.threshold) == (
        -1, 0.0, engine.WHEN_BOOSTER_THRUST_FRACTION, 0, 0.02)
    assert vehicle.events.names[engine.EV_BOOSTER_JETTISON] == "booster_jettison"
    # the jettison leaves the stack as shipped, the sequence after it unchanged
    shipped = load_vehicle(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle, SHIPPED / "ares_i")
    assert list(vehicle.configurations)[1:] == list(shipped.configurations)
    for name, c in shipped.configurations.items():
        np.testing.assert_array_equal(vehicle.configurations[name].mass.mass_kg, c.mass.mass_kg)


def check_first_stage_slosh(vehicle):
    # every tank with a slosh section, by the file's names, in the order of the propellant states
    assert tuple(vehicle.slosh_spec) == vehicle.tanks == ("first_stage_lox", "rp1", "lox", "lh2")
    assert vehicle.slosh_spec["rp1"]["table"] == "slosh_rp1.csv"
    assert vehicle.keys["slosh.rp1"] == "vehicle.stages.first_stage.tanks.rp1.slosh"
    cfg = validate(task_config(compose_config(["slosh=on"], None)))
    assert build.state_layout(cfg, vehicle).slosh_tanks == vehicle.tanks


#: the example of the page an example is written over (its own chain first)
BUILDS_ON = {"a-given-mixing-matrix": "a-two-engine-cluster", "a-first-stage-cutoff": "a-liquid-first-stage",
             "first-stage-slosh": "a-liquid-first-stage", "booster-tvc": "strap-on-boosters"}
#: sections of the vehicle it is written over that an example replaces whole (emptied before the merge)
REPLACES = {"a-liquid-first-stage": ("stages.first_stage",), "a-first-stage-cutoff": ("events",),
            "items-in-any-phase": ("events",),
            "strap-on-boosters": ("events",)}
def check_booster_tvc(vehicle):
    b = vehicle.boosters
    assert b.tvc and b.gimbal_limit_rad == np.radians(6.0) and vehicle.gimbaled_boosters == 2
    assert (b.engine.mass_kg, b.engine.cg_from_gimbal_m, b.engine.inertia_about_gimbal_kgm2) == (900.0, 0.9, 1500.0)
    rows = cluster.boosted_mounts(vehicle)  # the page's allocation of one radian of pitch
    assert rows[:, cluster.M_PITCH_PITCH] == pytest.approx([1.18, 0.064, 0.064], abs=0.005)
    assert rows[1:, cluster.M_PITCH_ROLL].tolist() == [-1.0, 1.0]  # the pair rolls by differential pitch


def check_a_throttled_upper_stage(vehicle):
    th = vehicle.upper_stage.throttle
    assert (th.minimum, th.maximum, th.rate_per_s, th.axial_acceleration_limit_mps2) == (0.6, 1.0, 0.2, 25.0)
    assert th.time_s is None and vehicle.first_stage.liquid is None


def check_an_upper_stage_restart(vehicle):
    cut, again = _rule(vehicle, engine.EV_US_CUTOFF), _rule(vehicle, engine.EV_RESTART)
    assert (cut.after, cut.delay_s, cut.when) == (engine.EV_IGNITION, 500.0, engine.WHEN_NONE)
    assert (again.after, again.delay_s, again.when, again.above, again.threshold) == (
        engine.EV_US_CUTOFF, 10.0, engine.WHEN_RADIAL_SPEED, False, 0.0)
    assert vehicle.events.names[-2:] == ("j2x_cutoff", "j2x_restart") and vehicle.events.has("upper_stage_restart")
    assert len(vehicle.configurations) == len(_loaded("a-throttled-upper-stage").configurations)  # no new part
    assert (vehicle.rcs.pitch_yaw_thrust_N, vehicle.rcs.pitch_yaw_jets_per_direction) == (445.0, 2)


def check_modal_sets_per_configuration(vehicle):
    """The shipped four sets, the LES's configuration on its ignition set alone and the
    upper configuration on the set without the LES, read into the plant's map; the
    shipped four modes refused (the set without the LES has its second pair at 44 Hz),
    two flown."""
    from savant_cli.config import shipped_option
    from savant_cli.errors import ConfigError
    from savant_cli.flex_slosh import FLEX_SETS, load_flex

    with pytest.raises(ConfigError) as exc:
        load_flex(vehicle, shipped_option("flex", "on"), 200.0)
    assert exc.value.key == "flex.n_modes" and "44.0 Hz" in exc.value.allowed
    flex = load_flex(vehicle, dataclasses.replace(shipped_option("flex", "on"), n_modes=2), 200.0)
    assert tuple(ms.name for ms in flex.sets) == FLEX_SETS
    assert flex.set_map[:, :5].tolist() == [[2, 0, 0.0, 1, 1.0], [1, 2, 0.0, 0, 0.0], [1, 3, 0.0, 0, 0.0]]


CHECKS = {"jettison-on-a-condition": check_jettison_on_a_condition,
          "a-delay-arms-a-condition": check_a_delay_arms_a_condition,
          "composed-mass-properties": check_composed_mass_properties,
          "items-in-any-phase": check_items_in_any_phase,
          "ignition-on-a-tank": check_ignition_on_a_tank,
          "a-two-engine-cluster": check_a_two_engine_cluster,
          "a-given-mixing-matrix": check_a_given_mixing_matrix,
          "a-liquid-first-stage": check_a_liquid_first_stage,
          "a-first-stage-cutoff": check_a_first_stage_cutoff,
          "strap-on-boosters": check_strap_on_boosters,
          "first-stage-slosh": check_first_stage_slosh,
          "booster-tvc": check_booster_tvc,
          "a-throttled-upper-stage": check_a_throttled_upper_stage,
          "an-upper-stage-restart": check_an_upper_stage_restart,
          "modal-sets-per-configuration": check_modal_sets_per_configuration}


def test_every_example_on_the_page_has_a_check():
    assert set(examples()) == set(CHECKS)


@pytest.mark.parametrize("name", sorted(CHECKS))
def test_the_example_loads_and_does_what_the_page_says(name):
    CHECKS[name](_loaded(name))
