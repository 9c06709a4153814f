"""navcore.sensors.log_converters on small files written here by hand: which file and line
each refusal of a gnss-ins-sim folder or a KF-GINS file pair names, the columns and comments
the readers take, the visibility and the reference files, and the rates that tell a KF-GINS
GNSS file from an IMU file, down to the bounds."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.sensors.log_converters import (read_gnss_ins_sim, read_kf_gins, read_plain_text,
                                            read_titled_csv, KF_GINS_GNSS,
                                            KF_GINS_GNSS_VELOCITY)
from navcore.sensors.sensorlog import LogError

LAT, LON = 32.0, 120.0


def _csv(path, titles, rows):
    path.write_text(",".join(titles) + "\n" + "".join(",".join(str(v) for v in row) + "\n"
                                                       for row in rows))


def _gis(folder, times=(0.0, 0.01, 0.02, 0.03, 0.04), gps_times=(0.0, 0.02, 0.04),
         visibility=None, reference=True, gps_lat=LAT):
    """A gnss-ins-sim folder (ref_frame=0) of the given sample times: constant rates and
    specific force, fixes at ``gps_times``, the reference files unless ``reference`` is
    False, ``gps_visibility.csv`` if ``visibility`` (one value per fix) is given."""
    folder.mkdir(exist_ok=True)
    n, m = len(times), len(gps_times)
    _csv(folder / "time.csv", ["time (sec)"], [[t] for t in times])
    _csv(folder / "gyro-0.csv", [f"gyro_{a} (deg/s)" for a in "xyz"], [[1.0, 2.0, 3.0]] * n)
    _csv(folder / "accel-0.csv", [f"accel_{a} (m/s^2)" for a in "xyz"], [[0.1, 0.2, -9.8]] * n)
    _csv(folder / "gps_time.csv", ["gps_time (sec)"], [[t] for t in gps_times])
    _csv(folder / "gps-0.csv", ["gps_lat (deg)", "gps_lon (deg)", "gps_alt (m)", "gps_vN (m/s)",
                                "gps_vE (m/s)", "gps_vD (m/s)"],
         [[gps_lat, LON, 10.0, 1.0, 2.0, 0.5]] * m)
    if visibility is not None:
        _csv(folder / "gps_visibility.csv", ["gps_visibility ()"], [[v] for v in visibility])
    if reference:
        _csv(folder / "ref_pos.csv", ["ref_pos_lat (deg)", "ref_pos_lon (deg)",
                                      "ref_pos_alt (m)"], [[LAT, LON, 10.0]] * n)
        _csv(folder / "ref_vel.csv", [f"ref_vel_{a} (m/s)" for a in "xyz"], [[1.0, 2.0, 0.5]] * n)
        _csv(folder / "ref_att_euler.csv", ["ref_Yaw (deg)", "ref_Pitch (deg)", "ref_Roll (deg)"],
             [[30.0, 2.0, -1.0]] * n)
    return folder


def _refusal(call, *args):
    with pytest.raises(LogError) as e:
        call(*args)
    return str(e.value)


# -- gnss-ins-sim ----------------------------------------------------------------------------
def test_a_small_folder_is_read_with_its_increments_visibility_and_reference(tmp_path):
    d = _gis(tmp_path / "run", visibility=[1, 0, 1])
    log = read_gnss_ins_sim(d)
    assert log.imu["time"].tolist() == [0.01, 0.02, 0.03, 0.04]
    assert log.imu["dtheta_z"] == pytest.approx([math.radians(3.0) * 0.01] * 4)
    assert log.imu["dvel_z"] == pytest.approx([-9.8 * 0.01] * 4)
    assert log.gnss["valid"].tolist() == [1.0, 0.0, 1.0]
    assert log.gnss["lat"][0] == pytest.approx(math.radians(LAT))
    assert log.truth["yaw"][0] == pytest.approx(math.radians(30.0))
    assert log.truth["roll"][0] == pytest.approx(math.radians(-1.0))


def test_without_visibility_every_fix_is_valid_and_without_reference_no_truth(tmp_path):
    log = read_gnss_ins_sim(_gis(tmp_path / "run", reference=False))
    assert log.gnss["valid"].tolist() == [1.0, 1.0, 1.0]
    assert log.truth is None


def test_a_visibility_of_one_half_is_no_fix(tmp_path):
    log = read_gnss_ins_sim(_gis(tmp_path / "run", visibility=[1, 0.5, 0.51]))
    assert log.gnss["valid"].tolist() == [1.0, 0.0, 1.0]


def test_two_imu_samples_are_one_interval_and_one_is_refused(tmp_path):
    d = _gis(tmp_path / "two", times=(0.0, 0.01), gps_times=(0.0, 0.01))
    assert read_gnss_ins_sim(d).imu["time"].tolist() == [0.01]
    d = _gis(tmp_path / "one", times=(0.0,), gps_times=(0.0,))
    assert _refusal(read_gnss_ins_sim, d) == (f"{d / 'time.csv'}: at least two IMU samples "
                                              "are needed")


@pytest.mark.parametrize("short, against", [("gyro-0.csv", "time.csv"),
                                            ("accel-0.csv", "time.csv"),
                                            ("gps-0.csv", "gps_time.csv"),
                                            ("gps_visibility.csv", "gps_time.csv"),
                                            ("ref_pos.csv", "time.csv"),
                                            ("ref_vel.csv", "time.csv"),
                                            ("ref_att_euler.csv", "time.csv")])
def test_a_file_one_line_short_is_named_with_the_file_it_disagrees_with(tmp_path, short,
                                                                        against):
    d = _gis(tmp_path / "run", visibility=[1, 1, 1])
    lines = (d / short).read_text().splitlines()
    (d / short).write_text("\n".join(lines[:-1]) + "\n")
    n = len(lines) - 2
    assert _refusal(read_gnss_ins_sim, d) == (f"{d / short}: {n} samples, but {d / against} "
                                              f"has {n + 1} (one line per sample time)")


def test_the_rows_refused_by_the_log_rules_are_named_by_their_file_lines(tmp_path):
    # IMU: the time of line 5 (the 4th sample) repeats line 4's; the IMU row of that time is
    # the third interval
    d = _gis(tmp_path / "imu", times=(0.0, 0.01, 0.02, 0.02, 0.04))
    assert _refusal(read_gnss_ins_sim, d).startswith(f"{d / 'time.csv'}, line 5: ")
    # GNSS: the second fix (line 3) is at 95 deg latitude
    d = _gis(tmp_path / "gnss", gps_lat=LAT)
    rows = (d / "gps-0.csv").read_text().splitlines()
    rows[2] = rows[2].replace(str(LAT), "95.0", 1)
    (d / "gps-0.csv").write_text("\n".join(rows) + "\n")
    assert _refusal(read_gnss_ins_sim, d).startswith(f"{d / 'gps_time.csv'}, line 3: lat = ")
    # truth: 1.5 s between the samples of lines 3 and 4 (the IMU allows it, the truth not)
    d = _gis(tmp_path / "truth", times=(0.0, 0.01, 1.51, 1.52), gps_times=(0.0, 1.52))
    assert _refusal(read_gnss_ins_sim, d).startswith(f"{d / 'time.csv'}, line 4: gap of 1.5 s "
                                                     "after line 3")


def test_a_title_that_is_not_name_and_unit_is_refused_on_line_1(tmp_path):
    path = tmp_path / "time.csv"
    path.write_text("time (sec\n0\n")
    assert _refusal(read_titled_csv, path, [("time", "sec")]) == (
        f"{path}, line 1: column 'time (sec' does not match the expected 'time (sec)'")
    path.write_text("t (sec)\n0\n")
    assert "column 't (sec)' does not match" in _refusal(read_titled_csv, path, [("time", "sec")])
    assert read_titled_csv(path, [(None, "sec")]).tolist() == [[0.0]]     # any name


def test_a_bad_number_is_named_by_file_line_and_column_title(tmp_path):
    path = tmp_path / "gyro-0.csv"
    path.write_text("gyro_x (deg/s),gyro_y (deg/s)\n1,2\n3,abc\n")
    message = _refusal(read_titled_csv, path, [("gyro_x", "deg/s"), ("gyro_y", "deg/s")])
    assert message.startswith(f"{path}, line 3: column 'gyro_y': 'abc' is not a")


def test_an_empty_gps_file_and_the_local_frame_are_refused_by_name(tmp_path):
    d = _gis(tmp_path / "empty")
    (d / "gps-0.csv").write_text("")
    assert _refusal(read_gnss_ins_sim, d) == f"{d / 'gps-0.csv'}, line 1: no column titles"
    d = _gis(tmp_path / "local")
    (d / "gps-0.csv").write_text("gps_x (m),gps_y (m),gps_z (m)\n1,2,3\n")
    assert _refusal(read_gnss_ins_sim, d).startswith(
        f"{d / 'gps-0.csv'}, line 1: column 'gps_x (m)': this gnss-ins-sim run used ref_frame=1")


# -- KF-GINS text ----------------------------------------------------------------------------
def _kf(tmp_path, imu_rows, gnss_rows, imu_text=None):
    imu, gnss = tmp_path / "imu.txt", tmp_path / "gnss.txt"
    imu.write_text(imu_text if imu_text is not None else
                   "".join(" ".join(str(v) for v in r) + "\n" for r in imu_rows))
    gnss.write_text("".join(" ".join(str(v) for v in r) + "\n" for r in gnss_rows))
    return imu, gnss


def _imu_rows(times):
    return [[t, 1e-4, 2e-4, 3e-4, 0.01, 0.02, -0.098] for t in times]


def _gnss_rows(times, std=(1.0, 1.0, 2.0)):
    return [[t, LAT, LON, 10.0, *std] for t in times]


def test_comments_commas_and_blank_lines_of_plain_text(tmp_path):
    path = tmp_path / "gnss.txt"
    path.write_text("# KF-GINS GNSS file # with a second mark\n"
                    "1, 32, 120, 10, 1, 1, 2  # a fix # and more\n"
                    "\n"
                    "2 32 120 10 1 1 2\n")
    rows, lines, names = read_plain_text(path, KF_GINS_GNSS)
    assert rows.tolist() == [[1, 32, 120, 10, 1, 1, 2], [2, 32, 120, 10, 1, 1, 2]]
    assert lines.tolist() == [2, 4] and names == KF_GINS_GNSS


def test_the_column_count_refused_names_the_layouts_then_the_one_chosen(tmp_path):
    path = tmp_path / "gnss.txt"
    path.write_text("1 2 3\n")
    assert _refusal(read_plain_text, path, KF_GINS_GNSS, KF_GINS_GNSS_VELOCITY) == (
        f"{path}, line 1: 3 values, expected 7 ({', '.join(KF_GINS_GNSS)}) or 13 "
        f"({', '.join(KF_GINS_GNSS_VELOCITY)})")
    path.write_text("1 2 3 4 5 6 7\n1 2 3\n")
    assert _refusal(read_plain_text, path, KF_GINS_GNSS, KF_GINS_GNSS_VELOCITY) == (
        f"{path}, line 2: 3 values, expected 7 ({', '.join(KF_GINS_GNSS)})")
    assert _refusal(read_plain_text, path, KF_GINS_GNSS) == (
        f"{path}, line 2: 3 values, expected 7 ({', '.join(KF_GINS_GNSS)})")


def test_a_bad_number_in_plain_text_names_file_line_and_column(tmp_path):
    path = tmp_path / "gnss.txt"
    path.write_text("1 32 120 10 1 1 2\n2 32 x 10 1 1 2\n")
    assert _refusal(read_plain_text, path, KF_GINS_GNSS).startswith(
        f"{path}, line 2: column 'lon': 'x' is not a")


def test_two_imu_lines_are_one_interval_one_is_refused(tmp_path):
    imu, gnss = _kf(tmp_path, _imu_rows([0.0, 0.01]), _gnss_rows([0.01]))
    assert read_kf_gins(imu, gnss).imu["time"].tolist() == [0.01]
    imu, gnss = _kf(tmp_path, _imu_rows([0.0]), _gnss_rows([0.0]))
    assert _refusal(read_kf_gins, imu, gnss) == (f"{imu}: at least two lines are needed (the "
                                                 "first only marks the start)")


def test_an_imu_row_refused_by_the_log_rules_is_named_by_its_file_line(tmp_path):
    rows = _imu_rows([0.0, 0.01, 0.02, 0.02, 0.04])
    text = "# header\n" + "".join(" ".join(str(v) for v in r) + "\n" for r in rows)
    imu, gnss = _kf(tmp_path, None, _gnss_rows([0.01, 0.04]), imu_text=text)
    assert _refusal(read_kf_gins, imu, gnss).startswith(f"{imu}, line 5: ")


def test_a_standard_deviation_of_zero_is_refused(tmp_path):
    imu, gnss = _kf(tmp_path, _imu_rows(np.arange(0.0, 2.01, 0.01)),
                    _gnss_rows([0.5, 1.0]) + _gnss_rows([1.5], std=(1.0, 0.0, 2.0)))
    assert _refusal(read_kf_gins, imu, gnss).startswith(
        f"{gnss}, line 3: std_e = 0 m, a standard deviation must be positive (is {gnss} the "
        "IMU file?")


def test_fixes_faster_than_imu_samples_are_refused_with_both_rates(tmp_path):
    # IMU at 2 Hz over 0.5 s (2 intervals), fixes at 10 Hz over 0.3 s
    imu, gnss = _kf(tmp_path, _imu_rows([0.0, 0.25, 0.5]), _gnss_rows([0.2, 0.3, 0.4, 0.5]))
    assert _refusal(read_kf_gins, imu, gnss) == (
        f"{gnss}: 10 fixes per second, more than the 4 IMU samples per second of {imu}: are the "
        "files swapped? (the order is IMU_FILE GNSS_FILE)")


@pytest.mark.parametrize("imu_times, gnss_times", [
    ([0.0, 1.0, 2.0, 3.0], [1.0, 2.0, 3.0]),     # the same rate: accepted
    ([0.0, 0.5], [0.5]),                          # one IMU sample and one fix: no rate
    ([0.0, 2.0, 4.0, 6.0], [4.0]),                # one fix: no rate (not 1 per second)
])
def test_rates_that_do_not_refuse(tmp_path, imu_times, gnss_times):
    imu, gnss = _kf(tmp_path, _imu_rows(imu_times), _gnss_rows(gnss_times))
    assert len(read_kf_gins(imu, gnss).gnss["time"]) == len(gnss_times)


def test_a_single_imu_interval_has_no_rate_to_compare(tmp_path):
    # one IMU sample (span 0) and fixes at 2 Hz: nothing to compare, accepted
    imu, gnss = _kf(tmp_path, _imu_rows([0.0, 1.0]), _gnss_rows([0.5, 1.0]))
    log = read_kf_gins(imu, gnss)          # times held relative to the whole second 1
    assert (log.time_origin, log.imu["time"].tolist()) == (1.0, [0.0])


def test_a_nav_reference_changing_week_is_refused_at_the_first_line_of_the_new_week(tmp_path):
    imu, gnss = _kf(tmp_path, _imu_rows([0.0, 1.0, 2.0]), _gnss_rows([1.0, 2.0]))
    nav = tmp_path / "truth.nav"
    nav.write_text("2000 604799 32 120 10 1 2 0.5 0 0 30\n"
                   "2001 0 32 120 10 1 2 0.5 0 0 30\n"
                   "2001 1 32 120 10 1 2 0.5 0 0 30\n")
    assert _refusal(read_kf_gins, imu, gnss, nav) == (
        f"{nav}, line 2: the GPS week changes from 2000 to 2001; split the file at the week "
        "boundary")


def test_a_folder_without_gps_files_names_the_gps_times_first(tmp_path):
    d = _gis(tmp_path / "run")
    (d / "gps_time.csv").unlink()
    (d / "gps-0.csv").unlink()
    assert _refusal(read_gnss_ins_sim, d) == f"{d / 'gps_time.csv'}: file not found"
