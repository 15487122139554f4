"""The control mixer in the plant (models/cluster.py) and roll by the engines' gimbals
(models/roll_gimbal.py).

References: a nine-engine octaweb (eight engines on a ring, one in the middle), whose
allocation is known in closed form by its symmetry: a pitch or yaw command moves every
nozzle together; a roll command turns the eight ring nozzles tangentially by the same
angle, the centre one not at all, so the roll moment per radian is ``8 ρ T/9`` and no
side force or pitch or yaw moment appears; the plant's loads of those deflections
against numpy's cross products and that closed form. In flight, ares_i's motor split
into such an octaweb with its ring nozzles canted tangentially (a swirl): the roll
integrator must settle where the gimbals cancel the swirl exactly, ``δr = −swirl``,
while the jets alone lose the vehicle.
"""

from __future__ import annotations

import dataclasses
import json

import h5py
import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.config.study.linear import LinearStudyConfig
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.linear.charts import point_charts
from savant_cli.linear.loops import assemble
from savant_cli.linear.modes import plant_group
from savant_cli.linear.plant import linearize_plant
from savant_cli.linear.point_analysis import analyse
from savant_cli.linear.requirements import checks_array
from savant_cli.linear.store import write_linear_group
from savant_cli.models import actuator, blocks, cluster, layout, mass as mass_model, propulsion, roll_gimbal
from savant_cli.paths import hydra_search_dirs, shipped_config_dir
from savant_cli.plots.linear import plot_linear_point
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.plant import PlantTables, derivative
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from savant_cli.sim.staging_state import read_staging_state
from savant_cli.vehicle import CONFIG_NAMES, load_vehicle
from savant_cli.vehicle.tree import MovingMass
from savant_cli.vehicle.two_stage import Mount
from test_cluster import plant_loads
from test_vehicle_examples import examples

RING_M = 1.5  # ring radius, m
LIMIT = np.radians(6.0)
GIMBAL = np.array([40.0, 0.0, 0.0])  # the stage's gimbal point, structure frame, m
CG = np.array([20.0, 0.0, 0.0])  # reference CG: 20 m above the gimbal plane


def _octaweb() -> tuple[np.ndarray, np.ndarray]:
    """Offsets (structure frame, m) and cants (rad) of eight ring engines and a centre one."""
    theta = np.arange(8) * np.pi / 4
    offsets = np.vstack([np.column_stack([np.zeros(8), RING_M * np.cos(theta), RING_M * np.sin(theta)]),
                         np.zeros((1, 3))])
    return offsets, np.zeros((9, 2))


def _loads(coefficients: np.ndarray, offsets: np.ndarray, command: tuple[float, float, float], thrust: float):
    """The plant's thrust loads of the stage's engines with each channel at the mixer's
    command (rad): ``(Fx, Fy, Fz, Mx, My, Mz)``, body axes."""
    n = offsets.shape[0]
    rows = np.zeros((n, cluster.MOUNT_SIZE))
    rows[:, cluster.M_SHARE] = 1.0 / n
    rows[:, cluster.M_DX:cluster.M_DZ + 1] = offsets
    rows[:, cluster.M_PAIR] = np.arange(n)
    rows[:, cluster.M_PITCH_ROLL:cluster.M_YAW_YAW + 1] = coefficients
    arrays = [np.zeros(1)] * len(PlantTables._fields)
    arrays[cluster.T_MOUNTS] = rows
    tb = blocks.pack(arrays)
    p = np.zeros(layout.N_PARAM)
    p[actuator.P_N_CHANNELS] = 2 * n
    p[cluster.P_UPPER_FIRST] = n  # all first-stage engines
    p[actuator.P_FS_GIMBAL + actuator.G_LIMIT] = LIMIT
    x = np.zeros(actuator.N_PER_CHANNEL * 2 * n)
    channels = coefficients.reshape(2 * n, 3) @ np.asarray(command)
    x[::actuator.N_PER_CHANNEL] = channels
    arm = -(GIMBAL[0] - CG[0]), 0.0, 0.0
    loads, _, _ = plant_loads(tb, p, x, np.zeros_like(x), layout.ENGINE_FIRST, thrust, arm)
    return np.array(loads), channels


def test_an_octaweb_pitch_or_yaw_command_moves_every_nozzle_together():
    offsets, cants = _octaweb()
    k = cluster.stage_mixer(GIMBAL, offsets, cants, CG, LIMIT).reshape(18, 3)
    pitch, yaw = k[0::2], k[1::2]
    np.testing.assert_allclose(pitch[:, 1], 1.0, atol=1e-12)  # δp: every pitch channel by δp
    np.testing.assert_allclose(yaw[:, 2], 1.0, atol=1e-12)
    np.testing.assert_allclose(pitch[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(yaw[:, 1], 0.0, atol=1e-12)


def test_an_octaweb_roll_command_turns_the_ring_tangentially_by_the_command():
    offsets, cants = _octaweb()
    k = cluster.stage_mixer(GIMBAL, offsets, cants, CG, LIMIT).reshape(9, 2, 3)
    roll = k[:, :, 0]  # each engine's (pitch, yaw) channel per rad of δr
    theta = np.arange(8) * np.pi / 4
    magnitude = np.linalg.norm(roll[:8], axis=1)
    # the same tangential angle on every ring engine, the largest channel at δr
    np.testing.assert_allclose(magnitude, magnitude[0], rtol=1e-12)
    assert np.max(np.abs(roll)) == pytest.approx(1.0, rel=1e-15)
    assert magnitude[0] == pytest.approx(1.0, rel=1e-12)  # the engines on the y and z axes: one channel
    np.testing.assert_allclose(roll[8], 0.0, atol=1e-12)  # the centre engine cannot roll
    # tangential: the nozzle's lateral thrust direction (sin δp along z, −sin δy along y)
    # is perpendicular to the engine's radius
    lateral = np.column_stack([-roll[:8, 1], roll[:8, 0]])  # body (y, z) per unit δr
    radial = np.column_stack([np.cos(theta), -np.sin(theta)])  # body z is structure −z
    np.testing.assert_allclose(np.sum(lateral * radial, axis=1), 0.0, atol=1e-12)


def test_the_plant_rolls_an_octaweb_by_the_closed_form_moment_and_nothing_else():
    offsets, cants = _octaweb()
    k = cluster.stage_mixer(GIMBAL, offsets, cants, CG, LIMIT)
    thrust = 7.6e6
    for dr in (1e-3, 0.02):
        loads, channels = _loads(k, offsets, (dr, 0.0, 0.0), thrust)
        assert np.max(np.abs(channels)) == pytest.approx(dr, rel=1e-12)
        # each engine's share along its own line, written out with numpy's cross products
        # (body axes: structure z is body −z; pitch turns the thrust toward +z, yaw toward −y)
        arms = np.column_stack([np.full(9, -(GIMBAL[0] - CG[0])), offsets[:, 1], -offsets[:, 2]])
        dp, dy = channels[0::2], channels[1::2]
        forces = thrust / 9 * np.column_stack([np.cos(dp) * np.cos(dy), -np.sin(dy), np.sin(dp) * np.cos(dy)])
        np.testing.assert_allclose(loads[3:], np.cross(arms, forces).sum(axis=0), rtol=1e-12, atol=1e-9 * thrust)
        # the ring turned tangentially by dr: the roll moment 8 ρ T sin(dr)/9, to second order
        # in dr (the diagonal engines' two channels each at dr/√2 tilt the line by dr only
        # to first order)
        assert loads[3] == pytest.approx(8 * RING_M * thrust / 9 * np.sin(dr), rel=dr * dr)
        assert np.all(np.abs(loads[[1, 2]]) < 1e-9 * thrust)  # no side force
        assert np.all(np.abs(loads[[4, 5]]) < 1e-9 * thrust)  # no pitch or yaw moment
    # the roll effectiveness the gains are designed on: the same closed form per newton
    b, _ = cluster._effectiveness(GIMBAL, offsets, cants, CG)
    assert b[0] @ k.reshape(18, 3)[:, 0] == pytest.approx(8 * RING_M / 9, rel=1e-12)


def test_a_pitch_command_on_the_octaweb_is_the_equivalent_engine():
    offsets, cants = _octaweb()
    k = cluster.stage_mixer(GIMBAL, offsets, cants, CG, LIMIT)
    thrust, dp = 7.6e6, 0.03
    loads, _ = _loads(k, offsets, (0.0, dp, 0.0), thrust)
    arm = GIMBAL[0] - CG[0]
    # every nozzle at dp: the thrust turned by dp at the gimbal plane, 20 m behind the CG
    assert loads[2] == pytest.approx(thrust * np.sin(dp), rel=1e-12)
    assert loads[4] == pytest.approx(arm * thrust * np.sin(dp), rel=1e-12)
    assert abs(loads[3]) < 1e-9 * thrust


def test_one_engine_is_the_equivalent_engine_and_a_pair_on_the_axis_cannot_roll():
    one = cluster.stage_mixer(GIMBAL, np.zeros((1, 3)), np.zeros((1, 2)), CG, LIMIT)
    assert one.tolist() == [[0.0, 1.0, 0.0, 0.0, 0.0, 1.0]]
    stacked = np.array([[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0]])  # one behind the other, on the roll axis
    k = cluster.stage_mixer(GIMBAL, stacked, np.zeros((2, 2)), CG, LIMIT).reshape(4, 3)
    assert np.all(k[:, 0] == 0.0)


def test_roll_gains_on_a_stage_that_cannot_roll_are_refused_naming_the_key():
    cfg = validate(compose_config(["sim.progress=false", "controller.roll.gimbal.stack.kp=0.2"]))
    with pytest.raises(ConfigError, match=r"controller\.roll\.gimbal\.stack.*first stage's engines cannot roll"):
        prepare(cfg, hydra_search_dirs())  # (its build of the plant checks the run's config)


SWIRL = np.radians(0.2)  # the ring nozzles' tangential cant, rad


def _octaweb_first_stage(vehicle):
    """ares_i with its motor split into an octaweb of nine engines sharing its thrust,
    each with a ninth of its moving mass, the ring's nozzles canted tangentially by
    :data:`SWIRL` (a constant roll torque)."""
    fs = vehicle.first_stage
    offsets, cants = _octaweb()
    pattern = cluster.stage_mixer(np.asarray(fs.gimbal_m), offsets, cants, _ignition_cg(vehicle),
                                  fs.gimbal_limit_rad)[:, [0, 3]]
    mounts = tuple(Mount(f"e{i}", offsets[i], SWIRL * pattern[i]) for i in range(9))
    nine = MovingMass(fs.engine.mass_kg / 9, fs.engine.cg_from_gimbal_m, fs.engine.inertia_about_gimbal_kgm2 / 9)
    return dataclasses.replace(vehicle, first_stage=dataclasses.replace(fs, engine=nine, mounts=mounts))


def _ignition_cg(vehicle) -> np.ndarray:
    mass = vehicle.configurations[CONFIG_NAMES[0]].mass
    return np.asarray(mass.cg_m)[int(np.argmax(mass.propellant_kg))]


@pytest.mark.slow
def test_an_octaweb_holds_roll_against_its_swirl_by_differential_gimbal():
    """The ring's swirl is exactly the mixer's roll pattern times SWIRL, so the roll
    integrator must settle where the gimbals cancel it: δr = −SWIRL."""
    base = validate(compose_config(["sim.progress=false"]))
    prep = prepare(base, hydra_search_dirs())
    vehicle = _octaweb_first_stage(prep.vehicle)
    mass = vehicle.configurations[CONFIG_NAMES[0]].mass
    ixx = float(np.asarray(mass.inertia_kgm2)[int(np.argmax(mass.propellant_kg)), 0])
    b_r = float(np.max(vehicle.first_stage.thrust_vac_N)) * cluster.roll_effectiveness(vehicle, 0)
    w, zeta = 2.0, 0.7  # rad/s, 1: the rigid roll loop's design
    kp, kd = ixx * w * w / b_r, 2 * zeta * w * ixx / b_r
    gains = [f"controller.roll.gimbal.stack.kp={kp}", f"controller.roll.gimbal.stack.kd={kd}",
             f"controller.roll.gimbal.stack.ki={0.3 * w * kp}"]
    cfg = validate(compose_config(["sim.progress=false", *gains]))
    guidance = read_guidance(prep.command_file)
    model = build_model(cfg, vehicle, guidance)
    result = simulate(model, progress=False)
    sig = signals(result, model)
    t = sig["time"].data
    t_sep = result.events[engine.EV_SEPARATION]
    assert np.isfinite(t_sep)
    assert sig["gimbal_angle"].data.shape[1] == 18
    settled = (t > 30.0) & (t < t_sep - 5.0)
    command = sig["roll_gimbal_command"].data[settled]
    # measured −1.007 SWIRL: the pitch and yaw trims and the jets' first pulses aside
    assert np.mean(command) == pytest.approx(-SWIRL, rel=0.03)
    deadband = np.radians(cfg.controller.roll.attitude_deadband_deg)
    assert np.max(np.abs(sig["attitude_error"].data[settled, 0])) < deadband  # measured 0.06°: the jets may rest
    # without the roll law the jets alone cannot hold the swirl (measured: the vehicle
    # spins up to 60 deg/s and the run diverges at 44 s)
    bare_model = build_model(base, vehicle, guidance)
    bare = simulate(bare_model, progress=False)
    assert bare.status != "complete" and not np.isfinite(bare.events[engine.EV_SEPARATION])
    bare_rate = signals(bare, bare_model)["body_rate"].data[:, 0]
    assert np.max(np.abs(bare_rate)) > np.radians(cfg.controller.roll.rate_deadband_deg_s) * 10


def test_a_staging_state_written_before_the_roll_command_reads_it_as_zero(tmp_path):
    shipped = shipped_config_dir() / "phase" / "ares_i_peg_staging_state.json"
    doc = json.loads(shipped.read_text())
    assert len(doc["inputs"]) == layout.U_ROLL  # written before the roll command was appended
    state = read_staging_state(shipped)
    assert state.u.size == layout.N_INPUT and state.u[layout.U_ROLL] == 0.0
    np.testing.assert_array_equal(state.u[:layout.U_ROLL], doc["inputs"])
    doc["inputs"] = doc["inputs"] + [0.0] * (layout.N_INPUT - layout.U_ROLL + 1)  # more inputs than the plant has
    path = tmp_path / "staging.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=f"at most {layout.N_DISC} discrete and {layout.N_INPUT} input values"):
        read_staging_state(path)


def test_every_engines_channels_group_as_actuator_states_in_the_linear_modes():
    lay = layout.StateLayout(tanks=("grain", "lox", "lh2"), channels=layout.channel_names(3), simplex=True)
    names = lay.names()
    actuator_states = [n for n in names if plant_group(n) == "actuator"]
    # three engines × two channels × three states, plus the simplex valves' two per channel
    assert len(actuator_states) == 3 * 2 * 3 + 3 * 2 * 2
    assert {"dp3", "dy2_dot", "dp_piston", "valve_y3_dot"} <= set(actuator_states)
    assert plant_group("rcs_pos") == plant_group("p") == "rigid"


def test_the_roll_law_against_its_closed_form():
    d = np.zeros(layout.N_DISC)
    d[layout.D_ERR] = 0.01  # rad
    kp, ki, kd, dt, rate = 0.5, 0.1, 0.3, 0.02, 0.002
    gains = np.array([kp, ki, kd])
    for _ in range(3):
        roll_gimbal.roll_gimbal_step(d, gains, 0.5, rate, dt)
    assert d[roll_gimbal.D_INT_ROLL] == pytest.approx(3 * 0.01 * dt, rel=1e-15)
    assert d[roll_gimbal.D_CMD_ROLL] == pytest.approx(-0.5 * (kp * 0.01 + ki * 3 * 0.01 * dt + kd * rate), rel=1e-15)
    held = d[roll_gimbal.D_INT_ROLL]
    roll_gimbal.roll_gimbal_step(d, gains, 0.0, rate, dt)  # the coast: no command, the integrator held
    assert d[roll_gimbal.D_CMD_ROLL] == 0.0 and d[roll_gimbal.D_INT_ROLL] == held
    roll_gimbal.reset(d)
    assert d[roll_gimbal.D_CMD_ROLL] == d[roll_gimbal.D_INT_ROLL] == 0.0


def _two_engine_upper_stage():
    """The docs' example: ares_i with the J-2X split into two engines at y = ±1.2 m."""
    base = OmegaConf.load(shipped_config_dir() / "vehicle" / "ares_i.yaml").vehicle
    node = OmegaConf.merge(base, OmegaConf.create(examples()["a-two-engine-cluster"]))
    return load_vehicle(OmegaConf.to_container(node, resolve=True), shipped_config_dir() / "vehicle" / "ares_i")


def test_two_engines_side_by_side_roll_by_their_arm():
    """Differential pitch by δr gives each half of the thrust a lever of 1.2 m, so
    1.2 m/rad per newton."""
    vehicle = _two_engine_upper_stage()
    assert cluster.roll_effectiveness(vehicle, 1) == pytest.approx(1.2, rel=1e-12)
    assert cluster.roll_effectiveness(vehicle, 0) == 0.0  # the motor: one engine


@pytest.mark.slow
def test_the_docs_two_engine_upper_stage_rolls_by_its_gimbals_and_rests_its_jets():
    """docs/vehicles.md's gains (the design rule at 1 rad/s, ζ = 0.7 on the full upper
    stage): after the upper stage's start the jets need not fire, where alone they do
    (measured: 114 logged steps; roll error 0.96° alone, 0.10° with the gimbals)."""
    vehicle = _two_engine_upper_stage()
    mass = vehicle.configurations[CONFIG_NAMES[-1]].mass
    b_r = vehicle.upper_stage.thrust_vac_N * cluster.roll_effectiveness(vehicle, 1)
    ixx = float(np.max(np.asarray(mass.inertia_kgm2)[:, 0]))
    assert ixx / b_r == pytest.approx(0.43, rel=0.01) and 1.4 * ixx / b_r == pytest.approx(0.6, rel=0.01)
    base = validate(compose_config(["sim.progress=false"]))
    guidance = read_guidance(prepare(base, hydra_search_dirs()).command_file)
    fired = []
    for overrides in ([], ["controller.roll.gimbal.upper.kp=0.43", "controller.roll.gimbal.upper.kd=0.6"]):
        model = build_model(validate(compose_config(["sim.progress=false", *overrides])), vehicle, guidance)
        result = simulate(model, progress=False)
        assert result.status == "complete"
        sig = signals(result, model)
        upper = sig["time"].data > result.events[engine.EV_IGNITION] + 5.0
        fired.append(np.count_nonzero(sig["rcs_command"].data[upper]))
    assert fired[0] > 0 and fired[1] == 0


def _axis_roll_allocation(k: np.ndarray, scale: float) -> np.ndarray:
    """The octaweb's mixer with roll given to the four engines on the y and z axes only,
    each turned ``scale`` times δr (the ring's eight at δr give 8 ρ T/9 per rad; four at
    2 δr give the same)."""
    given = k.reshape(18, 3).copy()
    given[:, 0] = 0.0
    for i in (0, 2, 4, 6):  # θ = 0, 90, 180, 270°: one channel each
        given[2 * i:2 * i + 2, 0] = scale * k.reshape(18, 3)[2 * i:2 * i + 2, 0]
    return given


def test_a_given_mixer_with_the_allocations_moments_is_accepted_and_another_is_refused():
    offsets, cants = _octaweb()
    k = cluster.stage_mixer(GIMBAL, offsets, cants, CG, LIMIT)
    assert cluster.check_given_mixer(k.reshape(18, 3), GIMBAL, offsets, cants, CG, LIMIT) == []
    assert cluster.check_given_mixer(_axis_roll_allocation(k, 2.0), GIMBAL, offsets, cants, CG, LIMIT) == []
    # the same roll moment from four engines: the plant's loads agree to first order
    thrust, dr = 7.6e6, 1e-4
    by_four, _ = _loads(_axis_roll_allocation(k, 2.0).reshape(9, 6), offsets, (dr, 0.0, 0.0), thrust)
    assert by_four[3] == pytest.approx(8 * RING_M * thrust / 9 * dr, rel=1e-6)
    short = cluster.check_given_mixer(_axis_roll_allocation(k, 1.9), GIMBAL, offsets, cants, CG, LIMIT)
    assert len(short) == 1 and short[0].startswith("the roll command gives the moment")
    swapped = k.reshape(18, 3)[:, [0, 2, 1]]  # pitch and yaw commands exchanged
    assert [f.split(" gives")[0] for f in
            cluster.check_given_mixer(swapped, GIMBAL, offsets, cants, CG, LIMIT)] == ["the pitch command",
                                                                                    "the yaw command"]
    one = np.array([[0.1, 1.0, 0.0], [0.0, 0.0, 1.0]])  # roll asked of one engine on the axis
    assert cluster.check_given_mixer(one, GIMBAL, np.zeros((1, 3)), np.zeros((1, 2)), CG, LIMIT) == [
        "its roll column must be 0: the stage's engines cannot roll the vehicle"]


def _two_engine_node(**changes):
    base = OmegaConf.load(shipped_config_dir() / "vehicle" / "ares_i.yaml").vehicle
    node = OmegaConf.merge(base, OmegaConf.create(examples()["a-two-engine-cluster"]))
    for key, value in changes.items():
        OmegaConf.update(node, key, value, merge=False)
    return OmegaConf.to_container(node, resolve=True)


def test_a_stages_own_mixing_matrix_reaches_the_plant_and_a_wrong_one_is_refused_naming_it():
    own = cluster.mount_table(_two_engine_upper_stage())[-2:, cluster.M_PITCH_ROLL:cluster.M_YAW_YAW + 1]
    rows = own.reshape(4, 3).copy()
    rows[:, 0] *= -1.0  # roll the other way: refused, the roll moment has the wrong sign
    vehicle = load_vehicle(_two_engine_node(**{"stages.upper_stage.mixing_matrix": rows.tolist()}),
                           shipped_config_dir() / "vehicle" / "ares_i")
    with pytest.raises(ConfigError, match=r"vehicle\.stages\.upper_stage\.mixing_matrix.*the roll command gives"):
        cluster.mount_table(vehicle)
    rows[:, 0] *= -1.0
    rows[:, 2] += np.array([0.0, 1e-3, 0.0, -1e-3])  # yaw the pair apart (both at z = 0: no roll), same moments
    vehicle = load_vehicle(_two_engine_node(**{"stages.upper_stage.mixing_matrix": rows.tolist()}),
                           shipped_config_dir() / "vehicle" / "ares_i")
    np.testing.assert_array_equal(cluster.mount_table(vehicle)[-2:, cluster.M_PITCH_ROLL:cluster.M_YAW_YAW + 1],
                                  rows.reshape(2, 6))
    with pytest.raises(ConfigError, match=r"vehicle\.stages\.upper_stage\.mixing_matrix.*one row per gimbal "
                                          r"channel, 4"):
        load_vehicle(_two_engine_node(**{"stages.upper_stage.mixing_matrix": rows[:3].tolist()}),
                     shipped_config_dir() / "vehicle" / "ares_i")
    with pytest.raises(ConfigError, match=r"upper_stage\.mixing_matrix = \[\[1\.0, 2\.0\]\]: must be a list of rows of 3"):
        load_vehicle(_two_engine_node(**{"stages.upper_stage.mixing_matrix": [[1.0, 2.0]]}),
                     shipped_config_dir() / "vehicle" / "ares_i")


@pytest.mark.slow
def test_the_linear_roll_loop_is_the_rigid_roll_axis_at_low_frequency(tmp_path):
    """The octaweb at 60 s with stack roll gains: the loop broken at the roll command is,
    well below its crossover, the rigid roll axis under the PD law,
    ``L(jω) → −b_r (Kp + jω Kd) / (I_xx ω²)`` (b_r the delivered thrust times the roll
    effectiveness), so ``|L| ω² I_xx / (b_r Kp) → 1``, at −180°. The shipped vehicle
    keeps two loops and four plant inputs."""
    base = validate(compose_config(["sim.progress=false"]))
    prep = prepare(base, hydra_search_dirs())
    vehicle = _octaweb_first_stage(prep.vehicle)
    kp, kd = 0.4, 0.3
    cfg = validate(compose_config(["sim.progress=false", f"controller.roll.gimbal.stack.kp={kp}",
                                   f"controller.roll.gimbal.stack.kd={kd}"]))
    guidance = read_guidance(prep.command_file)
    rolling = build_model(cfg, vehicle, guidance)
    dt = rolling.rates.dt * rolling.rates.n_fcs
    step = int(round(60.0 / rolling.rates.dt))
    snap = simulate(rolling, progress=False, snapshot_steps=(step,), t_stop=61.0).snapshots[step]
    point = assemble(rolling, snap, linearize_plant(rolling, snap), dt)
    assert tuple(point.loops) == ("pitch", "yaw", "roll")
    assert point.closed.input_labels[:3] == ["pitch_command", "yaw_command", "roll_command"]
    aux, xd = np.zeros(layout.N_AUX), np.zeros(snap.x.size)
    tb = rolling.packed_tables
    derivative(snap.t, snap.x, snap.u, rolling.p, tb, aux, xd)
    config = int(snap.u[layout.U_CONFIG])
    ixx = mass_model.mass_properties(tb, config, aux[mass_model.A_PROP])[4]
    b_r = aux[propulsion.A_THRUST] * cluster.roll_effectiveness(vehicle, 0)
    for w in (0.01, 0.03):
        response = complex(np.squeeze(point.loops["roll"](np.exp(1j * w * dt))))
        assert abs(response) * w * w * ixx / (b_r * kp) == pytest.approx(1.0, rel=0.02)
        assert np.degrees(np.angle(-response)) == pytest.approx(0.0, abs=3.0)  # −180°, a little lead
    # the whole point analysis, its charts and its record carry the roll loop
    analysis = analyse(rolling, snap, LinearStudyConfig(), dt, cfg.requirements)
    roll_rows = [r for r in analysis.rows if r.axis == "roll"]
    assert {r.kind for r in roll_rows} >= {"gain", "phase"}
    assert analysis.scalars["roll_bandwidth_hz"] > 0.0 and "roll_disk_gain_margin_dB" in analysis.scalars
    assert analysis.verdict is not None and checks_array([analysis.verdict]).shape[0] > 0
    charts = point_charts(snap.t, analysis.point.loops, analysis.point.closed, analysis.rows)
    assert "roll" in [lp.label for lp in charts.loops]
    with h5py.File(tmp_path / "linear.h5", "w") as f:
        write_linear_group(f, [analysis.point], analysis.rows, {snap.t: charts}, cfg.requirements)
    assert len(plot_linear_point(charts, analysis.rows, tmp_path)) == 6
    shipped = build_model(base, prep.vehicle, guidance)
    snap = simulate(shipped, progress=False, snapshot_steps=(step,), t_stop=61.0).snapshots[step]
    plain = assemble(shipped, snap, linearize_plant(shipped, snap), dt)
    assert tuple(plain.loops) == ("pitch", "yaw") and plain.plant.ninputs == 4
