"""Strap-on boosters with TVC (``models/boosters.py``, ``models/cluster.py``,
``models/actuator.py``): the worked example of docs/vehicles.md, the two boosters of the
strap-on example with their nozzles gimbaled in pitch and yaw.

References: numpy's cross products of each engine's thrust direction derivative and arm
for the moment effectiveness the mixer allocates over (written out here, not the
mixer's kernel); the weighted minimum-norm condition ``δ = W⁻¹ Bᵀ λ``; the closed forms of
a deflected nozzle's thrust moment, of differential pitch's roll moment
``Σ y_i f sin δ_i`` and of a moving nozzle's reaction ``(J − m l x) δ̈``; the third-order
actuator's equation; the linear plant's columns against ``f (x_nozzle − x_cg) / I_yy``
with the plant's own CG and inertia (the composition is ``tests/test_boosters.py``'s).
"""

from __future__ import annotations

import numpy as np
import pytest

from savant_cli.config.actuator import STAGES
from savant_cli.errors import ConfigError
from savant_cli.io.guidance_file import read_guidance
from savant_cli.io.record import Signal
from savant_cli.linear.plant import linearize_plant
from savant_cli.models import actuator, aero, boosters, cluster, layout, propulsion, quaternion as qt, twd
from savant_cli.models.interp import tab
from savant_cli.paths import hydra_search_dirs
from savant_cli.sim import engine
from savant_cli.sim.build import build_model
from savant_cli.sim.health import assess
from savant_cli.sim.plant import derivative, mass_state
from savant_cli.sim.run import signals, simulate
from savant_cli.sim.setup import prepare
from test_boosters import _cfg, _vehicle
from test_health import CFG as HEALTH, FS, _history
from test_vehicle_examples import example_node

EXAMPLE = "booster-tvc"
LIMIT = np.radians(6.0)  # the page's gimbal limit
MOVING = (900.0, 0.9, 1500.0)  # the page's moving nozzle: kg, m, kg m²
Y_NOZZLE = 2.755  # each booster's nozzle off the axis, m
S = np.array([-1.0, 1.0, -1.0])  # structure → body axes


def _model(*overrides: str, node: dict | None = None):
    """The example (or ``node``) with ``overrides``, flying the shipped command file."""
    guidance = read_guidance(prepare(_cfg(), hydra_search_dirs()).command_file)
    return build_model(_cfg(*overrides), _vehicle(node or example_node(EXAMPLE)), guidance)


def _direction_derivative(cant_pitch: float, cant_yaw: float, axis: int) -> np.ndarray:
    """∂n/∂δ of the unit thrust n = (cos p cos y, −sin y, sin p cos y), by hand."""
    p, y = cant_pitch, cant_yaw
    if axis == 0:
        return np.array([-np.sin(p) * np.cos(y), 0.0, np.cos(p) * np.cos(y)])
    return np.array([-np.cos(p) * np.sin(y), -np.cos(y), -np.sin(p) * np.sin(y)])


def _effectiveness(points, cants, thrust, cg) -> np.ndarray:
    """B (3 × 2n), each engine's pitch then yaw channel, written out with numpy."""
    columns = []
    for point, cant, f in zip(points, cants, thrust):
        arm = S * (np.asarray(point) - cg)
        columns += [np.cross(arm, f * _direction_derivative(*cant, axis)) for axis in (0, 1)]
    return np.array(columns).T


def _thrust(f, pitch, yaw):
    return f * np.array([np.cos(pitch) * np.cos(yaw), -np.sin(yaw), np.sin(pitch) * np.cos(yaw)])


# ------------------------------------------------------------------ the mixer


def test_the_boosted_mixer_gives_the_commanded_moments_with_the_least_weighted_deflection():
    """Over the motor's nozzle and both boosters' at their rated thrusts and the liftoff
    CG: ``B K = diag(1, d_p, d_y)`` up to the roll column's scale (1e-9 of the largest
    moment), each column of ``K`` of the form ``W⁻¹ Bᵀ λ`` (the weighted minimum norm),
    the largest roll deflection 1 rad, and the page's 1.18 and 0.064 rad per rad of δp."""
    vehicle = _vehicle(example_node(EXAMPLE))
    rows = cluster.boosted_mounts(vehicle)
    assert rows.shape == (3, cluster.MOUNT_SIZE)
    assert rows[:, cluster.M_BOOSTER].tolist() == [0.0, 1.0, 2.0] and rows[:, cluster.M_PAIR].tolist() == [0, 1, 2]
    fs, b = vehicle.first_stage, vehicle.boosters
    mass = vehicle.configurations["boosted"].mass
    cg = mass.cg_m[np.argmax(mass.propellant_kg)]
    points = [fs.gimbal_m, *b.nozzle_m]
    thrust = [np.max(fs.thrust_vac_N), np.max(b.thrust_vac_N), np.max(b.thrust_vac_N)]
    big = _effectiveness(points, [(0.0, 0.0), *b.cant_rad], thrust, cg)
    k = rows[:, cluster.M_PITCH_ROLL:cluster.M_YAW_YAW + 1].reshape(6, 3)  # channels × (roll, pitch, yaw)
    d_p, d_y = big[1, 0::2].sum(), big[2, 1::2].sum()
    scale = np.max(np.abs(big))
    np.testing.assert_allclose(big @ k[:, 1], [0.0, d_p, 0.0], atol=1e-9 * scale)
    np.testing.assert_allclose(big @ k[:, 2], [0.0, 0.0, d_y], atol=1e-9 * scale)
    roll = big @ k[:, 0]
    assert abs(roll[0]) > 0.0 and np.max(np.abs(roll[1:])) < 1e-9 * abs(roll[0])
    assert np.max(np.abs(k[:, 0])) == pytest.approx(1.0, rel=1e-15)
    weights = np.repeat([fs.gimbal_limit_rad, LIMIT, LIMIT], 2) ** 2  # W⁻¹
    for c in range(3):
        lam, *_ = np.linalg.lstsq(weights[:, None] * big.T, k[:, c], rcond=None)
        np.testing.assert_allclose(weights * (big.T @ lam), k[:, c], atol=1e-9 * np.max(np.abs(k[:, c])))
    assert k[0, 1] == pytest.approx(1.18, abs=0.005) and k[2, 1] == pytest.approx(0.064, abs=0.0005)


def test_the_core_is_mixed_alone_once_the_boosters_leave():
    """The active records: the boosted ones in the liftoff configuration, the stage's own
    (one engine: the identity) after the jettison, the upper stage's after separation."""
    model = _model()
    p, tb = model.p, model.packed_tables
    o, n = tab(tb, cluster.T_MOUNTS)
    size = cluster.MOUNT_SIZE
    assert n == 5 * size
    assert cluster.stage_mounts(tb, p, layout.ENGINE_FIRST, 0) == (o, o + 3 * size)
    assert cluster.stage_mounts(tb, p, layout.ENGINE_FIRST, 1) == (o + 3 * size, o + 4 * size)
    assert cluster.stage_mounts(tb, p, layout.ENGINE_UPPER, 2) == (o + 4 * size, o + 5 * size)
    alone = tb[o + 3 * size:o + 4 * size]
    assert alone[cluster.M_PITCH_ROLL:cluster.M_YAW_YAW + 1].tolist() == [0.0, 1.0, 0.0, 0.0, 0.0, 1.0]


@pytest.mark.parametrize("config", [0, 1])
def test_a_pitch_command_drives_the_booster_channels_only_while_attached(config):
    """A pitch command at rest: each booster channel's δ⃛ is the third-order law
    ``ω_n² sat(ω_a K δp, ±R)`` of the boosters' actuator with its mixer coefficient K
    while attached; after the jettison it is exactly 0 and the core takes the command."""
    cfg = _cfg()
    model = _model()
    p, tb = model.p, model.packed_tables
    x, u = model.x0.copy(), model.u0.copy()
    u[layout.U_CONFIG], u[layout.U_DPC] = config, 0.002
    xd, aux = np.zeros_like(x), np.zeros(layout.N_AUX)
    derivative(1.0, x, u, p, tb, aux, xd)
    a = cfg.actuator.boosters
    wn, rate = 2.0 * np.pi * a.natural_frequency_hz, np.radians(a.rate_limit_deg_s)
    rows = cluster.boosted_mounts(_vehicle(example_node(EXAMPLE)))
    for i in range(2):
        kp = boosters.booster_channel(p, i)
        expected = wn * wn * np.clip(a.loop_gain_rad_s * rows[1 + i, cluster.M_PITCH_PITCH] * 0.002, -rate, rate)
        assert xd[kp + 2] == (pytest.approx(expected, rel=1e-12) if config == 0 else 0.0)
        assert xd[kp + actuator.N_PER_CHANNEL + 2] == 0.0  # its yaw channel: no yaw command
    core = model.layout.channel(0)
    gain = rows[0, cluster.M_PITCH_PITCH] if config == 0 else 1.0
    f = cfg.actuator.first_stage
    assert xd[core + 2] == pytest.approx((2.0 * np.pi * f.natural_frequency_hz) ** 2 * f.loop_gain_rad_s * gain * 0.002,
                                         rel=1e-12)


# ------------------------------------------------------------------ the loads


def _moments(model, x, t=30.0):
    """The plant's thrust moment and tail-wags-dog moment (N·m, body axes), the boosters'
    delivered thrust (N, summed) and the rigid CG (structure, m) in the liftoff
    configuration at ``x``."""
    aux, xd = np.zeros(layout.N_AUX), np.zeros_like(x)
    derivative(t, x, model.u0, model.p, model.packed_tables, aux, xd)
    cg = np.array(mass_state(x, model.p, model.packed_tables, 0, np.zeros(layout.N_AUX))[2][1:4])
    return (aux[propulsion.A_MOMENT:propulsion.A_MOMENT + 3].copy(), aux[twd.A_MOMENT:twd.A_MOMENT + 3].copy(),
            aux[boosters.A_THRUST], cg)


def test_a_deflected_booster_turns_its_thrust_at_its_nozzle():
    """The left booster's nozzle at +0.03 rad pitch, the right's at −0.02 rad yaw (one of
    them canted): the change of the thrust moment equals the boosters' ``r × F`` at the
    deflected minus the null directions, numpy's cross products (1e-9)."""
    node = example_node(EXAMPLE)
    node["boosters"]["booster_right"]["engines"]["booster_right_motor"]["cant_deg"] = [1.0, -2.0]
    model = _model(node=node)
    x0 = model.x0.copy()
    x = x0.copy()
    left, right = boosters.booster_channel(model.p, 0), boosters.booster_channel(model.p, 1)
    x[left] = 0.03
    x[right + actuator.N_PER_CHANNEL] = -0.02
    m0, _, thrust, cg = _moments(model, x0)
    m1, _, _, _ = _moments(model, x)
    f = thrust / 2.0  # identical boosters at the same load
    cant = np.radians([1.0, -2.0])
    expected = np.zeros(3)
    for nozzle, (p0, y0), (p1, y1) in ((np.array([91.5, -Y_NOZZLE, 0.0]), (0.0, 0.0), (0.03, 0.0)),
                                       (np.array([91.5, Y_NOZZLE, 0.0]), cant, cant + [0.0, -0.02])):
        arm = S * (nozzle - cg)
        expected += np.cross(arm, _thrust(f, p1, y1)) - np.cross(arm, _thrust(f, p0, y0))
    np.testing.assert_allclose(m1 - m0, expected, atol=1e-9 * f * 50.0)
    assert np.linalg.norm(expected) > 1e5  # a real moment


def test_differential_booster_pitch_rolls_the_vehicle_by_the_hand_computed_moment():
    """The mixer's roll pattern, the boosters' pitch channels at ∓a: the roll moment is
    ``Σ (y_i − y_cg) f sin δ_i`` = ``2 · 2.755 · f sin a`` (1e-9), and the pair's pitch
    moments cancel."""
    model = _model()
    rows = cluster.boosted_mounts(_vehicle(example_node(EXAMPLE)))
    a = 0.04
    x0 = model.x0.copy()
    x = x0.copy()
    deflections = [rows[1 + i, cluster.M_PITCH_ROLL] * a for i in range(2)]
    assert deflections == [-a, a]
    for i in range(2):
        x[boosters.booster_channel(model.p, i)] = deflections[i]
    m0, _, thrust, cg = _moments(model, x0)
    m1, *_ = _moments(model, x)
    f = thrust / 2.0
    roll = sum((y - cg[1]) * f * np.sin(d) for y, d in zip((-Y_NOZZLE, Y_NOZZLE), deflections))
    assert roll == pytest.approx(2.0 * Y_NOZZLE * f * np.sin(a), rel=1e-3)  # the CG is near the axis
    assert (m1 - m0)[0] == pytest.approx(roll, rel=1e-9)
    assert abs((m1 - m0)[1]) < 1e-9 * abs(roll)


def test_a_booster_nozzles_acceleration_reacts_by_its_moving_mass():
    """``twd=on``: the left booster's nozzle accelerating at δ̈ = 2 rad/s² in pitch (its
    δ̈ state) pushes on the vehicle at its nozzle with ``m l δ̈`` along body z and turns it
    with ``J δ̈`` about body y: the moment ``r × (0, 0, m l δ̈) + (0, J δ̈, 0)`` with r the
    nozzle's body arm (1e-9: a roll part too, the nozzle being off the axis), and nothing
    with ``twd=off``."""
    for on in (True, False):
        model = _model(f"twd={'on' if on else 'off'}")
        x0 = model.x0.copy()
        x = x0.copy()
        x[boosters.booster_channel(model.p, 0) + 2] = 2.0
        _, w0, _, cg = _moments(model, x0)
        _, w1, _, _ = _moments(model, x)
        mass, arm, inertia = MOVING
        r = S * (np.array([91.5, -Y_NOZZLE, 0.0]) - cg)
        expected = np.cross(r, [0.0, 0.0, mass * arm * 2.0]) + [0.0, inertia * 2.0, 0.0] if on else np.zeros(3)
        np.testing.assert_allclose(w1 - w0, expected, rtol=1e-9, atol=1e-9)
        if on:
            assert abs(expected[0]) > 4000.0 and abs(expected[1]) > 1e4


def test_a_booster_channel_is_judged_at_its_own_gimbal_stop():
    """The health check of the first stage reads each channel at its own stop: a booster
    nozzle 2 s at its 6° stop is 2 s at the gimbal stop (the run "saturated"), and the
    motor's nozzle at the same 6°, inside its 8°, is not."""
    model = _model()
    for channel, held in ((boosters.booster_channel(model.p, 0) - model.layout.channel(0), 2.0), (0, 0.0)):
        result, sig = _history(int(300 * FS), 130.0)
        n = sig["time"].data.size
        for name in ("gimbal_angle", "gimbal_rate"):
            sig[name] = Signal(np.zeros((n, len(model.layout.channels))), "rad", "")
        t = sig["time"].data
        sig["gimbal_angle"].data[(t >= 50.0) & (t < 52.0), channel // actuator.N_PER_CHANNEL] = LIMIT
        h = assess(result, sig, model, HEALTH)
        assert h["time_at_gimbal_stop_first_stage_s"] == pytest.approx(held, abs=1e-9)
        assert (result.status == "saturated") == (held > 0.0)


# ------------------------------------------------------------------ refusals


@pytest.mark.parametrize("change, key", [
    ({"gimbal_axes": ["pitch"]}, "booster_left_motor.gimbal_axes"),
    ({"gimbal_limit_deg": 5.0}, "booster_right_motor.gimbal_limit_deg"),
])
def test_a_booster_gimbal_outside_what_the_plant_flies_is_refused_naming_the_key(change, key):
    node = example_node(EXAMPLE)
    side = "left" if "left" in key else "right"
    node["boosters"][f"booster_{side}"]["engines"][f"booster_{side}_motor"].update(change)
    with pytest.raises(ConfigError) as exc:
        _vehicle(node)
    assert exc.value.key.endswith(key)


def test_the_boosters_actuator_keys_are_checked_naming_them():
    assert "boosters" in STAGES
    with pytest.raises(ConfigError) as exc:
        _cfg("actuator.boosters.rate_limit_deg_s=-1")
    assert exc.value.key == "actuator.boosters.rate_limit_deg_s"


# ------------------------------------------------------------------ flight


@pytest.mark.slow
def test_the_linear_plant_turns_on_each_booster_nozzle_by_its_thrust_and_arm():
    """At 40 s: each booster pitch channel's column in the pitch-rate row is
    ``f (x_nozzle − x_cg) / I_yy`` with the booster's delivered thrust f, the plant's CG
    and pitch inertia (2e-3: the finite differences), and the core's is the stage's
    thrust at its gimbal's arm likewise."""
    model = _model()
    step = int(round(40.0 / model.rates.dt))
    snap = simulate(model, progress=False, snapshot_steps=(step,), t_stop=41.0).snapshots[step]
    lin = linearize_plant(model, snap)
    aux, xd = np.zeros(layout.N_AUX), np.zeros(snap.x.size)
    derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, xd)
    rigid = mass_state(snap.x, model.p, model.packed_tables, 0, np.zeros(layout.N_AUX))[2]
    cg_x, i_yy = rigid[1], rigid[5]
    row = list(lin.z_index).index(layout.W + 1)
    f = aux[boosters.A_THRUST] / 2.0
    for i in range(2):
        col = list(lin.z_index).index(boosters.booster_channel(model.p, i))
        assert lin.sys.A[row, col] == pytest.approx(f * (91.5 - cg_x) / i_yy, rel=2e-3)
    col = list(lin.z_index).index(model.layout.channel(0))
    v = _vehicle(example_node(EXAMPLE))
    assert lin.sys.A[row, col] == pytest.approx(aux[propulsion.A_THRUST] * (v.first_stage.gimbal_m[0] - cg_x) / i_yy,
                                                rel=2e-3)


def _plant_pitch_coefficients(model, snap, k_pitch: np.ndarray) -> tuple[float, float]:
    """μα and μc (1/s²) of the plant itself at a snapshot, by central differences of its
    derivative's pitch acceleration ω̇_y: the air-relative velocity turned by ±1° in the
    body x-z plane (speed, Mach, dynamic pressure and sideslip unchanged), and every gimbal
    channel's angle moved by ±1e-4 rad times its coefficient of the pitch command
    (``k_pitch``, the channels in the plant's order)."""
    def pitch_acceleration(x: np.ndarray) -> tuple[float, np.ndarray]:
        aux, xd = np.zeros(layout.N_AUX), np.zeros(x.size)
        derivative(snap.t, x, snap.u, model.p, model.packed_tables, aux, xd)
        return xd[layout.W + 1], aux

    _, aux = pitch_acceleration(snap.x)
    alpha, beta, speed = aux[aero.A_ALPHA], aux[aero.A_BETA], aux[aero.A_VREL]
    to_eci = np.array(qt.dcm_xyz(*snap.x[layout.Q:layout.Q + 4])).reshape(3, 3)
    body = speed * np.array([np.cos(alpha) * np.cos(beta), np.sin(beta), np.sin(alpha) * np.cos(beta)])
    turned = []
    for d_alpha in (np.radians(1.0), -np.radians(1.0)):
        a = alpha + d_alpha
        x = snap.x.copy()
        x[layout.V:layout.V + 3] += to_eci @ (speed * np.array([np.cos(a) * np.cos(beta), np.sin(beta),
                                                                 np.sin(a) * np.cos(beta)]) - body)
        turned.append(pitch_acceleration(x)[0])
    moved = []
    for eps in (1e-4, -1e-4):
        x = snap.x.copy()
        for k, coefficient in enumerate(k_pitch):
            x[model.layout.channel(k)] += eps * coefficient
        moved.append(pitch_acceleration(x)[0])
    return (turned[0] - turned[1]) / np.radians(2.0), (moved[0] - moved[1]) / 2e-4


@pytest.mark.slow
@pytest.mark.parametrize("example", ["booster-tvc", "strap-on-boosters"])
def test_the_gain_generators_boosted_design_point_is_the_plants_own_pitch_plane(example):
    """At 40 s, boosters burning, calm air: the gain generator's μα and μc
    (``fcs_gains.pitch_coefficients`` on the flown state, its mass properties from the
    reference's booster trace) are the plant's own, by central differences of its
    derivative (:func:`_plant_pitch_coefficients`): μα to 2e-3 (the generator's ±1° about
    zero against the plant's about the flown α: the tables' curvature, 3e-4 here), μc to
    2e-4 (the boosters' propellant and thrust on the trace's 20,001 samples against the
    flight's integration, 3e-5 here; the core's moment alone would be 16 % low with TVC).
    With TVC on the boosters μc is the mixer's pitch column over every
    nozzle; the fixed nozzles of the other example add none, and their μc is the core's
    own thrust at its arm over the exchanged pitch inertia."""
    from savant_cli.datagen import fcs_gains
    from savant_cli.datagen.guidance_commands import Program, Reference

    vehicle = _vehicle(example_node(example))
    cfg = _cfg("winds=none")
    model = _model("winds=none", node=example_node(example))
    step = int(round(40.0 / model.rates.dt))
    snap = simulate(model, progress=False, snapshot_steps=(step,), t_stop=40.5).snapshots[step]
    assert vehicle.first_stage_engine_count == 1  # without TVC the pitch command is the one engine's pitch angle
    k_pitch = cluster.boosted_mixer(vehicle).reshape(-1, 3)[:, 1] if vehicle.boosters.tvc else np.array([1.0, 0.0])
    mu_alpha, mu_c = _plant_pitch_coefficients(model, snap, k_pitch)
    ref = Reference(cfg, vehicle, Program.from_config(dict(cfg.guidance.generator)))
    y = np.concatenate([snap.x[layout.R:layout.R + 3], snap.x[layout.V:layout.V + 3],
                        [propulsion.first_stage_propellant(snap.x, model.p), 0.0, 0.0]])
    generated = fcs_gains.pitch_coefficients(ref, snap.t, y, 0)
    assert generated[0] == pytest.approx(mu_alpha, rel=2e-3)
    assert generated[1] == pytest.approx(mu_c, rel=2e-4)


@pytest.mark.slow
def test_the_boosters_differential_gimbal_holds_the_roll_inside_the_jets_deadband():
    """Roll by the boosters (docs/vehicles.md): gains from the roll law's design rule
    (``models/roll_gimbal.py``: ω = 2 rad/s, ζ = 0.7, with ``b_r`` the roll moment of
    one radian of δr from numpy's effectiveness at the rated thrusts and I_xx the liftoff
    configuration's at full load) hold the roll attitude inside the roll jets' 1°
    deadband while the boosters are attached; without them the jets alone let it reach
    several degrees. The logged booster angles show how: without the gains the two
    nozzles move as one, with them they differ in pitch."""
    vehicle = _vehicle(example_node(EXAMPLE))
    fs, b = vehicle.first_stage, vehicle.boosters
    mass = vehicle.configurations["boosted"].mass
    full = int(np.argmax(mass.propellant_kg))
    big = _effectiveness([fs.gimbal_m, *b.nozzle_m], [(0.0, 0.0), *b.cant_rad],
                         [np.max(fs.thrust_vac_N), np.max(b.thrust_vac_N), np.max(b.thrust_vac_N)], mass.cg_m[full])
    k_roll = cluster.boosted_mounts(vehicle)[:, [cluster.M_PITCH_ROLL, cluster.M_YAW_ROLL]].ravel()
    b_r = float((big @ k_roll)[0])
    omega, zeta, i_xx = 2.0, 0.7, mass.inertia_kgm2[full, 0]
    errors, differential = [], []
    for kp, kd in ((0.0, 0.0), (i_xx * omega ** 2 / b_r, 2.0 * zeta * omega * i_xx / b_r)):
        model = _model(f"controller.roll.gimbal.stack.kp={kp}", f"controller.roll.gimbal.stack.kd={kd}")
        result = simulate(model, progress=False, t_stop=96.0)
        sig = signals(result, model)
        t = sig["time"].data
        attached = (t > 5.0) & (t < result.events[engine.EV_BOOSTER_JETTISON])
        errors.append(np.degrees(np.max(np.abs(sig["attitude_error"].data[attached, 0]))))
        angles = sig["booster_gimbal_angle"]
        assert angles.columns == ("booster_1_pitch", "booster_1_yaw", "booster_2_pitch", "booster_2_yaw")
        differential.append(np.max(np.abs(angles.data[attached, 0] - angles.data[attached, 2])))
    assert errors[1] < 1.0 < 3.0 < errors[0]
    assert differential[0] < 1e-12 and differential[1] > np.radians(0.01)


@pytest.fixture(scope="module")
def flight():
    model = _model()
    return model, simulate(model, progress=False)


@pytest.mark.slow
def test_the_example_flies_to_orbit_with_the_booster_nozzles_steering_until_their_jettison(flight):
    """The run completes at PEG's cutoff; both boosters' logged gimbal angles move within
    ±6° while they are attached and are exactly 0 after the jettison; the first one's
    channel is held to the bit until separation, when every channel comes to rest at
    null."""
    model, result = flight
    assert result.status == "complete", result.message
    sig = signals(result, model)
    t, angles = sig["time"].data, sig["booster_gimbal_angle"].data
    t_drop = result.events[engine.EV_BOOSTER_JETTISON]
    assert 90.0 < t_drop < 100.0
    on, off = t < t_drop - 0.1, t > t_drop + 0.1
    assert np.max(np.abs(angles[on])) <= LIMIT
    assert angles.shape[1] == 4 and np.min(np.max(np.abs(angles[on]), axis=0)) > 1e-4  # each nozzle steers
    assert np.all(angles[off] == 0.0)
    states = result.log[:, 1 + boosters.booster_channel(model.p, 0)]  # the log's rows: t, then x
    held = off & (t < result.events[engine.EV_SEPARATION])
    assert np.all(states[held] == states[held][0]) and np.all(states[t > result.events[engine.EV_SEPARATION]] == 0.0)
