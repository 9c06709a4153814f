"""Paper 003's sensors and attitude filters without FMI: the magnetometer on a turntable,
the rotate segment, the vibration disturbance, and UkfAhrs/FuzzyUkfAhrs on short runs."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navcore.core import signals
from navcore.filters.ahrs import triad_attitude
from navcore.components.ahrs_components import FuzzyUkfAhrs, UkfAhrs
from navcore.core.component import ParameterError
from navcore.components.registry import TrajectoryImu
from navcore.ins.rotations import wrap_angle

H, INCL = 5.4e-5, math.radians(56.8)
FIELD_NED = np.array([H * math.cos(INCL), 0.0, H * math.sin(INCL)])
TABLE = {"start": {"lat_deg": 38.0, "lon_deg": 114.5, "h": 80.0, "roll_deg": 5.0,
                   "pitch_deg": -10.0, "yaw_deg": 170.0},
         "segments": [{"type": "static", "duration": 2.0},
                      {"type": "hold_attitude", "duration": 4.0, "roll_deg": -20.0,
                       "pitch_deg": 30.0, "yaw_deg": -60.0},
                      {"type": "rotate", "duration": 6.0, "axis_n": 1.0, "axis_e": 1.0,
                       "axis_d": 0.0, "rate_deg": 10.0, "transition": 1.0},
                      {"type": "rotate", "duration": 8.0, "angle_deg": 200.0}]}


@pytest.fixture(scope="module")
def profiles(tmp_path_factory):
    """Write a profile dict to a JSON file (the 'profile' parameter is a name or a path)."""
    folder = tmp_path_factory.mktemp("profiles")
    counter = iter(range(1000))

    def write(profile):
        path = folder / f"p{next(counter)}.json"
        path.write_text(json.dumps(profile))
        return str(path)

    return write


def _trajectory(profile, period=0.02, **params):
    t = TrajectoryImu(profile=profile, imu_period=period, mag_field_T=H,
                      mag_inclination=INCL, **params)
    return t, t.initialize(0.0)


def test_noiseless_magnetometer_is_the_rotated_field(profiles):
    traj, out = _trajectory(profiles(TABLE))
    worst = 0.0
    for k in range(1000):
        out = traj.step(k * 0.02, 0.02, {})
        C_bn = Rotation.from_euler("ZYX", [out["truth_yaw"], out["truth_pitch"],
                                           out["truth_roll"]]).as_matrix()
        expected = C_bn.T @ FIELD_NED
        got = np.array([out["mag_x"], out["mag_y"], out["mag_z"]])
        worst = max(worst, float(np.max(np.abs(got - expected))))
        assert out["mag_time"] == out["imu_time"]
    assert worst <= 1e-12 * H


def test_hard_and_soft_iron(profiles):
    soft = "1.02,0.01,0,0.01,0.98,0,0,0,1.01"
    traj, out = _trajectory(
        profiles(TABLE), mag_hard_iron_x=1e-6, mag_hard_iron_z=-2e-6, mag_soft_iron=soft
    )
    C_bn = Rotation.from_euler("ZYX", [out["truth_yaw"], out["truth_pitch"],
                                       out["truth_roll"]]).as_matrix()
    S = np.array([float(v) for v in soft.split(",")]).reshape(3, 3)
    expected = S @ C_bn.T @ FIELD_NED + np.array([1e-6, 0.0, -2e-6])
    np.testing.assert_allclose([out["mag_x"], out["mag_y"], out["mag_z"]], expected,
                               atol=1e-12 * H)
    with pytest.raises(ParameterError, match="mag_soft_iron"):
        _trajectory("turntable_240s", mag_soft_iron="1,2,3")


def test_rotate_segment_ends_on_the_rotated_attitude(profiles):
    traj, out = _trajectory(profiles(TABLE))
    for k in range(1000):
        out = traj.step(k * 0.02, 0.02, {})
    # the last segment turns 200 deg about down from the end of the previous one
    before = TrajectoryImu(profile=profiles({**TABLE, "segments": TABLE["segments"][:3]}),
                           imu_period=0.02)
    b = before.initialize(0.0)
    for k in range(600):
        b = before.step(k * 0.02, 0.02, {})
    start = Rotation.from_euler("ZYX", [b["truth_yaw"], b["truth_pitch"], b["truth_roll"]])
    end = Rotation.from_rotvec([0.0, 0.0, math.radians(200.0)]) * start
    np.testing.assert_allclose(
        [out["truth_roll"], out["truth_pitch"], out["truth_yaw"]],
        end.as_euler("ZYX")[::-1], atol=1e-9)


def test_rotate_segment_checks_its_parameters(profiles):
    bad = {"start": TABLE["start"], "segments": [{"type": "rotate", "duration": 5.0,
                                                  "axis_n": 0, "axis_d": 0, "rate_deg": 5}]}
    with pytest.raises(ParameterError, match="axis_n"):
        TrajectoryImu(profile=profiles(bad)).initialize(0.0)
    tilt = {
        "start": {**TABLE["start"], "yaw_deg": 0.0},
        "segments": [
            {"type": "rotate", "duration": 5.0, "axis_e": 1, "axis_d": 0, "angle_deg": 120}
        ],
    }
    with pytest.raises(ParameterError, match="pitch"):
        TrajectoryImu(profile=profiles(tilt)).initialize(0.0)


def test_magnetometer_leaves_the_imu_numbers_unchanged():
    common = dict(profile="turntable_240s", imu_period=0.02, seed=4, gyro_arw_dpsh=0.5,
                  accel_vrw_ugpsHz=300.0, gyro_bias_dph=20.0)
    plain = TrajectoryImu(**common)
    plain.initialize(0.0)
    with_mag, _ = _trajectory("turntable_240s", seed=4, gyro_arw_dpsh=0.5,
                              accel_vrw_ugpsHz=300.0, gyro_bias_dph=20.0, mag_noise_T=1e-7)
    for k in range(200):
        a, b = plain.step(k * 0.02, 0.02, {}), with_mag.step(k * 0.02, 0.02, {})
        for p in signals.IMU:
            assert a[p.name] == b[p.name]
        assert a["mag_x"] == 0.0 and b["mag_x"] != 0.0


def test_vibration_raises_accelerometer_and_magnetometer_noise():
    traj, _ = _trajectory("turntable_240s", mag_noise_T=1e-7, vibration_start_s=10.0,
                          vibration_accel_noise_mps2=0.5, vibration_mag_factor=4.0)
    rows = []
    for k in range(1000):
        o = traj.step(k * 0.02, 0.02, {})
        rows.append((o["imu_time"], o["imu_accel_x"], o["mag_y"]))
    rows = np.array(rows)
    quiet, loud = rows[:, 0] < 10.0, rows[:, 0] >= 10.0
    assert np.std(rows[quiet, 1]) < 1e-9                 # no accelerometer noise configured
    assert np.std(rows[loud, 1]) == pytest.approx(0.5, rel=0.1)
    assert np.std(rows[quiet, 2]) == pytest.approx(1e-7, rel=0.15)
    assert np.std(rows[loud, 2]) == pytest.approx(4e-7, rel=0.15)


def test_triad_recovers_the_attitude():
    C_bn = Rotation.from_euler("ZYX", [2.5, -0.4, 0.3]).as_matrix()
    f_b = C_bn.T @ np.array([0.0, 0.0, -9.8])
    m_b = C_bn.T @ FIELD_NED
    np.testing.assert_allclose(triad_attitude(f_b, m_b, INCL), C_bn, atol=1e-12)


AHRS_PARAMS = dict(mag_field_T=H, mag_inclination=INCL, gravity_mps2=9.7997,
                   r_accel_mps2=0.0208, r_mag_T=1e-7, q_gyro_arw_dpsh=0.5,
                   p0_gyro_bias_dph=50.0)
SENSORS = dict(seed=3, gyro_arw_dpsh=0.5, gyro_bias_dph=50.0, accel_vrw_ugpsHz=300.0,
               mag_noise_T=1e-7)


def _run(cls, profile, n, delay=0, **params):
    """Trajectory and filter stepped side by side; ``delay`` steps of input lag (Jacobi)."""
    traj, out = _trajectory(profile, **SENSORS)
    f = cls(**{**AHRS_PARAMS, **params})
    f.initialize(0.0)
    names = [p.name for p in f.inputs]
    queue = [{n_: out[n_] for n_ in names}] * delay
    rows = []
    for k in range(n):
        out = traj.step(k * 0.02, 0.02, {})
        queue.append({n_: out[n_] for n_ in names})
        fo = f.step(k * 0.02, 0.02, queue.pop(0))
        rows.append([fo["nav_time"], fo["nav_roll"], fo["nav_pitch"], fo["nav_yaw"],
                     fo["std_roll"], fo["std_pitch"], fo["std_yaw"], out["imu_time"],
                     out["truth_roll"], out["truth_pitch"], out["truth_yaw"]])
    return f, np.array(rows)


@pytest.mark.parametrize("cls", [UkfAhrs, FuzzyUkfAhrs])
def test_filter_is_accurate_and_consistent_at_rest(cls):
    f, r = _run(cls, "turntable_240s", 3000)
    assert np.all(r[:, 0] == r[:, 7])                       # solution valid at imu_time
    late = r[500:]
    err = wrap_angle(late[:, 1:4] - late[:, 8:11])
    rms = np.sqrt(np.mean(err ** 2, axis=0))
    assert np.all(np.degrees(rms) < [0.05, 0.05, 0.15])
    normalized = np.sqrt(np.mean((err / late[:, 4:7]) ** 2, axis=0))
    assert np.all(normalized < 1.5) and np.all(normalized > 0.5)


def test_filter_through_the_shadow_set_switch(profiles):
    """A table turning 200 deg in yaw from yaw 170: |sigma| crosses 1, the state switches to
    the shadow set and the attitude stays accurate."""
    profile = {"start": TABLE["start"], "segments": [
        {"type": "static", "duration": 5.0},
        {"type": "rotate", "duration": 20.0, "angle_deg": 200.0, "transition": 3.0},
        {"type": "static", "duration": 5.0}]}
    f, r = _run(UkfAhrs, profiles(profile), 1500)
    assert f.engine.shadow_switches >= 1
    err = wrap_angle(r[250:, 1:4] - r[250:, 8:11])
    assert np.degrees(np.max(np.abs(err))) < 0.5


def test_time_tags_not_call_order_decide():
    """Inputs one step late (Jacobi exchange): the same solutions, one step later."""
    _, now = _run(FuzzyUkfAhrs, "turntable_240s", 600)
    _, late = _run(FuzzyUkfAhrs, "turntable_240s", 601, delay=1)
    np.testing.assert_array_equal(now[:, :7], late[1:, :7])


def test_bad_parameters_name_themselves():
    with pytest.raises(ParameterError, match="r_accel_mps2"):
        UkfAhrs(r_accel_mps2=-1.0).initialize(0.0)
    with pytest.raises(ParameterError, match="fuzzy_window"):
        FuzzyUkfAhrs(fuzzy_window=1).initialize(0.0)
    with pytest.raises(ParameterError, match="init_attitude"):
        UkfAhrs(init_attitude="guess").initialize(0.0)
