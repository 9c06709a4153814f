"""Readers of other tools' sensor data, returning a :class:`~navcore.sensors.sensorlog.SensorLog`.

gnss-ins-sim (Aceinna, MIT licence; run with ``ref_frame=0``, the NED frame with latitude and
longitude: the local frame of ``ref_frame=1`` is refused) writes one CSV per quantity with
``name (unit)`` titles:
``time.csv`` (sec), ``gyro-R.csv`` (deg/s), ``accel-R.csv`` (m/s^2) for run ``R`` at the IMU
sample instants; ``gps_time.csv`` (sec), ``gps-R.csv`` (lat deg, lon deg, alt m, vN/vE/vD
m/s) and ``gps_visibility.csv`` (1 with a fix) at the GPS instants; and, when present, the
reference ``ref_pos.csv`` (lat, lon deg, alt m), ``ref_vel.csv`` (NED m/s) and
``ref_att_euler.csv`` (yaw, pitch, roll deg, ZYX) at the IMU instants.

KF-GINS (i2Nav, Wuhan University) reads whitespace- (or comma-) separated text without titles:
the IMU file ``time [s], dtheta_x/y/z [rad], dvel_x/y/z [m/s]`` (increments over the interval
ending at ``time``, body forward-right-down), the GNSS file ``time [s], lat [deg], lon [deg],
h [m], std_n/e/d [m]`` (7 columns: positions only) or ``time, lat, lon, h, vn/ve/vd [m/s],
std_n/e/d, std_vn/ve/vd [m/s]`` (13 columns, with velocity: KF-GINS's loader reads the
position sigmas from columns 8-10 of such a file; the velocity and its sigmas are kept as
``vn/ve/vd`` and ``std_vn/ve/vd``), every line a valid fix, and writes its solution and
reference as ``.nav`` text ``week, sow [s], lat [deg], lon [deg], h [m], vn/ve/vd [m/s],
roll/pitch/yaw [deg]``.

Rates to increments (gnss-ins-sim): the samples are the rates at the instants ``t_k``; the
increment over ``[t_{k-1}, t_k]`` is the trapezoid ``(t_k - t_{k-1}) (w_{k-1} + w_k) / 2``.
Its error over one interval (trapezoid minus exact integral) is ``dt^3 w''/12`` plus higher
orders (third order in the step; second order over a fixed time span), exact for rates
linear in time.  KF-GINS's first IMU line only marks the
start (its interval is unknown): the log starts with the second line, ``dt`` is the
difference of consecutive times.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from ..ins.constants import DEG as _D2R
from ..ins.rotations import wrap_angle
from .log_time import exact_intervals, exact_times
from .sensorlog import (GNSS_FILE, IMU_FILE, TRUTH_FILE, LogError, SensorLog, check_log,
    parse_numbers, parse_rows, read_lines)

_TITLE = re.compile(r"^\s*(?P<name>[^()]*?)\s*(?:\((?P<unit>[^)]*)\))?\s*$")


# -- text tables -----------------------------------------------------------------------------
def read_titled_csv(path, expected: Sequence[tuple]) -> np.ndarray:
    """A gnss-ins-sim CSV: titles ``name (unit)`` equal to ``expected`` ((name, unit), ...;
    name None = any name), then rows of numbers.  Returns an (n, columns) array."""
    path = Path(path)
    lines = read_lines(path)
    if not lines:
        raise LogError(f"{path}, line 1: no column titles")
    titles = [t for t in lines[0].split(",")]
    if len(titles) != len(expected):
        raise LogError(f"{path}, line 1: {len(titles)} columns, expected {len(expected)} ("
                       + ", ".join(f"{n or '*'} ({u})" for n, u in expected) + ")")
    names = []
    for title, (name, unit) in zip(titles, expected):
        m = _TITLE.match(title)
        got_unit = (m.group("unit") or "").strip() if m else None
        if got_unit != unit or (name is not None and m.group("name") != name):
            raise LogError(f"{path}, line 1: column '{title.strip()}' does not match the "
                           f"expected '{name or '*'} ({unit})'")
        names.append(m.group("name"))
    return parse_rows(path, lines, names)[0]


def read_plain_text(path, names: Sequence[str], *layouts: Sequence[str]):
    """A KF-GINS text file: no titles, ``len(names)`` numbers per line separated by
    whitespace or commas; ``#`` starts a comment.  Further ``layouts`` (other column lists)
    are accepted too, chosen by the number of values on the first line.  Returns an (n,
    columns) array, the line number of each row and the column names."""
    rows, numbers, names = plain_text_fields(path, names, *layouts)
    return parsed(path, rows, numbers, names), numbers, names


def parsed(path, rows, numbers, names) -> np.ndarray:
    """The text ``rows`` (lines ``numbers``) as an (n, columns) array of finite floats."""
    return np.array([parse_numbers(path, n, r, names) for r, n in zip(rows, numbers)],
                    dtype=np.float64)


def plain_text_fields(path, names: Sequence[str], *layouts: Sequence[str]):
    """:func:`read_plain_text` as text: the fields of each row (a list of strings; a time
    is then read exactly, :mod:`navcore.sensors.log_time`), the line numbers, the names."""
    path = Path(path)
    rows, numbers = [], []
    accepted = {len(c): c for c in (names, *layouts)}
    for number, line in enumerate(read_lines(path), start=1):
        fields = line.split("#", 1)[0].replace(",", " ").split()
        if not fields:
            continue
        if not rows and len(fields) in accepted:
            names = accepted[len(fields)]
        if len(fields) != len(names):
            expected = (f"{len(names)} ({', '.join(names)})" if not layouts or rows else
                        " or ".join(f"{len(c)} ({', '.join(c)})" for c in accepted.values()))
            raise LogError(f"{path}, line {number}: {len(fields)} values, expected {expected}")
        rows.append(fields)
        numbers.append(number)
    if not rows:
        raise LogError(f"{path}: no samples")
    return rows, np.array(numbers), tuple(names)


# -- rates to increments ---------------------------------------------------------------------
def trapezoid_increments(time, rates):
    """Increments over ``[t_{k-1}, t_k]`` (n-1 rows) of rates sampled at the instants ``time``
    (n,), ``rates`` (n, m): ``dt (w_{k-1} + w_k) / 2`` (module docstring)."""
    return trapezoid_over(np.diff(np.asarray(time, dtype=float)), rates)


def trapezoid_over(dt, rates):
    """:func:`trapezoid_increments` of the intervals ``dt`` (n-1,) between the samples."""
    rates = np.asarray(rates, dtype=float)
    return 0.5 * np.asarray(dt, dtype=float)[:, None] * (rates[:-1] + rates[1:])


# -- gnss-ins-sim ----------------------------------------------------------------------------
def _same_length(path_a, a, path_b, b):
    if len(a) != len(b):
        raise LogError(f"{path_b}: {len(b)} samples, but {path_a} has {len(a)} (one line per "
                       "sample time)")


def _refuse_local_frame(path) -> None:
    """gnss-ins-sim's ``ref_frame=1`` writes positions in a local frame (``gps_x (m)``...):
    refused, naming the setting (only ``ref_frame=0``, NED with latitude/longitude, is read)."""
    lines = read_lines(path) if Path(path).is_file() else []
    first = lines[0].split(",")[0].strip() if lines else ""
    if first.startswith("gps_x"):
        raise LogError(f"{path}, line 1: column '{first}': this gnss-ins-sim run used "
                       "ref_frame=1 (positions in a local frame, in metres); only ref_frame=0 "
                       "(NED, latitude and longitude in degrees) is read: run the simulation "
                       "with ref_frame=0")


def read_gnss_ins_sim(folder, run: int = 0) -> SensorLog:
    """The log of run ``run`` of a gnss-ins-sim output folder (module docstring)."""
    d = Path(folder)
    if not d.is_dir():
        raise LogError(f"gnss-ins-sim folder not found: {d}")
    xyz = ("x", "y", "z")
    time = read_titled_csv(d / "time.csv", [("time", "sec")])[:, 0]
    gyro = read_titled_csv(d / f"gyro-{run}.csv", [(f"gyro_{a}", "deg/s") for a in xyz])
    accel = read_titled_csv(d / f"accel-{run}.csv", [(f"accel_{a}", "m/s^2") for a in xyz])
    _same_length(d / "time.csv", time, d / f"gyro-{run}.csv", gyro)
    _same_length(d / "time.csv", time, d / f"accel-{run}.csv", accel)
    if len(time) < 2:
        raise LogError(f"{d / 'time.csv'}: at least two IMU samples are needed")
    dtheta = trapezoid_increments(time, gyro * _D2R)
    dvel = trapezoid_increments(time, accel)
    imu = {"time": time[1:], "dt": np.diff(time)}
    for i, a in enumerate(xyz):
        imu[f"dtheta_{a}"] = dtheta[:, i]
        imu[f"dvel_{a}"] = dvel[:, i]

    _refuse_local_frame(d / f"gps-{run}.csv")
    gps_time = read_titled_csv(d / "gps_time.csv", [("gps_time", "sec")])[:, 0]
    gps = read_titled_csv(d / f"gps-{run}.csv", [
        ("gps_lat", "deg"), ("gps_lon", "deg"), ("gps_alt", "m"), ("gps_vN", "m/s"),
        ("gps_vE", "m/s"), ("gps_vD", "m/s")])
    _same_length(d / "gps_time.csv", gps_time, d / f"gps-{run}.csv", gps)
    visibility = d / "gps_visibility.csv"
    if visibility.exists():
        valid = read_titled_csv(visibility, [("gps_visibility", "")])[:, 0]
        _same_length(d / "gps_time.csv", gps_time, visibility, valid)
    else:
        valid = np.ones_like(gps_time)
    gnss = {"time": gps_time, "lat": gps[:, 0] * _D2R, "lon": gps[:, 1] * _D2R,
            "h": gps[:, 2], "vn": gps[:, 3], "ve": gps[:, 4], "vd": gps[:, 5],
            "valid": (valid > 0.5).astype(float)}

    truth = None
    if (d / "ref_pos.csv").exists():
        pos = read_titled_csv(d / "ref_pos.csv", [("ref_pos_lat", "deg"), ("ref_pos_lon", "deg"),
                                                  ("ref_pos_alt", "m")])
        vel = read_titled_csv(d / "ref_vel.csv", [(None, "m/s")] * 3)
        att = read_titled_csv(d / "ref_att_euler.csv", [("ref_Yaw", "deg"), ("ref_Pitch", "deg"),
                                                        ("ref_Roll", "deg")])
        for name, arr in (("ref_pos.csv", pos), ("ref_vel.csv", vel),
                          ("ref_att_euler.csv", att)):
            _same_length(d / "time.csv", time, d / name, arr)
        truth = {"time": time, "lat": pos[:, 0] * _D2R, "lon": pos[:, 1] * _D2R, "h": pos[:, 2],
                 "vn": vel[:, 0], "ve": vel[:, 1], "vd": vel[:, 2],
                 "roll": wrap_angle(att[:, 2] * _D2R), "pitch": att[:, 1] * _D2R,
                 "yaw": wrap_angle(att[:, 0] * _D2R)}
    n = len(time)
    imu["_line"] = np.arange(3, n + 2)
    gnss["_line"] = np.arange(2, len(gps_time) + 2)
    if truth is not None:
        truth["_line"] = np.arange(2, n + 2)
    log = SensorLog(imu, gnss, truth)
    check_log(log, where=str(d), sources={IMU_FILE: d / "time.csv", GNSS_FILE: d / "gps_time.csv",
                                          TRUTH_FILE: d / "time.csv"})
    return log


# -- KF-GINS ---------------------------------------------------------------------------------
KF_GINS_IMU = ("time", "dtheta_x", "dtheta_y", "dtheta_z", "dvel_x", "dvel_y", "dvel_z")
KF_GINS_GNSS = ("time", "lat", "lon", "h", "std_n", "std_e", "std_d")
KF_GINS_GNSS_VELOCITY = ("time", "lat", "lon", "h", "vn", "ve", "vd", "std_n", "std_e", "std_d",
                         "std_vn", "std_ve", "std_vd")
_STD = ("std_n", "std_e", "std_d")
_STD_V = ("std_vn", "std_ve", "std_vd")
KF_GINS_NAV = ("week", "sow", "lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw")


def _check_kf_gins_pair(imu_file, imu, gnss_file, gnss) -> None:
    """What tells a KF-GINS GNSS file from an IMU file (both have seven columns): the
    standard deviations are positive, and fixes come less often than IMU samples."""
    for axis in ("std_n", "std_e", "std_d"):
        bad = np.flatnonzero(~(gnss[axis] > 0.0))
        if bad.size:
            raise LogError(f"{gnss_file}, line {gnss['_line'][bad[0]]}: {axis} = "
                           f"{gnss[axis][bad[0]]:g} m, a standard deviation must be positive "
                           f"(is {gnss_file} the IMU file? the order is IMU_FILE GNSS_FILE)")
    span = lambda t: float(t[-1] - t[0]) if len(t) > 1 else 0.0
    imu_rate = (len(imu["time"]) - 1) / span(imu["time"]) if span(imu["time"]) > 0 else 0.0
    gnss_rate = (len(gnss["time"]) - 1) / span(gnss["time"]) if span(gnss["time"]) > 0 else 0.0
    if imu_rate and gnss_rate > imu_rate:
        raise LogError(f"{gnss_file}: {gnss_rate:.3g} fixes per second, more than the "
                       f"{imu_rate:.3g} IMU samples per second of {imu_file}: are the files "
                       "swapped? (the order is IMU_FILE GNSS_FILE)")


def read_kf_gins(imu_file, gnss_file, truth_file=None) -> SensorLog:
    """The log of KF-GINS's IMU and GNSS text files and, optionally, a ``.nav`` reference
    (module docstring).  Times are the seconds of the GPS week; a ``.nav`` file must stay in
    one week.  Every time, and each ``dt``, is taken from the decimal text exactly
    (:mod:`navcore.sensors.log_time`), relative to the log's origin."""
    rows, raw_lines, _ = plain_text_fields(imu_file, KF_GINS_IMU)
    if len(rows) < 2:
        raise LogError(f"{imu_file}: at least two lines are needed (the first only marks the "
                       "start)")
    raw = parsed(imu_file, rows, raw_lines, KF_GINS_IMU)
    stamps = [r[0] for r in rows]
    origin, ends = exact_times(imu_file, stamps[1:], raw_lines[1:])
    imu: Dict[str, np.ndarray] = {"time": ends,
                                  "dt": exact_intervals(imu_file, stamps, raw_lines)}
    for j, name in enumerate(KF_GINS_IMU[1:], start=1):
        imu[name] = raw[1:, j]
    imu["_line"] = raw_lines[1:]
    rows, g_lines, columns = plain_text_fields(gnss_file, KF_GINS_GNSS, KF_GINS_GNSS_VELOCITY)
    g = parsed(gnss_file, rows, g_lines, columns)
    column = {name: g[:, j] for j, name in enumerate(columns)}
    gnss = {"time": exact_times(gnss_file, [r[0] for r in rows], g_lines, origin)[1],
            "lat": column["lat"] * _D2R, "lon": column["lon"] * _D2R,
            "valid": np.ones(len(g)), "_line": g_lines,
            **{k: column[k] for k in ("h", "vn", "ve", "vd", *_STD, *_STD_V) if k in column}}
    _check_kf_gins_pair(imu_file, imu, gnss_file, gnss)
    truth: Optional[Dict[str, np.ndarray]] = None
    if truth_file is not None:
        rows, nav_lines, _ = plain_text_fields(truth_file, KF_GINS_NAV)
        nav = parsed(truth_file, rows, nav_lines, KF_GINS_NAV)
        weeks = np.flatnonzero(nav[:, 0] != nav[0, 0])
        if weeks.size:
            raise LogError(f"{truth_file}, line {nav_lines[weeks[0]]}: the GPS week changes "
                           f"from {nav[0, 0]:g} to {nav[weeks[0], 0]:g}; split the file at the "
                           "week boundary")
        truth = {"time": exact_times(truth_file, [r[1] for r in rows], nav_lines, origin)[1],
                 "lat": nav[:, 2] * _D2R, "lon": nav[:, 3] * _D2R,
                 "h": nav[:, 4], "vn": nav[:, 5], "ve": nav[:, 6], "vd": nav[:, 7],
                 "roll": nav[:, 8] * _D2R, "pitch": nav[:, 9] * _D2R,
                 "yaw": wrap_angle(nav[:, 10] * _D2R), "_line": nav_lines}
    log = SensorLog(imu, gnss, truth, origin)
    check_log(log, sources={IMU_FILE: imu_file, GNSS_FILE: gnss_file, TRUTH_FILE: truth_file})
    return log
