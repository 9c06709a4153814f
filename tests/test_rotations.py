"""Rotations: known values, agreement with scipy's independent implementation, round trips."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navcore.ins.rotations import (
    dcm_to_euler,
    dcm_to_rotvec,
    euler_to_dcm,
    quat_from_dcm,
    quat_normalize,
    quat_to_dcm,
    rotvec_to_dcm,
    wrap_angle,
)

RNG_SEED = 20240601


def random_rotvecs(n, seed=RNG_SEED):
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    angles = rng.uniform(0.0, math.pi, size=n)
    return axes * angles[:, None]


@pytest.mark.parametrize("euler_deg, body, ned", [
    ((0, 0, 90), [1, 0, 0], [0, 1, 0]),     # yaw 90: nose points east
    ((0, 90, 0), [1, 0, 0], [0, 0, -1]),    # pitch 90: nose points up
    ((90, 0, 0), [0, 1, 0], [0, 0, 1]),     # roll 90: right wing points down
    ((0, 0, 180), [0, 1, 0], [0, -1, 0]),   # yaw 180: right wing points west
])
def test_euler_to_dcm_known_values(euler_deg, body, ned):
    C = euler_to_dcm(*np.radians(euler_deg))
    np.testing.assert_allclose(C @ body, ned, atol=1e-15)


def test_euler_to_dcm_matches_scipy_zyx():
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(50):
        roll, yaw = rng.uniform(-math.pi, math.pi, 2)
        pitch = rng.uniform(-1.5, 1.5)
        ref = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
        np.testing.assert_allclose(euler_to_dcm(roll, pitch, yaw), ref, atol=1e-15)


def test_dcm_to_euler_round_trip_and_yaw_range():
    rng = np.random.default_rng(RNG_SEED + 1)
    for _ in range(200):
        roll, yaw = rng.uniform(-math.pi, math.pi, 2)
        pitch = rng.uniform(-1.55, 1.55)
        r, p, y = dcm_to_euler(euler_to_dcm(roll, pitch, yaw))
        assert abs(wrap_angle(r - roll)) < 1e-12
        assert abs(p - pitch) < 1e-12
        assert abs(wrap_angle(y - yaw)) < 1e-12
        assert -math.pi < y <= math.pi
    # yaw of exactly -pi is reported as +pi
    assert dcm_to_euler(euler_to_dcm(0.0, 0.0, -math.pi))[2] == pytest.approx(math.pi, abs=1e-15)
    assert dcm_to_euler(euler_to_dcm(0.0, 0.0, math.pi))[2] > 0


def test_rotvec_to_dcm_matches_scipy_and_is_orthonormal():
    for phi in random_rotvecs(100):
        C = rotvec_to_dcm(phi)
        np.testing.assert_allclose(C, Rotation.from_rotvec(phi).as_matrix(), atol=2e-15)
        np.testing.assert_allclose(C @ C.T, np.eye(3), atol=2e-15)
        assert np.linalg.det(C) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("angle", [0.0, 1e-15, 1e-12, 1e-9, 1e-6, 7.3e-7, 1e-4, 9.99e-4, 1.001e-3,
                                   0.1, 1.0, 3.0, math.pi - 1e-6])
def test_rotvec_round_trip_all_angles(angle):
    axis = np.array([0.48, -0.6, 0.64])
    phi = axis * angle
    back = dcm_to_rotvec(rotvec_to_dcm(phi))
    # absolute accuracy at rounding level, independent of the angle (tiny angles included);
    # near pi the axis comes from the symmetric part and is good to ~sqrt(eps)
    atol = 1e-15 if angle < 3.0 else 1e-8
    np.testing.assert_allclose(back, phi, rtol=0, atol=atol)


def test_small_rotvec_series_matches_closed_form_across_threshold():
    axis = np.array([0.0, 0.6, 0.8])
    below = rotvec_to_dcm(axis * (1e-3 * (1 - 1e-9)))
    above = rotvec_to_dcm(axis * (1e-3 * (1 + 1e-9)))
    np.testing.assert_allclose(below, above, atol=2e-12)


def test_quaternion_dcm_round_trip_and_scipy():
    for phi in random_rotvecs(100, seed=RNG_SEED + 2):
        C = rotvec_to_dcm(phi)
        q = quat_from_dcm(C)
        assert q[0] >= 0.0
        assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-15)
        np.testing.assert_allclose(quat_to_dcm(q), C, atol=2e-15)
        xyzw = Rotation.from_matrix(C).as_quat()
        ref = np.r_[xyzw[3], xyzw[:3]] * np.sign(xyzw[3])
        np.testing.assert_allclose(q, ref, atol=2e-15)


def test_quat_normalize():
    np.testing.assert_allclose(quat_normalize([2.0, 0.0, 0.0, 0.0]), [1, 0, 0, 0])
    np.testing.assert_allclose(np.linalg.norm(quat_normalize([1.0, 2.0, -3.0, 4.0])), 1.0)
    with pytest.raises(ValueError):
        quat_normalize([0.0, 0.0, 0.0, 0.0])


def test_wrap_angle():
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)
    np.testing.assert_allclose(wrap_angle(np.array([0.1, 2 * math.pi + 0.1, -7.0])),
                               [0.1, 0.1, -7.0 + 2 * math.pi])
