"""`navfmu convert imu-csv`: a plain IMU CSV by a column map with signs and units.  Values
distinct per axis and per column (a swap or a lost sign shows); the trimmed real drive
(g and deg/s, a millisecond counter) against its first lines by hand."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from navcore.errors import LogError
from navcore.sensors.imu_csv import ImuCsvSpec, read_imu_csv

IMU = Path(__file__).parent / "data" / "rtklib_drive" / "imu_1934_trimmed.csv"
G0, D2R = 9.80665, math.pi / 180.0


def _spec(**values):
    base = dict(gyro="x=col4,y=-col6,z=col5", accel="x=-col3,y=col1,z=col2",
                gyro_unit="deg/s", accel_unit="g", rate=50.0, start="408640.97")
    return ImuCsvSpec.from_mapping({**base, **values}, "test")


def test_axes_signs_and_units_of_rates(tmp_path):
    """Columns 1..6 constant at 0.1, 0.2, 0.3 g and 4, 5, 6 deg/s: x=-col3, y=col1,
    z=col2 and x=col4, y=-col6, z=col5 over 20 ms intervals."""
    path = tmp_path / "imu.csv"
    path.write_text("ax,ay,az,gx,gy,gz\n" + "0.1,0.2,0.3,4,5,6\n" * 4)
    imu, origin = read_imu_csv(path, _spec(header_lines=1))
    dt = 0.02
    assert origin == 408640.0 and imu["time"].tolist() == pytest.approx(
        [0.99, 1.01, 1.03], abs=1e-12)
    assert np.all(imu["dt"] == 0.02)
    assert imu["dvel_x"][0] == pytest.approx(-0.3 * G0 * dt, rel=1e-15)
    assert imu["dvel_y"][0] == pytest.approx(0.1 * G0 * dt, rel=1e-15)
    assert imu["dvel_z"][0] == pytest.approx(0.2 * G0 * dt, rel=1e-15)
    assert imu["dtheta_x"][0] == pytest.approx(4 * D2R * dt, rel=1e-15)
    assert imu["dtheta_y"][0] == pytest.approx(-6 * D2R * dt, rel=1e-15)
    assert imu["dtheta_z"][0] == pytest.approx(5 * D2R * dt, rel=1e-15)


def test_increments_with_a_time_column_in_microseconds(tmp_path):
    """Increments (rad, m/s) over the interval ending at the line's time; the first line
    only starts; the us column put on --start."""
    path = tmp_path / "imu.txt"
    path.write_text("1000 0.001 0.002 0.003 0.01 0.02 0.03\n"
                    "6000 0.004 0.005 0.006 0.04 0.05 0.06\n"
                    "11000 0.007 0.008 0.009 0.07 0.08 0.09\n")
    spec = _spec(rate=None, time=1, time_unit="us", start="1700000000.5",
                 gyro="x=col2,y=col3,z=col4", accel="x=col5,y=col6,z=-col7",
                 gyro_unit="rad", accel_unit="m/s")
    imu, origin = read_imu_csv(path, spec)
    assert origin == 1700000000.0 and imu["time"].tolist() == [0.505, 0.51]
    assert np.all(imu["dt"] == 0.005)
    assert imu["dtheta_x"].tolist() == [0.004, 0.007]
    assert imu["dtheta_z"].tolist() == [0.006, 0.009]
    assert imu["dvel_z"].tolist() == [-0.06, -0.09]


def test_the_real_drive_by_hand():
    """Lines 1-2 of the drive: accel 0.119/0.027/1.013 then 0.116/0.031/0.985 g, gyro
    -0.671/3.082/0.198 then -0.359/0.946/0.168 deg/s, counter 261906 then 261916 ms."""
    spec = ImuCsvSpec.from_mapping(dict(time=7, time_unit="ms", start="1752003261.854",
                                        gyro="x=col4,y=col5,z=col6",
                                        accel="x=col1,y=col2,z=col3", gyro_unit="deg/s",
                                        accel_unit="g"), "test")
    imu, origin = read_imu_csv(IMU, spec)
    assert len(imu["time"]) == 1199 and origin == 1752003261.0
    assert imu["time"][0] == pytest.approx(0.864, abs=1e-12) and imu["dt"][0] == 0.01
    assert imu["dvel_x"][0] == pytest.approx(0.005 * (0.119 + 0.116) * G0, rel=1e-14)
    assert imu["dvel_z"][0] == pytest.approx(0.005 * (1.013 + 0.985) * G0, rel=1e-14)
    assert imu["dtheta_y"][0] == pytest.approx(0.005 * (3.082 + 0.946) * D2R, rel=1e-14)
    # the last line's counter 273897: 11.991 s after the first
    assert imu["time"][-1] == pytest.approx(0.854 + 11.991, abs=1e-9)


@pytest.mark.parametrize("values, message", [
    (dict(accel_unit="m/s"), "mix rates and increments"),
    (dict(time=7), "either a time column"),
    (dict(gyro="x=col4,y=col5"), "no column for axis z"),
    (dict(gyro="x=col4,y=col5,x=col6"), "axis x given twice"),
    (dict(gyro="x=4,y=5,z=c6"), "'z=c6' is not AXIS=[-]colN"),
    (dict(gyro_unit="dps"), "gyro_unit 'dps': one of deg/s, rad/s, deg, rad"),
    (dict(rate=-1.0), "rate = -1.0"),
    (dict(colour=1), "unknown key 'colour'"),
])
def test_bad_maps_are_named(values, message):
    with pytest.raises(LogError, match=message.replace("[", r"\[").replace("]", r"\]")):
        _spec(**values)


def test_a_cut_off_last_line_is_named(tmp_path):
    path = tmp_path / "imu.csv"
    path.write_text("0.1,0.2,0.3,4,5,6\n0.1,0.2,0.3,4,5,6\n0.1,0.2\n")
    with pytest.raises(LogError, match=r"line 3: 2 values, but line 1 has 6 \(a cut-off"):
        read_imu_csv(path, _spec())


def test_config_file_with_options_over_it(tmp_path, navfmu_cli):
    (tmp_path / "imu.yaml").write_text("gyro: x=col4,y=col5,z=col6\naccel: x=col1,y=col2,"
                                       "z=col3\ngyro_unit: rad/s\naccel_unit: g\ntime: 7\n"
                                       "time_unit: ms\nstart: 1752003261.854\n")
    code, out, err = navfmu_cli("convert", "imu-csv", IMU, tmp_path / "log", "--config",
                                tmp_path / "imu.yaml", "--gyro-unit", "deg/s")
    assert code == 0, err
    text = (tmp_path / "log" / "imu.csv").read_text().splitlines()
    assert text[1].startswith("1752003261.864,0.01,")
    dtheta_y = float(text[1].split(",")[3])
    assert dtheta_y == pytest.approx(0.005 * (3.082 + 0.946) * D2R, rel=1e-14)  # deg/s won
    (tmp_path / "bad.yaml").write_text("- a list\n")
    code, _, err = navfmu_cli("convert", "imu-csv", IMU, tmp_path / "l2", "--config",
                              tmp_path / "bad.yaml")
    assert code == 2 and "bad.yaml: expected a mapping of keys" in err
