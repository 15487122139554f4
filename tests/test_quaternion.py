"""Quaternion algebra against rotation matrices from scipy, and kinematics."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from savant_cli.models import quaternion as qt


def _random_unit(rng):
    q = rng.standard_normal(4)
    return q / np.linalg.norm(q)


def test_dcm_matches_scipy_active_rotation():
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = _random_unit(rng)
        ref = Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix()  # scipy: scalar last
        np.testing.assert_allclose(qt.dcm(q), ref, atol=1e-12)
        np.testing.assert_allclose(qt.from_dcm(ref), q * np.sign(q[0]), atol=1e-12)


def test_product_composes_rotations():
    rng = np.random.default_rng(1)
    a, b = _random_unit(rng), _random_unit(rng)
    np.testing.assert_allclose(qt.dcm(qt.qmul(a, b)), qt.dcm(a) @ qt.dcm(b), atol=1e-12)


def test_rotation_vector_round_trip():
    phi = np.array([0.3, -1.2, 2.0])
    np.testing.assert_allclose(qt.to_rotation_vector(qt.from_rotation_vector(phi)), phi, atol=1e-12)
    ref = Rotation.from_rotvec(phi).as_matrix()
    np.testing.assert_allclose(qt.dcm(qt.from_rotation_vector(phi)), ref, atol=1e-12)


def test_kinematics_constant_rate_matches_exponential_and_keeps_norm():
    """RK4 on q̇ = ½ q ⊗ ω for a constant body rate equals the exact exponential; the
    norm drifts only by integration error."""
    w = np.array([0.1, -0.4, 0.25])
    q = np.array([1.0, 0.0, 0.0, 0.0])
    dt = 0.01
    for _ in range(1000):
        k1 = qt.derivative(q, w)
        k2 = qt.derivative(q + 0.5 * dt * k1, w)
        k3 = qt.derivative(q + 0.5 * dt * k2, w)
        k4 = qt.derivative(q + dt * k3, w)
        q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(q, qt.from_rotation_vector(w * 10.0), atol=1e-9)


def test_euler_321_of_known_rotation():
    roll, pitch, yaw = 0.1, -0.3, 1.2
    m = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
    np.testing.assert_allclose(qt.euler_321(m[None])[0], [roll, pitch, yaw], atol=1e-12)


def test_dcm_array_matches_scalar_dcm():
    rng = np.random.default_rng(3)
    qs = np.array([_random_unit(rng) for _ in range(10)])
    np.testing.assert_allclose(qt.dcm_array(qs), np.stack([qt.dcm(q) for q in qs]), atol=1e-14)
