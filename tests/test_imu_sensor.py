"""ImuSensor: TrajectoryImu's IMU on a vehicle's truth inputs.

The reference is TrajectoryImu itself, an independent path to the same increments: it builds
them from its motion profile's kinematics, ImuSensor from the truth signals alone (rounded
through the outputs' angle wrapping).  The truth outputs wrap roll and yaw into (-pi, pi]
(``wrap_pi``: ``fmod(a + pi, 2 pi) - pi``), which rounds them by up to one unit in the last
place of pi (4.4e-16 rad) even inside the range, while the generator's rotation matrices come
from the unwrapped angles; on a profile where roll or yaw move the increments therefore agree
to ``DTHETA_TOL``/``DVEL_TOL`` (two attitudes each rounded by 4.4e-16 rad, times 4 margin),
with every random draw identical (the same seed, the same error-model code)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from imu_sensor_models import through_imu_sensor
from navcore.components.imu_sensor import RATE_NAMES, TRUTH_NAMES
from navcore.components.registry import ImuSensor, TrajectoryImu
from navcore.core import signals
from navcore.errors import InputError, ParameterError
from orchestrator.running import scenarios

MODELS = Path(__file__).resolve().parents[1] / "models"
IMU_NAMES = tuple(p.name for p in signals.IMU + signals.MAG)
#: increments' tolerance past an angle wrap (module docstring) [rad], [m/s]
DTHETA_TOL = 4 * 2 * 4.4e-16
DVEL_TOL = 1e-15
ERRORS = dict(gyro_bias_dph=5.0, gyro_arw_dpsh=0.06, accel_bias_ug=100.0,
              accel_vrw_ugpsHz=10.0, gyro_scale_factor_ppm=300.0, noise_intensity_gain=5.0,
              mag_field_T=5e-5, mag_noise_T=1e-7, seed=7)


def _pair(profile, dt=0.01, **errors):
    trajectory = TrajectoryImu(profile=profile, imu_period=dt, **errors)
    sensor = ImuSensor(imu_period=dt, **errors)
    truth = trajectory.start(0.0)
    sensor.start(0.0)
    started = sensor.initial_inputs(truth)
    return trajectory, sensor, truth, started


def _fly(profile, n, dt=0.01, **errors):
    """(trajectory outputs, sensor outputs) per sample, the sensor on the trajectory's truth."""
    trajectory, sensor, truth, started = _pair(profile, dt, **errors)
    a, b = [truth], [started]
    for k in range(n):
        out = trajectory.advance(k * dt, dt, {})
        a.append(dict(out))
        b.append(dict(sensor.advance(k * dt, dt, out)))
    return a, b


def test_sensor_on_the_trajectorys_truth_gives_its_imu_outputs_bit_for_bit():
    # aircraft_500s' first 200 s: roll and yaw stay at 0, where the wrap is exact
    a, b = _fly("aircraft_500s", 20000, **ERRORS)
    for x, y in zip(a, b):
        assert all(x[n] == y[n] for n in IMU_NAMES)
    assert abs(a[-1]["imu_dvel_x"]) > 0 and a[-1]["mag_x"] != 0.0


def test_sensor_on_a_manoeuvring_truth_agrees_to_the_wrapping_rounding():
    a, b = _fly("uav_maneuver", 30000, dt=0.02, **ERRORS)
    dtheta = max(abs(x[f"imu_dtheta_{c}"] - y[f"imu_dtheta_{c}"]) for x, y in zip(a, b)
                 for c in "xyz")
    dvel = max(abs(x[f"imu_dvel_{c}"] - y[f"imu_dvel_{c}"]) for x, y in zip(a, b) for c in "xyz")
    assert 0.0 < dtheta <= DTHETA_TOL and dvel <= DVEL_TOL
    assert all(x["imu_time"] == y["imu_time"] and x["mag_x"] == y["mag_x"] for x, y in zip(a, b))
    # the errors are applied (the comparison is not of two ideal IMUs)
    assert max(abs(x["imu_gyro_z"]) for x in a) > 0.01


def _kf_metrics(model_dir, stop):
    run = scenarios.simulate_scenario(scenarios.load_scenario(model_dir), backend="direct",
                                      stop_time=stop, log=None)
    return run.metrics["filter"]


def _same_metrics(a, b, rel):
    for key in ("position_rms_m", "velocity_rms_mps", "attitude_rms_deg", "position_max_m"):
        assert a[key].keys() == b[key].keys()
        np.testing.assert_allclose(list(b[key].values()), list(a[key].values()), rtol=rel,
                                   atol=0.0, err_msg=key)


def test_kf_on_aircraft_500s_through_the_sensor_gives_the_same_metrics(tmp_path):
    via = through_imu_sensor(MODELS / "aircraft_500s", tmp_path / "aircraft_500s")
    a, b = _kf_metrics(MODELS / "aircraft_500s", None), _kf_metrics(via, None)
    # bit for bit until the final turn moves yaw (then the rounding of the module
    # docstring: measured 4e-14 relative on the down RMS)
    _same_metrics(a, b, 1e-9)


@pytest.mark.parametrize("stop", [pytest.param(300.0, id="300s"),
                                  pytest.param(None, id="full", marks=pytest.mark.slow)])
def test_kf_on_uav_maneuver_through_the_sensor_gives_the_same_metrics(tmp_path, stop):
    via = through_imu_sensor(MODELS / "uav_maneuver", tmp_path / "uav_maneuver")
    a, b = _kf_metrics(MODELS / "uav_maneuver", stop), _kf_metrics(via, stop)
    # increments differing by 1e-15 rad move the filter's RMS by rounding only
    _same_metrics(a, b, 1e-9)


# -- refusals ------------------------------------------------------------------------------
def _started_sensor(**params):
    trajectory, sensor, truth, _ = _pair("aircraft_500s", **params)
    return trajectory, sensor


def _refusal(truth_change, k=0):
    trajectory, sensor = _started_sensor()
    for i in range(k):
        sensor.advance(i * 0.01, 0.01, trajectory.advance(i * 0.01, 0.01, {}))
    out = dict(trajectory.advance(k * 0.01, 0.01, {}))
    out.update(truth_change(out))
    with pytest.raises(InputError) as err:
        sensor.advance(k * 0.01, 0.01, out)
    return str(err.value)


@pytest.mark.parametrize("change, words", [
    (lambda o: {"truth_vn": math.nan}, ["input 'truth_vn' = nan"]),
    (lambda o: {"truth_h": math.inf}, ["input 'truth_h' = inf"]),
    (lambda o: {"truth_time": o["truth_time"] - 0.02}, ["'truth_time'", "goes back",
                                                       "at 0.04"]),
    (lambda o: {"truth_time": o["truth_time"] + 0.005}, ["'truth_time' = 0.055",
                                                        "imu_period' = 0.01"]),
    (lambda o: {"truth_vn": o["truth_vn"] + 20.0}, ["'truth_vn'", "truth_time = 0.05 s",
                                                   "20 m/s"]),
    (lambda o: {"truth_yaw": o["truth_yaw"] + 1.0}, ["'truth_roll'", "turns by 1 rad",
                                                    "truth_time = 0.05 s"]),
    (lambda o: {"truth_lat": o["truth_lat"] + 1e-4}, ["'truth_lat'", "truth_time = 0.05 s",
                                                     "from where the velocities lead"]),
], ids=["nan", "inf", "back", "interval", "velocity-jump", "attitude-jump", "position-jump"])
def test_bad_truth_is_refused_naming_the_input_and_the_time(change, words):
    message = _refusal(change, k=4)
    assert message.startswith("ImuSensor: input '")
    for w in words:
        assert w in message, message


def test_a_repeated_sample_holds_and_a_missing_start_is_named():
    trajectory, sensor = _started_sensor()
    first = dict(trajectory.advance(0.0, 0.01, {}))
    out = dict(sensor.advance(0.0, 0.01, first))
    assert sensor.advance(0.01, 0.01, first) == out      # the same truth_time again: hold
    # no start sample (a host setting no inputs in initialization mode): the first truth
    # starts the sensor, with a warning, and the next one closes the first interval
    fresh = ImuSensor()
    fresh.start(0.0)
    assert fresh.initial_inputs({n: 0.0 for n in TRUTH_NAMES + RATE_NAMES}) is None
    held = dict(fresh.advance(0.0, 0.01, first))
    assert held["imu_dt"] == 0.0
    assert "no truth at the start time 0.0 s" in fresh.take_notices()[0]
    second = dict(trajectory.advance(0.01, 0.01, {}))
    out = fresh.advance(0.01, 0.01, second)
    assert out["imu_time"] == second["truth_time"] and out["imu_dt"] == 0.01


def test_an_unknown_input_form_is_refused():
    with pytest.raises(ParameterError, match="'input_form' = 'rate'"):
        ImuSensor(input_form="rate").start(0.0)
