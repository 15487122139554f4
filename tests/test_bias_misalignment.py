"""Gimbal null bias and sensor mounting misalignment (docs/models.md, "Gimbal null bias
and sensor misalignment") against independent references: the thrust moment
r × T t̂(δ + b), the controller trimming a bias out, small-angle rotations of the
sensed attitude error and gyro rates, the linear model's sensor outputs, and config
refusals naming the key."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import synthetic
from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.linear.plant import SENSOR_NAMES, linearize_plant
from savant_cli.models import actuator, layout, propulsion, sensors
from savant_cli.models.sensors import GyroModel, misalignment
from savant_cli.sim import engine
from savant_cli.sim.plant import derivative, pack_tables
from savant_cli.sim.run import log_columns, simulate
from savant_cli.sim.setup import prepare

FS_BIAS = actuator.P_FS_GIMBAL + actuator.G_BIAS_PITCH  # pitch, then yaw
US_BIAS = actuator.P_US_GIMBAL + actuator.G_BIAS_PITCH

THRUST = 2.0e6
L_C = 10.0 - 5.0  # synthetic gimbal station minus CG station, m


def _model(overrides: list[str]):
    return prepare(validate(compose_config(["phase=first_stage", "winds=none"] + overrides))).model


def _skew(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


# ------------------------------------------------------------------ gimbal null bias

def _first_stage_point():
    tb = pack_tables(synthetic.tables(cg=(5.0, 0.0, 0.0))._replace(fs_thrust=np.full(2, THRUST)))
    p = synthetic.parameters(thrust=True)
    u = synthetic.coast_inputs()
    u[layout.U_CONFIG], u[layout.U_ENGINE] = layout.CONFIG_STACK, layout.ENGINE_FIRST
    x = np.zeros(synthetic.LAYOUT.n)
    x[layout.R], x[layout.Q], x[synthetic.FS] = 7.0e6, 1.0, 1000.0  # vacuum, no aero: thrust alone
    return tb, p, u, x


def _thrust_moment(tb, p, u, x) -> tuple[np.ndarray, np.ndarray]:
    aux = np.zeros(layout.N_AUX)
    derivative(0.5, x, u, p, tb, aux, np.zeros(synthetic.LAYOUT.n))
    return aux[propulsion.A_MOMENT:propulsion.A_MOMENT + 3].copy(), aux


def test_gimbal_bias_turns_the_thrust_line():
    """Pitch bias b: M_y = T l_c sin(δ + b); with both axes the moment is r_cg→gimbal ×
    T t̂(δp + bp, δy + by). The logged gimbal angle stays the actuator's, the limit
    applies to the actuator, and the other stage's bias plays no part."""
    tb, p, u, x = _first_stage_point()
    delta, b = 0.03, 0.01
    x[synthetic.ACT_P] = delta
    m0, _ = _thrust_moment(tb, p, u, x)
    p[FS_BIAS] = b
    p[US_BIAS:US_BIAS + 2] = 0.05, -0.05  # inactive stage
    m1, aux = _thrust_moment(tb, p, u, x)
    assert m0[1] == pytest.approx(THRUST * L_C * np.sin(delta), rel=1e-12)
    assert m1[1] == pytest.approx(THRUST * L_C * np.sin(delta + b), rel=1e-12)
    assert m1[1] - m0[1] == pytest.approx(THRUST * L_C * b * np.cos(delta), rel=1e-3)  # ≈ T l_c b
    assert aux[actuator.A_ANGLES] == delta  # logged actuator angle, bias excluded

    # both axes against an independent cross product
    p[FS_BIAS + 1] = -0.02
    x[synthetic.ACT_Y] = 0.015
    m2, aux = _thrust_moment(tb, p, u, x)
    a, c = delta + b, 0.015 - 0.02
    t_hat = np.array([np.cos(a) * np.cos(c), -np.sin(c), np.sin(a) * np.cos(c)])
    np.testing.assert_allclose(m2, np.cross([-L_C, 0.0, 0.0], THRUST * t_hat), rtol=1e-12, atol=1e-9)
    assert aux[actuator.A_ANGLES + 1] == 0.015

    # the actuator at its stop: the thrust line is the limit plus the bias
    x[synthetic.ACT_P], x[synthetic.ACT_Y] = 0.5, 0.0
    m3, aux = _thrust_moment(tb, p, u, x)
    lim = p[actuator.P_FS_GIMBAL + actuator.G_LIMIT]
    assert aux[actuator.A_ANGLES] == lim
    assert m3[1] == pytest.approx(THRUST * L_C * np.sin(lim + b) * np.cos(-0.02), rel=1e-12)


def test_controller_trims_a_gimbal_bias_out():
    """A first-stage flight with a null bias b (pitch +0.5°, yaw −0.3°): the integral
    action settles the actuator at the nominal flight's angle minus b, so the thrust line
    (actuator + bias) is the nominal one: within 10 % of b from 5 s to 15 s, while the
    biased flight's path still follows the nominal's (the trim transient turns it a
    little, so the wind and aerodynamic loads it trims drift apart later: 0.05° by 25 s
    with the shipped msfc_pid; a PD without the integral keeps the whole offset)."""
    bias = np.radians([0.5, -0.3])
    nominal_model = _model(["sim.max_time_s=20"])
    nom = simulate(nominal_model, progress=False)
    biased = simulate(_model(["sim.max_time_s=20", "actuator.first_stage.null_bias_deg=[0.5,-0.3]"]),
                      progress=False)
    t = nom.log[:, 0]
    settled = (t >= 5.0) & (t <= 15.0)
    for c in range(2):
        state = nominal_model.layout.channel(c)
        offset = biased.log[settled, 1 + state] - nom.log[settled, 1 + state]
        assert np.all(np.abs(offset + bias[c]) < 0.10 * abs(bias[c])), (c, offset.min(), offset.max())
    assert biased.status == "complete"


# --------------------------------------------------------------- sensor misalignment

def _first_cycle(model, w0=None) -> np.ndarray:
    """The flight-software state after the first plant step (guidance, gyros and flight
    control all run on step 0, from the model's initial state)."""
    from savant_cli.sim import loop_perturbation

    x, d, u, ev = model.x0.copy(), model.d0.copy(), model.u0.copy(), model.events0.copy()
    if w0 is not None:
        x[layout.W:layout.W + 3] = w0
    log = np.empty((1, log_columns(x.size)))
    engine.advance(x, d, u, ev, model.k0, 1, model.rates, model.p, model.packed_tables, model.fcs, model.gyro,
                   model.smoother, model.guidance, model.sched, log, 0, loop_perturbation.NONE)
    return d


def test_zero_misalignment_is_the_exact_identity():
    """What keeps the nominal run bit-identical: ε = 0 gives q = [1, 0, 0, 0] and I exactly."""
    q, c = misalignment(np.zeros(3))
    assert np.array_equal(q, [1.0, 0.0, 0.0, 0.0])
    assert np.array_equal(c, np.eye(3))


def test_imu_misalignment_shifts_the_attitude_error():
    """IMU misaligned by ε about body y: the flight software's pitch error at the same
    state is larger by ε (sensed attitude q_b2i ⊗ q(ε)); roll and yaw errors change only
    to second order."""
    eps = np.radians(0.5)
    e_ref = _first_cycle(_model([]))[layout.D_ERR:layout.D_ERR + 3]
    e_mis = _first_cycle(_model(["sensors.misalignment_deg.imu=[0.0,0.5,0.0]"]))[layout.D_ERR:layout.D_ERR + 3]
    small = np.abs(e_ref).max() * eps + eps**3  # second-order terms
    assert abs(e_ref[1]) < 0.1 * eps  # the reference error is small next to ε
    assert e_mis[1] - e_ref[1] == pytest.approx(eps, abs=small)
    assert abs(e_mis[0] - e_ref[0]) <= small and abs(e_mis[2] - e_ref[2]) <= small


def test_gyro_misalignment_mixes_pitch_rate_into_the_other_axes():
    """A pure body pitch rate q, gyros with unit transfer function: the upper-stage gyro
    turned by εx about x reads −εx q in yaw, the IMU gyro (with the IMU) turned by εz
    about z reads +εz q in roll, ω_s = ω − ε × ω to first order."""
    model = _model(["sensors.misalignment_deg.rate_gyro_upper_stage=[0.5,0.0,0.0]",
                    "sensors.misalignment_deg.imu=[0.0,0.0,0.8]",
                    "sensors.misalignment_deg.rate_gyro_first_stage=[0.0,0.3,0.0]"])
    model.gyro = GyroModel(ad=np.zeros((2, 2)), bd=np.zeros(2), cd=np.zeros(2), dd=1.0)  # pass-through
    q = 0.02
    w = np.array([0.0, q, 0.0])
    d = _first_cycle(model, w)
    read = d[layout.D_GYRO_Y:layout.D_GYRO_Y + 9].reshape(3, 3)  # [gyro (upper, IMU, first)][axis]
    for g, eps_deg in enumerate(([0.5, 0.0, 0.0], [0.0, 0.0, 0.8], [0.0, 0.3, 0.0])):
        eps = np.radians(eps_deg)
        exact = Rotation.from_rotvec(eps).as_matrix().T @ w  # R(ε)ᵀ ω, independent rotation code
        np.testing.assert_allclose(read[g], exact, rtol=0, atol=1e-15)
        np.testing.assert_allclose(read[g], w - np.cross(eps, w), rtol=0, atol=q * np.abs(eps).max() ** 2)
    assert read[0, 2] == pytest.approx(-np.radians(0.5) * q, rel=1e-4)
    assert read[1, 0] == pytest.approx(np.radians(0.8) * q, rel=1e-4)
    np.testing.assert_array_equal(read[2, [0, 2]], 0.0)  # ε along ω: no cross-coupling


def test_linear_sensor_outputs_carry_the_misalignment():
    """The linear model's sensor rows: the nav attitude and each gyro's rate are the
    aligned ones rotated by R(ε)ᵀ ≈ I − [ε×] (the time run's sensing, linearized)."""
    eps = {"imu": [0.4, -0.6, 0.2], "rate_gyro_upper_stage": [0.7, 0.0, -0.3], "rate_gyro_first_stage": [0.0, 0.5, 0.9]}
    over = [f"sensors.misalignment_deg.{k}=[{','.join(map(str, v))}]" for k, v in eps.items()]
    lin = {}
    for name, ov in (("aligned", []), ("misaligned", over)):
        model = _model(["sim.max_time_s=1"] + ov)
        snap = simulate(model, progress=False, snapshot_steps=(100,)).snapshots[100]
        lin[name] = linearize_plant(model, snap).sys
    sys0, sys1 = lin["aligned"], lin["misaligned"]
    states = list(sys0.state_labels)
    att = [states.index(f"dtheta_{a}") for a in "xyz"]
    rate = [states.index(a) for a in "pqr"]
    blocks = (("nav", att, eps["imu"]), ("gyro_upper", rate, eps["rate_gyro_upper_stage"]),
              ("gyro_imu", rate, eps["imu"]), ("gyro_first", rate, eps["rate_gyro_first_stage"]))
    for prefix, cols, e_deg in blocks:
        rows = [i for i, n in enumerate(SENSOR_NAMES) if n.startswith(prefix)]
        c0 = sys0.C[np.ix_(rows, cols)]
        c1 = sys1.C[np.ix_(rows, cols)]
        np.testing.assert_allclose(c0, np.eye(3), atol=1e-8)
        eps = np.radians(e_deg)
        np.testing.assert_allclose(c1, Rotation.from_rotvec(eps).as_matrix().T @ c0, atol=1e-8)
        np.testing.assert_allclose(c1, (np.eye(3) - _skew(eps)) @ c0, atol=np.abs(eps).max() ** 2)


# ---------------------------------------------------------------------- config

@pytest.mark.parametrize("override, key", [
    ("actuator.first_stage.null_bias_deg=[2.5,0.0]", "actuator.first_stage.null_bias_deg[0]"),
    ("actuator.upper_stage.null_bias_deg=[0.0,-3.0]", "actuator.upper_stage.null_bias_deg[1]"),
    ("actuator.first_stage.null_bias_deg=[0.1,0.1,0.1]", "actuator.first_stage.null_bias_deg"),
    ("actuator.upper_stage.null_bias_deg=[nan,0.0]", "actuator.upper_stage.null_bias_deg[0]"),
    ("sensors.misalignment_deg.imu=[0.0,1.5,0.0]", "sensors.misalignment_deg.imu[1]"),
    ("sensors.misalignment_deg.rate_gyro_upper_stage=[0.0,0.0,-1.01]",
     "sensors.misalignment_deg.rate_gyro_upper_stage[2]"),
    ("sensors.misalignment_deg.rate_gyro_first_stage=[0.5,0.5]", "sensors.misalignment_deg.rate_gyro_first_stage"),
])
def test_out_of_range_values_are_refused_naming_the_key(override, key):
    with pytest.raises(ConfigError) as exc:
        validate(compose_config([override]))
    assert exc.value.key == key
    assert "deg" in exc.value.allowed
    assert key in str(exc.value)


def test_limits_are_accepted_and_reach_the_parameters_in_radians():
    model = prepare(validate(compose_config(["actuator=simplex", "actuator.first_stage.null_bias_deg=[2.0,-1.0]",
                                             "actuator.upper_stage.null_bias_deg=[-2.0,0.5]",
                                             "sensors.misalignment_deg.imu=[1.0,-1.0,0.25]",
                                             "sensors.misalignment_deg.rate_gyro_upper_stage=[0.1,0.2,0.3]",
                                             "sensors.misalignment_deg.rate_gyro_first_stage=[-0.1,0.0,1.0]"]))).model
    p = model.p
    np.testing.assert_allclose(p[FS_BIAS:FS_BIAS + 2], np.radians([2.0, -1.0]))
    np.testing.assert_allclose(p[US_BIAS:US_BIAS + 2], np.radians([-2.0, 0.5]))
    np.testing.assert_allclose(p[sensors.P_IMU_MISALIGN:sensors.P_IMU_MISALIGN + 3], np.radians([1.0, -1.0, 0.25]))
    np.testing.assert_allclose(p[sensors.P_GYRO_US_MISALIGN:sensors.P_GYRO_US_MISALIGN + 3], np.radians([0.1, 0.2, 0.3]))
    np.testing.assert_allclose(p[sensors.P_GYRO_FS_MISALIGN:sensors.P_GYRO_FS_MISALIGN + 3], np.radians([-0.1, 0.0, 1.0]))
    assert p.size == layout.N_PARAM
    default = prepare(validate(compose_config([]))).model.p
    error_sources = [*range(FS_BIAS, FS_BIAS + 2), *range(US_BIAS, US_BIAS + 2)] + [
        base + i for base in (sensors.P_IMU_MISALIGN, sensors.P_GYRO_US_MISALIGN, sensors.P_GYRO_FS_MISALIGN)
        for i in range(3)]
    assert not np.any(default[error_sources])  # nominal: every error source 0
