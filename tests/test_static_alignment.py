"""Static alignment at the start (init_mode = 'static', navcore.filters.static_alignment):
a tilted IMU at rest with gyro biases, a motion burst, the rest after it, then a walk; the
level and the gyro biases against the ones put in, the rest period the detector found, the
sigmas the filter starts with; data that is not static warns and estimates nothing."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.components import registry
from navcore.filters.static_alignment import RestDetector
from navcore.ins import earth
from navcore.ins.constants import WGS84_OMEGA_IE
from navcore.ins.rotations import euler_to_dcm
from walk_inputs import LAT, walk_fix

ROLL, PITCH, YAW = math.radians(3.0), math.radians(-2.0), 2.0
GYRO_BIAS = np.array([0.002, -0.003, 0.0045])        # rad/s: 413, -619, 928 deg/h
DT = 0.1
ACCEL_BIAS_SIGMA = 0.02                              # m/s^2 (p0_accel_bias_ug = 2039)


def _imu(k, rng, moving):
    """The tilted IMU at rest (the Earth rate and gravity in its axes, GYRO_BIAS, white
    noise of 1e-4 rad/s and 0.01 m/s^2), shaken while ``moving``."""
    g = earth.gravity(LAT, 100.0)
    c_bn = euler_to_dcm(ROLL, PITCH, YAW)
    w_b = c_bn.T @ (WGS84_OMEGA_IE * np.array([math.cos(LAT), 0.0, -math.sin(LAT)]))
    w_b = w_b + GYRO_BIAS + 1e-4 * rng.standard_normal(3)
    f_b = c_bn.T @ np.array([0.0, 0.0, -g]) + 0.01 * rng.standard_normal(3)
    if moving:
        w_b = w_b + 0.2 * math.sin(2.0 * k) * np.array([1.0, 0.5, 0.0])
        f_b = f_b + 1.0 * math.cos(3.0 * k) * np.array([1.0, 0.0, 0.5])
    return {"imu_time": (k + 1) * DT, "imu_dt": DT,
            **{f"imu_dtheta_{a}": w_b[i] * DT for i, a in enumerate("xyz")},
            **{f"imu_dvel_{a}": f_b[i] * DT for i, a in enumerate("xyz")}}


def _start(name, moving):
    """Filter ``name`` with init_mode 'static' on 30 s of IMU (``moving(t)``: shaken at t),
    then fixes at 1.8 m/s: (the filter at its start, its notices)."""
    rng = np.random.default_rng(7)
    f = registry.REGISTRY[name](init_mode="static", init_lat=LAT, init_h=100.0,
                                p0_att_yaw=math.radians(100.0),
                                p0_accel_bias_ug=ACCEL_BIAS_SIGMA / 9.80665e-6)
    f.start(0.0)
    notices = []
    for k in range(320):
        f.advance(k * DT, DT, {**_imu(k, rng, moving(k * DT)), **walk_fix(k, DT, 30.0)})
        notices += f.take_notices()
        if f.out["aligned"]:
            return f, notices
    raise AssertionError("the filter did not start")


@pytest.mark.parametrize("name", ["Kf", "Ukf"])
def test_the_rest_after_a_motion_levels_the_imu_and_gives_the_gyro_biases(name):
    f, notices = _start(name, lambda t: 5.0 <= t < 8.0)
    assert not notices
    assert f.rest.rest_time == pytest.approx(22.0, abs=1.01)    # 8-30 s, whole windows
    roll, pitch = f.out["nav_roll"], f.out["nav_pitch"]
    # noise 0.01 m/s^2 over ~220 samples: 7e-4 m/s^2, 4e-3 deg of level
    assert math.degrees(abs(roll - ROLL)) < 0.01 and math.degrees(abs(pitch - PITCH)) < 0.01
    # what stays in the estimate: the horizontal Earth rate (11.5 deg/h) in the body axes,
    # and the noise, 1e-4 rad/s / sqrt(220) = 7e-6 rad/s per axis (3 sigma: 2e-5)
    horizontal = WGS84_OMEGA_IE * math.cos(LAT)
    stays = euler_to_dcm(ROLL, PITCH, YAW).T @ np.array([horizontal, 0.0, 0.0])
    np.testing.assert_allclose(f.engine.gyro_bias, GYRO_BIAS + stays, rtol=0, atol=2e-5)
    # the level's sigma is the accelerometer bias over g; the yaw's the course's, not 100 deg
    level_sigma = ACCEL_BIAS_SIGMA / earth.gravity(LAT, 100.0)
    assert f.out["std_att_n"] == pytest.approx(level_sigma, rel=0.01)
    # (the course of a 1.8 m/s walk with the default 0.3 m/s velocity sigma: 9.5 deg)
    assert f.out["std_att_d"] == pytest.approx(math.atan2(0.3, 1.8), rel=1e-6)


def test_data_that_is_not_static_warns_and_estimates_nothing():
    f, notices = _start("Kf", lambda t: True)
    assert len(notices) == 1
    assert "init_mode 'static': the IMU is not static" in notices[0]
    assert "limit 0.01" in notices[0]
    np.testing.assert_array_equal(f.engine.gyro_bias, np.zeros(3))


def test_the_rest_period_is_the_latest_run_of_windows_at_rest():
    det = RestDetector(1.0, 0.2, 0.01)
    still, shaken = ([0.0, 0.0, 1e-4], [0.0, 0.0, -0.98]), ([0.05, 0.0, 0.0], [0.3, 0.0, -0.98])
    for k in range(100):                    # 3 s at rest, 1 s shaken, 6 s at rest (10 Hz)
        dtheta, dvel = shaken if 30 <= k < 40 and k % 2 else still
        det.add_interval(dtheta, dvel, 0.1)
    assert det.rest_time == pytest.approx(6.0)
    assert det.rest.n == 60
    for k in range(20):                     # the vehicle drives off: the rest stays
        det.add_interval(*(shaken if k % 2 else still), 0.1)
    assert det.rest_time == pytest.approx(6.0) and not det.resting


def test_the_yaw_sigma_from_differenced_fixes_takes_the_receivers_sigmas_and_their_gap():
    """Position fixes 1 s apart with the receiver's 0.1 m sigmas (r_from_receiver): the
    velocity differenced from two fixes has sigma sqrt(2) 0.1 / 1 m/s, the course of a
    1.8 m/s walk atan(0.141 / 1.8) = 4.5 deg (r_pos_* = 5 m would say 76 deg)."""
    rng = np.random.default_rng(7)
    f = registry.REGISTRY["Kf"](init_mode="static", init_lat=LAT, init_h=100.0,
                                measurement="position", r_from_receiver=True,
                                p0_att_yaw=math.radians(100.0))
    f.start(0.0)
    std = {f"gnss_std_{a}": 0.1 for a in "ned"}
    for k in range(320):
        f.advance(k * DT, DT, {**_imu(k, rng, False), **walk_fix(k, DT, 30.0), **std})
        if f.out["aligned"]:
            break
    assert f.out["std_att_d"] == pytest.approx(math.atan(math.sqrt(2.0) * 0.1 / 1.8),
                                               rel=1e-6)


def test_a_state_taken_during_the_rest_continues_to_the_same_start():
    """The detector's sums are the filter's declared state: a filter restored from a state
    taken at 15 s starts, levelled and with the gyro biases, bit for bit as the original."""
    rng = np.random.default_rng(7)
    params = dict(init_mode="static", init_lat=LAT, init_h=100.0)
    f = registry.REGISTRY["Kf"](**params)
    f.start(0.0)
    inputs = [{**_imu(k, rng, 5.0 <= k * DT < 8.0), **walk_fix(k, DT, 30.0)} for k in range(320)]
    copy = None
    for k, step in enumerate(inputs):
        if k == 150:
            copy = registry.REGISTRY["Kf"](**params)
            copy.set_state(f.get_state())
        f.advance(k * DT, DT, step)
        if copy is not None:
            copy.advance(k * DT, DT, step)
        if f.out["aligned"]:
            break
    assert copy.out["aligned"] and copy.out == f.out
    np.testing.assert_array_equal(copy.engine.gyro_bias, f.engine.gyro_bias)
