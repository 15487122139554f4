"""Import of modal data (``savant_cli.io.modal_data``) against hand conversions.

* The source paper's renormalization: inches → feet with lbf divides displacements by
  √12 and multiplies rotations by √12 (unit generalized mass kept); in→ft→in and
  in→m→in are the identity.
* The shipped ``ares_i`` sets read in SI have unit generalized mass and are
  mass-orthogonal with the node masses of ``<set>_nodes.csv`` converted by hand
  (1 lbf·s²/in = 175.126835 kg, 1 lbf·in·s² = 0.112984829 kg·m²).
* Structure → body is diag(−1, 1, −1) for displacements and rotations: every row of the
  raw shape files, converted by hand, equals the imported shape; the body-frame
  rotations are still the slopes of the body-frame displacements.
* Hand-made sets in metres/newtons read back unchanged apart from the frame flip (and
  the 1/√M normalization); the same physical mode written in feet/lbf reads back to the
  same SI shape.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from savant_cli.errors import ConfigError
from savant_cli.io.modal_data import conversion_factors, convert_shapes, read_modal_set
from savant_cli.paths import shipped_config_dir

FLEX_DIR = shipped_config_dir() / "vehicle" / "ares_i" / "flex"
SETS = ("first_stage_liftoff", "first_stage_burnout", "second_stage_ignition", "second_stage_burnout")
IN_M = 0.0254  # m per inch (exact)
FT_M = 0.3048  # m per foot (exact)
LBF_N = 0.45359237 * 9.80665  # N per lbf (exact: avoirdupois pound × standard gravity)
SLUG_PER_IN_KG = 175.126835  # kg per lbf·s²/in
LBF_IN_S2_KGM2 = 0.112984829  # kg·m² per lbf·in·s²
FLIP = np.array([-1.0, 1.0, -1.0, -1.0, 1.0, -1.0])  # structure → body, (d, r)


def _rows(path: Path) -> tuple[list[str], np.ndarray]:
    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    return lines[0].split(","), np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])


# ------------------------------------------------------------------- unit conversion


def test_inches_to_feet_is_the_papers_sqrt12():
    rng = np.random.default_rng(0)
    shapes = rng.standard_normal((3, 5, 6))
    orig = shapes.copy()
    out = convert_shapes(shapes, ("in", "lbf"), ("ft", "lbf"))
    np.testing.assert_allclose(out[..., :3], shapes[..., :3] / np.sqrt(12.0), rtol=1e-14)
    np.testing.assert_allclose(out[..., 3:], shapes[..., 3:] * np.sqrt(12.0), rtol=1e-14)
    np.testing.assert_array_equal(shapes, orig)  # input untouched


@pytest.mark.parametrize("via", [("ft", "lbf"), ("m", "N"), ("m", "lbf"), ("in", "N")])
def test_round_trip_is_identity(via):
    rng = np.random.default_rng(1)
    shapes = rng.standard_normal((4, 7, 6))
    back = convert_shapes(convert_shapes(shapes, ("in", "lbf"), via), via, ("in", "lbf"))
    np.testing.assert_allclose(back, shapes, rtol=1e-14)


def test_si_factors_by_hand():
    """Unit generalized mass in (in, lbf, s) → (m, N, s): the generalized-mass unit
    lbf·in·s² is LBF·IN kg·m², so the modal coordinate scales by √(LBF·IN): a displacement
    per unit coordinate φ [in] becomes φ·IN/√(LBF·IN) m per √(kg·m²), a rotation
    σ/√(LBF·IN) rad per √(kg·m²)."""
    d, r = conversion_factors("in", "lbf")
    assert d == pytest.approx(IN_M / np.sqrt(LBF_N * IN_M), rel=1e-14)
    assert r == pytest.approx(1.0 / np.sqrt(LBF_N * IN_M), rel=1e-14)
    d, r = conversion_factors("ft", "lbf")
    assert d == pytest.approx(FT_M / np.sqrt(LBF_N * FT_M), rel=1e-14)
    assert r == pytest.approx(1.0 / np.sqrt(LBF_N * FT_M), rel=1e-14)
    assert conversion_factors("m", "N") == (1.0, 1.0)
    # the hand constants of the brief are the same units
    assert LBF_N / IN_M == pytest.approx(SLUG_PER_IN_KG, rel=1e-8)
    assert LBF_N * IN_M == pytest.approx(LBF_IN_S2_KGM2, rel=1e-8)


# ------------------------------------------------------------- shipped ares_i sets


@pytest.fixture(scope="module")
def imported():
    return {name: read_modal_set(FLEX_DIR, name, ("in", "lbf"), f"vehicle.flex set {name}") for name in SETS}


@pytest.mark.parametrize("name", SETS)
def test_si_shapes_have_unit_generalized_mass_and_are_orthogonal(imported, name):
    ms = imported[name]
    _, nd = _rows(FLEX_DIR / f"{name}_nodes.csv")
    ids = nd[:, 0].astype(int)
    mass = nd[:, 2] * SLUG_PER_IN_KG
    inertia = nd[:, 3] * LBF_IN_S2_KGM2
    idx = np.array([int(np.nonzero(ms.nodes == i)[0][0]) for i in ids])
    assert sorted(idx.tolist()) == list(range(ms.nodes.size))  # every node once
    phi = ms.shapes[:, idx, :3]  # (modes, nodes, 3)
    sig = ms.shapes[:, idx, 3:]
    gm = np.einsum("n,ink,jnk->ij", mass, phi, phi) + np.einsum("n,ink,jnk->ij", inertia, sig, sig)
    np.testing.assert_allclose(np.diag(gm), 1.0, rtol=1e-7)
    off = gm - np.diag(np.diag(gm))
    assert np.abs(off).max() < 1e-7
    # the importer's own node masses are the same conversion
    np.testing.assert_allclose(ms.node_mass_kg[idx], mass, rtol=1e-8)
    np.testing.assert_allclose(ms.node_inertia_kgm2[idx], inertia, rtol=1e-8)


@pytest.mark.parametrize("name", SETS)
def test_structure_to_body_row_by_row(imported, name):
    ms = imported[name]
    _, md = _rows(FLEX_DIR / f"{name}_modes.csv")
    header, sd = _rows(FLEX_DIR / f"{name}_shapes.csv")
    assert header == ["mode", "node", "station_in", "dx_in", "dy_in", "dz_in", "rx_rad", "ry_rad", "rz_rad"]
    kd = IN_M / np.sqrt(LBF_N * IN_M)
    kr = 1.0 / np.sqrt(LBF_N * IN_M)
    np.testing.assert_allclose(ms.frequency_rad_s, 2 * np.pi * md[:, 1], rtol=1e-15)
    assert sd.shape[0] == ms.shapes.shape[0] * ms.shapes.shape[1]
    for row in sd:
        mode, node = int(row[0]), int(row[1])
        j = int(np.nonzero(ms.nodes == node)[0][0])
        expected = np.concatenate([row[3:6] * kd, row[6:9] * kr]) * FLIP / np.sqrt(md[mode - 1, 2])
        np.testing.assert_allclose(ms.shapes[mode - 1, j], expected, rtol=1e-13, atol=0)
        assert ms.station_m[j] == pytest.approx(row[2] * IN_M, rel=1e-14)


def test_body_rotation_is_the_slope_of_body_displacement(imported):
    """A proper rotation keeps the small-rotation kinematics: in body axes θ_y = −∂w/∂x_b and
    θ_z = +∂v/∂x_b with x_b = −station. Central differences over the 1 m mesh of the
    first pitch and yaw modes reproduce the imported rotations."""
    ms = imported["first_stage_liftoff"]
    order = np.argsort(ms.station_m, kind="stable")
    keep = np.concatenate([[True], np.diff(ms.station_m[order]) > 1e-9])  # drop alias nodes
    xb = -ms.station_m[order][keep]
    assert xb.size > 90
    for mode, (disp, rot, sign) in ((0, (2, 4, -1.0)), (1, (1, 5, 1.0)), (2, (2, 4, -1.0)), (3, (1, 5, 1.0))):
        shp = ms.shapes[mode][order][keep]
        slope = np.gradient(shp[:, disp], xb)
        inner = slice(2, -2)
        scale = np.abs(shp[:, rot]).max()
        assert np.abs(sign * slope[inner] - shp[inner, rot]).max() < 0.02 * scale
        other_plane = [1, 5] if disp == 2 else [2, 4]  # pitch modes have no dy, rz; yaw modes no dz, ry
        assert np.all(shp[:, other_plane] == 0.0) and scale > 0.0


# ---------------------------------------------------------------- hand-made sets


def _write_set(folder: Path, name: str, units: tuple[str, str], freq_hz, gmass, stations, shapes,
               masses=None, inertias=None, node_units: tuple[str, str] | None = None) -> None:
    """Write a set in the shipped format; ``shapes`` (n_modes, n_nodes, 6) structure frame;
    the nodes file's mass and inertia suffixes ``node_units``, by default the declared
    system's force·s²/length and force·length·s²."""
    lu, fu = units
    folder.mkdir(parents=True, exist_ok=True)
    lines = ["# hand-made test set", "mode,frequency_hz,generalized_mass"]
    lines += [f"{i + 1},{f!r},{g!r}" for i, (f, g) in enumerate(zip(freq_hz, gmass))]
    (folder / f"{name}_modes.csv").write_text("\n".join(lines) + "\n")
    lines = ["# hand-made test set", f"mode,node,station_{lu},dx_{lu},dy_{lu},dz_{lu},rx_rad,ry_rad,rz_rad"]
    for i in range(shapes.shape[0]):
        for j in range(shapes.shape[1]):
            lines.append(",".join([str(i + 1), str(100 + j), repr(float(stations[j]))]
                                  + [repr(float(v)) for v in shapes[i, j]]))
    (folder / f"{name}_shapes.csv").write_text("\n".join(lines) + "\n")
    if masses is not None:
        mu, iu = node_units or (f"{fu}_s2_per_{lu}", f"{fu}_{lu}_s2")
        lines = [f"node,station_{lu},mass_{mu},rotary_inertia_{iu}"]
        lines += [f"{100 + j},{float(stations[j])!r},{float(masses[j])!r},{float(inertias[j])!r}"
                  for j in range(len(stations))]
        (folder / f"{name}_nodes.csv").write_text("\n".join(lines) + "\n")


def test_si_set_reads_back_unchanged_apart_from_the_frame_flip(tmp_path):
    rng = np.random.default_rng(7)
    stations = np.array([0.0, 1.5, 3.0, 4.5])
    shapes = rng.standard_normal((2, 4, 6))
    _write_set(tmp_path, "hand", ("m", "N"), [1.5, 4.0], [1.0, 1.0], stations, shapes)
    ms = read_modal_set(tmp_path, "hand", ("m", "N"), "test")
    np.testing.assert_array_equal(ms.nodes, [100, 101, 102, 103])
    np.testing.assert_allclose(ms.station_m, stations, rtol=0, atol=0)
    np.testing.assert_allclose(ms.frequency_rad_s, 2 * np.pi * np.array([1.5, 4.0]), rtol=1e-15)
    np.testing.assert_allclose(ms.shapes, shapes * FLIP, rtol=1e-15, atol=0)
    assert ms.node_mass_kg is None
    # a point averaging two nodes is their mean shape; an unknown node names its key
    np.testing.assert_allclose(ms.at_nodes([101, 102], "k"), 0.5 * (shapes[:, 1] + shapes[:, 2]) * FLIP, rtol=1e-15)
    with pytest.raises(ConfigError) as exc:
        ms.at_nodes([100, 555], "vehicle.flex.nodes.imu")
    assert exc.value.key == "vehicle.flex.nodes.imu" and exc.value.value == 555


def test_generalized_mass_normalization(tmp_path):
    """A mode given with generalized mass M is divided by √M (unit generalized mass)."""
    rng = np.random.default_rng(8)
    shapes = rng.standard_normal((2, 3, 6))
    _write_set(tmp_path, "gm", ("m", "N"), [2.0, 3.0], [1.0, 4.0], np.array([0.0, 1.0, 2.0]), shapes)
    ms = read_modal_set(tmp_path, "gm", ("m", "N"), "test")
    np.testing.assert_allclose(ms.shapes[0], shapes[0] * FLIP, rtol=1e-15)
    np.testing.assert_allclose(ms.shapes[1], shapes[1] * FLIP / 2.0, rtol=1e-15)


def test_same_physical_mode_in_feet_and_pounds_reads_back_to_the_same_si_shape(tmp_path):
    """A mode with unit generalized mass in kg·m² over given node masses, rewritten by hand
    in (ft, lbf, s) with unit generalized mass in lbf·ft·s², imports to the same SI shape
    and to the same node masses."""
    rng = np.random.default_rng(9)
    n_nodes = 5
    stations = np.linspace(0.0, 8.0, n_nodes)
    mass = rng.uniform(100.0, 500.0, n_nodes)  # kg
    inertia = rng.uniform(10.0, 50.0, n_nodes)  # kg m²
    raw = rng.standard_normal((2, n_nodes, 6))
    raw[:, :, 3:] *= 0.3
    gm = np.einsum("n,ink->i", mass, raw[:, :, :3] ** 2) + np.einsum("n,ink->i", inertia, raw[:, :, 3:] ** 2)
    si = raw / np.sqrt(gm)[:, None, None]  # unit generalized mass, SI
    _write_set(tmp_path / "si", "m", ("m", "N"), [1.0, 2.0], [1.0, 1.0], stations, si, mass, inertia)

    mass_ft = mass / (LBF_N / FT_M)  # slug = lbf s²/ft
    inertia_ft = inertia / (LBF_N * FT_M)  # lbf ft s²
    ft = np.empty_like(si)
    ft[..., :3] = si[..., :3] / FT_M  # same physical shape, in feet …
    ft[..., 3:] = si[..., 3:]
    gm_ft = np.einsum("n,ink->i", mass_ft, ft[:, :, :3] ** 2) + np.einsum("n,ink->i", inertia_ft, ft[:, :, 3:] ** 2)
    ft /= np.sqrt(gm_ft)[:, None, None]  # … renormalized to 1 lbf ft s²
    _write_set(tmp_path / "ft", "m", ("ft", "lbf"), [1.0, 2.0], [1.0, 1.0], stations / FT_M, ft, mass_ft, inertia_ft)

    a = read_modal_set(tmp_path / "si", "m", ("m", "N"), "test")
    b = read_modal_set(tmp_path / "ft", "m", ("ft", "lbf"), "test")
    np.testing.assert_allclose(b.shapes, a.shapes, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(a.shapes, si * FLIP, rtol=1e-15)
    np.testing.assert_allclose(b.station_m, stations, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(b.node_mass_kg, mass, rtol=1e-12)
    np.testing.assert_allclose(b.node_inertia_kgm2, inertia, rtol=1e-12)
    # and with those masses the imported SI shapes have unit generalized mass
    g = np.einsum("n,ink->i", b.node_mass_kg, b.shapes[:, :, :3] ** 2) + np.einsum(
        "n,ink->i", b.node_inertia_kgm2, b.shapes[:, :, 3:] ** 2)
    np.testing.assert_allclose(g, 1.0, rtol=1e-12)


def test_node_masses_read_in_the_units_their_suffixes_name(tmp_path):
    """The same lumped masses in kg and kg·m², in slug and lbf·in·s², and in the declared
    system's lbf·s²/in (converted by hand from the exact inch and pound-force) read to the
    same SI values, whatever the set's declared (length, force) system."""
    rng = np.random.default_rng(12)
    stations = np.array([0.0, 1.0, 2.0])
    shapes = rng.standard_normal((1, 3, 6))
    mass = rng.uniform(100.0, 500.0, 3)  # kg
    inertia = rng.uniform(10.0, 50.0, 3)  # kg·m²
    slug = LBF_N / FT_M  # kg per lbf·s²/ft
    cases = {"si": (("m", "N"), mass, inertia, ("kg", "kgm2")),
             "slug": (("m", "N"), mass / slug, inertia / (LBF_N * IN_M), ("slug", "lbf_in_s2")),
             "inch": (("in", "lbf"), mass / (LBF_N / IN_M), inertia / (LBF_N * IN_M), None)}
    for case, (units, m, j, node_units) in cases.items():
        _write_set(tmp_path / case, "n", units, [1.0], [1.0], stations / (IN_M if units[0] == "in" else 1.0),
                   shapes, m, j, node_units)
        ms = read_modal_set(tmp_path / case, "n", units, "test")
        np.testing.assert_allclose(ms.node_mass_kg, mass, rtol=1e-12, err_msg=case)
        np.testing.assert_allclose(ms.node_inertia_kgm2, inertia, rtol=1e-12, err_msg=case)


@pytest.mark.parametrize("column, suffix, dimension", [("mass", "in", "mass"), ("mass", "x", "mass"),
                                                       ("rotary_inertia", "lbf_s2_per_in", "inertia")])
def test_a_node_column_without_a_unit_of_its_dimension_is_refused(tmp_path, column, suffix, dimension):
    units = {"mass": ("kg", "kgm2"), "rotary_inertia": ("kg", "kgm2")}[column]
    units = (suffix, units[1]) if column == "mass" else (units[0], suffix)
    _write_set(tmp_path, "a", ("m", "N"), [1.0], [1.0], np.array([0.0, 1.0]), np.ones((1, 2, 6)),
               [1.0, 2.0], [1.0, 1.0], units)
    with pytest.raises(ConfigError) as exc:
        read_modal_set(tmp_path, "a", ("m", "N"), "vehicle.flex set a")
    assert exc.value.key.endswith(f"/a_nodes.csv:{column}_{suffix}") and exc.value.value == suffix
    assert f"needs a {dimension} unit suffix" in exc.value.allowed
    assert ("lbf_s2_per_in" if dimension == "mass" else "lbf_in_s2") in exc.value.allowed


@pytest.mark.parametrize("bad_id", [999, 50])
def test_nodes_file_with_an_unknown_node_is_refused(tmp_path, bad_id):
    sh = np.ones((1, 3, 6))
    _write_set(tmp_path, "a", ("m", "N"), [1.0], [1.0], np.array([0.0, 1.0, 2.0]), sh,
               [1.0, 2.0, 3.0], [1.0, 1.0, 1.0])
    f = tmp_path / "a_nodes.csv"
    f.write_text(f.read_text().replace("\n102,", f"\n{bad_id},"))
    with pytest.raises(ConfigError) as exc:
        read_modal_set(tmp_path, "a", ("m", "N"), "vehicle.flex set a")
    assert exc.value.key.endswith("/a_nodes.csv:node") and exc.value.value == bad_id
    assert "row 3 (line 4)" in exc.value.allowed


def test_shapes_file_needs_each_mode_node_pair_once(tmp_path):
    sh = np.ones((2, 3, 6))
    _write_set(tmp_path, "b", ("m", "N"), [1.0, 2.0], [1.0, 1.0], np.array([0.0, 1.0, 2.0]), sh)
    f = tmp_path / "b_shapes.csv"
    lines = f.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("1,101,"))
    lines[i] = lines[i].replace("1,101,1.0,", "1,100,0.0,")  # (1, 100) twice, (1, 101) missing
    f.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError):
        read_modal_set(tmp_path, "b", ("m", "N"), "vehicle.flex set b")
