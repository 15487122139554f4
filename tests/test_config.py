"""Config composition and refusal of bad configs before any computation."""

from pathlib import Path

import numpy as np
import pytest
from omegaconf import open_dict

from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir
from savant_cli.sim.setup import prepare


def test_default_config_composes_and_validates(compose_cfg):
    cfg = validate(compose_cfg())
    assert cfg.vehicle["name"] == "ares_i"
    assert cfg.phase.name == "ascent"
    assert cfg.study.name == "nominal"
    assert cfg.actuator.name == "third_order"
    assert cfg.winds.enabled and cfg.winds.name == "ksc_mean_annual"
    assert cfg.controller.name == "msfc_pid"
    assert sum(cfg.controller.blending.stack) == pytest.approx(1.0)


def test_group_overrides(compose_cfg):
    cfg = validate(compose_cfg(["winds=none", "phase=first_stage"]))
    assert not cfg.winds.enabled
    assert cfg.phase.stop_at == "separation"


def _expect(cfg_raw, key_part):
    with pytest.raises(ConfigError) as exc:
        typed = validate(cfg_raw)
        prepare(typed)
    assert key_part in exc.value.key, exc.value
    return exc.value


def test_unknown_key_refused(compose_cfg):
    raw = compose_cfg()
    with open_dict(raw):
        raw.sim.plant_rat_hz = 100.0
    err = _expect(raw, "sim.plant_rat_hz")
    assert "unknown key" in err.allowed


def test_wrong_type_refused(compose_cfg):
    raw = compose_cfg()
    with open_dict(raw):
        raw.sim.max_time_s = "long"
    _expect(raw, "sim.max_time_s")


def test_blending_must_sum_to_one(compose_cfg):
    err = _expect(compose_cfg(["controller.blending.stack=[0.5,0.0,0.2]"]), "controller.blending.stack")
    assert "sum to 1" in err.allowed


def test_rates_must_divide(compose_cfg):
    _expect(compose_cfg(["sim.fcs_rate_hz=30"]), "sim.fcs_rate_hz")


def test_gain_breakpoints_must_increase(compose_cfg):
    raw = compose_cfg()
    bp = list(raw.controller.gains.stack.breakpoints)
    bp[2], bp[3] = bp[3], bp[2]
    raw.controller.gains.stack.breakpoints = bp
    _expect(raw, "controller.gains.stack.breakpoints")


def test_negative_actuator_frequency_refused(compose_cfg):
    _expect(compose_cfg(["actuator.first_stage.natural_frequency_hz=-3"]), "actuator.first_stage.natural_frequency_hz")


def test_missing_command_file_refused(compose_cfg):
    _expect(compose_cfg(["guidance.command_file=nope.csv"]), "guidance.command_file")


def _vehicle_copy(tmp_path: Path) -> Path:
    import shutil

    src = shipped_config_dir() / "vehicle"
    dst = tmp_path / "vehicle"
    shutil.copytree(src, dst)
    return dst


def _with_vehicle_dir(compose_cfg, vdir: Path):
    raw = compose_cfg()
    raw.vehicle.data_dir = str(vdir)
    return raw


def test_negative_mass_in_table_refused(compose_cfg, tmp_path):
    vdir = _vehicle_copy(tmp_path) / "ares_i"
    f = vdir / "mass_stack.csv"
    lines = f.read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if line and line[0].isdigit())
    cells = lines[i].split(",")
    cells[1] = "-" + cells[1].strip()
    lines[i] = ",".join(cells)
    f.write_text("\n".join(lines) + "\n")
    _expect(_with_vehicle_dir(compose_cfg, vdir), "mass")


def test_non_monotonic_table_axis_refused(compose_cfg, tmp_path):
    vdir = _vehicle_copy(tmp_path) / "ares_i"
    f = vdir / "first_stage_thrust.csv"
    lines = f.read_text().splitlines()
    data = [k for k, line in enumerate(lines) if line and (line[0].isdigit())]
    lines[data[3]], lines[data[4]] = lines[data[4]], lines[data[3]]
    f.write_text("\n".join(lines) + "\n")
    _expect(_with_vehicle_dir(compose_cfg, vdir), "first_stage_thrust")


def test_missing_data_file_refused(compose_cfg, tmp_path):
    vdir = _vehicle_copy(tmp_path) / "ares_i"
    (vdir / "aero_stack.csv").unlink()
    _expect(_with_vehicle_dir(compose_cfg, vdir), "aero_stack")


def test_malformed_data_file_refused(compose_cfg, tmp_path):
    vdir = _vehicle_copy(tmp_path) / "ares_i"
    (vdir / "rcs_thrust.csv").write_text("altitude_m,thrust_vac_N\n0,abc\n1000\n")
    _expect(_with_vehicle_dir(compose_cfg, vdir), "rcs_thrust")


def test_negative_thrust_refused(compose_cfg):
    _expect(compose_cfg(["vehicle.stages.upper_stage.engines.j2x.thrust_vac_N=-1"]), "thrust")


def test_staging_state_for_another_vehicle_refused(compose_cfg, tmp_path):
    import json

    src = shipped_config_dir() / "phase" / "ares_i_iss_staging_state.json"
    doc = json.loads(src.read_text())
    doc["vehicle"] = "other_vehicle"
    bad = tmp_path / "staging.json"
    bad.write_text(json.dumps(doc))
    err = _expect(compose_cfg(["phase=upper_stage", f"phase.staging_state_file={bad}"]), "phase.staging_state_file")
    assert "other_vehicle" in err.allowed


def test_upper_stage_phase_needs_a_state_file(compose_cfg):
    _expect(compose_cfg(["phase=upper_stage", "phase.staging_state_file="]), "phase.staging_state_file")


def test_hdf5_command_file_reads_like_csv(tmp_path):
    import h5py

    from savant_cli.io.guidance_file import read_guidance

    csv = read_guidance(shipped_config_dir() / "guidance" / "ares_i_iss_commands.csv")
    h5 = tmp_path / "cmd.h5"
    with h5py.File(h5, "w") as f:
        f["time_s"] = csv.time
        f["quaternion"] = csv.quat
        f["rate_rad_s"] = csv.rate
    back = read_guidance(h5)
    np.testing.assert_array_equal(back.time, csv.time)
    np.testing.assert_allclose(back.quat, csv.quat, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(back.rate, csv.rate)


def test_non_unit_command_quaternion_refused(tmp_path):
    from savant_cli.io.guidance_file import read_guidance

    bad = tmp_path / "cmd.csv"
    bad.write_text("time_s,q_w,q_x,q_y,q_z,rate_x_rad_s,rate_y_rad_s,rate_z_rad_s\n0,1,0,0,0,0,0,0\n1,2,0,0,0,0,0,0\n")
    with pytest.raises(ConfigError) as exc:
        read_guidance(bad)
    assert "unit norm" in exc.value.allowed


# ------------------------------------------------------------ one schema per group option

@pytest.mark.parametrize("overrides, key, belongs", [
    (["actuator=third_order", "+actuator.first_stage.valve_frequency_hz=1"], "actuator.first_stage.valve_frequency_hz",
     "actuator=simplex"),
    (["actuator=simplex", "+actuator.upper_stage.natural_frequency_hz=9"], "actuator.upper_stage.natural_frequency_hz",
     "actuator=third_order"),
    (["+slosh.damping_scale=5"], "slosh.damping_scale", "slosh=on"),
    (["+flex.n_modes=2"], "flex.n_modes", "flex=on"),
])
def test_a_key_of_another_option_is_refused_naming_where_it_belongs(overrides, key, belongs):
    from conftest import compose_config
    from savant_cli.config import validate

    with pytest.raises(ConfigError) as exc:
        validate(compose_config(overrides))
    assert exc.value.key == key
    assert belongs in exc.value.allowed


def test_an_unknown_key_of_a_variant_group_is_refused():
    from conftest import compose_config
    from savant_cli.config import validate

    with pytest.raises(ConfigError) as exc:
        validate(compose_config(["+actuator.first_stage.bogus=1"]))
    assert exc.value.key == "actuator.first_stage.bogus"
    assert "nor of any other actuator option" in exc.value.allowed


def test_each_option_is_typed_by_its_own_schema():
    from conftest import compose_config
    from savant_cli.config import SimplexStage, ThirdOrderStage, validate

    third = validate(compose_config([]))
    assert isinstance(third.actuator.first_stage, ThirdOrderStage) and not hasattr(third.actuator.first_stage,
                                                                                   "valve_frequency_hz")
    assert not hasattr(third.flex, "n_modes") and not hasattr(third.slosh, "damping_scale")
    full = validate(compose_config(["actuator=simplex", "flex=on", "slosh=on", "twd=on"]))
    assert isinstance(full.actuator.first_stage, SimplexStage) and not hasattr(full.actuator.first_stage, "damping")
    assert full.flex.n_modes == 4 and full.slosh.damping_scale == 1.0 and full.twd.enabled


def test_hydra_refusal_of_another_options_key_gets_the_same_explanation():
    from savant_cli.hydra_compose import variant_key_hint

    defaults = {"flex": "off", "actuator": "third_order"}
    assert "not a key of flex=off; it belongs to flex=on" in variant_key_hint(["flex.n_modes=3"], defaults)
    assert variant_key_hint(["flex=on", "flex.n_modes=3"], defaults) == ""
    assert "actuator=simplex" in variant_key_hint(["actuator.first_stage.valve_damping=0.5"], defaults)


def test_sim_rates_have_documented_bounds():
    from conftest import compose_config
    from savant_cli.config import SIM_BOUNDS, validate

    with pytest.raises(ConfigError) as exc:
        validate(compose_config(["sim.plant_rate_hz=1e9"]))
    assert exc.value.key == "sim.plant_rate_hz" and "10000" in exc.value.allowed
    for name, (low, high) in SIM_BOUNDS.items():
        assert 0 < low < high, name


@pytest.mark.parametrize("override, key", [
    ("study.frozen_time.criteria=[period,thrust]", "study.frozen_time.criteria[1]"),
    ("study.frozen_time.criteria=[period,period]", "study.frozen_time.criteria"),
    ("study.frozen_time.scan_s=0", "study.frozen_time.scan_s"),
    ("study.frozen_time.step_s=30", "study.frozen_time.step_s"),
    ("study.frozen_time.excitation_deg=-1", "study.frozen_time.excitation_deg"),
])
def test_bad_frozen_time_settings_are_refused(override, key):
    from conftest import compose_config
    from savant_cli.config import validate

    with pytest.raises(ConfigError) as exc:
        validate(compose_config(["study=linear", override]))
    assert exc.value.key == key


@pytest.mark.parametrize("overrides, key, value", [
    (["controller.ignition_fade.start_s=-0.1"], "controller.ignition_fade.start_s", -0.1),
    (["controller.ignition_fade.end_s=0.2"], "controller.ignition_fade.end_s", 0.2),
    (["controller.ignition_fade.end_s=inf"], "controller.ignition_fade.end_s", float("inf")),
])
def test_an_ignition_fade_that_ends_before_it_starts_is_refused(compose_cfg, overrides, key, value):
    """The fade of the upper-stage gains (controller.ignition_fade) starts at or after the
    ignition command and ends, finitely, no earlier than it starts."""
    err = _expect(compose_cfg(overrides), key)
    assert err.key == key and err.value == value
