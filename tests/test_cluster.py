"""Engine clusters (models/cluster.py, vehicle/two_stage.py): each engine of the burning
stage carries its share of the stage's thrust along its own thrust line at its own arm,
and reacts with its own moving mass.

References: the loads against numpy's cross products of each engine's force and arm
written out separately (an asymmetric, canted three-engine cluster); a flight against
superposition: one engine split into a symmetric pair of half engines must fly the same
ascent, since the pair's forces and moments sum to the single engine's; the vehicle
file's cluster against its refusals.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.models import actuator, blocks, cluster, layout, twd
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import PlantTables
from savant_cli.sim.run import simulate
from savant_cli.sim.setup import prepare
from savant_cli.vehicle import load_vehicle
from savant_cli.vehicle.tree import MovingMass
from savant_cli.vehicle.two_stage import Mount
from test_vehicle_examples import examples

SHIPPED = shipped_config_dir() / "vehicle"


def _packed(mounts: np.ndarray) -> np.ndarray:
    """A packed table array holding ``mounts`` (the other tables empty), each engine on
    its own channel pair, ganged (the mixer's columns of a single engine)."""
    arrays = [np.zeros(1)] * len(PlantTables._fields)
    rows = np.zeros((len(mounts), cluster.MOUNT_SIZE))
    rows[:, :7] = mounts
    rows[:, cluster.M_PAIR] = np.arange(len(mounts)) - np.count_nonzero(mounts[:, 0] == 0.0) * mounts[:, 0]
    rows[:, cluster.M_PITCH_PITCH] = rows[:, cluster.M_YAW_YAW] = 1.0
    arrays[cluster.T_MOUNTS] = rows
    return blocks.pack(arrays)


def _plant_vectors(n_pairs: int, angles=(), accelerations=(), limit=0.2):
    """``p``, ``x`` and ``xd`` of a plant whose gimbal channels start at index 0 of ``x``:
    ``angles[k]`` and ``accelerations[k]`` (rad, rad/s²) of channel ``k`` (pitch, yaw of
    each engine in turn)."""
    p = np.zeros(layout.N_PARAM)
    p[actuator.P_N_CHANNELS] = 2 * n_pairs
    p[actuator.P_VALVE_OFFSET] = -1
    p[actuator.P_US_GIMBAL + actuator.G_LIMIT] = p[actuator.P_FS_GIMBAL + actuator.G_LIMIT] = limit
    x, xd = np.zeros(actuator.N_PER_CHANNEL * 2 * n_pairs), np.zeros(actuator.N_PER_CHANNEL * 2 * n_pairs)
    for k, (a, dd) in enumerate(zip(angles, accelerations)):
        x[actuator.N_PER_CHANNEL * k] = a
        xd[actuator.N_PER_CHANNEL * k + 1] = dd
    return p, x, xd


def plant_loads(tb: np.ndarray, p: np.ndarray, x: np.ndarray, xd: np.ndarray, engine: int, thrust: float, arm):
    """``cluster.cluster_loads`` as the plant calls it, no null bias or flex: the first
    engine's limited angles and nozzle accelerations from its channels (pair 0), the
    others' read by the kernel from ``x`` and ``xd``."""
    k, lim = int(p[actuator.P_CHANNEL_OFFSET]), p[actuator.gimbal_stage(engine) + actuator.G_LIMIT]
    ky = k + actuator.N_PER_CHANNEL
    return cluster.cluster_loads(tb, p, x, xd, engine, 0, thrust, actuator.clip(x[k], lim), actuator.clip(x[ky], lim),
                                 xd[k + 1], xd[ky + 1], 0.0, 0.0, 0.0, 0.0, *arm)


def _reference_loads(mounts, thrust, pitch, yaw, dd, arm, moving):
    """Each engine's force and moment written out with numpy (body axes): the thrust
    along the canted line, and the moving mass's reaction ``m l δ̈`` at the gimbal with
    the torque ``I δ̈``; and the engines' forces' couple about the stage's gimbal point."""
    m, l_cg, inertia = moving
    force, moment, twd_force, twd_moment = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    couple = np.zeros(3)
    for stage, share, dx, dy, dz, cp, cy in mounts:
        if stage != 1.0:
            continue
        r = np.asarray(arm) + np.array([-dx, dy, -dz])
        tp, ty = pitch + cp, yaw + cy
        f = share * thrust * np.array([np.cos(tp) * np.cos(ty), -np.sin(ty), np.sin(tp) * np.cos(ty)])
        force += f
        moment += np.cross(r, f)
        fw = m * l_cg * np.array([0.0, -dd[1], dd[0]])
        twd_force += fw
        twd_moment += np.cross(r, fw) + inertia * np.array([0.0, dd[0], dd[1]])
        couple += np.cross(np.array([-dx, dy, -dz]), f + fw)
    return force, moment, twd_force, twd_moment, couple


def test_an_asymmetric_canted_cluster_against_its_engines_written_out():
    mounts = np.array([[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],          # a first-stage engine: not flown here
                       [1.0, 0.5, 0.3, 1.1, -0.4, 0.02, -0.03],
                       [1.0, 0.25, -0.2, -0.9, 0.7, -0.01, 0.05],
                       [1.0, 0.25, 0.0, 0.1, 1.3, 0.04, 0.0]])
    moving = (800.0, 1.2, 3000.0)
    thrust, pitch, yaw, dd, arm = 1.2e6, 0.013, -0.021, (0.7, -1.9), (-24.0, 0.05, -0.08)
    p, x, xd = _plant_vectors(3, [pitch, yaw] * 3, list(dd) * 3)
    p[cluster.P_UPPER_FIRST] = 1.0
    p[twd.P_ON] = 1.0
    p[twd.P_US_ENGINE:twd.P_US_ENGINE + twd.ENGINE.size] = moving
    loads, reaction, couple = plant_loads(_packed(mounts), p, x, xd, layout.ENGINE_UPPER, thrust, arm)
    force, moment, twd_force, twd_moment, ref_couple = _reference_loads(mounts, thrust, pitch, yaw, dd, arm, moving)
    # what the flexible body's gimbal node carries: the forces' couple about the stage's gimbal point
    np.testing.assert_allclose(couple, ref_couple, rtol=1e-13, atol=1e-9 * thrust)
    assert np.linalg.norm(ref_couple) > 1e-3 * thrust
    np.testing.assert_allclose(loads[:3], force, rtol=1e-14, atol=1e-9 * thrust)
    np.testing.assert_allclose(loads[3:], moment, rtol=1e-14, atol=1e-9 * thrust)
    np.testing.assert_allclose(np.take(reaction, [0, 1, 2, 5, 6, 7]), np.r_[twd_force, twd_moment], rtol=1e-13,
                               atol=1e-9)
    # the torques at the gimbals: each engine's I δ̈
    np.testing.assert_allclose(reaction[3:5], 3 * moving[2] * np.array(dd), rtol=1e-15)
    # closed form: a canted engine's axial thrust is cos(cant) of its share
    axial = sum(s * thrust * np.cos(pitch + cp) * np.cos(yaw + cy) for st, s, *_, cp, cy in mounts if st == 1.0)
    assert loads[0] == pytest.approx(axial, rel=1e-14)


def test_a_symmetric_toed_in_pair_has_no_side_force_and_loses_cos_cant():
    cant = np.radians(3.0)
    mounts = np.array([[1.0, 0.5, 0.0, 1.5, 0.0, 0.0, cant], [1.0, 0.5, 0.0, -1.5, 0.0, 0.0, -cant]])
    thrust = 2.0e6
    p, x, xd = _plant_vectors(2)
    loads, _, couple = plant_loads(_packed(mounts), p, x, xd, layout.ENGINE_UPPER, thrust, (-20.0, 0.0, 0.0))
    assert loads[0] == pytest.approx(thrust * np.cos(cant), rel=1e-15)
    assert abs(loads[1]) < 1e-9 * thrust and abs(loads[2]) < 1e-9 * thrust
    assert np.all(np.abs(loads[3:]) < 1e-9 * thrust)  # the lines cross on the axis: no moment either
    assert np.all(np.abs(couple) < 1e-9 * thrust)  # nor about the gimbal point, on the axis


def _two_engine_vehicle():
    """The shipped ares_i with its J-2X split into two half engines side by side (the
    docs' example, from the vehicle file) and its motor into two half nozzles above and
    below the axis (each its stage's thrust share and half the moving mass)."""
    base = OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle
    node = OmegaConf.merge(base, OmegaConf.create(examples()["a-two-engine-cluster"]))
    vehicle = load_vehicle(OmegaConf.to_container(node, resolve=True), SHIPPED / "ares_i")
    fs = vehicle.first_stage
    half = MovingMass(fs.engine.mass_kg / 2, fs.engine.cg_from_gimbal_m, fs.engine.inertia_about_gimbal_kgm2 / 2)
    mounts = (Mount("upper", np.array([0.0, 0.0, 1.5]), np.zeros(2)),
              Mount("lower", np.array([0.0, 0.0, -1.5]), np.zeros(2)))
    return dataclasses.replace(vehicle, first_stage=dataclasses.replace(fs, engine=half, mounts=mounts))


def test_a_symmetric_split_of_each_engine_flies_the_same_ascent():
    cfg = validate(compose_config(["sim.progress=false", "twd=on"]))
    prep = prepare(cfg, hydra_search_dirs())
    guidance = read_guidance(prep.command_file)
    single = simulate(build_model(cfg, prep.vehicle, guidance), progress=False)
    pair = simulate(build_model(cfg, _two_engine_vehicle(), guidance), progress=False)
    assert single.stop_code == pair.stop_code == engine.STOP_GUIDANCE_CUTOFF
    for slot in (engine.EV_SEPARATION, engine.EV_IGNITION, engine.EV_LES):
        assert pair.events[slot] == pytest.approx(single.events[slot], abs=1e-9)
    n = min(len(single.log), len(pair.log))
    assert abs(len(single.log) - len(pair.log)) <= 1
    rs, rp = single.log[:n, 1 + layout.R:1 + layout.R + 3], pair.log[:n, 1 + layout.R:1 + layout.R + 3]
    vs, vp = single.log[:n, 1 + layout.V:1 + layout.V + 3], pair.log[:n, 1 + layout.V:1 + layout.V + 3]
    ws, wp = single.log[:n, 1 + layout.W:1 + layout.W + 3], pair.log[:n, 1 + layout.W:1 + layout.W + 3]
    # roundoff (measured 2e-9 m, 3e-10 m/s, 3e-12 rad/s); the motor's nozzles each at the
    # whole moving mass (twice the reaction) miss by 5 mm, 5e-4 m/s and 4e-5 rad/s
    assert np.max(np.linalg.norm(rp - rs, axis=1)) < 1e-6  # m, over a 580 km-long ascent
    assert np.max(np.linalg.norm(vp - vs, axis=1)) < 1e-7  # m/s
    assert np.max(np.abs(wp - ws)) < 1e-10  # rad/s


def _cluster_node(**j2x_b):
    base = OmegaConf.load(SHIPPED / "ares_i.yaml").vehicle
    node = OmegaConf.merge(base, OmegaConf.create(examples()["a-two-engine-cluster"]))
    for key, value in j2x_b.items():
        OmegaConf.update(node, key, value, merge=False)
    return OmegaConf.to_container(node, resolve=True)


def test_engines_of_one_stage_that_differ_are_refused_naming_the_engine():
    node = _cluster_node(**{"stages.upper_stage.engines.j2x_b.isp_vac_s": 450.0})
    with pytest.raises(ConfigError, match=r"vehicle\.stages\.upper_stage\.engines\.j2x_b\.thrust.*identical"):
        load_vehicle(node, SHIPPED / "ares_i")


def test_an_ignition_that_leaves_an_engine_of_the_cluster_dark_is_refused():
    node = _cluster_node(**{"events.upper_stage_ignition.ignite": ["j2x"]})
    with pytest.raises(ConfigError, match=r"vehicle\.events\.upper_stage_ignition.*ignite \['j2x', 'j2x_b'\]"):
        load_vehicle(node, SHIPPED / "ares_i")
