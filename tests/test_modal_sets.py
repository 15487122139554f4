"""Modal sets per configuration (``vehicle.flex.sets``): any number of sets per
configuration, each at a burned fraction of its stage's propellant, blended piecewise
linearly (``flex.switching: propellant``) or the configuration's first set alone
(``separation``); a set belongs to one structure; bad maps are refused naming the key.

The extra sets come from the default vehicle's own beam model
(``savant_cli.datagen.ares_i_flex``), generated here at fills the shipped data lack."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from omegaconf import OmegaConf

from savant_cli.datagen import ares_i_flex
from savant_cli.datagen.ares_i_tables import M_FS_PROP, M_LH2, M_LOX
from savant_cli.errors import ConfigError
from savant_cli.flex_slosh import FIRST_STAGE, UPPER_STAGE, set_plan
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import flex, layout, propulsion
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import derivative
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from test_boosters import _cfg

SHIPPED = shipped_config_dir() / "vehicle"
#: the sets generated beside the shipped four: (configuration, propellant of its burning stage left, kg)
EXTRA = {"first_stage_half": ("stack", 0.5 * M_FS_PROP), "first_stage_quarter": ("stack", 0.75 * M_FS_PROP),
         "upper_ignition": ("upper", M_LOX + M_LH2)}
#: the map under test: three sets across the first stage's burn, the LES's set held until
#: the LES leaves, then the upper stage's own pair
SETS = {"stack": [{"set": "first_stage_liftoff", "burned_fraction": 0.0},
                  {"set": "first_stage_half", "burned_fraction": 0.5},
                  {"set": "first_stage_burnout", "burned_fraction": 1.0}],
        "upper_les": [{"set": "second_stage_ignition", "burned_fraction": 0.0}],
        "upper": [{"set": "upper_ignition", "burned_fraction": 0.0},
                  {"set": "second_stage_burnout", "burned_fraction": 1.0}]}


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A copy of the ares_i folder whose flex folder holds the beam model's sets, the
    shipped four and :data:`EXTRA`, generated together (one mesh)."""
    root = tmp_path_factory.mktemp("modal_sets") / "ares_i"
    shutil.copytree(SHIPPED / "ares_i", root)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ares_i_flex, "SETS", {**ares_i_flex.SETS, **EXTRA})
        sets = ares_i_flex.write_all(root / "flex")
    return root, sets


def _node(sets=None) -> dict:
    node = OmegaConf.to_container(OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle, resolve=True)
    if sets is not None:
        node["flex"]["sets"] = sets
    return node


def _model(root, *overrides):
    cfg = _cfg("flex=on", "flex.n_modes=2", *overrides)
    vehicle = load_vehicle(_node(SETS), root)
    return build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file))


def _burned(model, stage_fraction_burned: float, upper: bool = False) -> np.ndarray:
    """The pad state with the first stage's (or the upper stage's) propellant that
    fraction burned."""
    x, lay = model.x0.copy(), model.layout
    names = ("lox", "lh2") if upper else ("grain",)
    for t in names:
        x[lay.tank(t)] *= 1.0 - stage_fraction_burned
    return x


def test_a_configuration_blends_between_the_two_sets_around_its_burn(data):
    root, _ = data
    model = _model(root, "flex.switching=propellant")
    tb, p = model.packed_tables, model.p
    plan = set_plan(load_vehicle(_node(SETS), root))
    i = {n: plan.names.index(n) for n in plan.names}
    assert plan.roles[i["first_stage_half"]] == FIRST_STAGE and plan.roles[i["upper_ignition"]] == UPPER_STAGE
    # 25 % burned: halfway from the liftoff set (0) to the half set (0.5)
    assert flex.flex_sets(_burned(model, 0.25), 0, p, tb) == (i["first_stage_liftoff"], i["first_stage_half"],
                                                              pytest.approx(0.5, rel=1e-12))
    # 80 % burned: (0.8 - 0.5) / (1 - 0.5) of the way from the half set to burnout
    assert flex.flex_sets(_burned(model, 0.8), 0, p, tb) == (i["first_stage_half"], i["first_stage_burnout"],
                                                             pytest.approx(0.6, rel=1e-12))
    x_upper = _burned(model, 0.3, upper=True)
    # the LES on: its one set whatever the burn; after it: 30 % from the upper stage's own ignition set
    assert flex.flex_sets(x_upper, 1, p, tb) == (i["second_stage_ignition"], i["second_stage_ignition"], 0.0)
    assert flex.flex_sets(x_upper, 2, p, tb) == (i["upper_ignition"], i["second_stage_burnout"],
                                                 pytest.approx(0.3, rel=1e-12))
    assert propulsion.first_stage_propellant(_burned(model, 0.25), p) == pytest.approx(0.75 * M_FS_PROP, rel=1e-9)


def test_separation_switching_flies_each_configurations_first_set(data):
    root, _ = data
    model = _model(root, "flex.switching=separation")
    plan = set_plan(load_vehicle(_node(SETS), root))
    for config, first in ((0, "first_stage_liftoff"), (1, "second_stage_ignition"), (2, "upper_ignition")):
        sa, sb, w = flex.flex_sets(_burned(model, 0.8, upper=config > 0), config, model.p, model.packed_tables)
        assert (plan.names[sa], w) == (first, 0.0)


def test_a_third_set_brings_the_blended_frequency_closer_to_the_structures(data):
    """At 25 % of the first stage burned the beam's own first bending frequency lies on
    a curve; the two-set blend (liftoff to burnout) misses it by the curve's sag over
    the whole burn, the three-set blend by the sag over half of it (a quarter for a
    smooth curve: interpolation error goes as the interval squared)."""
    _, sets = data
    f = {n: sets[n].freq_hz[0] for n in ("first_stage_liftoff", "first_stage_half", "first_stage_quarter",
                                         "first_stage_burnout")}
    two = 0.75 * f["first_stage_liftoff"] + 0.25 * f["first_stage_burnout"]
    three = 0.5 * f["first_stage_liftoff"] + 0.5 * f["first_stage_half"]
    truth = f["first_stage_quarter"]
    assert f["first_stage_liftoff"] < truth < f["first_stage_burnout"]  # the structure stiffens as it empties
    assert abs(three - truth) < 0.5 * abs(two - truth)


def test_the_modes_ring_at_the_blended_frequency(data):
    """q₁ = 1, q̇ = 0 and nothing loading the modes (the upper stage coasting, its jets
    quiet, slosh and tail-wags-dog off): the plant's q̈₁ is −ω² with ω the blend, 30 %
    burned, of the upper configuration's two sets' first frequencies (hand-computed)."""
    root, sets = data
    model = _model(root, "flex.switching=propellant", "twd=off", "slosh=off")
    x = _burned(model, 0.3, upper=True)
    fo = model.layout.flex
    x[fo] = 1.0
    u = model.u0.copy()
    u[layout.U_CONFIG] = layout.CONFIG_UPPER  # after the LES's jettison
    u[layout.U_ENGINE] = layout.ENGINE_OFF
    xd = np.zeros_like(x)
    derivative(0.0, x, u, model.p, model.packed_tables, np.zeros(layout.N_AUX), xd)
    w = 2 * np.pi * (0.7 * sets["upper_ignition"].freq_hz[0] + 0.3 * sets["second_stage_burnout"].freq_hz[0])
    assert xd[fo + model.layout.n_modes] == pytest.approx(-w * w, rel=1e-9)


@pytest.mark.slow
def test_a_vehicle_with_its_own_sets_flies_to_orbit(data):
    root, _ = data
    result = simulate(_model(root, "flex.switching=propellant"), progress=False)
    assert result.status == "complete", result.message
    assert np.isfinite(result.events[[engine.EV_LES, engine.EV_CUTOFF]]).all()  # the LES's set and the upper's flew


@pytest.mark.parametrize("change, key, says", [
    (lambda s: s.update(upper_lez=s.pop("upper")), "vehicle.flex.sets.upper_lez", "not a configuration"),
    (lambda s: s.pop("upper"), "vehicle.flex.sets.upper", "non-empty list"),
    (lambda s: s["stack"].reverse(), "vehicle.flex.sets.stack[1].burned_fraction", "increasing"),
    (lambda s: s["stack"][2].update(burned_fraction=1.2), "vehicle.flex.sets.stack[2].burned_fraction", "0 to 1"),
    (lambda s: s["stack"][0].update(burned_fraction="start"), "vehicle.flex.sets.stack[0].burned_fraction", "0 to 1"),
    (lambda s: s["stack"][1].update(set="upper_ignition"), "vehicle.flex.sets.upper[0].set", "one structure"),
    (lambda s: s["stack"][1].update(fraction=0.5), "vehicle.flex.sets.stack[1]", "burned_fraction"),
    (lambda s: s.update(stack=[{"set": f"s{k}", "burned_fraction": k / 9} for k in range(9)]),
     "vehicle.flex.sets.stack", "at most 8"),
])
def test_a_bad_map_is_refused_naming_its_key(data, change, key, says):
    sets = {k: [dict(e) for e in v] for k, v in SETS.items()}
    change(sets)
    vehicle = load_vehicle(_node(sets), data[0])
    with pytest.raises(ConfigError) as exc:
        set_plan(vehicle)
    assert exc.value.key == key and says in exc.value.allowed


def test_without_a_map_each_stage_flies_its_liftoff_and_burnout_pair():
    """The source paper's sets: the first stage's liftoff → burnout for the stack, the
    second stage's ignition → burnout for both upper configurations."""
    plan = set_plan(load_vehicle(_node(), SHIPPED / "ares_i"))
    assert plan.names == ("first_stage_liftoff", "first_stage_burnout", "second_stage_ignition", "second_stage_burnout")
    assert plan.by_configuration == (((0, 0.0), (1, 1.0)), ((2, 0.0), (3, 1.0)), ((2, 0.0), (3, 1.0)))


def test_the_gyro_blend_is_designed_on_the_stacks_first_set():
    """The flight-control design's gyro blend reads the stack's liftoff set: the shipped
    name by default, else the first set the map gives the first booster-free
    configuration."""
    from savant_cli.datagen.flex_filters import stack_liftoff_set

    assert stack_liftoff_set(_node()) == "first_stage_liftoff"
    sets = {k: [dict(e) for e in v] for k, v in SETS.items()}
    sets["stack"] = sets["stack"][1:]
    assert stack_liftoff_set(_node(sets)) == "first_stage_half"
