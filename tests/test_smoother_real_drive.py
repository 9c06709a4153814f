"""The smoother on the real car's first seconds (tests/data/rtklib_drive: the car at rest,
RTK fixes at 4 Hz): a 5 s outage cut into the fixes, the Kf and its smoothed solution
against the uncut fixes, and the rest the static alignment's detector finds in the IMU."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.filters.initial_state import level
from navcore.filters.static_alignment import RestDetector
from navcore.sensors.sensorlog import SensorLog, read_log, write_log
from orchestrator.cli.convert import convert_imu_csv, convert_rtklib, imu_csv_spec
from orchestrator.results import metrics as nav_metrics
from orchestrator.running import scenarios, smoothing

from test_rts_smoother import ROOT

DRIVE = ROOT / "tests" / "data" / "rtklib_drive"
#: the sensor's axes to the car's (forward, right, down): roll 180 and yaw 180 deg, the
#: drive's own rotation without its 6.8 deg pitch and 5.4 deg yaw (the alignment levels)
AXES = {"gyro": "x=-col4,y=col5,z=-col6", "accel": "x=-col1,y=col2,z=-col3"}
OUTAGE = (5.0, 10.0)                        # [s] of the log's time (after 1752003261 s)


@pytest.fixture(scope="module")
def drive_log(tmp_path_factory):
    """The trimmed drive as a sensor log: the fixes inside OUTAGE invalid, the uncut fixes
    within the IMU's span as the truth (attitude not known: 0, not scored)."""
    raw = tmp_path_factory.mktemp("drive") / "raw"
    convert_rtklib(DRIVE / "gnss_1934_sf_trimmed.pos", raw, time_scale="unix")
    spec = imu_csv_spec(None, {"time": 7, "time_unit": "ms", "start": "1752003261.854",
                               "gyro_unit": "deg/s", "accel_unit": "g", **AXES})
    convert_imu_csv(DRIVE / "imu_1934_trimmed.csv", raw, spec)
    log = read_log(raw)
    g = dict(log.gnss)
    inside = (g["time"] > log.imu["time"][0]) & (g["time"] < log.imu["time"][-1])
    g = {k: v[inside] for k, v in g.items()}
    zero = 0.0 * g["time"]
    truth = {"time": g["time"].copy(), **{k: g[k].copy() for k in
                                          ("lat", "lon", "h", "vn", "ve", "vd")},
             "roll": zero, "pitch": zero, "yaw": zero}
    g["valid"] = np.where((g["time"] > OUTAGE[0]) & (g["time"] <= OUTAGE[1]), 0.0, g["valid"])
    cut = raw.parent / "log"
    write_log(cut, SensorLog(log.imu, g, truth, log.time_origin))
    return cut, read_log(cut)


def _parameters(log):
    """Kf from the first fix at rest, levelled on the first 2 s of the IMU."""
    imu = log.imu
    first = imu["time"] <= imu["time"][0] + 2.0
    f = np.array([imu[f"dvel_{a}"][first].sum() for a in "xyz"]) / imu["dt"][first].sum()
    roll, pitch = level(f)
    g = log.gnss
    return {"filter.init_lat": float(g["lat"][0]), "filter.init_lon": float(g["lon"][0]),
            "filter.init_h": float(g["h"][0]), "filter.init_roll": roll,
            "filter.init_pitch": pitch, "filter.p0_pos": 0.05, "filter.p0_vel": 0.05,
            "filter.p0_att_level": 0.02, "filter.p0_att_yaw": 0.1,
            "filter.p0_gyro_bias_dph": 720.0, "filter.p0_accel_bias_ug": 20000.0,
            "filter.measurement": "position", "filter.r_from_receiver": True,
            "filter.q_gyro_arw_dpsh": 0.228, "filter.q_accel_vrw_ugpsHz": 140.0}


def _outage_rms(run):
    e = nav_metrics.navigation_errors(run.results, scenarios.FILTER_COMPONENT)
    inside = e["valid"] & (e["time"] > OUTAGE[0]) & (e["time"] <= OUTAGE[1])
    return math.sqrt(np.mean(e["pos_n"][inside] ** 2 + e["pos_e"][inside] ** 2
                             + e["pos_d"][inside] ** 2))


def test_the_smoother_on_the_real_car_at_rest(drive_log):
    folder, log = drive_log
    model = scenarios.load_scenario(ROOT / "models" / "replay_gnss_ins_sim")
    common = dict(filter="Kf", log=None, replay=folder, parameters=_parameters(log))
    forward = scenarios.simulate_scenario(model, backend="direct", **common)
    smoothed = smoothing.smoothed_run(model, **common)
    rms_forward, rms_smoothed = _outage_rms(forward), _outage_rms(smoothed)
    # measured: 0.22 m forward (5 s of INS at rest), 0.014 m smoothed (the 1-cm fixes)
    assert rms_forward > 0.1
    assert rms_smoothed < 0.05 and rms_smoothed < 0.2 * rms_forward, (rms_smoothed,
                                                                      rms_forward)
    # at rest the IMU's clock cannot be matched to the fixes' course: no second run
    meta = smoothed.results.metadata["smoother"]
    assert meta["imu_time_offset_s"] == 0.0
    assert "while moving" in meta["imu_time_offset_not_estimated"], meta


def test_the_detector_finds_the_car_at_rest(drive_log):
    """The raw 100 Hz rates of the idling car scatter by 0.026 rad/s at the quietest: above
    the default limit (the warning names it), inside a limit of 0.05 rad/s, which then
    takes the whole 12 s; the gyro bias is the mean rate less the vertical Earth rate."""
    _, log = drive_log
    imu = log.imu
    lat = float(log.gnss["lat"][0])
    strict, loose = RestDetector(), RestDetector(1.0, 0.2, 0.05)
    for k in range(len(imu["time"])):
        for det in (strict, loose):
            det.add_interval([imu[f"dtheta_{a}"][k] for a in "xyz"],
                             [imu[f"dvel_{a}"][k] for a in "xyz"], imu["dt"][k])
    warning = strict.estimate(lat, np.full(3, 0.2), 9.8)[-1]
    assert "the IMU is not static" in warning and "limit 0.01" in warning
    assert 0.02 < strict.quietest[1] < 0.03
    assert loose.rest_time == pytest.approx(12.0, abs=1.0)
    roll, pitch, _, bias, _, warning = loose.estimate(lat, np.full(3, 0.2), 9.8)
    assert warning is None
    n = loose.rest.n
    mean_rate = np.array([imu[f"dtheta_{a}"][:n].sum() for a in "xyz"]) / imu["dt"][:n].sum()
    np.testing.assert_allclose(bias, mean_rate, rtol=0, atol=6e-5)    # Earth: 4.7e-5 rad/s
    assert abs(math.degrees(pitch)) > 3.0     # the 6.8 deg pitch of the mount, roughly
