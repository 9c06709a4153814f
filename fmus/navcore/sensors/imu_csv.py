"""Plain IMU CSV files as the IMU table of a sensor log: a column map and units.

A logger's IMU file is rows of numbers, one sample a line, separated by commas or whitespace,
optionally after title lines.  What the numbers are is said by an :class:`ImuCsvSpec` (from
the command line or a small YAML file, the same keys):

``time``         the time column (1 = the first), with ``time_unit`` ``s`` (default), ``ms``,
                 ``us`` or ``ns``; or none, and ``rate`` [Hz]: sample k at ``start + k / rate``
``start``        [s] the time of the first sample in the log's time scale (default: with a
                 time column its values as they are; with ``rate``, 0); with a time column
                 the column is shifted so that its first value is ``start`` (a logger's
                 counter put on GPS or UNIX time)
``gyro``         the body axes (forward-right-down) from the columns, with signs:
``accel``        ``x=-col3,y=col2,z=col1`` (``colN`` or ``N``, 1 = the first column)
``gyro_unit``    ``deg/s`` or ``rad/s`` (rates), ``deg`` or ``rad`` (angle increments)
``accel_unit``   ``g`` (standard gravity 9.80665 m/s^2) or ``m/s^2`` (rates), ``m/s``
                 (velocity increments); rates and increments are not mixed
``header_lines`` the number of title lines to skip (default 0)

Rates are samples at the instants ``t_k``: the increment over ``[t_{k-1}, t_k]`` is the
trapezoid of :func:`navcore.sensors.log_converters.trapezoid_over`.  Increments are over
the interval ending at the line's time.  Either way the first line only starts the first
interval, and each ``dt`` is the exact difference of the decimal times
(:mod:`navcore.sensors.log_time`).  A RTKLIB time-tag file is not read: give the time of the
first sample as ``start``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, fields
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Tuple

import numpy as np

from ..errors import LogError
from ..ins.constants import DEG, G0
from .log_converters import trapezoid_over
from .log_time import exact_intervals, exact_times
from .sensorlog import parse_numbers, read_lines

TIME_UNITS = {"s": Decimal(1), "ms": Decimal("1e-3"), "us": Decimal("1e-6"),
              "ns": Decimal("1e-9")}
#: unit -> (factor to SI, True for a rate)
GYRO_UNITS = {"deg/s": (DEG, True), "rad/s": (1.0, True), "deg": (DEG, False),
              "rad": (1.0, False)}
ACCEL_UNITS = {"g": (G0, True), "m/s^2": (1.0, True), "m/s": (1.0, False)}
_AXIS = re.compile(r"^\s*([xyz])\s*=\s*([+-]?)\s*(?:col)?(\d+)\s*$")


def axis_map(text: str, where: str) -> Tuple[Tuple[int, float], ...]:
    """``x=-col3,y=col2,z=col1`` as ((column index from 0, sign) for x, y, z)."""
    found: Dict[str, Tuple[int, float]] = {}
    for item in str(text).split(","):
        m = _AXIS.match(item)
        if not m or int(m.group(3)) < 1:
            raise LogError(f"{where}: '{item.strip()}' is not AXIS=[-]colN (x=-col3,y=col2,"
                           "z=col1; columns from 1)")
        if m.group(1) in found:
            raise LogError(f"{where}: axis {m.group(1)} given twice")
        found[m.group(1)] = (int(m.group(3)) - 1, -1.0 if m.group(2) == "-" else 1.0)
    missing = [a for a in "xyz" if a not in found]
    if missing:
        raise LogError(f"{where}: no column for axis {missing[0]} (x, y and z are needed)")
    return tuple(found[a] for a in "xyz")


@dataclass(frozen=True)
class ImuCsvSpec:
    """What the columns of an IMU CSV file are (module docstring)."""

    gyro: str
    accel: str
    gyro_unit: str
    accel_unit: str
    time: Optional[int] = None
    time_unit: str = "s"
    rate: Optional[float] = None
    start: Optional[str] = None
    header_lines: int = 0

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any], where: str) -> "ImuCsvSpec":
        """A spec from ``values`` (None values left out); unknown or missing keys, and
        values of the wrong kind, are errors naming ``where`` and the key."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise LogError(f"{where}: unknown key '{unknown[0]}' (keys: "
                           f"{', '.join(sorted(known))})")
        given = {k: v for k, v in values.items() if v is not None}
        for key in ("gyro", "accel", "gyro_unit", "accel_unit"):
            if key not in given:
                raise LogError(f"{where}: '{key}' is needed")
        spec = cls(**{k: str(v) if k in ("gyro", "accel", "gyro_unit", "accel_unit",
                                         "time_unit", "start") else v
                      for k, v in given.items()})
        spec.check(where)
        return spec

    def check(self, where: str) -> None:
        """Units known, rates and increments not mixed, one of time column and rate."""
        for key, units in (("gyro_unit", GYRO_UNITS), ("accel_unit", ACCEL_UNITS),
                           ("time_unit", TIME_UNITS)):
            if getattr(self, key) not in units:
                raise LogError(f"{where}: {key} '{getattr(self, key)}': one of "
                               f"{', '.join(units)}")
        if GYRO_UNITS[self.gyro_unit][1] != ACCEL_UNITS[self.accel_unit][1]:
            raise LogError(f"{where}: gyro_unit '{self.gyro_unit}' and accel_unit "
                           f"'{self.accel_unit}' mix rates and increments")
        if (self.time is None) == (self.rate is None):
            raise LogError(f"{where}: give either a time column ('time') or a fixed 'rate' "
                           "[Hz], not both or neither")
        for key in ("time", "header_lines"):
            value = getattr(self, key)
            if value is not None and (not isinstance(value, int) or isinstance(value, bool)
                                      or value < (1 if key == "time" else 0)):
                raise LogError(f"{where}: {key} = {value!r}: expected a whole number "
                               f"{'from 1' if key == 'time' else 'at least 0'}")
        if self.rate is not None and not (isinstance(self.rate, (int, float))
                                          and 0 < self.rate < float("inf")):
            raise LogError(f"{where}: rate = {self.rate!r}: expected a positive number [Hz]")
        if self.start is not None:
            _decimal(self.start, f"{where}: start")
        axis_map(self.gyro, f"{where}: gyro")
        axis_map(self.accel, f"{where}: accel")


def _decimal(text, where) -> Decimal:
    try:
        value = Decimal(str(text).strip())
    except InvalidOperation:
        value = Decimal("nan")
    if not value.is_finite():
        raise LogError(f"{where}: '{text}' is not a number")
    return value


def _rows(path, spec: ImuCsvSpec):
    """The fields of the sample lines and their line numbers."""
    rows, numbers = [], []
    for number, line in enumerate(read_lines(path), start=1):
        if number <= spec.header_lines:
            continue
        fields_ = line.replace(",", " ").split()
        if not fields_:
            continue
        if rows and len(fields_) != len(rows[0]):
            raise LogError(f"{path}, line {number}: {len(fields_)} values, but line "
                           f"{numbers[0]} has {len(rows[0])} (a cut-off last line?)")
        rows.append(fields_)
        numbers.append(number)
    if len(rows) < 2:
        raise LogError(f"{path}: at least two samples are needed (the first only starts the "
                       "first interval)")
    return rows, np.array(numbers)


def _time_texts(path, rows, numbers, spec: ImuCsvSpec) -> list:
    """Each sample's time as exact decimal text (module docstring)."""
    start = None if spec.start is None else _decimal(spec.start, "start")
    if spec.rate is not None:
        period = Decimal(1) / _decimal(repr(float(spec.rate)), "rate")
        base = start if start is not None else Decimal(0)
        return [str(base + k * period) for k in range(len(rows))]
    j, unit = spec.time - 1, TIME_UNITS[spec.time_unit]
    if j >= len(rows[0]):
        raise LogError(f"{path}, line {numbers[0]}: no column {spec.time} for the time "
                       f"({len(rows[0])} columns)")
    stamps = [_decimal(r[j], f"{path}, line {n}: column {spec.time} (time)") * unit
              for r, n in zip(rows, numbers)]
    if start is not None:
        stamps = [start + s - stamps[0] for s in stamps]
    return [str(s) for s in stamps]


def _axes(path, values, numbers, text, where, factor):
    columns = axis_map(text, where)
    for j, _ in columns:
        if j >= values.shape[1]:
            raise LogError(f"{path}, line {numbers[0]}: no column {j + 1} for {where} "
                           f"({values.shape[1]} columns)")
    return np.stack([sign * factor * values[:, j] for j, sign in columns], -1)


def read_imu_csv(path, spec: ImuCsvSpec) -> Tuple[Dict[str, np.ndarray], float]:
    """The IMU table of ``path`` read as ``spec`` says (module docstring), times relative to
    the returned origin (the whole second at or below the first interval's end)."""
    path = Path(path)
    rows, numbers = _rows(path, spec)
    names = [f"column {j + 1}" for j in range(len(rows[0]))]
    values = np.array([parse_numbers(path, n, r, names) for r, n in zip(rows, numbers)],
                      dtype=np.float64)
    texts = _time_texts(path, rows, numbers, spec)
    origin, ends = exact_times(path, texts[1:], numbers[1:])
    dt = exact_intervals(path, texts, numbers)
    gyro_factor, rates = GYRO_UNITS[spec.gyro_unit]
    gyro = _axes(path, values, numbers, spec.gyro, "gyro", gyro_factor)
    accel = _axes(path, values, numbers, spec.accel, "accel", ACCEL_UNITS[spec.accel_unit][0])
    if rates:
        dtheta, dvel = trapezoid_over(dt, gyro), trapezoid_over(dt, accel)
    else:
        dtheta, dvel = gyro[1:], accel[1:]
    table = {"time": ends, "dt": dt, "_line": numbers[1:]}
    for i, a in enumerate("xyz"):
        table[f"dtheta_{a}"] = dtheta[:, i]
        table[f"dvel_{a}"] = dvel[:, i]
    return table, origin
