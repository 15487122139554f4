"""Tables out of order are refused, never repaired (issue 27 item 7, docs/vehicles.md).

Each test corrupts a copy of a shipped table of one kind by putting two rows (or two
blocks of rows) of its axis out of order, and checks the refusal: the key
``<folder>/<file>:<column>`` (a YAML list: ``key[i]``), the value as written in the
file, and the row with its line in the file. Before issue 27 an aero table with its Mach
breakpoints out of order was silently re-sorted and flown.
"""

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
from savant_cli.io.guidance_file import read_guidance
from savant_cli.io.modal_data import read_modal_set
from savant_cli.io.table_order import NEVER_SORTED, require_grid_order, require_increasing
from savant_cli.paths import shipped_config_dir
from savant_cli.vehicle import load_vehicle

CONF = shipped_config_dir()
DATA_DIR = CONF / "vehicle" / "ares_i"


def _cfg() -> dict:
    return OmegaConf.to_container(OmegaConf.load(CONF / "vehicle" / "ares_i.yaml").vehicle, resolve=True)


@pytest.fixture
def copy(tmp_path) -> Path:
    d = tmp_path / "ares_i"
    shutil.copytree(DATA_DIR, d)
    return d


def _data_lines(path: Path) -> tuple[list[str], list[int]]:
    """The file's lines and the 0-based index of each data row (after the header)."""
    lines = path.read_text().splitlines()
    body = [i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    return lines, body[1:]


def _swap_rows(path: Path, a: int, b: int) -> None:
    """Swap data rows ``a`` and ``b`` (0-based) of a CSV."""
    lines, rows = _data_lines(path)
    lines[rows[a]], lines[rows[b]] = lines[rows[b]], lines[rows[a]]
    path.write_text("\n".join(lines) + "\n")


def _swap_blocks(path: Path, start: int, size: int) -> None:
    """Swap the block of ``size`` data rows at ``start`` with the block after it."""
    lines, rows = _data_lines(path)
    first = [lines[rows[i]] for i in range(start, start + size)]
    second = [lines[rows[i]] for i in range(start + size, start + 2 * size)]
    for k, text in enumerate(second + first):
        lines[rows[start + k]] = text
    path.write_text("\n".join(lines) + "\n")


def _cell(path: Path, row: int, column: str) -> float:
    lines, rows = _data_lines(path)
    header = [h.strip() for h in lines[rows[0] - 1].split(",")]
    return float(lines[rows[row]].split(",")[header.index(column)])


def _line(path: Path, row: int) -> int:
    """1-based file line of data row ``row`` (0-based)."""
    return _data_lines(path)[1][row] + 1


def _assert_refused(exc: ConfigError, key: str, value: float, path: Path, row: int) -> None:
    """The refusal names ``key``, the value as written and ``row N (line L)``."""
    assert exc.key == key, exc
    assert exc.value == pytest.approx(value, rel=0, abs=0), exc
    assert f"row {row + 1} (line {_line(path, row)})" in exc.allowed, exc
    assert NEVER_SORTED in exc.allowed


# ------------------------------------------------------------------ vehicle tables
@pytest.mark.parametrize("file, column, row", [
    ("base_force_stack.csv", "time_s", 5),
    ("mass_upper.csv", "propellant_remaining_kg", 7),
    ("mass_stack.csv", "propellant_remaining_kg", 20),
    ("first_stage_thrust.csv", "time_s", 10),
    ("j2x_startup.csv", "time_s", 3),
    ("rcs_thrust.csv", "altitude_m", 2),
])
def test_one_axis_tables_out_of_order_are_refused(copy, file, column, row):
    """Rows ``row`` and ``row + 1`` swapped: refused at ``row + 1``, whose value is the one
    that was at ``row``."""
    path = copy / file
    value = _cell(path, row, column)
    _swap_rows(path, row, row + 1)
    with pytest.raises(ConfigError) as info:
        load_vehicle(_cfg(), copy)
    _assert_refused(info.value, f"ares_i/{file}:{column}", value, path, row + 1)


def test_aero_mach_breakpoints_out_of_order_are_refused_not_sorted(copy):
    """The issue's case: the Mach 0.5 and 0.6 blocks of the stack's aero table swapped
    (each block a full alpha x beta grid, every row still there) used to be re-sorted and
    flown; now the first Mach 0.5 row, after the 0.6 block, is refused."""
    path = copy / "aero_stack.csv"
    per_mach = 121
    assert _cell(path, 2 * per_mach, "mach") == 0.5 and _cell(path, 3 * per_mach, "mach") == 0.6
    _swap_blocks(path, 2 * per_mach, per_mach)
    with pytest.raises(ConfigError) as info:
        load_vehicle(_cfg(), copy)
    _assert_refused(info.value, "ares_i/aero_stack.csv:mach", 0.5, path, 3 * per_mach)
    assert "mach slowest and beta_deg fastest" in info.value.allowed


@pytest.mark.parametrize("column, first, size", [
    ("alpha_deg", 11, 11),    # two alpha blocks of the first Mach block swapped (-8 before -10)
    ("beta_deg", 3, 1),       # two betas of one alpha swapped
])
def test_aero_inner_axes_out_of_order_are_refused_in_file_units(copy, column, first, size):
    """The inner axes are refused within their block, with the value in the file's unit
    (deg here, although savant holds radians) and the outer breakpoints named."""
    path = copy / "aero_upper.csv"
    value = _cell(path, first, column)
    _swap_blocks(path, first, size)
    with pytest.raises(ConfigError) as info:
        load_vehicle(_cfg(), copy)
    _assert_refused(info.value, f"ares_i/aero_upper.csv:{column}", value, path, first + size)
    assert "(at mach = 0" in info.value.allowed


def test_aero_repeated_row_is_refused_with_its_row(copy):
    path = copy / "aero_upper_les.csv"
    lines, rows = _data_lines(path)
    lines[rows[6]] = lines[rows[5]]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        load_vehicle(_cfg(), copy)
    assert info.value.key == "ares_i/aero_upper_les.csv:beta_deg"
    assert f"row 7 (line {_line(path, 6)}) repeats row 6 (line {_line(path, 5)})" in info.value.allowed


def test_aero_grid_with_a_gap_names_the_first_missing_point(copy):
    """In order but one point short (the last beta of the first alpha of Mach 0): the
    grid is not full, and the message names the first missing (mach, alpha, beta)."""
    path = copy / "aero_stack.csv"
    lines, rows = _data_lines(path)
    del lines[rows[10]]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        load_vehicle(_cfg(), copy)
    assert info.value.key == "ares_i/aero_stack.csv"
    assert "1 missing, the first at row 11 (mach = 0, alpha_deg = -10, beta_deg = 10)" in info.value.allowed


# ----------------------------------------------------------------------------- slosh
@pytest.mark.parametrize("tank", ["lox", "lh2"])
def test_slosh_level_out_of_order_is_refused(copy, tank):
    path = copy / f"slosh_{tank}.csv"
    value = _cell(path, 12, "level_m")
    _swap_rows(path, 12, 13)
    vehicle = load_vehicle(_cfg(), copy)
    slosh_cfg = validate(compose_config(["slosh=on"])).slosh
    with pytest.raises(ConfigError) as info:
        load_slosh(vehicle, slosh_cfg)
    _assert_refused(info.value, f"ares_i/slosh_{tank}.csv:level_m", value, path, 13)


# ------------------------------------------------------------------------ modal data
@pytest.fixture
def flex(tmp_path) -> Path:
    d = tmp_path / "flex"
    shutil.copytree(DATA_DIR / "flex", d)
    return d


def _read_set(folder: Path, name: str = "first_stage_liftoff"):
    return read_modal_set(folder, name, ("in", "lbf"), f"vehicle.flex set {name}")


def test_modes_out_of_order_are_refused(flex):
    path = flex / "second_stage_ignition_modes.csv"
    _swap_rows(path, 2, 3)
    with pytest.raises(ConfigError) as info:
        _read_set(flex, "second_stage_ignition")
    _assert_refused(info.value, "flex/second_stage_ignition_modes.csv:mode", 3.0, path, 3)


def test_mode_frequencies_must_not_fall(flex):
    """Modes renumbered in order but with a higher mode listed before a lower one."""
    path = flex / "first_stage_burnout_modes.csv"
    lines, rows = _data_lines(path)
    a, b = lines[rows[1]].split(","), lines[rows[2]].split(",")  # modes 2 and 3: a pair apart
    assert float(a[1]) < float(b[1])
    a[1:], b[1:] = b[1:], a[1:]
    lines[rows[1]], lines[rows[2]] = ",".join(a), ",".join(b)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        _read_set(flex, "first_stage_burnout")
    assert info.value.key == "flex/first_stage_burnout_modes.csv:frequency_hz"
    assert info.value.value == float(b[1]) and f"row 3 (line {_line(path, 2)})" in info.value.allowed


def test_shape_rows_with_modes_out_of_order_are_refused(flex):
    """Mode 2's block of the shapes file before mode 1's."""
    path = flex / "first_stage_liftoff_shapes.csv"
    n_nodes = sum(1 for _ in _data_lines(flex / "first_stage_liftoff_nodes.csv")[1])
    _swap_blocks(path, 0, n_nodes)
    with pytest.raises(ConfigError) as info:
        _read_set(flex)
    _assert_refused(info.value, "flex/first_stage_liftoff_shapes.csv:mode", 1.0, path, n_nodes)


def test_shape_rows_with_nodes_in_another_order_are_refused(flex):
    """Node ids are names (the shipped sets list them by station, not by id): any order
    is taken as mode 1 gives it, but every mode must repeat it; two nodes swapped in
    mode 2 only would pair mode 2's values with the wrong nodes if re-sorted silently."""
    path = flex / "first_stage_liftoff_shapes.csv"
    n_nodes = sum(1 for _ in _data_lines(flex / "first_stage_liftoff_nodes.csv")[1])
    moved = _cell(path, n_nodes + 1, "node")
    _swap_rows(path, n_nodes, n_nodes + 1)
    with pytest.raises(ConfigError) as info:
        _read_set(flex)
    assert info.value.key == "flex/first_stage_liftoff_shapes.csv:node" and info.value.value == moved
    assert f"row {n_nodes + 1} (line {_line(path, n_nodes)})" in info.value.allowed
    assert f"should be mode 2, node {int(_cell(path, n_nodes + 1, 'node'))}" in info.value.allowed


def test_node_order_of_the_shipped_sets_is_kept(flex):
    """The loader keeps the file's node order (no sorting by id): node 4021 sits between
    1013 and 6003 by station, as written."""
    ms = _read_set(flex)
    ids = ms.nodes.tolist()
    assert ids.index(4021) == ids.index(1013) + 1 and ids.index(6003) == ids.index(4021) + 1
    assert np.all(np.diff(ms.station_m) >= 0.0)


# ---------------------------------------------------------------- guidance commands
def test_guidance_command_times_out_of_order_are_refused(tmp_path):
    folder = tmp_path / "guidance"
    folder.mkdir()
    path = folder / "ares_i_iss_commands.csv"
    shutil.copy(CONF / "guidance" / "ares_i_iss_commands.csv", path)
    value = _cell(path, 40, "time_s")
    _swap_rows(path, 40, 41)
    with pytest.raises(ConfigError) as info:
        read_guidance(path)
    _assert_refused(info.value, "guidance/ares_i_iss_commands.csv:time_s", value, path, 41)


def test_reference_speed_out_of_order_in_the_first_stage_is_refused():
    """``guidance.first_stage_schedule=relative_velocity`` indexes the first stage by the
    command file's ``v_rel_m_s``: two first-stage samples swapped are refused, naming the
    column, the sample and its time (the schedule is never re-sorted)."""
    from savant_cli.sim.build import first_stage_profile

    table = read_guidance(CONF / "guidance" / "ares_i_iss_commands.csv")
    speed = table.speed.copy()
    speed[30], speed[31] = speed[31], speed[30]
    cfg = validate(compose_config(["guidance.first_stage_schedule=relative_velocity"]))
    with pytest.raises(ConfigError) as info:
        first_stage_profile(table._replace(speed=speed), cfg, 130.0)
    assert info.value.key == "guidance/ares_i_iss_commands.csv:v_rel_m_s"
    assert info.value.value == float(table.speed[30])
    assert f"sample 32 (t = {table.time[31]:g} s)" in info.value.allowed


# ----------------------------------------------------------------- tables in YAML
def _swapped(values: list, i: int) -> str:
    v = list(values)
    v[i], v[i + 1] = v[i + 1], v[i]
    return "[" + ",".join(repr(float(x)) for x in v) + "]"


def test_wind_profile_altitudes_out_of_order_are_refused():
    alt = OmegaConf.load(CONF / "winds" / "ksc_mean_annual.yaml").profile.altitude_m
    with pytest.raises(ConfigError) as info:
        validate(compose_config(["winds=ksc_mean_annual", f"winds.profile.altitude_m={_swapped(alt, 3)}"]))
    assert info.value.key == "winds.profile.altitude_m[4]" and info.value.value == float(alt[3])
    assert f"follows {float(alt[4]):g} at [3]" in info.value.allowed


@pytest.mark.parametrize("schedule", ["stack", "upper"])
def test_controller_gain_breakpoints_out_of_order_are_refused(schedule):
    bp = OmegaConf.load(CONF / "controller" / "msfc_pid.yaml").gains[schedule].breakpoints
    with pytest.raises(ConfigError) as info:
        validate(compose_config([f"controller.gains.{schedule}.breakpoints={_swapped(bp, 1)}"]))
    assert info.value.key == f"controller.gains.{schedule}.breakpoints[2]" and info.value.value == float(bp[1])


def test_modal_nodes_listed_twice_are_refused(flex):
    path = flex / "first_stage_burnout_nodes.csv"
    lines, rows = _data_lines(path)
    node = lines[rows[3]].split(",")[0]
    cells = lines[rows[4]].split(",")
    cells[0] = node
    lines[rows[4]] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as info:
        _read_set(flex, "first_stage_burnout")
    assert info.value.key == "flex/first_stage_burnout_nodes.csv:node" and info.value.value == int(node)
    assert f"row 5 (line {_line(path, 4)}): node listed twice" in info.value.allowed


# --------------------------------------------------------------------- the helpers
def test_helpers_accept_ordered_tables_and_name_the_first_fault():
    require_increasing("f.csv:x", np.array([0.0, 1.0, 2.0]))
    require_increasing("f.csv:x", np.array([0.0, 1.0, 1.0]), strict=False)
    with pytest.raises(ConfigError) as info:
        require_increasing("f.csv:x", np.array([0.0, 1.0, 1.0, 0.5]), [3, 4, 6, 7])
    assert info.value.value == 1.0 and info.value.allowed.startswith("row 3 (line 6):")
    a, b = np.array([0, 0, 1, 1.0]), np.array([0, 1, 0, 1.0])
    require_grid_order(["f.csv:a", "f.csv:b"], [a, b])
    with pytest.raises(ConfigError) as info:
        require_grid_order(["f.csv:a", "f.csv:b"], [a, b[[1, 0, 2, 3]]])
    assert info.value.key == "f.csv:b" and info.value.value == 0.0 and "(at a = 0)" in info.value.allowed
