"""RTKLIB solution files (``.pos``) as the GNSS table of a sensor log, with per-epoch sigmas.

RTKLIB (and the engines that share its output: RTKLIB demo5, rtkexplorer's builds, many
receivers' post-processing) writes one solution epoch a line after ``%`` comment lines; the
last ``%`` line before the data names the columns (RTKLIB ``outsolheads``):

``%  GPST  latitude(deg) longitude(deg) height(m) Q ns sdn(m) sde(m) sdu(m) sdne(m) sdeu(m)
sdun(m) age(s) ratio [vn(m/s) ve(m/s) vu(m/s) sdvn sdve sdvu sdvne sdveu sdvun]``, or with
ECEF positions ``x-ecef(m) y-ecef(m) z-ecef(m) Q ns sdx(m) sdy(m) sdz(m) sdxy(m) sdyz(m)
sdzx(m) age(s) ratio [vx(m/s) vy(m/s) vz(m/s) sdvx sdvy sdvz sdvxy sdvyz sdvzx]``.

* Time: GPST, as ``yyyy/mm/dd hh:mm:ss.sss`` or as GPS week and seconds of the week (two
  fields either way).  UTC or JST solutions are refused (RTKLIB ``out-timesys=gpst``): the
  IMU's time scale is GPST.  The log's time (``time_scale``): ``week``, the seconds of the
  GPS week (as KF-GINS; a file crossing a week boundary is refused), or ``unix``, the
  seconds since 1970-01-01 on the GPST scale (no leap seconds, as RTKLIB's time tags).  Every
  time is exact decimal arithmetic on the text (:mod:`navcore.sensors.log_time`).
* Position: latitude and longitude [deg] and height [m] (RTKLIB's ellipsoidal height; a
  geodetic height, ``out-height=geodetic``, cannot be told from the file and would be off by
  the geoid), or ECEF x/y/z [m] converted to WGS-84 latitude, longitude and height.  The
  degree-minute-second form (``latitude(d'")``) and E/N/U baselines are refused by name.
* Sigmas: ``sdn/sde/sdu`` [m] give ``std_n/e/d`` (down = up, a sigma); the ECEF covariance
  (``sdx``... diagonal, ``sdxy/sdyz/sdzx`` the signed square roots of the off-diagonal terms,
  RTKLIB's ``sqvar``) is rotated to NED, ``std_n/e/d`` the square roots of its diagonal.
* Velocity, when the file has it: ``vn/ve/vu`` [m/s] give ``vn, ve, vd = -vu`` and the sigmas
  ``sdvn/sdve/sdvu`` give ``std_vn/ve/vd``; ECEF ``vx/vy/vz`` and their covariance are rotated
  to NED at the epoch's position as above.
* Quality Q (:data:`QUALITY`: 1 fix, 2 float, 3 sbas, 4 dgps, 5 single, 6 ppp): an epoch whose
  quality is not in ``keep`` is written ``valid`` = 0 (an outage to the filter); the sigmas of
  an epoch of quality q are multiplied by ``sigma_scale[q]`` (default 1), so a filter with
  ``r_from_receiver`` weights it with R times the square of the factor.  A kept epoch needs
  positive sigmas.
"""
from __future__ import annotations

import calendar
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from ..errors import LogError
from ..ins.constants import DEG as _D2R
from .log_time import exact_times
from .sensorlog import parse_numbers, read_lines

#: RTKLIB's solution quality flags (Q)
QUALITY = {1: "fix", 2: "float", 3: "sbas", 4: "dgps", 5: "single", 6: "ppp"}
#: the log's time scales of an RTKLIB file (module docstring)
TIME_SCALES = ("week", "unix")
#: the GPS epoch 1980-01-06 00:00:00 in seconds since 1970-01-01 (GPST: no leap seconds)
GPS_EPOCH_UNIX = 315964800
WEEK_SECONDS = 604800
_LLH = ("latitude(deg)", "longitude(deg)", "height(m)")
_XYZ = ("x-ecef(m)", "y-ecef(m)", "z-ecef(m)")
_LLH_SIGMAS = ("sdn(m)", "sde(m)", "sdu(m)")
_XYZ_COV = ("sdx(m)", "sdy(m)", "sdz(m)", "sdxy(m)", "sdyz(m)", "sdzx(m)")
_LLH_VEL = ("vn(m/s)", "ve(m/s)", "vu(m/s)", "sdvn", "sdve", "sdvu")
_XYZ_VEL = ("vx(m/s)", "vy(m/s)", "vz(m/s)")
_XYZ_VEL_COV = ("sdvx", "sdvy", "sdvz", "sdvxy", "sdvyz", "sdvzx")


def quality_names(text: str, where: str) -> Tuple[int, ...]:
    """``fix,float`` as the quality flags (1, 2); an unknown name is an error naming
    ``where``."""
    by_name = {v: k for k, v in QUALITY.items()}
    names = [n.strip() for n in text.split(",") if n.strip()]
    for n in names:
        if n not in by_name:
            raise LogError(f"{where}: unknown quality '{n}' (one of {', '.join(by_name)})")
    if not names:
        raise LogError(f"{where}: no quality named (one of {', '.join(by_name)})")
    return tuple(by_name[n] for n in names)


def quality_factors(text: str, where: str) -> Dict[int, float]:
    """``fix=1,float=10`` as {1: 1.0, 2: 10.0}: a positive finite factor per quality."""
    factors = {}
    for item in (i.strip() for i in text.split(",") if i.strip()):
        name, _, value = item.partition("=")
        (q,) = quality_names(name, where)
        try:
            factor = float(value)
        except ValueError:
            factor = float("nan")
        if not (0.0 < factor < float("inf")):
            raise LogError(f"{where}: '{item}': expected QUALITY=FACTOR with a positive "
                           "number (fix=1,float=10,single=100)")
        factors[q] = factor
    return factors


def _columns(path, lines) -> Tuple[Tuple[str, ...], int]:
    """The column names of the last ``%`` title line before the data, and the index of the
    first data line."""
    titles, first = None, None
    for i, line in enumerate(lines):
        if line.startswith("%"):
            tokens = line[1:].replace(",", " ").split()
            if tokens and "Q" in tokens:
                titles, number = tokens, i + 1
        elif line.strip():
            first = i
            break
    if titles is None:
        raise LogError(f"{path}: no column title line ('%  GPST  latitude(deg) ... Q ...'; "
                       "write the solution with RTKLIB's out-outhead=on)")
    if titles[0] != "GPST":
        raise LogError(f"{path}, line {number}: time system {titles[0]}: only GPST is read "
                       "(RTKLIB option out-timesys=gpst), the IMU's time scale")
    if first is None:
        raise LogError(f"{path}: no solution epochs after the titles")
    return tuple(titles[1:]), first


def _need(path, columns, names, what) -> None:
    missing = [n for n in names if n not in columns]
    if missing:
        raise LogError(f"{path}: {what}: no column '{missing[0]}' in the titles "
                       f"({' '.join(columns)})")


def _position_form(path, columns) -> str:
    """``llh`` or ``xyz`` from the titles; other forms refused by name."""
    if _LLH[0] in columns:
        _need(path, columns, _LLH + _LLH_SIGMAS, "latitude/longitude solution")
        return "llh"
    if _XYZ[0] in columns:
        _need(path, columns, _XYZ + _XYZ_COV, "ECEF solution")
        return "xyz"
    if any(c.startswith("latitude(d") for c in columns):
        raise LogError(f"{path}: latitude in degrees, minutes and seconds: write decimal "
                       "degrees (RTKLIB option out-degform=deg)")
    raise LogError(f"{path}: neither latitude(deg)/longitude(deg)/height(m) nor "
                   f"x-ecef(m)/y-ecef(m)/z-ecef(m) in the titles ({' '.join(columns)}); E/N/U "
                   "baselines are not read (RTKLIB option out-solformat=llh or xyz)")


def _epoch_seconds(path, number, first: str, second: str) -> Tuple[int, Decimal]:
    """(GPS week, seconds of the week) of a time written as a GPST date and time or as a
    week and seconds, exactly."""
    try:
        if "/" in first:
            y, mo, d = (int(x) for x in first.split("/"))
            h, mi, s = second.split(":")
            day = calendar.timegm((y, mo, d, int(h), int(mi), 0)) - GPS_EPOCH_UNIX
            since = Decimal(day) + Decimal(s)
            week = int(since // WEEK_SECONDS)
            return week, since - week * WEEK_SECONDS
        return int(first), Decimal(second)
    except (ValueError, InvalidOperation, OverflowError):
        raise LogError(f"{path}, line {number}: time '{first} {second}' is neither "
                       "'yyyy/mm/dd hh:mm:ss.sss' nor 'week seconds'") from None


def _time_texts(path, stamps, numbers, time_scale) -> list:
    """The log's times (decimal text) of the (week, seconds) ``stamps`` in ``time_scale``."""
    if time_scale == "unix":
        return [str(GPS_EPOCH_UNIX + w * WEEK_SECONDS + s) for w, s in stamps]
    for (w, _), number in zip(stamps, numbers):
        if w != stamps[0][0]:
            raise LogError(f"{path}, line {number}: the GPS week changes from {stamps[0][0]} "
                           f"to {w}; use the time scale unix (seconds since 1970 on GPST)")
    return [str(s) for _, s in stamps]


def _table(path, lines, columns, first):
    """The fields of every data line: times (week, seconds), values (n, columns), line
    numbers."""
    stamps, rows, numbers = [], [], []
    for i in range(first, len(lines)):
        fields = lines[i].replace(",", " ").split()
        if not fields or lines[i].startswith("%"):
            continue
        number = i + 1
        if len(fields) != 2 + len(columns):
            raise LogError(f"{path}, line {number}: {len(fields)} fields, expected "
                           f"{2 + len(columns)} (date and time, or week and seconds, then "
                           f"{' '.join(columns)})")
        stamps.append(_epoch_seconds(path, number, fields[0], fields[1]))
        rows.append(parse_numbers(path, number, fields[2:], columns))
        numbers.append(number)
    return stamps, np.array(rows, dtype=np.float64), np.array(numbers)


def _signed_square(s):
    """RTKLIB's ``sqvar`` undone: a covariance from its signed square root."""
    return np.sign(s) * s * s


def _ned_sigmas(lat, lon, col, names) -> Tuple[np.ndarray, ...]:
    """The NED 1-sigmas of the ECEF covariance given by the columns ``names``
    (xx, yy, zz, xy, yz, zx as RTKLIB writes them) at each epoch's latitude and longitude."""
    xx, yy, zz = (col[n] ** 2 for n in names[:3])
    xy, yz, zx = (_signed_square(col[n]) for n in names[3:])
    cov = np.stack([np.stack([xx, xy, zx], -1), np.stack([xy, yy, yz], -1),
                    np.stack([zx, yz, zz], -1)], -2)
    rot = _ned_from_ecef(lat, lon)
    ned = rot @ cov @ np.swapaxes(rot, -1, -2)
    return tuple(np.sqrt(np.maximum(ned[:, i, i], 0.0)) for i in range(3))


def _ned_from_ecef(lat, lon) -> np.ndarray:
    """The rotations (n, 3, 3) from ECEF to the local NED frame."""
    import pymap3d

    unit = np.eye(3)
    columns = [np.stack([np.reshape(c, -1) for c in
                         pymap3d.ecef2nedv(*unit[i], lat, lon, deg=False)], -1)
               for i in range(3)]         # (pymap3d returns scalars for one epoch)
    return np.stack(columns, -1)


def _geodetic(col) -> Dict[str, np.ndarray]:
    """lat, lon [rad], h [m] and the NED sigmas and velocity of an ECEF solution."""
    import pymap3d

    lat, lon, h = pymap3d.ecef2geodetic(*(col[n] for n in _XYZ), deg=False)
    lat, lon, h = (np.asarray(a, dtype=np.float64).reshape(-1) for a in (lat, lon, h))
    out = {"lat": lat, "lon": lon, "h": h}
    out.update(zip(("std_n", "std_e", "std_d"), _ned_sigmas(lat, lon, col, _XYZ_COV)))
    if _XYZ_VEL[0] in col:
        vel = np.stack([col[n] for n in _XYZ_VEL], -1)
        out.update(zip(("vn", "ve", "vd"), np.moveaxis(
            np.einsum("kij,kj->ki", _ned_from_ecef(lat, lon), vel), -1, 0)))
        out.update(zip(("std_vn", "std_ve", "std_vd"),
                       _ned_sigmas(lat, lon, col, _XYZ_VEL_COV)))
    return out


def _llh(col) -> Dict[str, np.ndarray]:
    out = {"lat": col[_LLH[0]] * _D2R, "lon": col[_LLH[1]] * _D2R, "h": col[_LLH[2]],
           "std_n": col["sdn(m)"], "std_e": col["sde(m)"], "std_d": col["sdu(m)"]}
    if _LLH_VEL[0] in col:
        out.update(vn=col["vn(m/s)"], ve=col["ve(m/s)"], vd=-col["vu(m/s)"],
                   std_vn=col["sdvn"], std_ve=col["sdve"], std_vd=col["sdvu"])
    return out


def _check_velocity_columns(path, columns, form) -> None:
    first, rest = ((_LLH_VEL[0], _LLH_VEL) if form == "llh" else
                   (_XYZ_VEL[0], _XYZ_VEL + _XYZ_VEL_COV))
    if first in columns:
        _need(path, columns, rest, "velocity")


def read_rtklib_pos(path, time_scale: str = "week", keep: Optional[Sequence[int]] = None,
                    sigma_scale: Optional[Mapping[int, float]] = None, origin=None):
    """The GNSS table of an RTKLIB ``.pos`` file (module docstring): ``(table, origin,
    counts)`` with the table's times relative to ``origin`` (None: the whole second at or
    below the first epoch), and the number of epochs per quality name."""
    path = Path(path)
    if time_scale not in TIME_SCALES:
        raise LogError(f"time scale '{time_scale}': one of {', '.join(TIME_SCALES)}")
    lines = read_lines(path)
    columns, first = _columns(path, lines)
    form = _position_form(path, columns)
    _check_velocity_columns(path, columns, form)
    _need(path, columns, ("Q",), "quality")
    stamps, values, numbers = _table(path, lines, columns, first)
    if not len(numbers):
        raise LogError(f"{path}: no solution epochs after the titles")
    col = {name: values[:, j] for j, name in enumerate(columns)}
    texts = _time_texts(path, stamps, numbers, time_scale)
    origin, times = exact_times(path, texts, numbers, origin)
    table = {"time": times, **(_llh(col) if form == "llh" else _geodetic(col))}
    quality = col["Q"].astype(int)
    _apply_quality(path, table, quality, numbers, keep, sigma_scale or {})
    table["_line"] = numbers
    counts = {QUALITY.get(q, f"Q={q}"): int((quality == q).sum()) for q in np.unique(quality)}
    return table, origin, counts


def _apply_quality(path, table, quality, numbers, keep, sigma_scale) -> None:
    """``valid`` from ``keep``, the sigmas scaled per quality (module docstring)."""
    keep = tuple(QUALITY) if keep is None else tuple(keep)
    table["valid"] = np.isin(quality, keep).astype(np.float64)
    factor = np.array([sigma_scale.get(int(q), 1.0) for q in quality])
    sigmas = [k for k in ("std_n", "std_e", "std_d", "std_vn", "std_ve", "std_vd")
              if k in table]
    for k in sigmas:
        table[k] = table[k] * factor
    for k in sigmas[:3]:
        bad = np.flatnonzero((table["valid"] == 1) & ~(table[k] > 0))
        if bad.size:
            raise LogError(f"{path}, line {numbers[bad[0]]}: {k} = {table[k][bad[0]]:g} m for "
                           f"a kept epoch of quality {QUALITY.get(int(quality[bad[0]]))}: a "
                           "standard deviation must be positive (leave that quality out "
                           "with --keep)")
