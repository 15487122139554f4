"""Configuration of the fidelity models (flex, slosh, tail-wags-dog, simplex actuator).

Bad input is refused by ``validate`` + ``prepare`` (before any simulation) with a
ConfigError naming the key or the file and column: more modes than the data has, a node
missing from a modal set, a non-positive modal frequency, negative structural damping,
a slosh table that does not cover the tank, and retained modes the RK4 step does not
resolve (f < plant rate / 8, on the sets actually used by the switching rule).

The slow test flies every combination of flex × slosh × twd × actuator through a
shortened first-stage phase and the upper stage (from the shipped staging state) without
divergence, and checks the new signals of the all-on case against hand computations.
"""

from __future__ import annotations

import itertools
import logging
import shutil
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.setup import prepare

FLEX_ON = ["flex=on"]


def _expect(raw, key_part: str) -> ConfigError:
    with pytest.raises(ConfigError) as exc:
        prepare(validate(raw))
    assert key_part in exc.value.key, exc.value
    return exc.value


def _vehicle_copy(tmp_path: Path) -> Path:
    dst = tmp_path / "vehicle"
    shutil.copytree(shipped_config_dir() / "vehicle", dst)
    return dst / "ares_i"


def _set_first_frequency(modes_csv: Path, value: float) -> None:
    lines = modes_csv.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("1,"))
    cells = lines[i].split(",")
    cells[1] = repr(value)
    lines[i] = ",".join(cells)
    modes_csv.write_text("\n".join(lines) + "\n")


# ----------------------------------------------------------------------- refusals


def test_more_modes_than_the_data_has():
    err = _expect(compose_config(FLEX_ON + ["flex.n_modes=13"]), "flex.n_modes")
    assert err.value == 13 and "12 modes" in err.allowed


def test_node_missing_from_a_modal_set():
    err = _expect(compose_config(FLEX_ON + ["vehicle.flex.nodes.imu=[99999]"]), "vehicle.flex.nodes.imu")
    assert err.value == 99999


def test_first_stage_node_missing_from_an_edited_modal_set(tmp_path):
    """The first-stage gimbal node deleted from the liftoff set (shapes and masses)."""
    vdir = _vehicle_copy(tmp_path)
    for kind, pattern in (("shapes", ",718,"), ("nodes", "718,")):
        f = vdir / "flex" / f"first_stage_liftoff_{kind}.csv"
        lines = [ln for ln in f.read_text().splitlines() if not (pattern in ln and (kind == "shapes" or ln.startswith("718,")))]
        f.write_text("\n".join(lines) + "\n")
    raw = compose_config(FLEX_ON)
    raw.vehicle.data_dir = str(vdir)
    _expect(raw, "vehicle.flex.nodes.gimbal_first_stage")


@pytest.mark.parametrize("value,via", [(0.0, "data_dir"), (-1.0, "flex_directory")])
def test_non_positive_modal_frequency(tmp_path, value, via):
    vdir = _vehicle_copy(tmp_path)
    _set_first_frequency(vdir / "flex" / "second_stage_ignition_modes.csv", value)
    raw = compose_config(FLEX_ON)
    if via == "data_dir":
        raw.vehicle.data_dir = str(vdir)
    else:  # the shipped vehicle, its flex folder elsewhere (absolute directory)
        raw.vehicle.flex.directory = str(vdir / "flex")
    err = _expect(raw, "second_stage_ignition_modes.csv:frequency_hz")
    # a table value is named <folder>/<file>.csv:<column> with its row (docs/vehicles.md)
    assert err.key == "flex/second_stage_ignition_modes.csv:frequency_hz"
    assert err.value == value and "positive" in err.allowed and "row 1 (line" in err.allowed


def test_missing_flex_folder():
    _expect(compose_config(FLEX_ON + ["vehicle.flex.directory=no_such_folder"]), "vehicle.flex.directory")


@pytest.mark.parametrize("override,key", [
    ("flex.damping=-0.1", "flex.damping"),
    ("flex.damping_per_mode=[0.01,-0.01,0.01,0.01]", "flex.damping_per_mode[1]"),
])
def test_negative_damping(override, key):
    err = _expect(compose_config(FLEX_ON + [override]), key)
    assert err.value < 0


def test_slosh_table_must_cover_the_tank(tmp_path):
    """LOX load 114.3 t (the public 135.1 t at MR 5.5) at 1141 kg/m³ in a 2.75 m radius
    tank fills 4.217 m; a table cut short of that level is refused."""
    vdir = _vehicle_copy(tmp_path)
    f = vdir / "slosh_lox.csv"
    lines = f.read_text().splitlines()
    f.write_text("\n".join(lines[:-5]) + "\n")  # drop the five highest levels
    full = 135100.0 * 5.5 / 6.5 / (1141.0 * np.pi * 2.75**2)
    last_level = float(lines[-6].split(",")[0])
    assert last_level < full
    raw = compose_config(["slosh=on"])
    raw.vehicle.data_dir = str(vdir)
    err = _expect(raw, "slosh_lox.csv:level_m")
    assert err.value[-1] == pytest.approx(last_level) and f"{full:.4f}" in err.allowed


@pytest.mark.parametrize("overrides,ok", [
    (["flex.n_modes=4"], True),  # 2 x 9.5 Hz, 2 x 21.7 Hz (ignition set) < 25 Hz
    (["flex.n_modes=5"], False),  # ignition set mode 5: 36.5 Hz > 200 Hz / 8
    (["flex.n_modes=5", "sim.plant_rate_hz=400"], True),  # < 50 Hz
    (["flex.n_modes=3"], True),  # separation switching: burnout sets unused
    (["flex.n_modes=3", "flex.switching=propellant"], False),  # second_stage_burnout mode 3: 44.1 Hz
    (["flex.n_modes=4", "flex.frequency_scale=1.2"], False),  # 21.7 x 1.2 = 26.1 Hz
])
def test_modes_the_rk4_step_does_not_resolve(overrides, ok):
    raw = compose_config(FLEX_ON + overrides)
    if ok:
        model = prepare(validate(raw)).model
        f_max = model.tables.flex_freq.max() / (2 * np.pi)
        assert model.layout.n_modes == int(overrides[0].split("=")[1])
        assert f_max > 0
        return
    err = _expect(raw, "flex.n_modes")
    assert "plant_rate_hz" in err.allowed


# ---------------------------------------------------------------- combinations

COMBOS = list(itertools.product(("off", "on"), ("off", "on"), ("off", "on"), ("third_order", "simplex")))
PHASES = {"first_stage": 30.0, "upper_stage": 190.0}


@lru_cache(maxsize=None)
def _fly(flex: str, slosh: str, twd: str, actuator: str, phase: str):
    from savant_cli.sim.run import signals, simulate

    logging.getLogger("savant_cli.sim.setup").setLevel(logging.ERROR)  # "written without slosh"
    ov = [f"flex={flex}", f"slosh={slosh}", f"twd={twd}", f"actuator={actuator}", f"phase={phase}",
          f"sim.max_time_s={PHASES[phase]}"]
    cfg = validate(compose_config(ov))
    model = prepare(cfg).model
    result = simulate(model, progress=False)
    return cfg, model, result, signals(result, model)


@pytest.mark.slow
@pytest.mark.parametrize("flex,slosh,twd,actuator", COMBOS)
def test_every_model_combination_flies_without_divergence(flex, slosh, twd, actuator):
    for phase, t_max in PHASES.items():
        cfg, model, result, sig = _fly(flex, slosh, twd, actuator, phase)
        where = f"{phase} flex={flex} slosh={slosh} twd={twd} actuator={actuator}"
        assert result.status == "complete", (where, result.message)
        assert result.stop_code == engine.STOP_TIME, (where, result.message)
        assert result.t_final == pytest.approx(t_max, abs=0.01), where
        assert np.all(np.isfinite(result.log)), where
        assert model.layout.n_modes == (cfg.flex.n_modes if flex == "on" else 0)
        assert model.layout.slosh == (slosh == "on") and model.layout.simplex == (actuator == "simplex")
        # a controlled flight: body rate and attitude error stay small
        assert np.degrees(np.abs(sig["body_rate"].data).max()) < 10.0, where
        assert np.degrees(np.abs(sig["attitude_error"].data).max()) < 10.0, where
        if phase == "upper_stage":  # reached ignition and the J-2X is at full thrust
            assert not np.isnan(result.events[engine.EV_IGNITION]), where
            assert sig["thrust"].data[-1] > 1.2e6, where
        if twd == "off":
            np.testing.assert_array_equal(sig["twd_moment"].data, 0.0)
        else:
            assert np.abs(sig["twd_moment"].data).max() > 0.0, where


@pytest.mark.slow
@pytest.mark.parametrize("slosh,twd,actuator,phase", [
    (s, t, a, ph)
    for s, t, a in itertools.product(("off", "on"), ("off", "on"), ("third_order", "simplex"))
    for ph in PHASES])
def test_bending_modes_do_not_grow(slosh, twd, actuator, phase):
    """A stable closed loop: the modal amplitude over the last 10 s (first stage: forced by
    thrust and winds; upper stage: decaying after the separation restart) is not more than
    twice that of the 10 s before."""
    _, model, result, sig = _fly("on", slosh, twd, actuator, phase)
    t = sig["time"].data
    q = np.abs(sig["flex_q"].data)
    t1 = result.t_final
    late = q[(t >= t1 - 10.0)].max(axis=0)
    early = q[(t >= t1 - 20.0) & (t < t1 - 10.0)].max(axis=0)
    assert np.all(late <= 2.0 * early + 1e-6), (late, early)


@pytest.mark.slow
@pytest.mark.parametrize("phase", list(PHASES))
def test_all_on_signals_exist_with_units(phase):
    cfg, model, result, sig = _fly("on", "on", "on", "simplex", phase)
    n = len(sig["time"].data)
    units = {"flex_q": ("kg^0.5*m", cfg.flex.n_modes), "flex_qdot": ("kg^0.5*m/s", cfg.flex.n_modes),
             "slosh_position": ("m", 4), "slosh_velocity": ("m/s", 4), "slosh_frequency": ("Hz", 2),
             "liquid_level": ("m", 2), "twd_moment": ("N*m", 3), "gimbal_rate": ("rad/s", 2),
             "gimbal_acceleration": ("rad/s^2", 2), "sensed_rate": ("rad/s", 9)}
    for name, (unit, cols) in units.items():
        assert name in sig, name
        assert sig[name].units == unit, (name, sig[name].units)
        assert sig[name].data.shape == (n, cols), (name, sig[name].data.shape)
        assert np.all(np.isfinite(sig[name].data)), name
    # liquid level of a flat-bottom cylinder: m / (ρ π R²)
    prop = sig["propellant_remaining"].data
    for j, tank in enumerate(("lox", "lh2")):
        spec = cfg.vehicle["stages"]["upper_stage"]["tanks"][tank]["slosh"]
        level = prop[:, 1 + j] / (spec["density_kgm3"] * np.pi * spec["radius_m"] ** 2)
        np.testing.assert_allclose(sig["liquid_level"].data[:, j], level, rtol=1e-12)
    assert np.all(sig["slosh_frequency"].data > 0.0)
    # the gimbal rate is the time derivative of the gimbal angle (central differences, 50 Hz log)
    t = sig["time"].data[:-1]
    ang = sig["gimbal_angle"].data[:-1]
    rate = sig["gimbal_rate"].data[:-1]
    dt = np.diff(t)
    assert np.allclose(dt, dt[0])
    num = (ang[2:] - ang[:-2]) / (2 * dt[0])
    scale = np.abs(rate).max()
    assert np.median(np.abs(num - rate[1:-1])) < 0.05 * scale


@pytest.mark.slow
def test_tail_wags_dog_moment_is_engine_inertia_times_nozzle_acceleration():
    """Slosh off (the CG is the vehicle's): M_y = (I_R + m_R l_R l_c) δ̈_p and
    M_z = (I_R + m_R l_R l_c) δ̈_y with l_c the gimbal's distance aft of the CG."""
    cfg, model, result, sig = _fly("off", "off", "on", "third_order", "first_stage")
    motor = cfg.vehicle["stages"]["first_stage"]["engines"]["five_segment_motor"]
    eng = motor["moving_mass"]
    l_c = motor["gimbal_m"][0] - sig["cg_structure"].data[:, 0]
    j = eng["inertia_about_gimbal_kgm2"] + eng["mass_kg"] * eng["cg_from_gimbal_m"] * l_c
    acc = sig["gimbal_acceleration"].data
    m = sig["twd_moment"].data
    scale = np.abs(m).max()
    assert scale > 0.0
    np.testing.assert_allclose(m[:, 1], j * acc[:, 0], rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(m[:, 2], j * acc[:, 1], rtol=0, atol=1e-9 * scale)
    np.testing.assert_array_equal(m[:, 0], 0.0)
