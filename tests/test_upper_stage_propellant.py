"""Upper-stage propellant: usable and unusable residuals at the engine mixture ratio, the
tank-load and mixture-ratio dispersions, and the default loads at the engine's mixture
ratio (issue 26 items 2 and 3). References are hand calculations."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.montecarlo.targets import Target, apply_samples
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim.setup import prepare
from savant_cli.sim.summary import usable_propellant
from savant_cli.vehicle import check_consistency


@pytest.mark.parametrize("lox, lh2, mr, usable, limiting", [
    # 5,081 kg LOX and 2,597 kg LH2 at MR 5.5 (the issue's figures): LOX limits,
    # 5,081 / 5.5 = 923.8 kg of LH2 burns with it
    (5081.0, 2597.0, 5.5, 5081.0 + 5081.0 / 5.5, "lox"),
    # LH2 limits: 1,000 kg LH2 burns with 5,500 kg LOX; 1,000 kg LOX is left unusable
    (6500.0, 1000.0, 5.5, 6500.0 - 1000.0 + 1000.0, "lh2"),
    # exactly at the ratio: everything burns
    (5500.0, 1000.0, 5.5, 6500.0, "lox"),
    (0.0, 300.0, 5.0, 0.0, "lox"),
])
def test_usable_propellant_by_hand(lox, lh2, mr, usable, limiting):
    u, unusable, lim = usable_propellant(lox, lh2, mr)
    assert u == pytest.approx(usable, rel=1e-12)
    assert unusable == pytest.approx(lox + lh2 - usable, abs=1e-9)
    assert lim == limiting


def test_issue_figures_leave_1673_kg_of_lh2_unusable():
    _, unusable, _ = usable_propellant(5081.0, 2597.0, 5.5)
    assert unusable == pytest.approx(2597.0 - 5081.0 / 5.5, rel=1e-12)  # 1,673.2 kg
    assert unusable == pytest.approx(1673.2, abs=0.1)


@pytest.fixture(scope="module")
def base():
    cfg = validate(compose_config(["sim.progress=false"]))
    return cfg, prepare(cfg, hydra_search_dirs()).vehicle


def test_default_loads_are_at_the_engine_mixture_ratio(base):
    us = base[1].upper_stage
    assert us.lox_kg / us.lh2_kg == pytest.approx(us.mixture_ratio, rel=1e-4)
    assert us.lox_kg + us.lh2_kg == pytest.approx(112900.0 + 22200.0, abs=1.0)  # the public total


@pytest.mark.parametrize("name, k", [("tables.upper_stage.lox_load", 1.003), ("tables.upper_stage.lh2_load", 0.997)])
def test_tank_load_dispersion_keeps_the_vehicle_consistent(base, name, k):
    cfg, vehicle = base
    us0 = vehicle.upper_stage
    v = apply_samples(cfg, vehicle, [(Target(name, "tables"), "scale", k)], {}).vehicle
    us = v.upper_stage
    lox0, lh20 = us0.lox_kg, us0.lh2_kg
    lox, lh2 = (k * lox0, lh20) if "lox" in name else (lox0, k * lh20)
    assert (us.lox_kg, us.lh2_kg) == pytest.approx((lox, lh2))
    delta = lox + lh2 - lox0 - lh20
    check_consistency(v)  # tables end at the new total; staging and LES masses still agree
    for c in ("stack", "upper_les", "upper"):
        m0, m = vehicle.configurations[c].mass, v.configurations[c].mass
        assert m.mass_kg[-1] - m0.mass_kg[-1] == pytest.approx(delta, abs=1e-6)
    # the extra propellant sits in the tanks: forward of the stack's CG, so the stack CG moves forward
    # when the load grows (structure x is aft)
    s0, s = vehicle.configurations["stack"].mass, v.configurations["stack"].mass
    assert np.sign(s.cg_m[-1, 0] - s0.cg_m[-1, 0]) == -np.sign(delta)


def test_bad_load_factor_names_the_target(base):
    cfg, vehicle = base
    with pytest.raises(ConfigError) as err:
        apply_samples(cfg, vehicle, [(Target("tables.upper_stage.lh2_load", "tables"), "scale", -1.0)], {})
    assert err.value.key == "tables.upper_stage.lh2_load" and "positive" in str(err.value)


def test_dispersed_load_stays_inside_the_slosh_tables(base):
    """A +3σ LOX load (× 1.003) builds with slosh on: the slosh tables reach 1 % above the
    nominal fill."""
    from savant_cli.sim.build import model_inputs

    cfg, vehicle = base
    cfg_slosh = validate(compose_config(["slosh=on", "sim.progress=false"]))
    v = apply_samples(cfg, vehicle, [(Target("tables.upper_stage.lox_load", "tables"), "scale", 1.003)], {}).vehicle
    assert model_inputs(cfg_slosh, v).slosh is not None


def test_flown_mixture_ratio_sets_the_limiting_propellant():
    """Fly the upper stage at MR 5.6 from tanks loaded at 5.5: the engine draws LOX : LH2 =
    5.6 (from the flown states), LOX limits, and the LH2 left beyond L/5.6 is unusable."""
    from savant_cli.sim.run import simulate
    from savant_cli.sim.summary import propulsion_keys

    cfg = validate(compose_config(["phase=upper_stage", "sim.progress=false",
                                   "vehicle.stages.upper_stage.engines.j2x.mixture_ratio=5.6"]))
    prep = prepare(cfg, hydra_search_dirs())
    res = simulate(prep.model, progress=False)
    us = prep.vehicle.upper_stage
    lox, lh2 = (res.x[prep.model.layout.tank(t)] for t in ("lox", "lh2"))
    assert (us.lox_kg - lox) / (us.lh2_kg - lh2) == pytest.approx(5.6, rel=1e-9)
    keys = propulsion_keys(res, prep.model.p)
    assert keys["limiting_propellant"] == "lox"
    assert keys["usable_propellant_remaining_kg"] == pytest.approx(lox + lox / 5.6, rel=1e-12)
    assert keys["unusable_propellant_kg"] == pytest.approx(lh2 - lox / 5.6, rel=1e-9)
    assert keys["unusable_propellant_kg"] == pytest.approx(us.lh2_kg - us.lox_kg / 5.6, rel=1e-6)  # 372 kg stranded
