"""`navfmu convert rtklib`: RTKLIB .pos solutions as the log's gnss.csv.  On the trimmed real
drive (tests/data/rtklib_drive) against values read off its lines by hand; on small files
written here with sigmas and velocities distinct per axis (a swap of N/E/D shows), the ECEF
form built with the textbook WGS-84 formulas (independent of the converter's library)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from navcore.errors import LogError
from navcore.sensors.rtklib_pos import read_rtklib_pos
from navcore.sensors.sensorlog import read_log

DATA = Path(__file__).parent / "data" / "rtklib_drive"
POS = DATA / "gnss_1934_sf_trimmed.pos"
IMU = DATA / "imu_1934_trimmed.csv"
D2R = math.pi / 180.0
LLH_TITLES = ("%  GPST          latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   "
              "sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio    vn(m/s)    ve(m/s)"
              "    vu(m/s)      sdvn     sdve     sdvu    sdvne    sdveu    sdvun\n")
XYZ_TITLES = ("%  GPST               x-ecef(m)      y-ecef(m)      z-ecef(m)   Q  ns   sdx(m)"
              "   sdy(m)   sdz(m)  sdxy(m)  sdyz(m)  sdzx(m) age(s)  ratio    vx(m/s)    "
              "vy(m/s)    vz(m/s)      sdvx     sdvy     sdvz    sdvxy    sdvyz    sdvzx\n")


def test_the_real_drive_by_hand():
    """Lines 2 and 172 of the drive (a fix and a float epoch) read off by hand."""
    gnss, origin, counts = read_rtklib_pos(POS)
    assert counts == {"fix": 68, "float": 8}
    # 2025/07/08 19:34:18.499 GPST: Tuesday of week 2374, 2 * 86400 + 70458.499 s
    assert origin == 243258.0 and gnss["time"][0] == pytest.approx(0.499, abs=1e-12)
    assert gnss["lat"][0] == 40.0966268 * D2R and gnss["lon"][0] == -105.1474483 * D2R
    assert gnss["h"][0] == 1601.474
    assert (gnss["std_n"][0], gnss["std_e"][0], gnss["std_d"][0]) == (0.0098995, 0.0098995,
                                                                       0.01)
    assert (gnss["vn"][0], gnss["ve"][0], gnss["vd"][0]) == (0.01, -0.002, -0.009)
    assert gnss["std_vn"][0] == 0.0586899 and gnss["valid"].all()
    k = 66      # line 172: 2025/07/08 19:35:00.999, Q 2, sdn 0.0190919, sdu 0.0290000
    assert gnss["time"][k] == pytest.approx(42.999, abs=1e-12)
    assert (gnss["std_n"][k], gnss["std_d"][k]) == (0.0190919, 0.029)


def test_quality_kept_and_sigmas_scaled_per_quality():
    gnss, _, _ = read_rtklib_pos(POS, keep=(1,), sigma_scale={1: 2.0, 2: 10.0})
    assert gnss["valid"].sum() == 68 and not gnss["valid"][66:74].any()
    assert gnss["std_n"][66] == pytest.approx(0.190919, rel=1e-15)        # float x 10
    assert gnss["std_d"][0] == 0.02 and gnss["std_vn"][0] == 2 * 0.0586899  # fix x 2


def test_unix_time_and_week_seconds_are_the_same_instants(tmp_path):
    gnss, origin, _ = read_rtklib_pos(POS, time_scale="unix")
    # 1980-01-06 is 315964800 s after 1970-01-01; week 2374 starts 2374 * 604800 s later
    assert origin == 315964800 + 2374 * 604800 + 243258 == 1752003258
    lines = POS.read_text().splitlines()
    week_form = [lines[0]] + [f"2374 {243258.499 + 0.25 * k:.3f} " + " ".join(
        line.split()[2:]) for k, line in enumerate(lines[1:5])]
    (tmp_path / "w.pos").write_text("\n".join(week_form) + "\n")
    by_week, week_origin, _ = read_rtklib_pos(tmp_path / "w.pos")
    date, _, _ = read_rtklib_pos(POS)
    assert week_origin == 243258.0
    assert np.array_equal(by_week["time"], date["time"][:4])
    assert np.array_equal(by_week["lat"], date["lat"][:4])


def _llh_line(t, lat, lon, h, q, sig, vel, vsig):
    return (f"{t} {lat:.9f} {lon:.9f} {h:.4f} {q} 12 {sig[0]} {sig[1]} {sig[2]} 0 0 0 0.0 "
            f"0.0 {vel[0]} {vel[1]} {vel[2]} {vsig[0]} {vsig[1]} {vsig[2]} 0 0 0\n")


def test_llh_sigmas_and_velocity_keep_their_axes(tmp_path):
    """sdn/sde/sdu 0.011/0.022/0.033 m become std_n/e/d; vn/ve/vu 1.5/-2.5/0.5 m/s become
    vn/ve/vd = 1.5/-2.5/-0.5; sdvn/sdve/sdvu 0.04/0.05/0.06 become std_vn/ve/vd."""
    path = tmp_path / "llh.pos"
    path.write_text(LLH_TITLES + _llh_line("2025/07/08 19:34:18.500", 40.5, -105.25, 1600, 1,
                                           (0.011, 0.022, 0.033), (1.5, -2.5, 0.5),
                                           (0.04, 0.05, 0.06)))
    gnss, _, _ = read_rtklib_pos(path)
    assert [gnss[k][0] for k in ("std_n", "std_e", "std_d")] == [0.011, 0.022, 0.033]
    assert [gnss[k][0] for k in ("vn", "ve", "vd")] == [1.5, -2.5, -0.5]
    assert [gnss[k][0] for k in ("std_vn", "std_ve", "std_vd")] == [0.04, 0.05, 0.06]


def _ecef(lat, lon, h):
    """WGS-84 geodetic to ECEF (the textbook closed form)."""
    a, f = 6378137.0, 1.0 / 298.257223563
    e2 = f * (2.0 - f)
    n = a / math.sqrt(1.0 - e2 * math.sin(lat) ** 2)
    return np.array([(n + h) * math.cos(lat) * math.cos(lon),
                     (n + h) * math.cos(lat) * math.sin(lon),
                     (n * (1.0 - e2) + h) * math.sin(lat)])


def _ecef_from_ned(lat, lon):
    sl, cl, sp, cp = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    return np.array([[-sl * cp, -sp, -cl * cp], [-sl * sp, cp, -cl * sp], [cl, 0.0, -sl]])


def _sqvar(c):
    return math.copysign(math.sqrt(abs(c)), c)


def test_ecef_position_sigmas_and_velocity_rotated_to_ned(tmp_path):
    """A NED covariance diag(0.01, 0.02, 0.05)^2 m^2 and velocity (1, 2, -0.5) m/s at
    40 deg N, 105 deg W written as RTKLIB's ECEF form: read back as the same NED values."""
    lat, lon, h = 40.0 * D2R, -105.0 * D2R, 1600.0
    rot = _ecef_from_ned(lat, lon)
    pos = _ecef(lat, lon, h)
    cov = rot @ np.diag([0.01, 0.02, 0.05]) ** 2 @ rot.T
    vcov = rot @ np.diag([0.03, 0.04, 0.07]) ** 2 @ rot.T
    vel = (rot @ np.array([1.0, 2.0, -0.5])).tolist()
    pos = pos.tolist()

    def sd(c):
        c = c.tolist()
        return (f"{math.sqrt(c[0][0])!r} {math.sqrt(c[1][1])!r} {math.sqrt(c[2][2])!r} "
                f"{_sqvar(c[0][1])!r} {_sqvar(c[1][2])!r} {_sqvar(c[2][0])!r}")
    path = tmp_path / "xyz.pos"
    path.write_text(XYZ_TITLES + f"2374 243258.500 {pos[0]!r} {pos[1]!r} {pos[2]!r} 1 12 "
                    f"{sd(cov)} 0.0 0.0 {vel[0]!r} {vel[1]!r} {vel[2]!r} {sd(vcov)}\n")
    gnss, _, _ = read_rtklib_pos(path)
    assert gnss["lat"][0] == pytest.approx(lat, abs=1e-14)
    assert gnss["lon"][0] == pytest.approx(lon, abs=1e-14)
    assert gnss["h"][0] == pytest.approx(h, abs=1e-6)
    assert [gnss[k][0] for k in ("std_n", "std_e", "std_d")] == pytest.approx(
        [0.01, 0.02, 0.05], rel=1e-9)
    assert [gnss[k][0] for k in ("vn", "ve", "vd")] == pytest.approx([1.0, 2.0, -0.5],
                                                                     abs=1e-12)
    assert [gnss[k][0] for k in ("std_vn", "std_ve", "std_vd")] == pytest.approx(
        [0.03, 0.04, 0.07], rel=1e-9)


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("%  GPST ", "%  UTC  ", 1), "time system UTC: only GPST is read"),
    (lambda t: t.replace("latitude(deg) longitude(deg)", "latitude(d'\") longitude(d'\")", 1),
     "latitude in degrees, minutes and seconds"),
    (lambda t: t.replace("0.0098995 0.0098995 0.0100000", "0.0000000 0.0098995 0.0100000", 1),
     "line 2: std_n = 0 m for a kept epoch of quality fix"),
    (lambda t: t.replace("2025/07/08 19:34:18.749", "2025/07/08 19:34:18.x", 1),
     "line 3: time '2025/07/08 19:34:18.x' is neither"),
])
def test_refusals_name_the_file_line_and_setting(tmp_path, edit, message):
    path = tmp_path / "bad.pos"
    path.write_text(edit(POS.read_text()))
    with pytest.raises(LogError, match=message.replace("(", r"\(").replace(")", r"\)")):
        read_rtklib_pos(path)


def test_a_week_boundary_in_week_seconds_is_refused(tmp_path):
    path = tmp_path / "weeks.pos"
    line = " 40.0 -105.0 1600.0 1 12 0.01 0.02 0.03 0 0 0 0 0 0 0 0 0.1 0.1 0.1 0 0 0\n"
    path.write_text(LLH_TITLES + "2025/07/12 23:59:59.750" + line + "2025/07/13 00:00:00.000"
                    + line)
    with pytest.raises(LogError, match="line 3: the GPS week changes from 2374 to 2375"):
        read_rtklib_pos(path)
    gnss, origin, _ = read_rtklib_pos(path, time_scale="unix")
    assert gnss["time"][1] - gnss["time"][0] == 0.25


def test_cli_converts_the_drive_into_one_log_in_two_parts(tmp_path, navfmu_cli):
    """rtklib then imu-csv into one folder: a log read_log accepts, in UNIX seconds (GPST);
    an existing gnss.csv kept without --force; a bad --keep named."""
    dst = tmp_path / "log"
    code, out, err = navfmu_cli("convert", "rtklib", POS, dst, "--time", "unix", "--keep",
                                "fix", "--sigma-scale", "float=10")
    assert code == 0, err
    assert "76 epochs (fix 68, float 8; 68 valid)" in out and "has no imu.csv yet" in out
    code, out, err = navfmu_cli("convert", "imu-csv", IMU, dst, "--time", "7", "--time-unit",
                                "ms", "--start", "1752003261.854", "--gyro",
                                "x=col4,y=col5,z=col6", "--accel", "x=col1,y=col2,z=col3",
                                "--gyro-unit", "deg/s", "--accel-unit", "g")
    assert code == 0, err
    assert "1199 IMU intervals" in out and "is a complete log" in out
    log = read_log(dst)
    assert log.time_origin == 1752003261.0
    assert log.gnss["valid"].sum() == 68 and log.has_gnss_velocity
    code, _, err = navfmu_cli("convert", "rtklib", POS, dst)
    assert code == 2 and err.startswith(f"navfmu: error: convert: {dst / 'gnss.csv'} exists")
    code, _, err = navfmu_cli("convert", "rtklib", POS, tmp_path / "x", "--keep", "fixed")
    assert code == 2 and "--keep: unknown quality 'fixed'" in err
    assert not (tmp_path / "x" / "gnss.csv").exists()
