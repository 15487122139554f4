"""The flexible body with strap-on boosters (docs/vehicles.md, "Flexible body"): the
boosted configuration flies its own pair of modal sets (``boosted_liftoff``,
``boosted_burnout``, blended by the boosters' burned propellant), each booster's nozzle is
a flex point (``flex.nodes.nozzle_<booster>``) whose loads drive the modes, and its thrust
follows the structure's rotation there.

The modal data here are the shipped ares_i sets with the boosters' nozzles added as two
nodes of their own (the boosted sets are the first stage's, the booster nodes' shapes
chosen by the test): the checks are closed forms on them, not a claim about a boosted
vehicle's real modes.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.io.modal_data import read_modal_set
from savant_cli.models import actuator, boosters, flex, layout, propulsion, rigid_body
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import derivative, mass_state
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from test_boosters import _cfg
from test_vehicle_examples import example_node

SHIPPED = shipped_config_dir() / "vehicle"
NOZZLE_NODES = {"booster_left": 9001, "booster_right": 9002}
#: each booster nozzle node's shape per mode in the file's units (in, rad): dx, dy, dz, rx, ry, rz
NOZZLE_SHAPES = {9001: (0.01, 0.02, -0.04, 0.0, 3.0e-5, 1.0e-5), 9002: (-0.02, -0.03, 0.05, 0.0, -2.0e-5, 4.0e-5)}
#: each booster nozzle's fixed cant (pitch, yaw, deg), so that its thrust has lateral components
CANT_DEG = {"booster_left": (1.0, 0.5), "booster_right": (1.0, -0.5)}
N_MODES = 2  # the first bending mode in each plane (the upper-stage sets' second pair is above the RK4 bound)


def _data_dir(tmp: Path) -> Path:
    """The ares_i tables with the boosted sets: the first stage's, every shape zeroed but
    the two booster nozzle nodes' (the same shape in every mode, scaled by the mode's
    number), so the booster loads alone drive the modes."""
    data = tmp / "ares_i"
    shutil.copytree(SHIPPED / "ares_i", data)
    fdir = data / "flex"
    for boosted, source in (("boosted_liftoff", "first_stage_liftoff"), ("boosted_burnout", "first_stage_burnout")):
        shutil.copy(fdir / f"{source}_modes.csv", fdir / f"{boosted}_modes.csv")
        lines = (fdir / f"{source}_shapes.csv").read_text().splitlines()
        out, last_mode = [], None
        for line in lines:
            if line.startswith("#") or line.startswith("mode,"):
                out.append(line)
                continue
            cells = line.split(",")
            mode = int(cells[0])
            if last_mode is not None and mode != last_mode:
                out += _nozzle_rows(last_mode)
            last_mode = mode
            out.append(",".join(cells[:3] + ["0"] * 6))
        out += _nozzle_rows(last_mode)
        (fdir / f"{boosted}_shapes.csv").write_text("\n".join(out) + "\n")
        nodes = (fdir / f"{source}_nodes.csv").read_text().rstrip("\n")
        (fdir / f"{boosted}_nodes.csv").write_text(nodes + "\n9001,3602.36,0,0\n9002,3602.36,0,0\n")
    return data


def _nozzle_rows(mode: int) -> list[str]:
    return [f"{mode},{node},3602.36," + ",".join(f"{mode * v:.9g}" for v in shape)
            for node, shape in NOZZLE_SHAPES.items()]


def _vehicle(data: Path, example: str = "strap-on-boosters"):
    node = example_node(example)
    node["flex"]["nodes"].update({f"nozzle_{b}": [n] for b, n in NOZZLE_NODES.items()})
    for b, cant in CANT_DEG.items():
        node["boosters"][b]["engines"][f"{b}_motor"]["cant_deg"] = list(cant)
    return load_vehicle(node, data)


def _direction(pitch: float, yaw: float) -> np.ndarray:
    """The unit thrust line of a nozzle at thrust-line angles ``pitch``, ``yaw`` (rad), body
    axes (docs/models.md, "Propulsion")."""
    return np.array([np.cos(pitch) * np.cos(yaw), -np.sin(yaw), np.sin(pitch) * np.cos(yaw)])


@pytest.fixture(scope="module")
def boosted(tmp_path_factory):
    data = _data_dir(tmp_path_factory.mktemp("flex_boosters"))
    cfg = _cfg("flex=on", f"flex.n_modes={N_MODES}", "flex.switching=propellant")
    vehicle = _vehicle(data)
    model = build_model(cfg, vehicle, read_guidance(prepare(cfg, hydra_search_dirs()).command_file))
    return data, vehicle, model


def test_the_boosted_sets_fly_while_the_boosters_are_attached(boosted):
    _, _, model = boosted
    x, p = model.x0.copy(), model.p
    tanks = [model.layout.tank(t) for t in ("booster_left_grain", "booster_right_grain")]
    x[tanks] *= 0.25  # three quarters of the boosters' propellant burned
    tb = model.packed_tables
    assert flex.flex_sets(x, 0, p, tb) == (4, 5, pytest.approx(0.75, rel=1e-12))
    assert flex.flex_sets(x, 1, p, tb)[:2] == (0, 1)  # jettisoned: the first stage's own pair


def test_the_booster_nozzles_load_the_modes_with_their_thrust(boosted):
    """q = q̇ = 0, so q̈_i = Σ_b φ_i(nozzle_b)·F_b: every other point of the boosted sets
    has a zero shape. F_b: each booster's delivered thrust (half the logged sum: the two
    burn alike) along its fixed nozzle's cant."""
    data, _, model = boosted
    x, u, p, tb = model.x0.copy(), model.u0.copy(), model.p, model.packed_tables
    t = 20.0
    aux, xd = np.zeros(layout.N_AUX), np.zeros(x.size)
    derivative(t, x, u, p, tb, aux, xd)
    f_each = aux[boosters.A_THRUST] / 2.0
    assert f_each > 1.0e6
    phi = [read_modal_set(data / "flex", "boosted_liftoff", ("in", "lbf"), "test").at_nodes([n], "test")[:N_MODES]
           for n in NOZZLE_NODES.values()]
    expected = sum(ph[:, :3] @ (f_each * _direction(*np.radians(CANT_DEG[b]))) for ph, b in zip(phi, NOZZLE_NODES))
    fo, nm = model.layout.flex, N_MODES
    np.testing.assert_allclose(xd[fo + nm:fo + 2 * nm], expected, rtol=1e-12, atol=0.0)
    assert np.all(expected != 0.0)


def test_a_booster_thrust_follows_the_structure_at_its_nozzle(boosted):
    """With q ≠ 0 each nozzle turns by its rotation θ = Σ σ(nozzle) q: its thrust line
    moves from t̂(cant) to t̂(cant − θ) (pitch, yaw), and the rigid body's specific force
    changes by Σ_b F_b (t̂(cant_b − θ_b) − t̂(cant_b)) / m (no other point of the boosted
    sets moves)."""
    _, _, model = boosted
    x, u, p, tb = model.x0.copy(), model.u0.copy(), model.p, model.packed_tables
    fo = model.layout.flex
    aux0, aux = np.zeros(layout.N_AUX), np.zeros(layout.N_AUX)
    derivative(20.0, x, u, p, tb, aux0, np.zeros(x.size))
    x[fo] = 2.0  # the first mode's coordinate, √kg·m
    x[fo + 1] = -1.5
    derivative(20.0, x, u, p, tb, aux, np.zeros(x.size))
    f_each = aux0[boosters.A_THRUST] / 2.0
    change = np.zeros(3)
    for i, b in enumerate(NOZZLE_NODES):
        _, ty, tz = flex.rotation_at(x, 0, p, tb, flex.booster_point(p, tb, i), False)
        assert abs(ty) > 1e-6 and abs(tz) > 1e-6
        cant_p, cant_y = np.radians(CANT_DEG[b])
        change += f_each * (_direction(cant_p - ty, cant_y - tz) - _direction(cant_p, cant_y))
    mass = mass_state(x, p, tb, 0, np.zeros(layout.N_AUX))[1][0]
    accel = slice(rigid_body.A_ACCEL, rigid_body.A_ACCEL + 3)
    np.testing.assert_allclose(aux[accel] - aux0[accel], change / mass, rtol=1e-9, atol=1e-12)


def test_a_gimbaled_booster_nozzle_s_reaction_loads_the_modes_at_its_point(tmp_path):
    """Tail-wags-dog on, no thrust, the boosters' nozzles accelerating (third-order
    actuators, δ̈_p, δ̈_y): each moving nozzle (mass m_R, CG l_R aft of its pivot, inertia
    I_R about it) pushes the structure at its point with F = m_R l_R (0, −δ̈_y, δ̈_p) and
    M = I_R (0, δ̈_p, δ̈_y), so q̈_i = Σ_b φ_i(b)·F_b + σ_i(b)·M_b at q = q̇ = 0."""
    data = _data_dir(tmp_path)
    cfg = _cfg("flex=on", f"flex.n_modes={N_MODES}", "twd=on")
    model = build_model(cfg, _vehicle(data, "booster-tvc"),
                        read_guidance(prepare(cfg, hydra_search_dirs()).command_file))
    x, u, tb = model.x0.copy(), model.u0.copy(), model.packed_tables
    p = model.p.copy()
    p[propulsion.P_ON] = 0.0
    m_r, l_r, i_r = 900.0, 0.9, 1500.0  # the page's moving nozzle
    accel = {"booster_left": (3.0, -1.5), "booster_right": (-2.0, 2.5)}  # δ̈_p, δ̈_y, rad/s²
    expected = np.zeros(N_MODES)
    for i, (b, (ddp, ddy)) in enumerate(accel.items()):
        kp = boosters.booster_channel(p, i)
        x[kp + 2], x[kp + actuator.N_PER_CHANNEL + 2] = ddp, ddy
        shape = read_modal_set(data / "flex", "boosted_liftoff", ("in", "lbf"), "test").at_nodes(
            [NOZZLE_NODES[b]], "test")[:N_MODES]
        expected += shape[:, :3] @ (m_r * l_r * np.array([0.0, -ddy, ddp])) + shape[:, 3:] @ (
            i_r * np.array([0.0, ddp, ddy]))
    aux, xd = np.zeros(layout.N_AUX), np.zeros(x.size)
    derivative(20.0, x, u, p, tb, aux, xd)
    assert aux[boosters.A_THRUST] == 0.0
    fo = model.layout.flex
    np.testing.assert_allclose(xd[fo + N_MODES:fo + 2 * N_MODES], expected, rtol=1e-12)
    assert np.all(expected != 0.0)


@pytest.mark.slow
def test_a_boosted_vehicle_flies_with_flex_and_its_modes_restart_at_the_jettison(boosted):
    _, _, model = boosted
    result = simulate(model, progress=False, t_stop=120.0)
    assert result.status == "complete", result.message
    t_jet = result.events[engine.EV_BOOSTER_JETTISON]
    assert 80.0 < t_jet < 120.0  # the boosters' tail-off (their trace burns out near 95 s)
    k = int(round(t_jet / model.rates.dt))
    snap = simulate(model, progress=False, snapshot_steps=(k,), t_stop=(k + 1) * model.rates.dt).snapshots[k]
    fo = model.layout.flex
    assert np.all(snap.x[fo:fo + 2 * N_MODES] != 0.0)  # the boosted set's modes ring before the jettison
    x, u, d, ev = snap.x.copy(), snap.u.copy(), snap.d.copy(), snap.events.copy()
    engine.handle_events(snap.t, model.rates.dt, x, u, d, ev, model.sched, model.p, model.packed_tables,
                         engine.work_array(x.size))
    assert ev[engine.EV_BOOSTER_JETTISON] == snap.t and u[layout.U_CONFIG] == 1
    assert np.all(x[fo:fo + 2 * N_MODES] == 0.0)  # the first stage's set starts at rest


def test_a_booster_without_its_nozzle_node_is_refused(tmp_path):
    data = _data_dir(tmp_path)
    node = example_node("strap-on-boosters")
    node["flex"]["nodes"]["nozzle_booster_left"] = [NOZZLE_NODES["booster_left"]]
    cfg = _cfg("flex=on", f"flex.n_modes={N_MODES}")
    with pytest.raises(ConfigError) as info:
        build_model(cfg, load_vehicle(node, data), read_guidance(prepare(cfg, hydra_search_dirs()).command_file))
    assert info.value.key == "vehicle.flex.nodes.nozzle_booster_right"
