"""Modified Rodrigues parameters against scipy.spatial.transform.Rotation (an independent
implementation), the shadow set and its covariance Jacobian against finite differences."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navcore.ins import mrp
from navcore.filters.ahrs import quat_euler
from navcore.ins.rotations import euler_to_dcm

RNG = np.random.default_rng(3)
EULER = np.column_stack((RNG.uniform(-math.pi, math.pi, 200), RNG.uniform(-1.5, 1.5, 200),
                         RNG.uniform(-math.pi, math.pi, 200)))


def _scipy(roll, pitch, yaw):
    return Rotation.from_euler("ZYX", [yaw, pitch, roll])


@pytest.mark.parametrize("k", range(0, 200, 7))
def test_euler_to_mrp_matches_scipy(k):
    roll, pitch, yaw = EULER[k]
    ours = mrp.euler_to_mrp(roll, pitch, yaw)
    ref = _scipy(roll, pitch, yaw).as_mrp()
    assert np.linalg.norm(ours) <= 1.0 + 1e-15
    np.testing.assert_allclose(ours, ref, atol=1e-12)


def test_mrp_euler_round_trip_and_quaternion_against_scipy():
    for roll, pitch, yaw in EULER:
        sigma = mrp.euler_to_mrp(roll, pitch, yaw)
        np.testing.assert_allclose(mrp.mrp_to_euler(sigma), (roll, pitch, yaw), atol=1e-11)
        q = mrp.mrp_to_quat(sigma)
        w, x, y, z = q
        np.testing.assert_allclose(Rotation.from_quat([x, y, z, w]).as_matrix(),
                                   _scipy(roll, pitch, yaw).as_matrix(), atol=1e-12)
        np.testing.assert_allclose(quat_euler(tuple(q)), (roll, pitch, yaw), atol=1e-11)
        np.testing.assert_allclose(mrp.quat_to_mrp(-q), sigma, atol=1e-14)


def test_batch_dcm_matches_scipy_from_mrp():
    sigma = np.array([mrp.euler_to_mrp(*e) for e in EULER])
    np.testing.assert_allclose(mrp.mrp_to_dcm_batch(sigma), Rotation.from_mrp(sigma).as_matrix(),
                               atol=1e-12)


def test_shadow_set_is_the_same_attitude_and_an_involution():
    for roll, pitch, yaw in EULER[:50]:
        sigma = mrp.euler_to_mrp(roll, pitch, yaw)
        s = mrp.shadow(sigma)
        assert np.linalg.norm(s) >= 1.0 - 1e-12            # the long way round
        np.testing.assert_allclose(mrp.mrp_to_dcm(s), euler_to_dcm(roll, pitch, yaw),
                                   atol=1e-12)
        np.testing.assert_allclose(mrp.shadow(s), sigma, atol=1e-13)
        np.testing.assert_allclose(mrp.mrp_to_quat(s), -mrp.mrp_to_quat(sigma), atol=1e-12)


def test_shadow_switch_near_180_deg_and_nearest_set():
    # 179 and 181 deg about one axis: MRPs just inside/outside the unit sphere
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    inside = math.tan(math.radians(179.0) / 4.0) * axis
    outside = math.tan(math.radians(181.0) / 4.0) * axis
    assert np.linalg.norm(inside) < 1.0 < np.linalg.norm(outside)
    switched = mrp.shadow(outside)
    # 181 deg about +axis is 179 deg about -axis
    np.testing.assert_allclose(switched, -inside, atol=1e-12)
    np.testing.assert_allclose(Rotation.from_mrp(outside).as_matrix(),
                               Rotation.from_mrp(switched).as_matrix(), atol=1e-12)
    # points split across the boundary come back to one set
    short = math.tan(math.radians(179.5) / 4.0) * -axis      # 180.5 deg about +axis
    same = mrp.nearest_set(np.array([inside, short]), inside)
    np.testing.assert_allclose(same[0], inside)
    np.testing.assert_allclose(same[1], mrp.shadow(short))
    assert np.linalg.norm(same[1]) > 1.0 and np.linalg.norm(same[1] - inside) < 0.03


def test_shadow_jacobian_against_finite_differences():
    sigma = np.array([0.9, -0.4, 0.3])
    J = mrp.shadow_jacobian(sigma)
    eps = 1e-7
    numeric = np.column_stack([(mrp.shadow(sigma + eps * e) - mrp.shadow(sigma - eps * e))
                               / (2 * eps) for e in np.eye(3)])
    np.testing.assert_allclose(J, numeric, rtol=1e-6, atol=1e-8)
