"""The sensor-log format and the converters: round trips, the rate-to-increment rule against
the analytic integral, KF-GINS files written by their documented layout, the gnss-ins-sim copy
against the scenario's log, and every kind of bad log giving one error naming file and line
with nothing written."""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from navcore.ins.rotations import euler_to_dcm_array
from navcore.sensors import sensorlog
from navcore.sensors.log_converters import read_gnss_ins_sim, read_kf_gins, trapezoid_increments
from navcore.sensors.sensorlog import LogError, SensorLog, read_log, write_log
from conftest import bits

ROOT = Path(__file__).resolve().parents[1]
GNSS_INS_SIM = ROOT / "tests" / "data" / "gnss-ins-sim" / "motion_def-3d_mid_100Hz"
SCENARIO_LOG = ROOT / "models" / "replay_gnss_ins_sim" / "log"


def _log(n=50, dt=0.01, t0=0.0, truth=True, seed=3):
    rng = np.random.default_rng(seed)
    t = t0 + dt * np.arange(1, n + 1)
    imu = {"time": t, "dt": np.full(n, dt)}
    for a in "xyz":
        imu[f"dtheta_{a}"] = 1e-4 * rng.standard_normal(n)
        imu[f"dvel_{a}"] = 1e-2 * rng.standard_normal(n)
    tg = t0 + np.arange(0.1, n * dt, 0.1)
    m = len(tg)
    gnss = {"time": tg, "lat": 0.7 + 1e-7 * rng.standard_normal(m),
            "lon": 2.0 + 1e-7 * rng.standard_normal(m), "h": 100 + rng.standard_normal(m),
            "vn": rng.standard_normal(m), "ve": rng.standard_normal(m),
            "vd": rng.standard_normal(m), "valid": (np.arange(m) % 3 != 1).astype(float)}
    tr = None
    if truth:
        tt = t0 + dt * np.arange(n + 1)
        tr = {k: rng.standard_normal(n + 1) * 0.1 for k in sensorlog.TRUTH_COLUMNS}
        tr["time"] = tt
    return SensorLog(imu, gnss, tr)


#: a log of two IMU intervals, two fixes and three truth samples, written by hand from
#: docs/sensor_log.md (titles ``name [unit]``, a flag's title its name alone, flags 0/1,
#: columns in any order)
HANDMADE = {
    "imu.csv": ("time [s],dt [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dvel_x [m/s],"
                "dvel_y [m/s],dvel_z [m/s]\n"
                "0.01,0.01,1e-05,-2e-05,0.0015,0.002,0,-0.0981\n"
                "0.02,0.01,-0.1,0.30000000000000004,0,5e-324,-0,-0.098\n"),
    "gnss.csv": ("lat [rad],time [s],lon [rad],h [m],vn [m/s],ve [m/s],vd [m/s],valid\n"
                 "0.7,0.01,2,100.5,1,-1,0.25,1\n"
                 "-0.7,0.02,-3.1,-20,0,0,0,0\n"),
    "truth.csv": ("time [s],lat [rad],lon [rad],h [m],vn [m/s],ve [m/s],vd [m/s],roll [rad],"
                  "pitch [rad],yaw [rad]\n"
                  "0,0.7,2,100,1,0,0,0.1,-0.2,3\n"
                  "0.01,0.7,2,100,1,0,0,0.1,-0.2,3\n"
                  "0.02,0.7,2,100,1,0,0,0.1,-0.2,-3\n"),
}


def test_a_handmade_log_reads_as_its_text_says(tmp_path):
    """The reader against text written by hand from the format's description (not by the
    writer): values, column order by title, the flags; and the writer's text of that log is
    the documented titles with %.17g numbers, checked against the hand-written values."""
    for name, text in HANDMADE.items():
        (tmp_path / "in").mkdir(exist_ok=True)
        (tmp_path / "in" / name).write_text(text)
    log = read_log(tmp_path / "in")
    assert log.imu["time"].tolist() == [0.01, 0.02] and log.imu["dt"].tolist() == [0.01, 0.01]
    assert log.imu["dtheta_y"].tolist() == [-2e-05, 0.1 + 0.2]
    assert log.imu["dvel_x"].tolist() == [0.002, 5e-324]
    assert bits(log.imu["dvel_y"][1]) == bits(-0.0)
    assert log.gnss["time"].tolist() == [0.01, 0.02] and log.gnss["lat"].tolist() == [0.7, -0.7]
    assert log.gnss["h"].tolist() == [100.5, -20.0] and log.gnss["valid"].tolist() == [1.0, 0.0]
    assert log.truth["yaw"].tolist() == [3.0, 3.0, -3.0] and log.truth["pitch"][0] == -0.2
    write_log(tmp_path / "out", log)
    imu = (tmp_path / "out" / "imu.csv").read_text().splitlines()
    assert imu[0] == HANDMADE["imu.csv"].splitlines()[0]
    assert imu[2].split(",") == ["0.02", "0.01", "-0.10000000000000001", "0.30000000000000004",
                                 "0", "4.9406564584124654e-324", "-0", "-0.098000000000000004"]
    gnss = (tmp_path / "out" / "gnss.csv").read_text().splitlines()
    assert gnss[0].split(",")[:2] == ["time [s]", "lat [rad]"] and gnss[0].endswith(",valid")
    assert gnss[1].split(",")[:2] == ["0.01", "0.69999999999999996"]


def test_self_consistency_write_read_round_trip_is_exact(tmp_path):
    """Self-consistency (the reader undoes the writer; the test above is the independent
    one): %.17g text keeps every float64 bit; optional columns survive; no truth -> None."""
    log = _log()
    write_log(tmp_path / "a", log)
    back = read_log(tmp_path / "a")
    for part in ("imu", "gnss", "truth"):
        a, b = getattr(log, part), getattr(back, part)
        assert set(a) == set(b)
        for k in a:
            assert np.array_equal(a[k], b[k]), (part, k)
    header = (tmp_path / "a" / "imu.csv").read_text().splitlines()[0]
    assert header == ("time [s],dt [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],"
                      "dvel_x [m/s],dvel_y [m/s],dvel_z [m/s]")
    # rewriting the folder with a log without truth removes the old truth.csv
    write_log(tmp_path / "a", _log(truth=False))
    assert read_log(tmp_path / "a").truth is None
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["gnss.csv", "imu.csv"]
    assert [p.name for p in tmp_path.iterdir()] == ["a"]  # no temporary folder left


def _edit(path, line, new):
    lines = path.read_text().splitlines()
    if new is None:
        del lines[line - 1]
    else:
        lines[line - 1] = new(lines[line - 1]) if callable(new) else new
    path.write_text("\n".join(lines) + "\n")


def _replace_field(column):
    def edit(text):
        fields = text.split(",")
        fields[column] = "nan"
        return ",".join(fields)
    return edit


BAD_LOGS = [
    ("imu.csv", 1, lambda s: s.replace(",dvel_z [m/s]", ""), 1, "missing column 'dvel_z [m/s]'"),
    ("imu.csv", 1, lambda s: s.replace("dtheta_x [rad]", "dtheta_x [deg]"), 1,
     "unit header 'dtheta_x [deg]', expected 'dtheta_x [rad]'"),
    ("gnss.csv", 1, lambda s: s.replace(",vd [m/s]", ""), 1, "missing 'vd'"),
    ("imu.csv", 6, _replace_field(3), 6, "column 'dtheta_y' is nan"),
    ("imu.csv", 6, None, 6, "gap of 0.01 s"),
    ("truth.csv", 5, lambda s: "0.02" + s[s.index(","):], 5, "duplicated time 0.02"),
    ("gnss.csv", 3, lambda s: "0.05" + s[s.index(","):], 3, "non-monotonic time 0.05"),
    ("imu.csv", 9, lambda s: s + ",1", 9, "9 values, but 8 column titles"),
    ("imu.csv", 4, lambda s: s.replace(s.split(",")[2], "1e-4+x", 1), 4, "is not a number"),
]


@pytest.mark.parametrize("file,line,edit,expect_line,message", BAD_LOGS,
                         ids=["missing-column", "unit", "partial-group", "nan", "gap",
                              "duplicate", "non-monotonic", "extra-value", "expression"])
def test_bad_log_names_file_and_line(tmp_path, file, line, edit, expect_line, message):
    write_log(tmp_path / "log", _log())
    path = tmp_path / "log" / file
    _edit(path, line, edit)
    with pytest.raises(LogError) as exc:
        read_log(tmp_path / "log")
    text = str(exc.value)
    assert text.startswith(f"{path}, line {expect_line}: "), text
    assert message in text, text


def test_gnss_file_without_a_fix_and_bad_flags(tmp_path):
    log = _log()
    log.gnss["valid"][:] = 0.0
    with pytest.raises(LogError, match=r"gnss.csv: no valid fix"):
        write_log(tmp_path / "log", log)
    assert not (tmp_path / "log").exists()  # checked before anything is written
    log = _log()
    log.gnss["valid"][2] = 0.5
    with pytest.raises(LogError, match=r"gnss.csv, line 4: column 'valid' is 0.5"):
        write_log(tmp_path / "log", log)


def test_imu_intervals_that_do_not_tile_and_truth_gap_are_errors(tmp_path):
    log = _log()
    log.imu["dt"][10] = 0.011
    with pytest.raises(LogError, match=r"imu.csv, line 12: overlap of 0.001 s between the "
                       r"interval ending at 0.1 s \(line 11\)"):
        write_log(tmp_path / "log", log)
    log = _log()
    log.truth["time"][20:] += 1.5
    with pytest.raises(LogError, match=r"truth.csv, line 22: gap of 1.51 s .* bound 1 s"):
        write_log(tmp_path / "log", log)


def test_oversized_file_is_refused_before_parsing(tmp_path, monkeypatch):
    write_log(tmp_path / "log", _log())
    monkeypatch.setattr(sensorlog, "MAX_FILE_BYTES", 1000)
    with pytest.raises(LogError, match=r"imu.csv: \d+ bytes, more than the limit of 1000"):
        read_log(tmp_path / "log")


# -- rates to increments -------------------------------------------------------------------
def test_trapezoid_increments_against_the_analytic_integral():
    """w(t) = sin(a t): exact increment (cos(a t0) - cos(a t1)) / a.  The per-interval error
    of the trapezoid (trapezoid - exact) is dt^3 w''/12 + O(dt^5) (third order: halving dt divides
    it by 8), and
    a rate linear in time is integrated exactly."""
    a = 3.0
    errors = []
    for dt in (0.02, 0.01, 0.005):
        t = np.arange(0.0, 2.0 + dt / 2, dt)
        inc = trapezoid_increments(t, np.sin(a * t)[:, None])[:, 0]
        exact = (np.cos(a * t[:-1]) - np.cos(a * t[1:])) / a
        predicted = -dt**3 * a**2 * np.sin(a * (t[:-1] + dt / 2)) / 12  # dt^3 w''/12
        err = inc - exact
        assert np.max(np.abs(err - predicted)) < 0.02 * np.max(np.abs(predicted))
        errors.append(np.max(np.abs(err)))
    assert errors[0] / errors[1] == pytest.approx(8.0, rel=0.02)
    assert errors[1] / errors[2] == pytest.approx(8.0, rel=0.02)
    t = np.linspace(0.0, 1.0, 11)
    inc = trapezoid_increments(t, (2.0 + 5.0 * t)[:, None])[:, 0]
    assert np.allclose(inc, 2.0 * 0.1 + 2.5 * (t[1:] ** 2 - t[:-1] ** 2), rtol=1e-14, atol=0)


# -- KF-GINS -------------------------------------------------------------------------------
def _write_kf_gins(folder, log, week=2200):
    """A log in KF-GINS's text layout (as their documentation states it), written here
    independently of the converter: degrees, whitespace separated, no titles."""
    imu, gnss, truth = log.imu, log.gnss, log.truth
    first = np.concatenate([[imu["time"][0] - imu["dt"][0]], np.zeros(6)])
    rows = np.column_stack([imu["time"]] + [imu[k] for k in
                                            ("dtheta_x", "dtheta_y", "dtheta_z",
                                             "dvel_x", "dvel_y", "dvel_z")])
    np.savetxt(folder / "imu.txt", np.vstack([first, rows]), fmt="%.17g")
    d = 180.0 / math.pi
    np.savetxt(folder / "gnss.txt", np.column_stack(
        [gnss["time"], gnss["lat"] * d, gnss["lon"] * d, gnss["h"], gnss["std_n"],
         gnss["std_e"], gnss["std_d"]]), fmt="%.17g", delimiter="  ")
    np.savetxt(folder / "truth.nav", np.column_stack(
        [np.full(len(truth["time"]), week), truth["time"], truth["lat"] * d, truth["lon"] * d,
         truth["h"], truth["vn"], truth["ve"], truth["vd"], truth["roll"] * d,
         truth["pitch"] * d, truth["yaw"] * d]), fmt="%.17g")


def test_kf_gins_files_round_trip_through_the_converter(tmp_path, navfmu_cli):
    log = _log(n=400, dt=0.005, t0=456300.0)
    for k in ("vn", "ve", "vd"):
        del log.gnss[k]
    log.gnss["valid"][:] = 1.0
    for k, s in (("std_n", 1.5), ("std_e", 1.2), ("std_d", 3.0)):
        log.gnss[k] = np.full(len(log.gnss["time"]), s)
    log.truth["yaw"] = np.clip(log.truth["yaw"], -3.0, 3.0)
    _write_kf_gins(tmp_path, log)
    code, out, _ = navfmu_cli("convert", "kf-gins", tmp_path / "imu.txt", tmp_path / "gnss.txt",
                              tmp_path / "truth.nav", tmp_path / "log")
    assert code == 0
    assert "400 IMU intervals of 0.005 s" in out
    back = read_log(tmp_path / "log")
    assert not back.has_gnss_velocity
    assert back.time_origin == 456300.0     # times held relative to the whole second
    for part in ("imu", "gnss", "truth"):
        a, b = getattr(log, part), getattr(back, part)
        b["time"] = b["time"] + back.time_origin
        assert set(a) == set(b), part
        for k in a:
            # degrees <-> radians: a few ulp; dt differenced from times near 4.6e5 s: 1e-10 s
            assert np.allclose(b[k], a[k], rtol=1e-13, atol=1e-9 if k == "dt" else 1e-15), (part, k)


def test_kf_gins_bad_files(tmp_path):
    log = _log(n=100, dt=0.005, t0=1000.0)
    for k, s in (("std_n", 1.5), ("std_e", 1.2), ("std_d", 3.0)):
        log.gnss[k] = np.full(len(log.gnss["time"]), s)
    _write_kf_gins(tmp_path, log)
    lines = (tmp_path / "imu.txt").read_text().splitlines()
    lines[30] = lines[29]
    (tmp_path / "imu.txt").write_text("\n".join(lines) + "\n")
    with pytest.raises(LogError, match=r"imu.txt, line 31: duplicated time"):
        read_kf_gins(tmp_path / "imu.txt", tmp_path / "gnss.txt")
    (tmp_path / "gnss.txt").write_text("1000.1 30.0 114.0 20.0 1.0 1.0\n")
    with pytest.raises(LogError, match=r"gnss.txt, line 1: 6 values, expected 7"):
        read_kf_gins(tmp_path / "imu.txt", tmp_path / "gnss.txt")


# -- gnss-ins-sim ----------------------------------------------------------------------------
def test_gnss_ins_sim_copy_self_consistency_with_the_scenario_log(tmp_path):
    """Self-consistency: the checked-in gnss-ins-sim run converts to exactly the log the
    scenario ships (which this converter made), and the conversion follows the stated rule on
    the raw samples.  Its attitude is zero throughout, so the test against gnss-ins-sim's own
    references is the one below, on a run whose roll, pitch and yaw differ."""
    log = read_gnss_ins_sim(GNSS_INS_SIM)
    shipped = read_log(SCENARIO_LOG)
    for part in ("imu", "gnss", "truth"):
        a, b = getattr(log, part), getattr(shipped, part)
        assert set(a) == set(b)
        for k in a:
            assert np.array_equal(a[k], b[k]), (part, k)
    t = np.loadtxt(GNSS_INS_SIM / "time.csv", skiprows=1)
    gyro = np.loadtxt(GNSS_INS_SIM / "gyro-0.csv", delimiter=",", skiprows=1)
    k = 4321
    assert log.imu["time"][k - 1] == t[k]
    assert log.imu["dtheta_z"][k - 1] == pytest.approx(
        0.5 * (t[k] - t[k - 1]) * math.radians(gyro[k - 1, 2] + gyro[k, 2]), rel=1e-15)
    assert len(log.gnss["time"]) == 81 and int(log.gnss["valid"].sum()) == 41
    assert log.imu_period == pytest.approx(0.01) and log.stop_time == pytest.approx(80.05)


GNSS_INS_SIM_ATTITUDE = GNSS_INS_SIM.parent / "motion_def-attitude_mid_100Hz"


def _gnss_ins_sim_columns(name):
    """One gnss-ins-sim CSV read here, not by the converter: {title without unit: column}."""
    path = GNSS_INS_SIM_ATTITUDE / name
    titles = [t.split("(")[0].strip() for t in path.read_text().splitlines()[0].split(",")]
    values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {title: values[:, j] for j, title in enumerate(titles)}


def _body_to_ned_from_quaternion(q0, q1, q2, q3):
    """The rotation matrices (n, 3, 3) of unit quaternions, scalar first, body to NED (the
    textbook formula; gnss-ins-sim's ref_att_quat.csv convention)."""
    return np.moveaxis(np.array([
        [q0**2 + q1**2 - q2**2 - q3**2, 2 * (q1*q2 - q0*q3), 2 * (q1*q3 + q0*q2)],
        [2 * (q1*q2 + q0*q3), q0**2 - q1**2 + q2**2 - q3**2, 2 * (q2*q3 - q0*q1)],
        [2 * (q1*q3 - q0*q2), 2 * (q2*q3 + q0*q1), q0**2 - q1**2 - q2**2 + q3**2]]), -1, 0)


@pytest.fixture(scope="module")
def converted_attitude_run(tmp_path_factory):
    """`navfmu convert` of the gnss-ins-sim run whose attitude turns about all three axes."""
    from orchestrator.cli.commands import main
    out = tmp_path_factory.mktemp("attitude") / "log"
    with pytest.raises(SystemExit) as exc:
        main(["convert", "gnss-ins-sim", str(GNSS_INS_SIM_ATTITUDE), str(out)])
    assert exc.value.code == 0
    return read_log(out)


def test_gnss_ins_sim_truth_attitude_against_its_own_references(converted_attitude_run):
    """The converted truth's roll, pitch, yaw [rad] against gnss-ins-sim's ref_att_euler.csv
    (columns found by their titles here) and, through navcore's ZYX rotation, against the
    body-to-NED matrices of ref_att_quat.csv, which the converter never reads.  The run's
    angles are all different and change (roll -4..16, pitch 2..10.9 deg, yaw through 180 deg),
    so a swapped pair, a sign or degrees for radians fails."""
    truth = converted_attitude_run.truth
    assert np.array_equal(truth["time"], _gnss_ins_sim_columns("time.csv")["time"])
    euler = _gnss_ins_sim_columns("ref_att_euler.csv")
    for ours, theirs in (("roll", "ref_Roll"), ("pitch", "ref_Pitch"), ("yaw", "ref_Yaw")):
        difference = np.angle(np.exp(1j * (truth[ours] - np.radians(euler[theirs]))))
        assert np.abs(difference).max() < 1e-12, ours
    q = _gnss_ins_sim_columns("ref_att_quat.csv")
    reference = _body_to_ned_from_quaternion(q["q0"], q["q1"], q["q2"], q["q3"])
    ours = euler_to_dcm_array(truth["roll"], truth["pitch"], truth["yaw"])
    assert np.abs(ours - reference).max() < 1e-12
    assert np.ptp(truth["roll"]) > np.radians(19) and np.ptp(truth["pitch"]) > np.radians(8)


def test_gnss_ins_sim_truth_position_velocity_and_fixes_against_its_files(
        converted_attitude_run):
    """Truth position [rad, m] and NED velocity at the GPS instants against ref_gps.csv (not
    read by the converter), and the fixes against gps-0.csv, gps_visibility.csv."""
    log = converted_attitude_run
    reference = _gnss_ins_sim_columns("ref_gps.csv")
    gps_time = _gnss_ins_sim_columns("gps_time.csv")["gps_time"]
    at_fix = np.searchsorted(log.truth["time"], gps_time)
    assert np.array_equal(log.truth["time"][at_fix], gps_time)
    for ours, theirs, scale in (("lat", "ref_gps_lat", math.radians(1)),
                                ("lon", "ref_gps_lon", math.radians(1)), ("h", "ref_gps_alt", 1),
                                ("vn", "ref_gps_vN", 1), ("ve", "ref_gps_vE", 1),
                                ("vd", "ref_gps_vD", 1)):
        assert log.truth[ours][at_fix] == pytest.approx(scale * reference[theirs],
                                                        rel=1e-14, abs=1e-14), ours
    measured = _gnss_ins_sim_columns("gps-0.csv")
    assert np.array_equal(log.gnss["time"], gps_time)
    for ours, theirs, scale in (("lat", "gps_lat", math.radians(1)),
                                ("lon", "gps_lon", math.radians(1)), ("h", "gps_alt", 1),
                                ("vn", "gps_vN", 1), ("ve", "gps_vE", 1), ("vd", "gps_vD", 1)):
        assert log.gnss[ours] == pytest.approx(scale * measured[theirs], rel=1e-15), ours
    visible = _gnss_ins_sim_columns("gps_visibility.csv")["gps_visibility"]
    assert np.array_equal(log.gnss["valid"], visible) and visible.sum() == 17


def test_gnss_ins_sim_imu_increments_against_its_true_rates(converted_attitude_run):
    """The converted increments over each interval divided by dt against the trapezoid of
    gnss-ins-sim's true rates (ref_gyro.csv, ref_accel.csv, not read by the converter), within
    6 sigma of the grade's white noise (../README.md: ARW 0.25 deg/sqrt(h), VRW 0.03
    m/s/sqrt(h), sampled at 100 Hz, two samples per trapezoid).  The body rates reach 8 deg/s
    and the specific forces differ by 0.17 m/s^2 or more between axes, so an axis swap, a sign
    or degrees for radians is far outside."""
    imu, dt = converted_attitude_run.imu, converted_attitude_run.imu["dt"]
    assert np.array_equal(imu["time"], _gnss_ins_sim_columns("time.csv")["time"][1:])
    rate_sigma = {"ref_gyro": math.radians(0.25 / 60) * 10 / math.sqrt(2),  # rad/s
                  "ref_accel": 0.03 / 60 * 10 / math.sqrt(2)}  # m/s^2
    for reference, ours, scale in (("ref_gyro", "dtheta", math.radians(1)),
                                   ("ref_accel", "dvel", 1.0)):
        true = _gnss_ins_sim_columns(f"{reference}.csv")
        for axis in "xyz":
            rate = scale * true[f"{reference}_{axis}"]
            error = imu[f"{ours}_{axis}"] / dt - 0.5 * (rate[:-1] + rate[1:])
            assert np.abs(error).max() < 6 * rate_sigma[reference], (ours, axis)


def test_gnss_ins_sim_unit_error_and_nothing_written(tmp_path, navfmu_cli):
    src = tmp_path / "sim"
    shutil.copytree(GNSS_INS_SIM, src)
    text = (src / "gyro-0.csv").read_text().replace("gyro_y (deg/s)", "gyro_y (rad/s)", 1)
    (src / "gyro-0.csv").write_text(text)
    code, _, err = navfmu_cli("convert", "gnss-ins-sim", src, tmp_path / "out")
    assert code == 2
    assert err.startswith(f"navfmu: error: {src / 'gyro-0.csv'}, line 1: column 'gyro_y "
                          "(rad/s)' does not match the expected 'gyro_y (deg/s)'")
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim"]


def test_docs_list_every_column_with_its_unit():
    """docs/sensor_log.md documents the format: every column of every file, with its unit,
    in that file's table."""
    text = (ROOT / "docs" / "sensor_log.md").read_text()
    for name, columns in sensorlog.COLUMNS.items():
        section = text.split(f"### {name}", 1)[1].split("###", 1)[0]
        rows = [r for r in section.splitlines() if r.startswith("| `")]
        for column, unit in columns.items():
            row = next((r for r in rows if f"`{column}`" in r.split("|")[1]), None)
            assert row is not None, (name, column)
            assert row.split("|")[2].strip() == (unit or "-"), (name, column, row)
