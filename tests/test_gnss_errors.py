"""Tests of navcore.sensors.gnss_errors: noise statistics, steps, outliers, outages, errors."""
import copy
import math

import numpy as np
import pytest

from navcore.core.component import InputError, ParameterError
from navcore.ins.earth import lla_delta_to_ned
from navcore.sensors.gnss_errors import GnssErrorModel, parse_records

LAT, LON, H = math.radians(40.1), math.radians(118.6), 100.0    # paper 001 start point
V = np.array([50.0, -20.0, 1.0])
SIGMAS = {"pos_sigma_n": 4.42, "pos_sigma_e": 2.56, "pos_sigma_d": 3.43,   # paper 000
          "vel_sigma_n": 0.3, "vel_sigma_e": 0.2, "vel_sigma_d": 0.1}


def run(params, times, seed=1):
    """Measure a fix at each time; return (n,3) position errors NED [m], (n,3) velocity
    errors [m/s], valid and outlier flags (errors as recorded by the model, after checking
    that the measured lat/lon/h and velocity carry them)."""
    model = GnssErrorModel(params, seed)
    n = len(times)
    pos, vel = np.empty((n, 3)), np.empty((n, 3))
    valid, outlier = np.empty(n, bool), np.empty(n, bool)
    for k, t in enumerate(times):
        fix = model.measure(t, LAT, LON, H, V)
        # the model's own record of the errors is exact; the outputs must carry them
        pos[k], vel[k] = model.last_pos_error_ned, model.last_vel_error_ned
        back = lla_delta_to_ned(LAT, H, fix["lat"] - LAT, fix["lon"] - LON, fix["h"] - H)
        assert np.abs(back - pos[k]).max() < 1e-7
        assert np.abs(np.array([fix["vn"], fix["ve"], fix["vd"]]) - V - vel[k]).max() < 1e-12
        valid[k], outlier[k] = fix["valid"], fix["outlier"]
    return pos, vel, valid, outlier


def test_per_axis_std_matches_sigma_and_lla_conversion():
    times = np.arange(20000) * 1.0
    pos, vel, valid, outlier = run(SIGMAS, times)
    pos_sigma = [SIGMAS[f"pos_sigma_{a}"] for a in "ned"]
    vel_sigma = [SIGMAS[f"vel_sigma_{a}"] for a in "ned"]
    # 20000 samples per axis: standard error of the std 0.5 %
    np.testing.assert_allclose(pos.std(axis=0), pos_sigma, rtol=0.02)
    np.testing.assert_allclose(vel.std(axis=0), vel_sigma, rtol=0.02)
    assert np.all(np.abs(pos.mean(axis=0)) < 4 * np.array(pos_sigma) / math.sqrt(20000))
    assert valid.all() and not outlier.any()
    # the NED error converts to lat/lon/h exactly as the model's own record of it
    model = GnssErrorModel(SIGMAS, 5)
    fix = model.measure(0.0, LAT, LON, H, V)
    back = lla_delta_to_ned(LAT, H, fix["lat"] - LAT, fix["lon"] - LON, fix["h"] - H)
    np.testing.assert_allclose(back, model.last_pos_error_ned, atol=1e-8)


def test_noise_steps_change_std_only_inside_windows():
    # paper 001: velocity noise 0.3 m/s, 1.5 m/s at 50-100 s, 3 m/s at 200-300 s
    base = {"pos_sigma_n": 5, "pos_sigma_e": 5, "pos_sigma_d": 5,
            "vel_sigma_n": 0.3, "vel_sigma_e": 0.3, "vel_sigma_d": 0.3}
    steps = {**base, "noise_steps": "50,100,vel,1.5,1.5,1.5; 200,300,vel,3,3,3"}
    times = np.arange(500) * 1.0
    pos0, vel0, _, _ = run(base, times)
    pos1, vel1, _, _ = run(steps, times)
    in1 = (times >= 50) & (times < 100)
    in2 = (times >= 200) & (times < 300)
    out = ~in1 & ~in2
    np.testing.assert_array_equal(vel1[out], vel0[out])
    np.testing.assert_allclose(vel1[in1], vel0[in1] * 5.0, rtol=1e-12)     # 1.5 / 0.3
    np.testing.assert_allclose(vel1[in2], vel0[in2] * 10.0, rtol=1e-12)    # 3 / 0.3
    np.testing.assert_allclose(pos1, pos0, rtol=1e-12, atol=1e-9)          # position untouched
    # and statistically, over many fixes inside a step
    times = np.arange(10000) * 0.1
    _, vel, _, _ = run({**base, "noise_steps": "0,500,vel,1.5,0.6,3"}, times)
    inside = times < 500
    np.testing.assert_allclose(vel[inside].std(axis=0), [1.5, 0.6, 3.0], rtol=0.04)
    np.testing.assert_allclose(vel[~inside].std(axis=0), [0.3, 0.3, 0.3], rtol=0.04)
    model = GnssErrorModel(steps, 0)
    np.testing.assert_array_equal(model.sigma_at(75.0)[1], [1.5, 1.5, 1.5])
    np.testing.assert_array_equal(model.sigma_at(100.0)[1], [0.3, 0.3, 0.3])


def test_outlier_patch_hits_named_axes_inside_window_only():
    # paper 001: 15 m/s outlier patch on east and north velocity at 350-360 s
    times = np.arange(0, 500, 0.2)
    clean_pos, clean_vel, _, clean_flag = run(SIGMAS, times)
    pos, vel, valid, flag = run({**SIGMAS, "outlier_patches": "350,360,vel,ne,15"}, times)
    inside = (times >= 350 - 1e-9) & (times < 360 - 1e-9)
    assert inside.sum() == 50
    np.testing.assert_array_equal(flag, inside)
    assert not clean_flag.any()
    np.testing.assert_allclose(pos, clean_pos, rtol=1e-12, atol=1e-9)
    added = vel - clean_vel
    assert not added[~inside].any()
    assert not added[inside, 2].any()                                  # down axis untouched
    magnitude = np.abs(added[inside, :2])
    assert magnitude.min() >= 7.5 - 1e-9 and magnitude.max() <= 15.0 + 1e-9
    assert (added[inside, :2] > 0).any() and (added[inside, :2] < 0).any()  # random sign


def test_patch_window_edges_with_accumulated_times():
    # times built by accumulating 0.1 s are slightly off (e.g. 349.99999999999...)
    times, t = [], 0.0
    for _ in range(4000):
        times.append(t)
        t += 0.1
    times = np.array(times)
    _, _, _, flag = run({**SIGMAS, "outlier_patches": "350,360,pos,d,20"}, times)
    assert flag.sum() == 100
    assert np.round(times[flag][0], 6) == 350.0 and np.round(times[flag][-1], 6) == 359.9


def test_periodic_outliers_at_expected_epochs_with_m_times_sigma():
    # paper 004: 1 s fixes, one m-times outlier every 10 s
    m = 6.0
    params = {**SIGMAS, "outlier_period": 10.0, "outlier_offset": 5.0, "outlier_multiple": m,
              "fix_interval": 1.0, "noise_steps": "100,200,pos,10,10,10"}
    times = np.arange(0, 300) * 1.0
    clean_pos, clean_vel, _, _ = run({**SIGMAS, "noise_steps": "100,200,pos,10,10,10"}, times)
    pos, vel, valid, flag = run(params, times)
    expected = (times >= 5) & (np.mod(times - 5, 10) == 0)
    np.testing.assert_array_equal(flag, expected)
    assert expected.sum() == 30
    pos_sigma = np.array([SIGMAS[f"pos_sigma_{a}"] for a in "ned"])
    vel_sigma = np.array([SIGMAS[f"vel_sigma_{a}"] for a in "ned"])
    step = (times >= 100) & (times < 200)
    sigma_in_force = np.where(step[:, None], 10.0, pos_sigma)
    added_pos, added_vel = pos - clean_pos, vel - clean_vel
    np.testing.assert_allclose(np.abs(added_pos[expected]), m * sigma_in_force[expected],
                               rtol=1e-6)
    np.testing.assert_allclose(np.abs(added_vel[expected]), m * vel_sigma * np.ones((30, 3)),
                               rtol=1e-9)
    assert np.abs(added_pos[~expected]).max() < 1e-8 and not added_vel[~expected].any()
    # total error at an outlier epoch is a gross error (noise is at most a few sigma)
    assert np.all(np.abs(vel[expected]) >= (m - 4.5) * vel_sigma)
    assert (added_vel[expected] > 0).any() and (added_vel[expected] < 0).any()


def test_periodic_outliers_pick_the_nearest_fix_at_10_hz():
    times, t = [], 0.0
    for _ in range(1000):            # 10 Hz, accumulated: drifts off the exact multiples
        times.append(t)
        t += 0.1
    times = np.array(times)
    params = {**SIGMAS, "outlier_period": 10.0, "outlier_offset": 0.0, "outlier_multiple": 3,
              "fix_interval": 0.1}
    _, _, _, flag = run(params, times)
    np.testing.assert_allclose(times[flag], [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0,
                                             80.0, 90.0], atol=1e-9)
    # an epoch that falls between fixes goes to the nearest one
    model = GnssErrorModel({**params, "outlier_offset": 0.04}, 0)
    assert model.is_periodic_outlier_epoch(10.0) and not model.is_periodic_outlier_epoch(10.1)
    model = GnssErrorModel({**params, "outlier_offset": 0.06}, 0)
    assert model.is_periodic_outlier_epoch(10.1) and not model.is_periodic_outlier_epoch(10.0)
    assert not model.is_periodic_outlier_epoch(-9.94)     # before the first epoch


def test_outages_set_valid_false_and_keep_the_noise_of_other_epochs():
    times = np.arange(0, 200) * 1.0
    pos0, vel0, valid0, _ = run(SIGMAS, times)
    pos1, vel1, valid1, _ = run({**SIGMAS, "outages": "20,40; 150.5,160"}, times)
    outage = ((times >= 20) & (times < 40)) | ((times >= 151) & (times < 160))
    np.testing.assert_array_equal(valid1, ~outage)
    assert valid0.all()
    # same draws per fix whatever the windows: identical values at every epoch
    np.testing.assert_array_equal(pos1, pos0)
    np.testing.assert_array_equal(vel1, vel0)
    assert np.isfinite(pos1).all() and np.isfinite(vel1).all()
    # a patch elsewhere does not shift the noise of the other epochs either
    pos2, vel2, _, _ = run({**SIGMAS, "outlier_patches": "50,60,pos,ned,30"}, times)
    other = (times < 50) | (times >= 60)
    np.testing.assert_array_equal(pos2[other], pos0[other])
    np.testing.assert_array_equal(vel2, vel0)


def test_same_seed_identical_and_deepcopy_continues():
    params = {**SIGMAS, "outlier_patches": "10,20,vel,ne,15", "outlier_period": 7,
              "outlier_multiple": 5, "noise_steps": "30,40,pos,9,9,9", "outages": "45,50"}
    times = np.arange(0, 60, 0.5)
    a = run(params, times, seed=3)
    b = run(params, times, seed=3)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    c = run(params, times, seed=4)
    assert not np.array_equal(a[0], c[0])
    model = GnssErrorModel(params, 3)
    for t in times[:60]:
        model.measure(t, LAT, LON, H, V)
    saved = copy.deepcopy(model)
    rest = [model.measure(t, LAT, LON, H, V) for t in times[60:]]
    again = [saved.measure(t, LAT, LON, H, V) for t in times[60:]]
    assert rest == again


@pytest.mark.parametrize("name,value,fragment", [
    ("pos_sigma_n", -1.0, "outside the accepted range [0, 10000] m"),
    ("pos_sigma_e", 1e300, "outside the accepted range [0, 10000] m"),
    ("noise_steps", "1,2,vel,1,1e300,1", "se"),
    ("noise_steps", "1,2,vel,1,500,1", "[0, 100] m/s"),
    ("outlier_patches", "1,2,vel,ne,1e300", "peak"),
    ("vel_sigma_d", float("nan"), "finite"),
    ("vel_sigma_e", "fast", "number"),
    ("fix_interval", 0.0, "(0, 3600] s"),
    ("outlier_multiple", -3.0, "[0, 10000]"),
    ("noise_steps", "1,2,acc,1,1,1", "1,2,acc,1,1,1"),
    ("noise_steps", "1,2,pos,1,1", "5 fields"),
    ("noise_steps", "1,2,pos,1,-1,1", "se"),
    ("noise_steps", "5,2,pos,1,1,1", "t1 must be after t0"),
    ("outlier_patches", "1,2,vel,nx,5", "axes"),
    ("outlier_patches", "1,2,vel,nn,5", "axes"),
    ("outlier_patches", "1,2,vel,ne,-5", "peak"),
    ("outlier_patches", "350,360,vel,ne", "350,360,vel,ne"),
    ("outages", "1,x", "t1"),
    ("outages", "10,20; 30", "'30'"),
])
def test_bad_parameters_raise_naming_parameter(name, value, fragment):
    with pytest.raises(ParameterError, match=name) as err:
        GnssErrorModel({**SIGMAS, name: value}, seed=0)
    assert fragment in str(err.value)


def test_unknown_parameter_and_bad_inputs():
    with pytest.raises(ParameterError, match="pos_sigma_x"):
        GnssErrorModel({"pos_sigma_x": 1.0}, seed=0)
    model = GnssErrorModel(SIGMAS, 0)
    with pytest.raises(InputError, match="lat"):
        model.measure(0.0, float("nan"), LON, H, V)
    with pytest.raises(InputError, match="v_ned"):
        model.measure(0.0, LAT, LON, H, [0.0, math.inf, 0.0])
    with pytest.raises(InputError, match="v_ned"):
        model.measure(0.0, LAT, LON, H, [0.0, 0.0])


def test_parse_records():
    fields = (("t0", float), ("t1", float), ("what", str))
    assert parse_records("", "p", fields) == []
    assert parse_records(" 1,2,a ;3,4, b;", "p", fields) == [(1.0, 2.0, "a"), (3.0, 4.0, "b")]
    assert parse_records([(1, 2, "a")], "p", fields) == [(1.0, 2.0, "a")]
    with pytest.raises(ParameterError, match="parameter 'p'"):
        parse_records("1,2", "p", fields)
