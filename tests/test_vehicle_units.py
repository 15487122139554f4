"""Unit suffixes of the slosh tables and the modal shape files (one unit table,
``savant_cli/io/units.py``): a file in other units gives the same SI numbers as the
shipped SI (or declared-unit) file, and a wrong suffix is refused with the file, column,
value and the units allowed."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.flex_slosh import load_slosh
from savant_cli.io.modal_data import read_modal_set
from savant_cli.io.units import UNITS, split_unit
from savant_cli.paths import shipped_config_dir
from savant_cli.vehicle import load_vehicle

CONF = shipped_config_dir()
DATA_DIR = CONF / "vehicle" / "ares_i"
# exact definitions (NIST SP 811), written here independently of savant_cli.constants
FOOT_M, INCH_M, POUND_KG = 0.3048, 0.0254, 0.45359237


@pytest.fixture
def copy(tmp_path) -> Path:
    """The shipped ares_i data folder, copied to be edited."""
    return Path(shutil.copytree(DATA_DIR, tmp_path / "ares_i"))


def _rewrite(path: Path, header: list[str], scale: list[float]) -> None:
    """Write ``path`` again with a new header, each column divided by its ``scale``."""
    lines = path.read_text().splitlines()
    body = [ln for ln in lines if ln.strip() and not ln.lstrip().startswith("#")][1:]
    data = np.array([[float(c) for c in ln.split(",")] for ln in body]) / np.array(scale)
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in data) + "\n")


def _slosh(folder: Path):
    """The slosh data of ares_i with its tables read from ``folder``."""
    vehicle_cfg = OmegaConf.to_container(OmegaConf.load(CONF / "vehicle" / "ares_i.yaml").vehicle, resolve=True)
    return load_slosh(load_vehicle(vehicle_cfg, folder), validate(compose_config(["slosh=on"])).slosh)


def test_slosh_table_in_other_units_gives_the_si_numbers(copy):
    si = _slosh(copy)
    for tank in ("lox", "lh2"):  # columns in any order, in feet, pounds and inches
        _rewrite(copy / f"slosh_{tank}.csv", ["level_ft", "frequency_Hz", "damping", "slosh_mass_lbm", "slosh_height_in"],
                 [FOOT_M, 1.0, 1.0, POUND_KG, INCH_M])
    other = _slosh(copy)
    assert [t.reference_accel_mps2 for t in other.tanks] == [t.reference_accel_mps2 for t in si.tanks]
    for a, b in zip(si.tanks, other.tanks):
        for name in ("level_m", "frequency_rad_s", "damping", "mass_kg", "height_m"):
            np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-13, atol=1e-13, err_msg=name)


def test_slosh_table_with_a_wrong_unit_is_refused(copy):
    path = copy / "slosh_lox.csv"
    path.write_text(path.read_text().replace("slosh_mass_kg", "slosh_mass_m"))
    with pytest.raises(ConfigError) as info:
        _slosh(copy)
    assert info.value.key == "ares_i/slosh_lox.csv:slosh_mass_m"
    assert "mass unit suffix" in info.value.allowed and "lbm" in info.value.allowed


def test_slosh_table_with_a_bad_cell_names_file_column_and_line(copy):
    path = copy / "slosh_lh2.csv"
    lines = path.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln and not ln.startswith("#")) + 3  # the third data row
    cells = lines[i].split(",")
    cells[1] = "fast"
    lines[i] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        _slosh(copy)
    assert info.value.key == "ares_i/slosh_lh2.csv:frequency_hz"
    assert info.value.value == "fast" and f"line {i + 1}" in info.value.allowed


# ------------------------------------------------------------------------ modal data
SET = "first_stage_liftoff"
DECLARED = ("in", "lbf")  # conf/vehicle/ares_i.yaml: flex.units


def test_modal_shapes_in_other_units_give_the_si_numbers(copy):
    si = read_modal_set(copy / "flex", SET, DECLARED, "vehicle.flex")
    path = copy / "flex" / f"{SET}_shapes.csv"
    header = path.read_text().splitlines()
    assert [h for h in header if not h.startswith("#")][0] == "mode,node,station_in,dx_in,dy_in,dz_in,rx_rad,ry_rad,rz_rad"
    # stations in metres, displacements in feet, rotations in degrees (new = old / scale)
    _rewrite(path, ["mode", "node", "station_m", "dx_ft", "dy_ft", "dz_ft", "rx_deg", "ry_deg", "rz_deg"],
             [1.0, 1.0, 1.0 / INCH_M] + [FOOT_M / INCH_M] * 3 + [np.pi / 180.0] * 3)
    other = read_modal_set(copy / "flex", SET, DECLARED, "vehicle.flex")
    np.testing.assert_array_equal(other.nodes, si.nodes)
    np.testing.assert_array_equal(other.frequency_rad_s, si.frequency_rad_s)
    np.testing.assert_allclose(other.station_m, si.station_m, rtol=1e-13, atol=1e-13)
    scale = np.abs(si.shapes).max(axis=(0, 1))  # per component, for the absolute tolerance
    np.testing.assert_allclose(other.shapes, si.shapes, rtol=1e-12, atol=1e-14 * scale.max())


@pytest.mark.parametrize("column,dimension", [("rx_rad", "angle"), ("dz_in", "length"), ("station_in", "length")])
def test_modal_shapes_with_a_wrong_unit_are_refused(copy, column, dimension):
    path = copy / "flex" / f"{SET}_shapes.csv"
    bad = column.split("_")[0] + "_kg"
    path.write_text(path.read_text().replace(column, bad))
    with pytest.raises(ConfigError) as info:
        read_modal_set(copy / "flex", SET, DECLARED, "vehicle.flex")
    assert info.value.key == f"flex/{SET}_shapes.csv:{bad}" and info.value.value == "kg"
    assert f"needs a {dimension} unit suffix" in info.value.allowed


# ------------------------------------------------------- one reader, one error format
@pytest.mark.parametrize("cell,allowed", [("x", "line {line}: cells must be numbers"),
                                          ("nan", "row 2 (line {line}): all values must be finite")])
def test_a_bad_modal_cell_names_file_column_row_and_line(copy, cell, allowed):
    path = copy / "flex" / f"{SET}_modes.csv"
    lines = path.read_text().splitlines()
    i = [k for k, ln in enumerate(lines) if ln and not ln.startswith("#")][2]  # header, row 1, row 2
    cells = lines[i].split(",")
    cells[1] = cell
    lines[i] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        read_modal_set(copy / "flex", SET, DECLARED, "vehicle.flex")
    assert info.value.key == f"flex/{SET}_modes.csv:frequency_hz"
    assert info.value.allowed == allowed.format(line=i + 1)


@pytest.mark.parametrize("column, base, unit", [
    ("mass_lbf_s2_per_in", "mass", "lbf_s2_per_in"), ("rotary_inertia_lbf_in_s2", "rotary_inertia", "lbf_in_s2"),
    ("mass_N_s2_per_m", "mass", "N_s2_per_m"), ("dx_in", "dx", "in"), ("thrust_vac_N", "thrust_vac", "N"),
    ("generalized_mass", "generalized_mass", None), ("mass_per_in", "mass_per", "in")])
def test_a_compound_suffix_is_read_whole(column, base, unit):
    assert split_unit(column) == (base, unit)


def test_compound_units_by_hand():
    """lbf·s²/in and lbf·in·s² from the exact pound-force (avoirdupois pound × standard
    gravity) and inch."""
    lbf = POUND_KG * 9.80665
    assert UNITS["lbf_s2_per_in"] == ("mass", pytest.approx(lbf / INCH_M, rel=1e-15))
    assert UNITS["lbf_s2_per_ft"] == ("mass", pytest.approx(lbf / FOOT_M, rel=1e-15))
    assert UNITS["lbf_in_s2"] == ("inertia", pytest.approx(lbf * INCH_M, rel=1e-15))
    assert UNITS["lbf_ft_s2"] == ("inertia", pytest.approx(lbf * FOOT_M, rel=1e-15))
