"""The ares_i flexible-body modal data (``conf/vehicle/ares_i/flex/``) and its beam solver
(``savant_cli.datagen.ares_i_flex``) against independent references: textbook free-free
beam frequencies, the rotation-sign convention of a rigid rotation, the shipped mass
tables, the vehicle YAML's sensor and gimbal stations, and the generator itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf
from scipy.spatial.transform import Rotation

from savant_cli.datagen import ares_i_flex as flex
from savant_cli.datagen.ares_i_tables import LAYOUT, Segment, stations
from savant_cli.paths import shipped_config_dir

FLEX_DIR = shipped_config_dir() / "vehicle" / "ares_i" / "flex"
VEHICLE_DIR = shipped_config_dir() / "vehicle" / "ares_i"
SETS = ("first_stage_liftoff", "first_stage_burnout", "second_stage_ignition", "second_stage_burnout")
KINDS = ("modes", "shapes", "nodes")
IN_M = 0.0254                        # m per inch
LBF_S2_PER_IN_KG = 175.126835        # kg per lbf s^2/in
LBF_IN_S2_KGM2 = 0.112984829         # kg m^2 per lbf in s^2
# mass table and propellant row of each set
MASS_ROW = {"first_stage_liftoff": ("stack", "max"), "first_stage_burnout": ("stack", "min"),
            "second_stage_ignition": ("upper_les", "max"), "second_stage_burnout": ("upper", "min")}
N_MODES = 12


def read_csv(path: Path) -> tuple[list[str], list[str], np.ndarray]:
    """Comment lines, header names and numeric rows of a shipped CSV."""
    lines = path.read_text().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
    return comments, body[0].split(","), np.array([[float(v) for v in ln.split(",")] for ln in body[1:]])


def load_set(name: str, folder: Path = FLEX_DIR) -> dict[str, np.ndarray]:
    """A set as arrays: freq (12,), node ids, stations (in), mass, inertia (rows) and
    shapes (12, rows, 6) aligned with the rows of ``<set>_nodes.csv``."""
    _, mh, md = read_csv(folder / f"{name}_modes.csv")
    _, sh, sd = read_csv(folder / f"{name}_shapes.csv")
    _, nh, nd = read_csv(folder / f"{name}_nodes.csv")
    assert mh == ["mode", "frequency_hz", "generalized_mass"]
    assert sh == ["mode", "node", "station_in", "dx_in", "dy_in", "dz_in", "rx_rad", "ry_rad", "rz_rad"]
    assert nh == ["node", "station_in", "mass_lbf_s2_per_in", "rotary_inertia_lbf_in_s2"]
    ids = nd[:, 0].astype(int)
    row = {nid: i for i, nid in enumerate(ids)}
    assert len(row) == len(ids), "node ids must be unique"
    shapes = np.full((N_MODES, len(ids), 6), np.nan)
    for r in sd:
        shapes[int(r[0]) - 1, row[int(r[1])]] = r[3:]
        assert r[2] == nd[row[int(r[1])], 1], "station differs between shapes and nodes files"
    assert not np.isnan(shapes).any(), "every (mode, node) needs one row"
    assert np.array_equal(md[:, 0], np.arange(1, N_MODES + 1))
    return {"freq": md[:, 1], "gm": md[:, 2], "ids": ids, "x_in": nd[:, 1], "mass": nd[:, 2],
            "inertia": nd[:, 3], "shapes": shapes}


@pytest.fixture(scope="module")
def shipped() -> dict[str, dict[str, np.ndarray]]:
    return {name: load_set(name) for name in SETS}


# ------------------------------------------------------------------- the solver
@pytest.mark.parametrize("n_elements", [100, 137])
def test_uniform_free_free_beam_matches_textbook(n_elements):
    """ω_n = (β_n L)² √(EI / (μ L⁴)), β_n L = 4.7300, 7.8532, 10.9956 (free-free)."""
    length, ei, mu = 40.0, 3.0e10, 2500.0
    x = np.linspace(0.0, length, n_elements + 1)
    mass, inertia = flex.lumped_mass(x, [Segment("beam", mu * length, 0.0, length, 0.0, 0.0)])
    assert mass.sum() == pytest.approx(mu * length, rel=1e-12)
    f, w, th = flex.free_free_bending_modes(x, np.full(n_elements, ei), mass, inertia, 3)
    ref = np.array([4.7300, 7.8532, 10.9956]) ** 2 * np.sqrt(ei / (mu * length**4)) / (2.0 * np.pi)
    np.testing.assert_allclose(f, ref, rtol=0.01)
    gm = w**2 @ mass + th**2 @ inertia
    np.testing.assert_allclose(gm, 1.0, rtol=1e-9)       # unit generalized mass, SI
    assert np.all(w[:, 0] > 0.0)
    # symmetric modes of a uniform beam: 1st and 3rd even, 2nd odd about mid-span
    np.testing.assert_allclose(w[0], w[0][::-1], atol=1e-6 * abs(w[0]).max())
    np.testing.assert_allclose(w[1], -w[1][::-1], atol=1e-6 * abs(w[1]).max())


def test_rotation_sign_convention_of_a_rigid_rotation():
    """A right-handed rotation θ about +y moves a point at +x toward −z (dz/dx = −θ), one
    about +z toward +y (dy/dx = +θ): hence ry = −d(dz)/dx and rz = +d(dy)/dx."""
    theta, x = 1e-4, np.array([1.0, 0.0, 0.0])
    assert Rotation.from_rotvec([0.0, theta, 0.0]).apply(x)[2] == pytest.approx(-theta, rel=1e-6)
    assert Rotation.from_rotvec([0.0, 0.0, theta]).apply(x)[1] == pytest.approx(theta, rel=1e-6)


# ------------------------------------------------------------- the shipped files
@pytest.mark.parametrize("name", SETS)
def test_planes_and_slope_convention(shipped, name):
    """x–z modes carry only dz, ry with ry = −d(dz)/dx; x–y modes only dy, rz with
    rz = +d(dy)/dx (finite difference between neighbouring nodes vs mean end slope)."""
    s = shipped[name]
    _, first = np.unique(s["x_in"], return_index=True)          # one row per station
    x, sh = s["x_in"][first], s["shapes"][:, first]
    for i in range(N_MODES):
        lat, rot, zero = (2, 4, [0, 1, 3, 5]) if i % 2 == 0 else (1, 5, [0, 2, 3, 4])
        sign = -1.0 if i % 2 == 0 else 1.0
        assert np.all(sh[i, :, zero] == 0.0), f"mode {i + 1}: out-of-plane components"
        fd = np.diff(sh[i, :, lat]) / np.diff(x)
        mean_slope = sign * 0.5 * (sh[i, 1:, rot] + sh[i, :-1, rot])
        tol = 0.05 * np.abs(sh[i, :, rot]).max()
        assert np.abs(fd - mean_slope).max() < tol, f"mode {i + 1}: slope convention"
        assert sh[i, 0, lat] > 0.0, f"mode {i + 1}: forward node's displacement must be positive"
    # each x–y mode is its x–z twin turned 90 deg about x: dy = dz, rz = −ry
    np.testing.assert_array_equal(sh[1::2, :, 1], sh[0::2, :, 2])
    np.testing.assert_array_equal(sh[1::2, :, 5], -sh[0::2, :, 4])


@pytest.mark.parametrize("name", SETS)
def test_unit_generalized_mass_and_orthogonality(shipped, name):
    s = shipped[name]
    np.testing.assert_array_equal(s["gm"], 1.0)
    w = np.concatenate([np.repeat(s["mass"][:, None], 3, 1), np.repeat(s["inertia"][:, None], 3, 1)], 1)
    phi = s["shapes"].reshape(N_MODES, -1)
    gm = phi @ (w.ravel()[:, None] * phi.T)
    np.testing.assert_allclose(gm, np.eye(N_MODES), atol=1e-7)


@pytest.mark.parametrize("name", SETS)
def test_node_masses_match_the_shipped_mass_tables(shipped, name):
    """Lumped masses reproduce the mass table's mass, CG and pitch inertia at the set's
    propellant load; an alias row (same station) carries no mass."""
    s = shipped[name]
    config, which = MASS_ROW[name]
    _, head, table = read_csv(VEHICLE_DIR / f"mass_{config}.csv")
    row = table[np.argmax(table[:, 0]) if which == "max" else np.argmin(table[:, 0])]
    ref = dict(zip(head, row))
    m = s["mass"] * LBF_S2_PER_IN_KG
    x = s["x_in"] * IN_M
    cg = float(m @ x / m.sum())
    iyy = float(m @ (x - cg) ** 2 + s["inertia"].sum() * LBF_IN_S2_KGM2)
    assert m.sum() == pytest.approx(ref["mass_kg"], rel=1e-6)
    assert cg == pytest.approx(ref["cg_x_m"], abs=0.01)
    assert iyy == pytest.approx(ref["iyy_kgm2"], rel=0.01)
    stations_with_mass = s["x_in"][s["mass"] > 0.0]
    assert len(np.unique(stations_with_mass)) == len(stations_with_mass), "mass counted twice"
    assert np.all(s["inertia"][s["mass"] == 0.0] == 0.0)


def test_frequencies(shipped):
    f = {name: s["freq"] for name, s in shipped.items()}
    assert f["first_stage_liftoff"][0] == pytest.approx(1.00, rel=0.01)
    for name, fr in f.items():
        np.testing.assert_array_equal(fr[0::2], fr[1::2])          # the two planes
        assert np.all(np.diff(fr[0::2]) > 0.0), name
        assert fr[0] > 0.0
    assert f["first_stage_burnout"][0] > f["first_stage_liftoff"][0]
    assert f["second_stage_burnout"][0] > f["second_stage_ignition"][0] > f["first_stage_burnout"][0]


def test_shipped_files_are_what_the_generator_writes(tmp_path, capsys):
    flex.main(["--out", str(tmp_path)])
    assert "first_stage_liftoff" in capsys.readouterr().out
    expected = sorted(f"{s}_{k}.csv" for s in SETS for k in KINDS)
    assert sorted(p.name for p in tmp_path.iterdir()) == expected
    assert sorted(p.name for p in FLEX_DIR.glob("*.csv")) == expected
    for fname in expected:
        c_new, h_new, d_new = read_csv(tmp_path / fname)
        c_old, h_old, d_old = read_csv(FLEX_DIR / fname)
        assert (c_new, h_new) == (c_old, h_old), fname
        assert d_new.shape == d_old.shape, fname
        # bit-identical here; the tolerance only absorbs LAPACK differences between builds
        scale = np.abs(d_old).max(axis=0)
        np.testing.assert_allclose(d_new, d_old, rtol=1e-7, atol=1e-9 * scale.max(), err_msg=fname)


def named_stations_m() -> dict[int, float]:
    """Named nodes' stations from the vehicle YAML and the segment layout."""
    y = OmegaConf.load(shipped_config_dir() / "vehicle" / "ares_i.yaml").vehicle  # a `_global_` preset file
    assert y.sensors.rate_gyro_upper_stage_m[0] == y.sensors.imu_m[0]
    st = stations(LAYOUT)
    return {4021: y.sensors.imu_m[0], 6030: y.sensors.rate_gyro_first_stage_m[0],
            718: y.stages.first_stage.engines.five_segment_motor.gimbal_m[0],
            6023: y.stages.upper_stage.roll_jets.location_m[0], 6226: y.stages.upper_stage.engines.j2x.gimbal_m[0],
            6003: st["lh2_fwd"], 6004: st["lox_fwd"], 6021: st["lox_fwd"], 6022: st["lox_aft"]}


@pytest.mark.parametrize("name", SETS)
def test_named_nodes_present_at_their_stations(shipped, name):
    s = shipped[name]
    expected = named_stations_m()
    if name.startswith("second_stage"):
        expected = {k: v for k, v in expected.items() if k not in (6030, 718)}
    for nid, x_m in expected.items():
        hit = np.nonzero(s["ids"] == nid)[0]
        assert hit.size == 1, f"node {nid} missing from {name}"
        assert s["x_in"][hit[0]] == pytest.approx(x_m / IN_M, abs=1e-6)
    # coincident named nodes share one shape
    row = {nid: i for i, nid in enumerate(s["ids"])}
    for a, b in ((6004, 6021), (6226, 6022)):
        np.testing.assert_array_equal(s["shapes"][:, row[a]], s["shapes"][:, row[b]])


def test_generic_nodes_numbered_from_the_nose_and_shared_between_sets(shipped):
    where: dict[int, float] = {}
    for s in shipped.values():
        gen = s["ids"] < 4000
        gen &= s["ids"] >= 1001
        ids, x = s["ids"][gen], s["x_in"][gen]
        assert np.all(np.diff(ids) > 0) and np.all(np.diff(x) > 0)
        assert np.diff(np.unique(s["x_in"])).max() * IN_M <= 1.0 + 1e-6      # spacing <= 1 m
        assert len(s["ids"]) <= 150
        for nid, xi in zip(ids, x):
            assert where.setdefault(int(nid), float(xi)) == float(xi), f"node {nid} moves between sets"
    assert min(where) == 1001


def test_one_stiffness_distribution_for_all_configurations():
    """Shared structure has the same EI in every configuration; aft of the upper stage the
    stack's interstage gives way to the (softer) J-2X stub once the first stage is gone."""
    fwd = np.array([12.0, 20.0, 30.0])                           # upper-stage tanks
    ei = {c: flex.element_ei(fwd, c) for c in ("stack", "upper_les", "upper")}
    np.testing.assert_array_equal(ei["stack"], ei["upper"])
    np.testing.assert_array_equal(ei["stack"], ei["upper_les"])
    aft = np.array([36.5, 37.5])
    assert flex.element_ei(aft, "upper")[0] == flex.element_ei(aft, "upper_les")[0]
    assert flex.element_ei(aft, "upper")[0] < flex.element_ei(aft, "stack")[0]
    with pytest.raises(ValueError):
        flex.element_ei(np.array([0.5, 1.5]), "upper")           # the LES has left
    assert flex.element_ei(fwd, "stack", scale=2.0) == pytest.approx(2.0 * ei["stack"])
