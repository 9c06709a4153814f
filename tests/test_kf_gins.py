"""KF-GINS and gnss-ins-sim coverage of `navfmu convert`: 13-column GNSS files with velocity,
the YAML configuration as a filter .ssv (units converted by the textbook factors, written
here independently), ref_frame=1 refused by name, an existing destination kept without
--force; and the receiver's per-fix sigmas as R (r_from_receiver) against the same R given
as parameters."""
from __future__ import annotations

import math
import re
import shutil

import numpy as np
import pytest

from navcore.components import registry as components
from navcore.core.component import InputError
from navcore.sensors.log_converters import read_kf_gins
from navcore.sensors.sensorlog import SensorLog, read_log, write_log
from orchestrator.building import build as fmu_build
from orchestrator.model.ssp import read_ssv
from orchestrator.running import scenarios
from test_sensorlog import GNSS_INS_SIM, _log, _write_kf_gins

GIS_MODEL = fmu_build.ROOT / "models" / "replay_gnss_ins_sim"

# a KF-GINS configuration in the layout of its dataset/kf-gins.yaml (keys, units, comments)
CONFIG = """\
imupath: "./dataset/imu.txt"
gnsspath: "./dataset/gnss.txt"
imudatalen: 7
imudatarate: 200
starttime: 456300
endtime: -1
initpos: [ 30.4447873701, 114.4718632047, 20.899 ]   # deg, deg, m
initvel: [ 0.0, 0.0, 0.0 ]
initatt: [ 0.85421502, -2.03480295, 185.70235133 ]   # roll, pitch, yaw deg
initgyrbias: [ 0, 0, 0 ]
initaccbias: [ 0, 0, 0 ]
initposstd: [ 0.005, 0.004, 0.008 ]
initvelstd: [ 0.003, 0.004, 0.004 ]
initattstd: [ 0.003, 0.003, 0.023 ]
imunoise:
  arw: [0.003, 0.003, 0.003]          # deg/sqrt(hr)
  vrw: [0.03, 0.03, 0.03]             # m/s/sqrt(hr)
  gbstd: [0.027, 0.027, 0.027]        # deg/hr
  abstd: [15.0, 15.0, 15.0]           # mGal
  gsstd: [300.0, 300.0, 300.0]        # ppm
  asstd: [300.0, 300.0, 300.0]        # ppm
  corrtime: 4.0                       # hr
antlever: [ 0.136, -0.301, -0.184 ]
"""
G0 = 9.80665                          # the ug of the datasheets: 1e-6 standard gravity


def _kf_gins_files(tmp_path, velocity):
    log = _log(n=400, dt=0.005, t0=456300.0)
    log.gnss["valid"][:] = 1.0
    for k, s in (("std_n", 0.02), ("std_e", 0.03), ("std_d", 0.05)):
        log.gnss[k] = np.full(len(log.gnss["time"]), s)
    log.truth["yaw"] = np.clip(log.truth["yaw"], -3.0, 3.0)
    _write_kf_gins(tmp_path, log)
    if velocity:       # KF-GINS's 13 columns: velocity after the position, sigmas after
        g = log.gnss
        d = 180.0 / math.pi
        np.savetxt(tmp_path / "gnss.txt", np.column_stack(
            [g["time"], g["lat"] * d, g["lon"] * d, g["h"], g["vn"], g["ve"], g["vd"],
             g["std_n"], g["std_e"], g["std_d"], *_velocity_sigmas(len(g["time"]))]),
            fmt="%.17g")
    return log


def _velocity_sigmas(n):
    """Per-axis velocity sigmas, distinct per axis (a swap shows) and varying per fix:
    medians 0.011, 0.023, 0.047 m/s."""
    wobble = 1.0 + 0.2 * np.sin(np.arange(n))
    return [s * wobble / np.median(wobble) for s in (0.011, 0.023, 0.047)]


def test_thirteen_column_gnss_file_keeps_the_velocity(tmp_path):
    log = _kf_gins_files(tmp_path, velocity=True)
    back = read_kf_gins(tmp_path / "imu.txt", tmp_path / "gnss.txt")
    assert back.has_gnss_velocity
    for k in ("vn", "ve", "vd", "std_n", "std_d", "h"):
        assert np.allclose(back.gnss[k], log.gnss[k], rtol=1e-15, atol=0), k
    for k, s in zip(("std_vn", "std_ve", "std_vd"), _velocity_sigmas(len(log.gnss["time"]))):
        assert np.array_equal(back.gnss[k], s), k
    (tmp_path / "gnss.txt").write_text("456300.1 30 114 20 1 2 3 4 5 6 7\n")
    with pytest.raises(Exception, match=r"gnss.txt, line 1: 11 values, expected 7 \(time, "
                       r"lat, lon, h, std_n, std_e, std_d\) or 13 \(time, lat, lon, h, vn"):
        read_kf_gins(tmp_path / "imu.txt", tmp_path / "gnss.txt")


def test_convert_keeps_an_existing_destination_without_force(tmp_path, navfmu_cli):
    _kf_gins_files(tmp_path, velocity=False)
    (tmp_path / "log").mkdir()
    (tmp_path / "log" / "mine.txt").write_text("keep me")
    args = ("convert", "kf-gins", tmp_path / "imu.txt", tmp_path / "gnss.txt", tmp_path / "log")
    code, _, err = navfmu_cli(*args)
    assert code == 2 and err.startswith(f"navfmu: error: convert: the destination "
                                        f"{tmp_path / 'log'} exists; give --force"), err
    assert sorted(p.name for p in (tmp_path / "log").iterdir()) == ["mine.txt"]
    code, out, err = navfmu_cli(*args, "--force")
    assert code == 0, err
    assert read_log(tmp_path / "log").time_origin == 456300.0


def test_config_becomes_a_filter_ssv_in_si_units(tmp_path, navfmu_cli):
    _kf_gins_files(tmp_path, velocity=False)
    (tmp_path / "kf-gins.yaml").write_text(CONFIG)
    code, out, err = navfmu_cli("convert", "kf-gins", tmp_path / "imu.txt",
                                tmp_path / "gnss.txt", tmp_path / "log", "--config",
                                tmp_path / "kf-gins.yaml")
    assert code == 0, err
    assert "--start 456300" in out and "gsstd" in out      # the start, and what is left out
    values = {k: v for k, (_, v) in read_ssv(tmp_path / "log" / "filter.ssv").items()}
    names = {p.name for p in components.Kf.parameters}
    assert set(values) <= names, set(values) - names
    d2r = math.pi / 180.0
    assert values["init_lat"] == pytest.approx(30.4447873701 * d2r, rel=1e-15)
    assert values["init_yaw"] == pytest.approx((185.70235133 - 360.0) * d2r, rel=1e-14)
    assert values["p0_pos"] == 0.008 and values["p0_att_yaw"] == pytest.approx(0.023 * d2r)
    # 0.03 m/s/sqrt(h) = 0.03/60 m/s^2/sqrt(Hz) = 50.99 ug/sqrt(Hz); 15 mGal = 15.30 ug
    assert values["q_accel_vrw_ugpsHz"] == pytest.approx(0.03 / 60 / (G0 * 1e-6), rel=1e-12)
    assert values["q_accel_vrw_ugpsHz"] == pytest.approx(50.99, abs=0.01)
    assert values["q_accel_bias_instability_ug"] == pytest.approx(15.296, abs=1e-3)
    assert values["q_gyro_bias_tau_s"] == 14400.0 and values["q_gyro_arw_dpsh"] == 0.003
    assert (values["lever_arm_x"], values["lever_arm_y"], values["lever_arm_z"]) == (
        0.136, -0.301, -0.184)
    assert values["r_from_receiver"] is True and values["measurement"] == "position"
    # a navigation-grade gyro (arw 0.003 deg/sqrt(h)): its figures as given; the receiver's
    # errors correlated over the time measured on a real drive
    assert values["imu_noise_factor"] == 1.0 and values["gnss_corr_time"] == 4.5
    (tmp_path / "mems.yaml").write_text(CONFIG.replace("arw: [0.003, 0.003, 0.003]",
                                                       "arw: [0.228, 0.1, 0.05]"))
    code, _, err = navfmu_cli("convert", "kf-gins", tmp_path / "imu.txt", tmp_path / "gnss.txt",
                              tmp_path / "log3", "--config", tmp_path / "mems.yaml")
    assert code == 0, err
    mems = {k: v for k, (_, v) in read_ssv(tmp_path / "log3" / "filter.ssv").items()}
    assert mems["imu_noise_factor"] == 30.0 and mems["q_gyro_arw_dpsh"] == 0.228
    comment = (tmp_path / "log3" / "filter.ssv").read_text()
    assert "imu_noise_factor 30 for a MEMS gyro" in comment and "gnss_corr_time 4.5 s" in comment
    assert "imu_noise_factor 1 for a gyro better than MEMS" in (
        tmp_path / "log" / "filter.ssv").read_text()
    (tmp_path / "bad.yaml").write_text(CONFIG.replace("initpos: [ 30.4447873701,", "initpos: ["))
    code, _, err = navfmu_cli("convert", "kf-gins", tmp_path / "imu.txt",
                              tmp_path / "gnss.txt", tmp_path / "log2", "--config",
                              tmp_path / "bad.yaml")
    assert code == 2 and "bad.yaml: key 'initpos': expected 3 finite numbers" in err
    assert not (tmp_path / "log2").exists()


def test_gnss_ins_sim_local_frame_is_refused_by_name(tmp_path, navfmu_cli):
    src = tmp_path / "sim"
    shutil.copytree(GNSS_INS_SIM, src)
    lines = (src / "gps-0.csv").read_text().splitlines()
    lines[0] = "gps_x (m),gps_y (m),gps_z (m),gps_vx (m/s),gps_vy (m/s),gps_vz (m/s)"
    (src / "gps-0.csv").write_text("\n".join(lines) + "\n")
    code, _, err = navfmu_cli("convert", "gnss-ins-sim", src, tmp_path / "out")
    assert code == 2 and "this gnss-ins-sim run used ref_frame=1" in err
    assert "only ref_frame=0" in err and not (tmp_path / "out").exists()


def _gis_with_sigmas(tmp_path, sigmas):
    log = read_log(GIS_MODEL / "log")
    n = len(log.gnss["time"])
    for k, s in zip(("std_n", "std_e", "std_d"), sigmas):
        log.gnss[k] = np.full(n, s)
    write_log(tmp_path / "log", SensorLog(log.imu, log.gnss, log.truth))
    return tmp_path / "log"


def test_receiver_sigmas_as_r_equal_the_same_r_given(tmp_path):
    """The log's std_n/e/d (5, 5, 7 m: the data's stated sigmas) as R with r_pos_* set to
    50 m: the very numbers of the run with r_pos_* = 5, 5, 7 m (the same R each update);
    without r_from_receiver the 50 m R halves the mean NIS."""
    log = _gis_with_sigmas(tmp_path, (5.0, 5.0, 7.0))
    model = scenarios.load_scenario(GIS_MODEL)
    wrong = {f"filter.r_pos_{a}": 50.0 for a in "ned"}
    run = scenarios.simulate_scenario(model, backend="direct", replay=log, log=None,
                                      parameters={**wrong, "filter.r_from_receiver": True})
    ref = scenarios.simulate_scenario(model, backend="direct", replay=log, log=None)
    assert np.array_equal(run.results.column("filter", "nav_lat"),
                          ref.results.column("filter", "nav_lat"))
    assert run.metrics["filter"]["nis"] == ref.metrics["filter"]["nis"]
    ignored = scenarios.simulate_scenario(model, backend="direct", replay=log, log=None,
                                          parameters=wrong)
    # (the position part of the NIS shrinks by 100 with R = 50^2; the velocity part stays)
    assert ignored.metrics["filter"]["nis"]["mean"] < 0.6 * ref.metrics["filter"]["nis"]["mean"]


def test_receiver_sigmas_missing_is_an_input_error():
    kf = components.Kf(r_from_receiver=True, measurement="position")
    kf.initialize(0.0)
    inputs = {p.name: p.default() for p in kf.inputs}
    inputs.update(imu_time=0.01, imu_dt=0.01, imu_dvel_z=-9.8 * 0.01, gnss_time=0.01,
                  gnss_lat=0.0, gnss_epoch=1, gnss_valid=True)
    with pytest.raises(InputError, match=r"input 'gnss_std_n' = 0.0 m for the fix at "
                       r"gnss_time = 0.01 s with parameter 'r_from_receiver' = true"):
        kf.step(0.0, 0.01, inputs)


def _stamped_kf_gins(folder, t0: str, rate=200, seconds=3):
    """KF-GINS files of ``seconds`` at ``rate`` Hz stamped from the decimal ``t0`` as a
    logger writes them (``%.3f``), a fix each second with sigmas distinct per axis."""
    base = float(t0)
    with open(folder / "imu.txt", "w") as f:
        for k in range(rate * seconds + 1):
            f.write(f"{base + k / rate:.3f} 1e-5 -2e-5 3e-5 1e-4 -2e-4 {-9.8 / rate!r}\n")
    with open(folder / "gnss.txt", "w") as f:
        for k in range(1, seconds + 1):
            f.write(f"{base + k:.3f} 30.5 114.25 20.0 0.02 0.03 0.05\n")
    return folder / "imu.txt", folder / "gnss.txt"


@pytest.mark.parametrize("t0", ["408640.970", "1700000000.970"])
def test_a_200_hz_log_in_gps_or_unix_seconds_replays_every_interval(tmp_path, t0):
    """The failing case: 200 Hz in GPS seconds of the week and in UNIX time.  Each dt was
    the float difference of two parsed stamps (9e-8 s off at 1.7e9 s), so the intervals no
    longer tiled the stamps and the filter refused them; now every stamp and dt is the
    exact decimal: dt is 0.005 s to the last bit, the written stamps are the input's text,
    and the replay integrates every interval."""
    imu_file, gnss_file = _stamped_kf_gins(tmp_path, t0)
    log = read_kf_gins(imu_file, gnss_file)
    assert log.time_origin == float(t0.split(".")[0])
    assert np.all(log.imu["dt"] == 0.005), np.unique(log.imu["dt"])
    write_log(tmp_path / "log", log)
    stamps = [line.split(",")[0] for line in
              (tmp_path / "log" / "imu.csv").read_text().splitlines()[1:4]]
    whole = t0.split(".")[0]
    assert stamps == [f"{whole}.975", f"{whole}.98", f"{whole}.985"]
    gnss = (tmp_path / "log" / "gnss.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in gnss[1:3]] == [f"{int(whole) + 1}.97",
                                                           f"{int(whole) + 2}.97"]
    model = scenarios.load_scenario(GIS_MODEL)
    run = scenarios.simulate_scenario(
        model, backend="direct", replay=tmp_path / "log", log=None,
        parameters={"filter.init_lat": math.radians(30.5), "filter.init_lon":
                    math.radians(114.25), "filter.init_h": 20.0, "filter.init_vn": 0.0,
                    "filter.init_ve": 0.0, "filter.init_vd": 0.0})
    nav_time = run.results.column("filter", "nav_time")
    assert nav_time[-1] == pytest.approx(0.97 + 3.0, abs=1e-9)
    assert len(np.unique(nav_time[nav_time > 0.97])) == 600     # every interval, once


def test_config_with_a_thirteen_column_file_uses_its_velocity(tmp_path, navfmu_cli):
    """--config on a 13-column GNSS file: the log keeps the velocity and its sigmas (per axis,
    distinct), the .ssv measures position and velocity with R_vel the median sigma per axis;
    the start time 408640.97 is printed exact (it was '%g': 408641)."""
    _kf_gins_files(tmp_path, velocity=True)
    (tmp_path / "kf-gins.yaml").write_text(CONFIG.replace("starttime: 456300",
                                                          "starttime: 408640.97"))
    code, out, err = navfmu_cli("convert", "kf-gins", tmp_path / "imu.txt",
                                tmp_path / "gnss.txt", tmp_path / "log", "--config",
                                tmp_path / "kf-gins.yaml")
    assert code == 0, err
    assert re.search(r"--start 408640\.97(?![0-9])", out), out
    values = {k: v for k, (_, v) in read_ssv(tmp_path / "log" / "filter.ssv").items()}
    assert values["measurement"] == "position_velocity" and values["r_from_receiver"] is True
    assert [values[f"r_vel_{a}"] for a in "ned"] == pytest.approx([0.011, 0.023, 0.047],
                                                                  rel=1e-12)
    log = read_log(tmp_path / "log")
    assert log.has_gnss_velocity
    assert [float(np.median(log.gnss[f"std_v{a}"])) for a in "ned"] == pytest.approx(
        [0.011, 0.023, 0.047], rel=1e-12)
    assert "408640.97" in (tmp_path / "log" / "filter.ssv").read_text()
