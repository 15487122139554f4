"""The control mixer (models/mixer.py) against hand-computed moments, the plant's own
thrust kernel, the closed-form minimum-norm solution and numpy's least squares."""

from __future__ import annotations

import numpy as np
import pytest

from savant_cli.models import mixer, propulsion


def _cluster(positions, thrust, cants=None, axes=("pitch", "yaw")):
    """Engines at ``positions`` (arm from the CG, body axes, m) with every named axis a channel."""
    arms = np.ascontiguousarray(positions, dtype=float)
    n = arms.shape[0]
    cants = np.zeros((n, 2)) if cants is None else np.ascontiguousarray(cants, dtype=float)
    codes = {"pitch": mixer.AXIS_PITCH, "yaw": mixer.AXIS_YAW}
    engine = np.array([i for i in range(n) for _ in axes], dtype=np.int64)
    axis = np.array([codes[a] for _ in range(n) for a in axes], dtype=np.int64)
    return arms, cants, np.full(n, float(thrust)) if np.isscalar(thrust) else np.asarray(thrust, float), engine, axis


def _octaweb(x_arm=-20.0, radius=1.2):
    """A Falcon-9-like cluster: 8 engines on a circle and one in the middle, aft of the CG."""
    angles = np.radians(np.arange(8) * 45.0 + 22.5)
    ring = [(x_arm, radius * np.cos(a), radius * np.sin(a)) for a in angles]
    return [*ring, (x_arm, 0.0, 0.0)]


def test_differential_yaw_gimbal_gives_the_hand_computed_roll_moment():
    # two engines 1.5 m either side of the axis along body z, 20 m aft of the CG, 800 kN each;
    # yaw gimbals deflected +δ and −δ: the side forces ∓Tδ ŷ at z = ±r give the roll moment
    # L = 2 r T δ and cancel in yaw (hand computation: r × F with r = (x, 0, ±r), F = (0, ∓Tδ, 0))
    r, t, delta, x_arm = 1.5, 8.0e5, 0.01, -20.0
    arms, cants, thrust, engine, axis = _cluster([(x_arm, 0.0, r), (x_arm, 0.0, -r)], t, axes=("yaw",))
    b = mixer.moment_effectiveness(arms, cants, thrust, engine, axis)
    moment = b @ np.array([delta, -delta])
    assert moment == pytest.approx([2.0 * r * t * delta, 0.0, 0.0], abs=1e-6)
    # the plant's own thrust kernel, at the finite angles, agrees to second order in δ
    exact = np.zeros(3)
    for (rx, ry, rz), d in zip(arms, (delta, -delta)):
        exact += propulsion.thrust_loads(t, 0.0, d, rx, ry, rz)[3:]
    assert exact[0] == pytest.approx(2.0 * r * t * np.sin(delta), rel=1e-12)
    assert np.allclose(moment, exact, rtol=0, atol=2.0 * r * t * delta ** 3)


@pytest.mark.parametrize("cant_deg", [(0.0, 0.0), (3.0, -2.0), (-5.0, 4.0)])
@pytest.mark.parametrize("axis_name", ["pitch", "yaw"])
def test_channel_effectiveness_is_the_derivative_of_the_plants_thrust_moment(cant_deg, axis_name):
    # a canted engine off the axis: each column of B is d(moment)/dδ of propulsion.thrust_loads
    # at the cant, by a central difference
    arm, t = (-18.0, 0.7, -1.1), 1.0e6
    cants = np.radians([cant_deg])
    arms, cants, thrust, engine, axis = _cluster([arm], t, cants=cants, axes=(axis_name,))
    b = mixer.moment_effectiveness(arms, cants, thrust, engine, axis)[:, 0]
    h = 1e-6
    cp, cy = cants[0]
    if axis_name == "pitch":
        plus, minus = propulsion.thrust_loads(t, cp + h, cy, *arm), propulsion.thrust_loads(t, cp - h, cy, *arm)
    else:
        plus, minus = propulsion.thrust_loads(t, cp, cy + h, *arm), propulsion.thrust_loads(t, cp, cy - h, *arm)
    fd = (np.array(plus[3:]) - np.array(minus[3:])) / (2 * h)
    assert np.allclose(b, fd, rtol=1e-7, atol=1e-3)


def _commands(rng, n=20):
    """Commands (L N·m, δp rad, δy rad) of a flight's size."""
    return np.column_stack([rng.uniform(-2e5, 2e5, n), rng.uniform(-0.02, 0.02, n), rng.uniform(-0.02, 0.02, n)])


@pytest.mark.parametrize("failed", [None, 0, 8])
def test_nine_engine_allocation_reproduces_the_commanded_moments(failed):
    # a 9-engine cluster, all up or one engine out (ring or centre): B K v = diag(1, d_p, d_y) v
    # within 1e-9 relative, the failed engine's channels idle, and K v is the limit-weighted
    # minimum-norm solution: the closed form W⁻¹Bᵀ(BW⁻¹Bᵀ)⁻¹M and numpy's least squares agree
    thrust = np.full(9, 8.45e5)
    if failed is not None:
        thrust[failed] = 0.0
    arms, cants, thrust, engine, axis = _cluster(_octaweb(), thrust)
    limits = np.radians(np.where(engine == 8, 6.0, 5.0))  # the centre engine gimbals further
    b = mixer.moment_effectiveness(arms, cants, thrust, engine, axis)
    k = mixer.mixing_matrix(b, limits, axis)
    d_p, d_y = mixer.equivalent_scales(b, axis)
    w_inv = np.diag(limits ** 2)
    for v in _commands(np.random.default_rng(7)):
        want = np.array([v[0], d_p * v[1], d_y * v[2]])
        delta = k @ v
        got = b @ delta
        assert np.max(np.abs(got - want)) <= 1e-9 * np.max(np.abs(want))
        closed = w_inv @ b.T @ np.linalg.solve(b @ w_inv @ b.T, want)
        lstsq = limits * np.linalg.lstsq(b * limits, want, rcond=None)[0]
        assert np.allclose(delta, closed, rtol=0, atol=1e-12 * np.max(np.abs(closed)))
        assert np.allclose(delta, lstsq, rtol=0, atol=1e-12 * np.max(np.abs(closed)))
        if failed is not None:
            assert np.all(delta[engine == failed] == 0.0)


def test_a_symmetric_cluster_moves_every_gimbal_by_the_equivalent_angle():
    # four equal engines on a square: a pure pitch (yaw) command δ is every pitch (yaw) gimbal at δ,
    # the equivalent engine's angle, with the other axis still
    corners = [(-15.0, 1.0, 1.0), (-15.0, -1.0, 1.0), (-15.0, -1.0, -1.0), (-15.0, 1.0, -1.0)]
    arms, cants, thrust, engine, axis = _cluster(corners, 2.0e6)
    k = mixer.mixing_matrix(mixer.moment_effectiveness(arms, cants, thrust, engine, axis),
                            np.full(engine.size, np.radians(6.0)), axis)
    pitch, yaw = axis == mixer.AXIS_PITCH, axis == mixer.AXIS_YAW
    assert np.allclose(k[pitch, mixer.PITCH], 1.0, atol=1e-12) and np.allclose(k[yaw, mixer.PITCH], 0.0, atol=1e-12)
    assert np.allclose(k[yaw, mixer.YAW], 1.0, atol=1e-12) and np.allclose(k[pitch, mixer.YAW], 0.0, atol=1e-12)


def test_one_engine_is_its_own_equivalent_engine_and_cannot_roll():
    arms, cants, thrust, engine, axis = _cluster([(-30.0, 0.0, 0.0)], 1.3e7)
    b = mixer.moment_effectiveness(arms, cants, thrust, engine, axis)
    k = mixer.mixing_matrix(b, np.full(2, np.radians(8.0)), axis)
    assert np.allclose(k, [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], atol=1e-12)  # roll unattainable: no command


def test_the_gimbal_limits_weight_the_allocation():
    # two engines side by side (same effectiveness), one with half the other's range: minimum
    # Σ(δ/limit)² puts δ ∝ limit², a 4:1 split
    arms, cants, thrust, engine, axis = _cluster([(-10.0, 0.0, 0.0), (-10.0, 0.0, 0.0)], 1.0e6, axes=("pitch",))
    b = mixer.moment_effectiveness(arms, cants, thrust, engine, axis)
    k = mixer.mixing_matrix(b, np.radians([6.0, 3.0]), axis)
    assert k[0, mixer.PITCH] / k[1, mixer.PITCH] == pytest.approx(4.0, rel=1e-12)
    assert k[0, mixer.PITCH] + k[1, mixer.PITCH] == pytest.approx(2.0, rel=1e-12)  # the pair's moment: 2 b δ


def test_a_given_mixing_matrix_is_checked_against_the_effectiveness():
    arms, cants, thrust, engine, axis = _cluster(_octaweb(), 8.45e5)
    limits = np.full(engine.size, np.radians(5.0))
    b = mixer.moment_effectiveness(arms, cants, thrust, engine, axis)
    own = mixer.mixing_matrix(b, limits, axis)
    assert mixer.check_mixing_matrix(own, b, limits, axis) == []
    # another allocation giving the same moments (plus a null-space move) passes; a wrong one is named
    null = np.linalg.svd(b)[2][-1]
    assert mixer.check_mixing_matrix(own + 0.1 * np.outer(null, [1e-6, 1.0, 0.0]), b, limits, axis) == []
    wrong = own.copy()
    wrong[:, mixer.YAW] *= 1.1
    assert [m.split(" gives")[0] for m in mixer.check_mixing_matrix(wrong, b, limits, axis)] == ["the yaw command"]
    assert "one row per gimbal channel" in mixer.check_mixing_matrix(own[:3], b, limits, axis)[0]
    # the tolerance's edge: a yaw column off by half of rtol passes, by twice rtol fails
    for factor, named in ((1.0 + 0.5e-6, []), (1.0 + 2.0e-6, ["the yaw command"])):
        near = own.copy()
        near[:, mixer.YAW] *= factor
        assert [m.split(" gives")[0] for m in mixer.check_mixing_matrix(near, b, limits, axis, rtol=1e-6)] == named
