"""Time stamps of a sensor log as recorded: the time origin, each IMU interval's own length
within a bound, and the step a replay needs.

Origin.  A log may be stamped in any time scale: seconds from power-on, GPS seconds of the
week, UNIX time (about 1.7e9 s, where consecutive float64 values are 2.4e-7 s apart, so a
100 Hz interval computed from two parsed stamps is off by up to 2e-5 relative).  Every time
of a log is therefore held relative to its origin: the whole second at or below the first IMU
line's time (:func:`time_origin`).  The stamps are subtracted from the origin as the decimal
text they were written in (:func:`relative_seconds`, exact), and only then rounded to
float64, so the stamps cost no precision whatever their scale; a log whose first stamp lies
in [0, 1) s keeps its times unchanged (origin 0).

Intervals.  The filters integrate each interval over its own ``dt`` (the filter contract
carries ``imu_dt`` per interval, as KF-GINS uses each line's own interval), so the rate need
not be constant.  An interval far from the log's nominal interval (the median ``dt``) is a
lost sample (a gap) or a doubled stamp (an overlap) more often than a real interval:
:func:`check_intervals` refuses ``|dt / nominal - 1| > max_dt_jitter``, naming the line.  A
user who knows the intervals are real raises the bound; nothing is ever resampled.

Replay step (:func:`replay_step`).  A replay gives a filter every interval, one per
communication step, as recorded: at the first interval's length when every step of that
length reaches exactly one interval end (a constant-rate log: the old grid, bit for bit),
otherwise at the shortest interval (a step then reaches at most one end; some reach none and
the outputs hold).
"""
from __future__ import annotations

import math
from decimal import Decimal, InvalidOperation
from typing import Sequence

import numpy as np

from ..errors import LogError
from ..core.timing import time_tolerance

#: default largest relative deviation of an IMU interval from the nominal (median) one:
#: accepts intervals of 0.25 to 1.75 nominal (a 166 Hz MEMS IMU stamped at 3, 6 and 9 ms),
#: refuses a lost sample (2 nominal)
DEFAULT_MAX_DT_JITTER = 0.75
#: largest accepted ``max_dt_jitter`` (intervals of up to 101 nominal)
MAX_DT_JITTER_LIMIT = 100.0


def _decimal(path, number, text) -> Decimal:
    try:
        value = Decimal(text.strip())
    except InvalidOperation:
        raise LogError(f"{path}, line {number}: column 'time': '{text.strip()}' is not a "
                       "number") from None
    if not value.is_finite():
        raise LogError(f"{path}, line {number}: column 'time' is {text.strip()} (values must "
                       "be finite)")
    return value


def time_origin(path, number, text) -> float:
    """The whole second at or below the time ``text`` of line ``number`` of ``path``."""
    return float(math.floor(_decimal(path, number, text)))


def relative_seconds(path, texts: Sequence[str], numbers: Sequence[int],
                     origin: float) -> np.ndarray:
    """The times ``texts`` (decimal text of the lines ``numbers``) minus ``origin`` (a whole
    second), subtracted exactly and then rounded to float64."""
    base = Decimal(int(origin))
    return np.array([float(_decimal(path, n, t) - base) for t, n in zip(texts, numbers)],
                    dtype=np.float64)


def exact_intervals(path, texts: Sequence[str], numbers: Sequence[int]) -> np.ndarray:
    """The lengths between consecutive times ``texts`` (decimal text of the lines
    ``numbers``), each subtracted exactly and then rounded to float64: a converter's ``dt``
    (the difference of two parsed stamps near 1.7e9 s is off by up to 2.4e-7 s, and such
    intervals no longer tile the stamps)."""
    stamps = [_decimal(path, n, t) for t, n in zip(texts, numbers)]
    return np.array([float(b - a) for a, b in zip(stamps[:-1], stamps[1:])], dtype=np.float64)


def exact_times(path, texts: Sequence[str], numbers: Sequence[int], origin=None):
    """The times ``texts`` (decimal text of the lines ``numbers``) relative to ``origin``
    (None: the whole second at or below the first of them), exact (:func:`relative_seconds`);
    returns ``(origin, times)``."""
    if origin is None:
        origin = time_origin(path, numbers[0], texts[0])
    return origin, relative_seconds(path, texts, numbers, origin)


def absolute_text(t: float, origin: float) -> str:
    """The text of the relative time ``t`` plus ``origin``, exact: what
    :func:`relative_seconds` reads back as ``t`` (the shortest text of ``t`` that does)."""
    if origin == 0.0:
        return repr(float(t))
    return str(Decimal(int(origin)) + Decimal(repr(float(t))))


def nominal_interval(dt: np.ndarray) -> float:
    """The log's nominal IMU interval: the median of ``dt``."""
    return float(np.median(dt))


def check_max_dt_jitter(value, where="max_dt_jitter") -> float:
    """``value`` as a float in [0, MAX_DT_JITTER_LIMIT]; the error names ``where``."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise LogError(f"{where} = {value!r} is not a number") from None
    if not 0.0 <= value <= MAX_DT_JITTER_LIMIT:
        raise LogError(f"{where} = {value!r} is outside [0, {MAX_DT_JITTER_LIMIT:g}] (the "
                       "largest relative deviation of an IMU interval from the nominal one)")
    return value


def check_intervals(path, dt, line_of, max_dt_jitter=DEFAULT_MAX_DT_JITTER) -> None:
    """Every ``dt`` within ``max_dt_jitter`` (relative) of the nominal interval; the error
    names the line (``line_of(k)`` for row k), says gap or overlap and how to accept it."""
    nominal = nominal_interval(dt)
    deviation = dt / nominal - 1.0
    bad = np.flatnonzero(np.abs(deviation) > max_dt_jitter)
    if bad.size:
        k = int(bad[0])
        kind = ("a gap (a lost sample?)" if deviation[k] > 0 else
                "an overlap (a repeated stamp?)")
        raise LogError(f"{path}, line {line_of(k)}: dt = {float(dt[k])!r} s is "
                       f"{dt[k] / nominal:.4g} times the nominal interval {nominal!r} s "
                       f"(median dt): {kind}, beyond max_dt_jitter = {max_dt_jitter:g} "
                       "(raise it to integrate such intervals as recorded)")


def _reaching_step(ends, start, step) -> np.ndarray:
    """Number n of the communication step ``(start + (n-1) step, start + n step]`` that
    reaches each of ``ends`` (within the time tolerance)."""
    tol = max(time_tolerance(step, float(ends[0])), time_tolerance(step, float(ends[-1])))
    return np.ceil((ends - start - tol) / step)


def replay_step(ends: np.ndarray, dt: np.ndarray) -> float:
    """The communication step of a replay of the IMU intervals ending at ``ends`` with
    lengths ``dt`` (module docstring)."""
    start = float(ends[0] - dt[0])
    first = float(dt[0])
    index = _reaching_step(ends, start, first)
    if index[0] == 1 and (np.diff(index) == 1).all():
        return first
    step = float(dt.min())
    while not (np.diff(_reaching_step(ends, start, step)) >= 1).all():
        step *= 0.5    # only at the tolerance's edge: a step a little shorter reaches one
    return step


def steps_to_reach(start: float, end: float, step: float) -> int:
    """The number of steps of ``step`` from ``start`` whose last reaches ``end`` (within the
    time tolerance), at least 0."""
    n = int(math.floor((end - start) / step + 1e-9))
    if start + n * step + time_tolerance(step, end) < end:
        n += 1                 # a shortest-interval step does not divide the span
    return max(n, 0)
