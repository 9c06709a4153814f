"""The offline calibration of a sensor log's IMU clock (orchestrator.running.clock_calibration,
``navfmu convert time-offset``): a simulated car's log whose IMU is stamped 0.2 s late is
calibrated to the lag within 10 ms, and the real-time Kf replaying the calibrated log is as
good in an outage through a turn as on the log on time, and calibrating it again changes
nothing; a log without motion is refused in one line; a folder that is no log is one error
line.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from land_vehicles import moving_windows, profile
from navcore.ins import earth
from navcore.sensors.sensorlog import SensorLog, read_log, write_log
from orchestrator.building.build import ROOT
from orchestrator.running import scenarios
from orchestrator.running.replay import write_sensor_log
from test_smoother_time_offset import FILTER, OUTAGE, RTK, TURNING_CAR

#: [s] the lag put into the IMU's stamps
LAG = 0.2
PARAMETERS = {f"filter.{k}": v for k, v in FILTER.items()}
SCENARIO_OPTIONS = ("--scenario", ROOT / "models" / "mems_outages",
                    *(x for k, v in PARAMETERS.items() for x in ("--set", f"{k}={v}")))


def _scenario():
    return scenarios.load_scenario(ROOT / "models" / "mems_outages")


def _simulated_log(spec, folder, outages=OUTAGE):
    """The sensor log of the mems_outages car driving ``spec`` with RTK fixes but in
    ``outages`` (as ``navfmu run --log-sensors`` writes it)."""
    prof, rests, duration = profile(spec)
    path = folder / "profile.json"
    path.write_text(json.dumps(prof))
    run = scenarios.simulate_scenario(
        _scenario(), backend="direct", stop_time=duration, log=None, parameters={
            "trajectory.profile": str(path), "trajectory.seed": 1,
            "trajectory.noise_level_windows": moving_windows(rests, duration),
            "gnss.outages": "; ".join(f"{a},{b}" for a, b in outages),
            **{f"gnss.{k}": v for k, v in RTK.items()}, **PARAMETERS})
    return write_sensor_log(run.results, folder / "on_time")


def _late(log, folder):
    """A copy of ``log`` with the IMU's stamps LAG late."""
    data = read_log(log)
    data.imu["time"] = data.imu["time"] + LAG
    return write_log(folder, data)


def _outage_error(log, truth):
    """RMS of the real-time Kf's horizontal error in the outage [m] replaying ``log``, at
    every IMU epoch against the log on time's ``truth`` (interpolated at the IMU's stamp)."""
    res = scenarios.simulate_scenario(_scenario(), filter="Kf", backend="direct", log=None,
                                      replay=log, parameters=PARAMETERS).results
    f = scenarios.FILTER_COMPONENT
    t = res.column(f, "nav_time")
    inside = (t > OUTAGE[0][0]) & (t <= OUTAGE[0][1])
    t = t[inside]
    lat = np.interp(t, truth["time"], truth["lat"])
    rn, re = earth.radii(float(lat[0]))
    dn = (res.column(f, "nav_lat")[inside] - lat) * rn
    de = ((res.column(f, "nav_lon")[inside] - np.interp(t, truth["time"], truth["lon"]))
          * re * np.cos(lat))
    return float(np.sqrt(np.mean(dn ** 2 + de ** 2)))


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("clock")
    on_time = _simulated_log(TURNING_CAR, folder)
    return on_time, _late(on_time, folder / "late")


def test_a_late_imu_is_calibrated_and_the_real_time_kf_recovers(logs, tmp_path, navfmu_cli):
    """Measured: the offset 0.2019 s (the course estimate, kept); the real-time Kf's RMS
    horizontal error in the outage 0.562 m on time, 4.353 m stamped late, 0.540 m
    calibrated; calibrated again: the course 0.000 s, no offset taken (10 runs)."""
    on_time, late = logs
    calibrated = _late(on_time, tmp_path / "calibrated")
    code, out, err = navfmu_cli("convert", "time-offset", calibrated, *SCENARIO_OPTIONS)
    assert code == 0, err
    offset = read_log(late).imu["time"][0] - read_log(calibrated).imu["time"][0]
    assert offset == pytest.approx(LAG, abs=0.01), out
    assert f"stamps are {offset:+.3f} s off the GNSS clock: accepted" in out
    assert f"wrote {calibrated / 'imu.csv'}: the IMU's times moved by {-offset:+.3f} s" in out
    np.testing.assert_allclose(read_log(calibrated).imu["time"],
                               read_log(late).imu["time"] - offset, atol=1e-9)
    truth = read_log(on_time).truth
    reference, stale, fixed = (_outage_error(log, truth) for log in (on_time, late, calibrated))
    print(f"outage RMS: on time {reference:.3f} m, late {stale:.3f} m, calibrated "
          f"{fixed:.3f} m; offset {offset:.4f} s")
    assert stale > 5.0 * reference, (stale, reference)
    assert fixed < 1.5 * reference, (fixed, reference)
    # calibrated once: again, no offset fits better beyond chance, the log stays as it is
    before = (calibrated / "imu.csv").read_bytes()
    code, out, err = navfmu_cli("convert", "time-offset", calibrated, *SCENARIO_OPTIONS)
    assert code == 0 and "\nnot accepted; " in out and f"{calibrated}: unchanged" in out, out
    assert (calibrated / "imu.csv").read_bytes() == before


def test_a_log_without_motion_is_refused_in_one_line(tmp_path, navfmu_cli):
    """A car at rest for 60 s (IMU on gravity alone, fixes at one point): one error line,
    the log untouched."""
    n, dt = 3000, 0.02
    t = dt * np.arange(1, n + 1)
    zero = np.zeros(n)
    imu = {"time": t, "dt": np.full(n, dt), "dtheta_x": zero, "dtheta_y": zero,
           "dtheta_z": zero, "dvel_x": zero, "dvel_y": zero, "dvel_z": np.full(n, -9.8 * dt)}
    tf = np.arange(0.2, 60.0, 0.2)
    lat, lon = FILTER["init_lat"], FILTER["init_lon"]
    gnss = {"time": tf, "lat": np.full(len(tf), lat), "lon": np.full(len(tf), lon),
            "h": np.full(len(tf), FILTER["init_h"]), "valid": np.ones(len(tf))}
    log = write_log(tmp_path / "rest", SensorLog(imu, gnss))
    before = (log / "imu.csv").read_bytes()
    code, out, err = navfmu_cli("convert", "time-offset", log, *SCENARIO_OPTIONS)
    assert code != 0 and err.startswith(f"navfmu: error: {log}: the IMU's time offset cannot "
                                        "be estimated: 0 fix epochs while moving"), err
    assert len(err.strip().splitlines()) == 1
    assert (log / "imu.csv").read_bytes() == before


def test_a_folder_that_is_no_log_is_one_error_line(tmp_path, navfmu_cli):
    code, out, err = navfmu_cli("convert", "time-offset", tmp_path / "none", *SCENARIO_OPTIONS)
    assert code != 0 and err.startswith("navfmu: error: ") and "none" in err, err
    assert len(err.strip().splitlines()) == 1
