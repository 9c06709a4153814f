"""The sensor-log format: recorded IMU increments, GNSS fixes and optional truth, as files.

A sensor log is a folder with three CSV files (``truth.csv`` optional).  The first line of
each file holds the column titles ``name [unit]`` (``name`` alone for a flag); every further
line holds one sample, values separated by commas, written with 17 significant digits
(``%.17g``, so a float64 survives the round trip exactly).  Columns may come in any order;
every title must be one of the file's columns below, with exactly that unit.

``imu.csv`` (required; one line per IMU interval, body frame forward-right-down)
    ``time [s]`` end of the interval, ``dt [s]`` its length (the interval is
    ``[time - dt, time]``), ``dtheta_x/y/z [rad]`` angle increments (integral of the
    inertial angular rate over the interval), ``dvel_x/y/z [m/s]`` velocity increments
    (integral of the specific force).
``gnss.csv`` (required; one line per fix, including fixes flagged invalid)
    ``time [s]`` time the fix was taken, ``lat [rad]``, ``lon [rad]``, ``h [m]`` (above the
    WGS-84 ellipsoid), ``valid`` (1 usable, 0 during an outage); optional, all three or
    none: ``vn/ve/vd [m/s]`` NED velocity; optional: ``std_n/e/d [m]`` the receiver's own
    1-sigma of the position (a filter with ``r_from_receiver`` takes it as R);
    optional, all three or none, only with the velocity: ``std_vn/ve/vd [m/s]`` the
    receiver's 1-sigma of the velocity (kept from KF-GINS and RTKLIB files); optional:
    ``outlier`` (1 where an outlier was injected, for evaluation only).
``truth.csv`` (optional; reference trajectory for the metrics)
    ``time [s]``, ``lat [rad]``, ``lon [rad]``, ``h [m]``, ``vn/ve/vd [m/s]``,
    ``roll/pitch/yaw [rad]`` (ZYX Euler angles).  Position and velocity are the IMU's (the
    point of the filters' ``nav_*``, which the metrics compare with it), not the GNSS
    antenna's: a recorded run's truth is its trajectory's, gnss-ins-sim's and KF-GINS's
    references are the IMU's.

Rules a log must satisfy (:func:`read_log` checks them and names file and line):

* each file at most :data:`MAX_FILE_BYTES`; every line has one value per title; every value
  is a finite decimal number (no NaN, no inf); flags are 0 or 1;
* times strictly increasing in every file (an equal time is "duplicated", a smaller one
  "non-monotonic");
* IMU: ``dt > 0``; each interval has its own ``dt`` (:mod:`navcore.sensors.log_time`), refused on
  reading only beyond ``max_dt_jitter`` relative to the nominal (median) interval, as a gap
  or an overlap naming the line; and the intervals tile time: the gap
  ``time[k] - dt[k] - time[k-1]`` between an interval and the previous one at most
  :data:`IMU_GAP_TOLERANCE` times ``dt`` in magnitude (a hole would lose motion);
* GNSS: at least one valid fix; ``|lat| < pi/2``;
* truth: consecutive samples at most :data:`TRUTH_MAX_GAP` apart (the metrics interpolate
  the truth linearly between samples);
* GNSS and truth times overlap the IMU's span (a file of another day or another time scale
  is refused naming both spans).

Times: every time is held relative to the log's origin, the whole second at or below the
first IMU line's time (:attr:`SensorLog.time_origin`, :mod:`navcore.sensors.log_time`), so epoch
and UNIX stamps cost no precision; writing adds the origin back exactly.

The file contents are parsed as numbers, never evaluated.  :func:`write_log` checks the same
rules before writing anything and writes the folder atomically (see its docstring).
"""
from __future__ import annotations

import math
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Optional, Tuple

import numpy as np

from ..errors import LogError
from .log_time import (DEFAULT_MAX_DT_JITTER, MAX_DT_JITTER_LIMIT, absolute_text,
                       check_intervals, nominal_interval, relative_seconds, replay_step,
                       time_origin)

#: largest accepted log file [bytes] (about 10 h of 200 Hz IMU data)
MAX_FILE_BYTES = 1 << 30
#: largest gap or overlap between consecutive IMU intervals, as a fraction of dt
IMU_GAP_TOLERANCE = 1e-6
#: largest spacing of truth samples [s]
TRUTH_MAX_GAP = 1.0

IMU_FILE, GNSS_FILE, TRUTH_FILE = "imu.csv", "gnss.csv", "truth.csv"
LOG_FILES = (IMU_FILE, GNSS_FILE, TRUTH_FILE)

_AXES = ("x", "y", "z")
_NED = ("n", "e", "d")
#: file -> ordered {column: unit}; flags have the unit "" and are written without brackets
IMU_COLUMNS = {"time": "s", "dt": "s", **{f"dtheta_{a}": "rad" for a in _AXES},
               **{f"dvel_{a}": "m/s" for a in _AXES}}
GNSS_COLUMNS = {"time": "s", "lat": "rad", "lon": "rad", "h": "m",
                **{f"v{a}": "m/s" for a in _NED}, "valid": "",
                **{f"std_{a}": "m" for a in _NED}, **{f"std_v{a}": "m/s" for a in _NED},
                "outlier": ""}
TRUTH_COLUMNS = {"time": "s", "lat": "rad", "lon": "rad", "h": "m",
                 **{f"v{a}": "m/s" for a in _NED}, "roll": "rad", "pitch": "rad", "yaw": "rad"}
COLUMNS = {IMU_FILE: IMU_COLUMNS, GNSS_FILE: GNSS_COLUMNS, TRUTH_FILE: TRUTH_COLUMNS}
#: columns a file may leave out, as groups that come all together or not at all
OPTIONAL_GROUPS = {IMU_FILE: (), TRUTH_FILE: (),
                   GNSS_FILE: (("vn", "ve", "vd"), ("std_n", "std_e", "std_d"),
                               ("std_vn", "std_ve", "std_vd"), ("outlier",))}
FLAGS = ("valid", "outlier")


@dataclass
class SensorLog:
    """The columns of a log as float64 arrays: ``imu``, ``gnss``, ``truth`` (None without a
    truth file) map column names (module docstring) to arrays of equal length; every
    ``time`` is relative to ``time_origin`` [s] (a whole second: the log's time of a
    relative time ``t`` is ``time_origin + t``)."""

    imu: Dict[str, np.ndarray]
    gnss: Dict[str, np.ndarray]
    truth: Optional[Dict[str, np.ndarray]] = None
    time_origin: float = 0.0

    @property
    def imu_period(self) -> float:
        """The nominal IMU interval (median dt) [s]."""
        return nominal_interval(self.imu["dt"])

    @property
    def replay_step(self) -> float:
        """The communication step that gives a filter every interval (navcore.sensors.log_time)."""
        return replay_step(self.imu["time"], self.imu["dt"])

    @property
    def start_time(self) -> float:
        """Start of the first IMU interval [s]."""
        return float(self.imu["time"][0] - self.imu["dt"][0])

    @property
    def stop_time(self) -> float:
        """End of the last IMU interval [s]."""
        return float(self.imu["time"][-1])

    @property
    def has_gnss_velocity(self) -> bool:
        return "vn" in self.gnss


def header_title(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def visible(text: str) -> str:
    """``text`` with every character that prints as nothing or as a blank other than the
    space (a byte-order mark, a zero-width or non-breaking space, a control character)
    written as its ``\\uXXXX`` escape, so an error message shows why a title does not match."""
    return "".join(c if c.isprintable() and (c == " " or not c.isspace())
                   else f"\\u{ord(c):04x}" for c in text)


def _parse_title(path, title: str, columns) -> Tuple[str, str]:
    title = title.strip()
    name, unit = title, ""
    if title.endswith("]") and " [" in title:
        name, unit = title[:-1].split(" [", 1)
    if name not in columns:
        raise LogError(f"{path}, line 1: unknown column '{visible(title)}' (columns of this "
                       "file: " + ", ".join(header_title(n, u) for n, u in columns.items()) + ")")
    if unit != columns[name]:
        raise LogError(f"{path}, line 1: column '{name}' has the unit header "
                       f"'{visible(title)}', expected '{header_title(name, columns[name])}'")
    return name, unit


def read_lines(path) -> list:
    """The lines of a text file, refusing files over :data:`MAX_FILE_BYTES`; a UTF-8
    byte-order mark at its start (as spreadsheet programs write) is dropped."""
    path = Path(path)
    if not path.is_file():
        raise LogError(f"{path}: file not found")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise LogError(f"{path}: {size} bytes, more than the limit of {MAX_FILE_BYTES}")
    try:
        with open(path, encoding="utf-8-sig", newline="") as f:
            return f.read().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise LogError(f"{path}: cannot be read: {exc}") from None


def parse_numbers(path, number, fields, names) -> list:
    """``fields`` (text) of line ``number`` as finite floats; errors name the column."""
    row = []
    for name, text in zip(names, fields):
        try:
            value = float(text)
        except ValueError:
            raise LogError(f"{path}, line {number}: column '{name}': '{text.strip()}' is not a "
                           "number") from None
        if not math.isfinite(value):
            raise LogError(f"{path}, line {number}: column '{name}' is {value} (values must "
                           "be finite)")
        row.append(value)
    return row


def _read_table(path: Path, origin: Optional[float]) -> Tuple[Dict[str, np.ndarray], float]:
    """Titles checked against the file's columns, values as arrays, times relative to
    ``origin`` (None: the origin of this file's first time); errors name the line.  Returns
    the table and the origin."""
    columns = COLUMNS[path.name]
    lines = read_lines(path)
    if not lines or not lines[0].strip():
        raise LogError(f"{path}, line 1: no column titles")
    titles = [_parse_title(path, t, columns)[0] for t in lines[0].split(",")]
    for i, t in enumerate(titles):
        if t in titles[:i]:
            raise LogError(f"{path}, line 1: column '{t}' appears twice")
    _check_columns(path, set(titles))
    table, numbers = parse_rows(path, lines, titles)
    data = {t: np.ascontiguousarray(table[:, j]) for j, t in enumerate(titles)}
    data["_line"] = numbers
    j = titles.index("time")
    texts = [lines[n - 1].split(",")[j] for n in numbers]
    if origin is None:
        origin = time_origin(path, int(numbers[0]), texts[0])
    if origin != 0.0:
        data["time"] = relative_seconds(path, texts, numbers, origin)
    return data, origin


def parse_rows(path, lines, titles):
    """The comma-separated rows after the title line ``lines[0]`` as an (n, len(titles))
    array, and the line number of each row (blank lines skipped)."""
    rows, numbers = [], []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        fields = line.split(",")
        if len(fields) != len(titles):
            raise LogError(f"{path}, line {number}: {len(fields)} values, but {len(titles)} "
                           "column titles")
        rows.append(parse_numbers(path, number, fields, titles))
        numbers.append(number)
    if not rows:
        raise LogError(f"{path}: no samples after the title line")
    return np.array(rows, dtype=np.float64), np.array(numbers)


def _check_columns(path, present) -> None:
    name = Path(path).name
    optional = {c for group in OPTIONAL_GROUPS[name] for c in group}
    for column in COLUMNS[name]:
        if column not in optional and column not in present:
            raise LogError(f"{path}, line 1: missing column "
                           f"'{header_title(column, COLUMNS[name][column])}'")
    for group in OPTIONAL_GROUPS[name]:
        have = [c for c in group if c in present]
        if have and len(have) != len(group):
            raise LogError(f"{path}, line 1: columns {', '.join(group)} come together; "
                           f"missing '{[c for c in group if c not in present][0]}'")
    if "std_vn" in present and "vn" not in present:
        raise LogError(f"{path}, line 1: columns std_vn, std_ve, std_vd (velocity sigmas) "
                       "without the velocity vn, ve, vd")


def _line(data, k) -> int:
    lines = data.get("_line")
    return int(lines[k]) if lines is not None else k + 2


def _check_times(path, data) -> None:
    t = data["time"]
    step = np.diff(t)
    bad = np.flatnonzero(step <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        what = "duplicated" if step[k - 1] == 0 else "non-monotonic"
        raise LogError(f"{path}, line {_line(data, k)}: {what} time {float(t[k])!r} s (line "
                       f"{_line(data, k - 1)} has {float(t[k - 1])!r} s; times must increase)")


def check_imu(path, imu, max_dt_jitter=None) -> None:
    """The IMU rules; ``max_dt_jitter`` None leaves the interval bound out (writing)."""
    _check_times(path, imu)
    dt = imu["dt"]
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        k = int(bad[0])
        raise LogError(f"{path}, line {_line(imu, k)}: dt = {float(dt[k])!r} s must be > 0")
    if max_dt_jitter is not None:
        check_intervals(path, dt, lambda k: _line(imu, k), max_dt_jitter)
    t = imu["time"]
    gap = t[1:] - dt[1:] - t[:-1]
    bad = np.flatnonzero(np.abs(gap) > IMU_GAP_TOLERANCE * dt[1:])
    if bad.size:
        k = int(bad[0]) + 1
        kind = "gap" if gap[k - 1] > 0 else "overlap"
        raise LogError(f"{path}, line {_line(imu, k)}: {kind} of {abs(gap[k - 1]):.6g} s "
                       f"between the interval ending at {float(t[k - 1])!r} s (line "
                       f"{_line(imu, k - 1)}) and this one, more than the bound "
                       f"{IMU_GAP_TOLERANCE:g} dt (the intervals must tile time)")


def check_gnss(path, gnss) -> None:
    _check_times(path, gnss)
    for flag in FLAGS:
        if flag in gnss:
            bad = np.flatnonzero((gnss[flag] != 0) & (gnss[flag] != 1))
            if bad.size:
                k = int(bad[0])
                raise LogError(f"{path}, line {_line(gnss, k)}: column '{flag}' is "
                               f"{float(gnss[flag][k])!r}, must be 0 or 1")
    bad = np.flatnonzero(~(np.abs(gnss["lat"]) < 0.5 * math.pi))
    if bad.size:
        k = int(bad[0])
        raise LogError(f"{path}, line {_line(gnss, k)}: lat = {float(gnss['lat'][k])!r} rad is not "
                       "a latitude (|lat| < pi/2; the unit is rad)")
    if not (gnss["valid"] == 1).any():
        raise LogError(f"{path}: no valid fix (every line has valid = 0)")


def check_truth(path, truth) -> None:
    _check_times(path, truth)
    step = np.diff(truth["time"])
    bad = np.flatnonzero(step > TRUTH_MAX_GAP)
    if bad.size:
        k = int(bad[0]) + 1
        raise LogError(f"{path}, line {_line(truth, k)}: gap of {step[k - 1]:.6g} s after "
                       f"line {_line(truth, k - 1)}, more than the bound {TRUTH_MAX_GAP:g} s "
                       "between truth samples")


_CHECKS = {IMU_FILE: check_imu, GNSS_FILE: check_gnss, TRUTH_FILE: check_truth}


def _span(t0, t1, origin) -> str:
    return f"{absolute_text(t0, origin)} to {absolute_text(t1, origin)} s"


def check_overlap(log: SensorLog, paths) -> None:
    """GNSS and truth times overlap the IMU's span (``paths``: file name -> path, for the
    message; times in the log's time, origin added)."""
    start, stop = log.start_time, log.stop_time
    for name, data in ((GNSS_FILE, log.gnss), (TRUTH_FILE, log.truth)):
        if data is None:
            continue
        t = data["time"]
        if t[0] > stop or t[-1] < start:
            raise LogError(
                f"{paths[name]}: times {_span(t[0], t[-1], log.time_origin)} do not overlap "
                f"the IMU's {_span(start, stop, log.time_origin)} ({paths[IMU_FILE]}); the "
                "files must share one time scale")


def read_log(folder, max_dt_jitter=DEFAULT_MAX_DT_JITTER) -> SensorLog:
    """Read and check the log in ``folder`` (module docstring), each IMU interval within
    ``max_dt_jitter`` of the nominal one (:mod:`navcore.sensors.log_time`); :class:`LogError`
    otherwise."""
    folder = Path(folder)
    if not folder.is_dir():
        raise LogError(f"sensor log folder not found: {folder}")
    tables = {}
    origin = None
    for name in LOG_FILES:
        path = folder / name
        if name == TRUTH_FILE and not path.exists():
            tables[name] = None
            continue
        data, origin = _read_table(path, origin)
        if name == IMU_FILE:
            check_imu(path, data, max_dt_jitter)
        else:
            _CHECKS[name](path, data)
        data.pop("_line")
        tables[name] = data
    log = SensorLog(tables[IMU_FILE], tables[GNSS_FILE], tables[TRUTH_FILE], origin)
    check_overlap(log, {name: folder / name for name in LOG_FILES})
    return log


def check_log(log: SensorLog, where="sensor log", sources=None) -> None:
    """The rules of :func:`read_log` on arrays (``imu`` and ``gnss`` required, as their files
    are).  Errors name ``sources[file]`` (the file the data came from) or ``where/file``, and
    the line given by an optional ``"_line"`` array of the table (else the line the row will
    have in the written file); ``"_line"`` arrays are removed afterwards."""
    sources = sources or {}
    for name, data in ((IMU_FILE, log.imu), (GNSS_FILE, log.gnss), (TRUTH_FILE, log.truth)):
        path = sources.get(name, f"{where}/{name}")
        if data is None:
            if name == TRUTH_FILE:
                continue
            # read_log would refuse the folder written without it
            raise LogError(f"{path}: no data (a sensor log needs {IMU_FILE} and {GNSS_FILE})")
        check_table(name, data, path, where)
    check_overlap(log, {name: sources.get(name, f"{where}/{name}") for name in LOG_FILES})


def check_table(name, data, path, where="sensor log") -> None:
    """The rules of the one file ``name`` (:func:`check_log`) on its ``data``; the
    ``"_line"`` array is removed afterwards."""
    columns = [c for c in data if c != "_line"]
    _check_columns(f"{where}/{name}", set(columns))
    for column in columns:
        if column not in COLUMNS[name]:
            raise LogError(f"{path}: unknown column '{column}'")
    n = {len(data[c]) for c in columns}
    if len(n) != 1 or 0 in n:
        raise LogError(f"{path}: columns of different or zero length {sorted(n)}")
    for column in columns:
        values = np.asarray(data[column], dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise LogError(f"{path}, line {_line(data, int(bad[0]))}: column '{column}' "
                           f"is {values[bad[0]]} (values must be finite)")
    _CHECKS[name](path, data)
    data.pop("_line", None)


def _write_table(path: Path, data, origin=0.0) -> None:
    """One file; times written as the log's time (``origin`` added exactly)."""
    columns = [c for c in COLUMNS[path.name] if c in data]
    table = np.column_stack([np.asarray(data[c], dtype=np.float64) for c in columns])
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(",".join(header_title(c, COLUMNS[path.name][c]) for c in columns) + "\n")
        if origin == 0.0:
            np.savetxt(f, table, fmt="%.17g", delimiter=",")
            return
        j = columns.index("time")
        for row in table.tolist():
            fields = ["%.17g" % v for v in row]
            fields[j] = absolute_text(row[j], origin)
            f.write(",".join(fields) + "\n")


def write_log(folder, log: SensorLog, before_commit=None) -> Path:
    """Check ``log`` (:func:`check_log`), then write it to ``folder`` without ever leaving a
    half-written log: the files are written into a fresh folder next to ``folder`` and moved
    in place only when all are complete (a ``truth.csv`` left from an earlier log in
    ``folder`` is removed when ``log`` has no truth).  ``before_commit()``, when given, is
    called just before the files are moved in place (an exception from it leaves nothing
    written: a host's Ctrl-C).  Returns ``folder``."""
    folder = Path(folder)
    check_log(log, where=str(folder))
    parent = folder.parent if str(folder.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise LogError(f"cannot write the sensor log {folder}: {exc}") from None
    if folder.exists() and not folder.is_dir():
        raise LogError(f"cannot write the sensor log {folder}: it exists and is not a folder")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".tmp", dir=parent))
    except OSError as exc:
        raise LogError(f"cannot write the sensor log {folder}: {exc.strerror or exc}") from None
    try:
        tables = {IMU_FILE: log.imu, GNSS_FILE: log.gnss, TRUTH_FILE: log.truth}
        for name, data in tables.items():
            if data is not None:
                _write_table(tmp / name, data, log.time_origin)
        if before_commit is not None:
            before_commit()
        if not folder.exists():
            os.chmod(tmp, 0o777 & ~_umask())
            os.replace(tmp, folder)
            return folder
        for name, data in tables.items():
            if data is not None:
                os.replace(tmp / name, folder / name)
            elif (folder / name).exists():
                os.unlink(folder / name)
    except OSError as exc:          # a full disk: the log named, nothing of it left
        raise LogError(f"cannot write the sensor log {folder}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return folder


def write_log_file(folder, name: str, data, origin: float = 0.0, source=None,
                   before_commit=None) -> Path:
    """Write one file ``name`` of a log (``imu.csv`` or ``gnss.csv``, times relative to
    ``origin``) into ``folder``, keeping the log's other files: a log converted part by part
    (the IMU from one tool, the fixes from another).  ``data`` is checked first (errors name
    ``source``, the file it came from); when ``folder`` already holds the other files, the
    whole log is read as a replay would (:func:`read_log`: the time spans must overlap)
    before the file is moved in place, so nothing is half-written (``before_commit()`` as
    in :func:`write_log`).  Returns the file."""
    folder = Path(folder)
    check_table(name, data, source or folder / name, str(folder))
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{name}.", suffix=".tmp", dir=folder))
    except OSError as exc:
        raise LogError(f"cannot write {folder / name}: {exc.strerror or exc}") from None
    try:
        _write_table(tmp / name, data, origin)
        others = [n for n in LOG_FILES if n != name and (folder / n).is_file()]
        if {IMU_FILE, GNSS_FILE} <= {name, *others}:
            for other in others:
                os.symlink((folder / other).resolve(), tmp / other)
            try:
                read_log(tmp, MAX_DT_JITTER_LIMIT)    # the interval bound is the replay's
            except LogError as exc:
                raise LogError(str(exc).replace(str(tmp), str(folder))) from None
        os.chmod(tmp / name, 0o666 & ~_umask())
        if before_commit is not None:
            before_commit()
        os.replace(tmp / name, folder / name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return folder / name


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
