"""Initial sensor biases (navcore.filters.initial_biases) through the filters' shell: given
per axis (distinct values, so a swap of axes shows), and the gyro bias estimated from a static
interval at the start against the bias put into the IMU, with the Earth rate's horizontal part
as the stated error; data that is not static warns and estimates nothing."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.components import registry
from navcore.filters.initial_biases import STATIC_RATE_SPREAD, StaticBiasEstimator
from navcore.ins import earth
from navcore.ins.constants import WGS84_OMEGA_IE
from walk_inputs import LAT, walk_fix

GYRO_BIAS = np.array([0.002, -0.003, 0.0045])        # rad/s: 413, -619, 928 deg/h
ACCEL_BIAS = np.array([0.05, -0.08, 0.12])           # m/s^2
GYRO_SIGMA = np.array([1e-3, 2e-3, 3e-3])
ACCEL_SIGMA = np.array([0.01, 0.02, 0.04])
DT = 0.1
FILTERS = ["Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf", "CtfaUkf",
           "ImmUkf", "InsOnly"]


def _given(**extra):
    return {**{f"init_gyro_bias_{a}": b for a, b in zip("xyz", GYRO_BIAS)},
            **{f"init_accel_bias_{a}": b for a, b in zip("xyz", ACCEL_BIAS)},
            **{f"p0_gyro_bias_{a}": s for a, s in zip("xyz", GYRO_SIGMA)},
            **{f"p0_accel_bias_{a}": s for a, s in zip("xyz", ACCEL_SIGMA)}, **extra}


@pytest.mark.parametrize("name", FILTERS)
def test_given_biases_and_sigmas_per_axis_reach_every_filter(name):
    f = registry.REGISTRY[name](init_lat=LAT, **_given())
    out = f.start(0.0)
    np.testing.assert_array_equal([out[f"nav_bg_{a}"] for a in "xyz"], GYRO_BIAS)
    np.testing.assert_array_equal([out[f"nav_ba_{a}"] for a in "xyz"], ACCEL_BIAS)
    np.testing.assert_allclose([out[f"std_bg_{a}"] for a in "xyz"], GYRO_SIGMA, rtol=1e-12)
    np.testing.assert_allclose([out[f"std_ba_{a}"] for a in "xyz"], ACCEL_SIGMA, rtol=1e-12)


def test_an_axis_without_its_own_sigma_takes_the_one_for_all():
    f = registry.REGISTRY["Kf"](p0_gyro_bias_dph=36.0, p0_accel_bias_ug=500.0,
                                p0_gyro_bias_y=2e-3, p0_accel_bias_z=0.04)
    out = f.start(0.0)
    dph, ug = math.radians(36.0) / 3600.0, 500.0e-6 * 9.80665
    np.testing.assert_allclose([out[f"std_bg_{a}"] for a in "xyz"], [dph, 2e-3, dph])
    np.testing.assert_allclose([out[f"std_ba_{a}"] for a in "xyz"], [ug, ug, 0.04], rtol=1e-6)


def _imu_at_rest(k, yaw, rng, rate_noise=1e-5):
    """An IMU level at rest heading ``yaw``: the Earth rate in the body plus GYRO_BIAS."""
    g = earth.gravity(LAT, 100.0)
    w_n = WGS84_OMEGA_IE * np.array([math.cos(LAT), 0.0, -math.sin(LAT)])
    c, s = math.cos(yaw), math.sin(yaw)
    w_b = np.array([c * w_n[0] + s * w_n[1], -s * w_n[0] + c * w_n[1], w_n[2]]) + GYRO_BIAS
    w_b = w_b + rate_noise * rng.standard_normal(3)
    return {"imu_time": (k + 1) * DT, "imu_dt": DT, **{f"imu_dtheta_{a}": w_b[i] * DT
                                                       for i, a in enumerate("xyz")},
            "imu_dvel_x": 0.0, "imu_dvel_y": 0.0, "imu_dvel_z": -g * DT}


def _start_after_rest(name, yaw, static_time, wobble=0.0):
    """Filter ``name`` with init_mode 'gnss' on 30 s at rest then fixes at 1.8 m/s: (its
    engine at the start, notices)."""
    rng = np.random.default_rng(5)
    f = registry.REGISTRY[name](init_mode="gnss", init_lat=LAT, init_h=100.0,
                                init_static_time=static_time)
    f.start(0.0)
    notices = []
    for k in range(320):
        fix = walk_fix(k, DT, moving_from=30.0)
        imu = _imu_at_rest(k, yaw, rng)
        if wobble:                                 # a vehicle that is not at rest
            imu["imu_dtheta_x"] += wobble * math.sin(k) * DT
        f.advance(k * DT, DT, {**imu, **fix})
        notices += f.take_notices()
        if f.out["aligned"]:
            return f, notices
    raise AssertionError("the filter did not start")


@pytest.mark.parametrize("name", ["Kf", "Ukf"])
@pytest.mark.parametrize("yaw", [0.0, 2.0])
def test_the_static_interval_gives_the_gyro_bias_within_the_horizontal_earth_rate(name, yaw):
    f, notices = _start_after_rest(name, yaw, 20.0)
    assert not notices
    bias = f.engine.gyro_bias
    horizontal = WGS84_OMEGA_IE * math.cos(LAT)              # 11.5 deg/h: stays in x, y
    err = bias - GYRO_BIAS
    assert math.hypot(err[0], err[1]) == pytest.approx(horizontal, rel=0.05)
    assert abs(err[2]) < 3e-6                                # the vertical part removed
    sigma = [f.out[f"std_bg_{a}"] for a in "xyz"]
    assert sigma == pytest.approx([math.hypot(horizontal, 1e-5 / math.sqrt(200))] * 3,
                                  rel=0.01)


def test_a_moving_start_warns_and_keeps_the_given_bias():
    f, notices = _start_after_rest("Kf", 0.0, 20.0, wobble=0.05)
    assert len(notices) == 1 and "the IMU is not static over the first 20 s" in notices[0]
    assert f"limit {STATIC_RATE_SPREAD:g}" in notices[0]
    np.testing.assert_array_equal(f.engine.gyro_bias, np.zeros(3))


def test_the_static_interval_needs_the_start_from_the_data():
    with pytest.raises(Exception, match=r"parameter 'init_static_time' = 10.0 > 0 needs "
                                        r"init_mode = 'gnss'"):
        registry.REGISTRY["Kf"](init_static_time=10.0).start(0.0)


def test_the_estimator_counts_only_its_interval():
    est = StaticBiasEstimator(0.3)
    for _ in range(5):
        est.add_interval([1e-3, 0.0, 0.0], [0.0, 0.0, -0.98], 0.1)
    assert est.n == 3 and est.elapsed == pytest.approx(0.3)
