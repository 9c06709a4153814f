"""A vehicle navfmu did not build: tests/cvehicle/racetrack.c, a car on a flat racetrack at
constant speed with truth outputs only, compiled here with the system ``cc`` against fmpy's
FMI 2 headers into an FMU, runs -> ImuSensor -> GnssReceiver -> Kf in our master and in
libcosim.  Its position errors are compared with the same IMU, receiver and filter on a
TrajectoryImu profile of the same dynamics (20 m/s, straights of 400 m, half circles of
100 m radius; the profile banks into its turns, the car does not)."""
from __future__ import annotations

import json
import math
import shutil
import subprocess
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest

from conftest import component_xml, connection_xml, ssd_text
from navcore.core import signals
from orchestrator.building import build as fmu_build
from orchestrator.cosim.master import Simulation
from orchestrator.model.ssp_archive import load_model
from orchestrator.results import metrics as nav_metrics

HERE = Path(__file__).resolve().parent / "cvehicle"
DIST = fmu_build.DIST
SPEED, RADIUS, HALF = 20.0, 100.0, 200.0
LAT0, LON0, H0 = 0.6998770300497261, 2.069960492865275, 100.0
STOP = 120.0
IMU = {"imu_period": ("Real", 0.01), "seed": ("Integer", 5), "gyro_bias_dph": ("Real", 1.0),
       "gyro_arw_dpsh": ("Real", 0.01), "accel_bias_ug": ("Real", 100.0),
       "accel_vrw_ugpsHz": ("Real", 20.0)}
GNSS = {"seed": ("Integer", 6), "fix_interval": ("Real", 1.0), "pos_sigma_n": ("Real", 2.0),
        "pos_sigma_e": ("Real", 2.0), "pos_sigma_d": ("Real", 3.0), "vel_sigma_n": ("Real", 0.1),
        "vel_sigma_e": ("Real", 0.1), "vel_sigma_d": ("Real", 0.1)}
TRUTH = [(p.name, p.unit) for p in signals.TRUTH]
IMU8 = [(p.name, p.unit) for p in signals.IMU[:8]]
FIX = [(p.name, p.type, p.unit) for p in signals.GNSS]


@pytest.fixture(scope="module")
def racetrack_fmu(tmp_path_factory):
    cc = shutil.which("cc")
    include = Path(fmpy.__file__).parent / "c-code"
    if cc is None or not (include / "fmi2Functions.h").is_file():
        pytest.skip("no C compiler 'cc' or no FMI 2 headers in fmpy")
    build = tmp_path_factory.mktemp("racetrack")
    lib = build / "racetrack.so"
    r = subprocess.run([cc, "-O1", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-I",
                        str(include), "-o", str(lib), str(HERE / "racetrack.c"), "-lm"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    fmu = build / "Racetrack.fmu"
    with zipfile.ZipFile(fmu, "w") as z:
        z.write(HERE / "modelDescription.xml", "modelDescription.xml")
        z.write(lib, "binaries/linux64/racetrack.so")
    fmu_build.build(log=None)
    return fmu


def _start():
    """The car's start: the south end of the eastern straight, northbound."""
    a, e2 = 6378137.0, 6.69437999014e-3
    w = 1.0 - e2 * math.sin(LAT0) ** 2
    re = a / math.sqrt(w)
    rn = re * (1.0 - e2) / w
    return LAT0 - HALF / (rn + H0), LON0 + RADIUS / ((re + H0) * math.cos(LAT0))


def _filter(lat, lon):
    params = {"init_lat": ("Real", lat), "init_lon": ("Real", lon), "init_h": ("Real", H0),
              "init_vn": ("Real", SPEED), "p0_pos": ("Real", 2.0), "p0_vel": ("Real", 0.1),
              "p0_att_level": ("Real", 0.001), "p0_att_yaw": ("Real", 0.01),
              "p0_gyro_bias_dph": ("Real", 1.0), "q_gyro_arw_dpsh": ("Real", 0.01),
              "q_accel_vrw_ugpsHz": ("Real", 20.0), "r_pos_n": ("Real", 2.0),
              "r_pos_e": ("Real", 2.0), "r_pos_d": ("Real", 3.0), "r_vel_n": ("Real", 0.1),
              "r_vel_e": ("Real", 0.1), "r_vel_d": ("Real", 0.1)}
    connectors = [(n, "input", "Real", u) for n, u in IMU8] + [
        (n, "input", t, u) if t == "Real" else (n, "input", t) for n, t, u in FIX]
    return component_xml("filter", str(DIST / "Kf.fmu"), connectors, params)


def _system(folder, vehicle_xml, source, imu_is_separate):
    gnss = component_xml("gnss", str(DIST / "GnssReceiver.fmu"),
                         [(n, "input", "Real", u) for n, u in TRUTH[:7]]
                         + [(n, "output", t, u) if t == "Real" else (n, "output", t)
                            for n, t, u in FIX], GNSS)
    lat, lon = _start()
    elements = [vehicle_xml, gnss, _filter(lat, lon)]
    connections = [connection_xml(f"{source}.{n}", f"gnss.{n}") for n, _ in TRUTH[:7]]
    connections += [connection_xml(f"gnss.{n}", f"filter.{n}") for n, _, _ in FIX]
    imu_source = "imu" if imu_is_separate else source
    if imu_is_separate:
        elements.insert(1, component_xml("imu", str(DIST / "ImuSensor.fmu"),
                                         [(n, "input", "Real", u) for n, u in TRUTH]
                                         + [(n, "output", "Real", u) for n, u in IMU8], IMU))
        connections += [connection_xml(f"{source}.{n}", f"imu.{n}") for n, _ in TRUTH]
    connections += [connection_xml(f"{imu_source}.{n}", f"filter.{n}") for n, _ in IMU8]
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "SystemStructure.ssd").write_text(ssd_text(
        "\n".join(elements), "\n".join(connections), base_step=0.01, stop=STOP,
        name=folder.name))
    return folder


def _car_system(tmp_path, fmu):
    car = component_xml("car", str(fmu), [(n, "output", "Real", u) for n, u in TRUTH],
                        {"speed": ("Real", SPEED), "radius": ("Real", RADIUS),
                         "half_straight": ("Real", HALF)})
    return _system(tmp_path / "racetrack", car, "car", True)


def _profile_system(tmp_path):
    """The same track as a TrajectoryImu profile: straight, half turn, straight, half turn."""
    half_turn = math.pi * RADIUS / SPEED
    straight = 2 * HALF / SPEED
    segments = []
    while sum(s["duration"] for s in segments) < STOP + 1.0:
        segments += [{"type": "level", "duration": straight},
                     {"type": "turn", "duration": half_turn, "heading_change_deg": -180.0,
                      "transition": 0.0}]
    lat, lon = _start()
    profile = {"start": {"lat_deg": math.degrees(lat), "lon_deg": math.degrees(lon),
                         "h": H0, "speed": SPEED, "yaw_deg": 0.0}, "segments": segments}
    path = tmp_path / "racetrack_profile.json"
    path.write_text(json.dumps(profile))
    params = dict(IMU, profile=("String", str(path)))
    trajectory = component_xml("trajectory", str(DIST / "TrajectoryImu.fmu"),
                               [(n, "output", "Real", u) for n, u in TRUTH + IMU8], params)
    return _system(tmp_path / "profile", trajectory, "trajectory", False)


def _horizontal_rms(results):
    e = nav_metrics.navigation_errors(results, "filter")
    keep = e["valid"] & (e["time"] >= 10.0)
    return float(np.sqrt(np.mean(e["pos_n"][keep] ** 2 + e["pos_e"][keep] ** 2)))


def test_a_c_vehicle_drives_our_sensors_and_filter_in_our_master(racetrack_fmu, tmp_path):
    car = Simulation(load_model(_car_system(tmp_path, racetrack_fmu))).run()
    profile = Simulation(load_model(_profile_system(tmp_path))).run()
    a, b = _horizontal_rms(car), _horizontal_rms(profile)
    # the filter follows the car: a lap and a half, position within the fixes' noise
    assert car.column("gnss", "gnss_epoch")[-1] == STOP
    assert a < 2.0 and b < 2.0
    # as small as on the built-in profile of the same dynamics (within a third)
    assert a < 1.34 * b, (a, b)


def test_the_c_vehicle_runs_the_same_in_libcosim(racetrack_fmu, tmp_path):
    pytest.importorskip("libcosimpy", reason="libcosimpy (the test extra) is not installed")
    from orchestrator.cosim.libcosim_run import run_libcosim

    folder = _car_system(tmp_path, racetrack_fmu)
    ours = Simulation(load_model(folder), algorithm="jacobi").run(20.0)
    theirs = run_libcosim(folder, 20.0)
    # not bit for bit: the car stamps truth_time = t + h from the host's t, which libcosim
    # accumulates (0.1 + 0.01 ...) where our master computes start + k h: 4e-15 s apart
    for c in ("car", "imu", "filter"):
        for j, v in enumerate(ours.columns[c]):
            np.testing.assert_allclose(theirs.data[c][1:, j], ours.data[c][1:, j], rtol=1e-9,
                                       atol=1e-9, err_msg=f"{c}.{v}")
    assert _horizontal_rms(theirs) < 2.0
