"""The time stamps of a sensor log (navcore.sensors.log_time) on values worked out by hand: the
origin, exact relative times and their text, the interval bound at its edges, the replay step.
"""
from __future__ import annotations

import numpy as np
import pytest

from navcore.core.timing import time_tolerance
from navcore.errors import LogError
from navcore.sensors import log_time as lt


@pytest.mark.parametrize("text, origin", [("1700000000.25", 1700000000.0), (" 0.3 ", 0.0),
                                          ("-0.5", -1.0), ("12", 12.0)])
def test_the_origin_is_the_whole_second_at_or_below(text, origin):
    assert lt.time_origin("log.csv", 2, text) == origin


@pytest.mark.parametrize("text, message", [("abc", r"^log\.csv, line 7: column 'time': 'abc' "
                                                   "is not a number"),
                                           ("nan", r"^log\.csv, line 7: column 'time' is nan")])
def test_a_stamp_that_is_no_finite_number_names_its_line(text, message):
    with pytest.raises(LogError, match=message):
        lt.time_origin("log.csv", 7, text)


def test_relative_seconds_are_the_decimal_differences():
    times = lt.relative_seconds("log.csv", ["1700000000.01", "1700000000.02", " 1700000001 "],
                                [2, 3, 4], 1700000000.0)
    assert times.dtype.name == "float64"
    assert times.tolist() == [0.01, 0.02, 1.0]      # float("0.01"), not 1700000000.01 - 1.7e9
    with pytest.raises(LogError, match=r"^log\.csv, line 9: "):
        lt.relative_seconds("log.csv", ["1.0", "x"], [8, 9], 0.0)


@pytest.mark.parametrize("t, origin, text", [(0.01, 0.0, "0.01"), (2.5, 0.0, "2.5"),
                                             (0.01, 1700000000.0, "1700000000.01"),
                                             (3.0, 5.0, "8.0"), (0.25, 1.0, "1.25"),
                                             (1e-07, 0.0, "1e-07")])
def test_absolute_text(t, origin, text):
    assert lt.absolute_text(t, origin) == text


def test_nominal_interval_is_the_median():
    assert lt.nominal_interval([1.0, 10.0, 2.0]) == 2.0


def test_max_dt_jitter_range():
    assert lt.check_max_dt_jitter(0) == 0.0 and lt.check_max_dt_jitter("100") == 100.0
    for value in (-0.5, 100.5):
        with pytest.raises(LogError, match=r"^imu\.max_dt_jitter = .* is outside \[0, 100\]"):
            lt.check_max_dt_jitter(value, "imu.max_dt_jitter")
    with pytest.raises(LogError, match=r"^max_dt_jitter = 'many' is not a number"):
        lt.check_max_dt_jitter("many")


# intervals exact in binary: nominal (median) 1 s, one interval of 1 + deviation
@pytest.mark.parametrize("last, bound, refused", [(1.75, 0.75, None), (2.0, 0.75, "a gap"),
                                                  (0.25, 0.75, None), (0.125, 0.75, "an overlap"),
                                                  (2.0, 1.0, None), (1.5, 0.25, "a gap")])
def test_interval_bound_is_inclusive_and_names_the_line(last, bound, refused):
    dt = _array([1.0, 1.0, 1.0, 1.0, last])
    if refused is None:
        lt.check_intervals("log.csv", dt, lambda k: k + 10, bound)
        return
    with pytest.raises(LogError, match=rf"^log\.csv, line 14: dt = {last!r} s is .*{refused}"):
        lt.check_intervals("log.csv", dt, lambda k: k + 10, bound)


def test_default_interval_bound_is_three_quarters():
    assert lt.DEFAULT_MAX_DT_JITTER == 0.75
    lt.check_intervals("log.csv", _array([1.0, 1.0, 1.75]), lambda k: k)
    with pytest.raises(LogError, match="a gap"):
        lt.check_intervals("log.csv", _array([1.0, 1.0, 1.875]), lambda k: k)


def test_replay_step_of_a_constant_and_of_a_jittered_log():
    ends = [0.125 * k for k in range(1, 9)]
    assert lt.replay_step(_array(ends), _array([0.125] * 8)) == 0.125
    # intervals 0.25, 0.125, 0.125: the step (0.25, 0.5] of the first length would reach the
    # ends 0.375 and 0.5 at once; a step of the shortest interval reaches one each
    ends, dt = _array([0.25, 0.375, 0.5]), _array([0.25, 0.125, 0.125])
    assert lt.replay_step(ends, dt) == 0.125


@pytest.mark.parametrize("start, end, step, n", [(0.0, 1.0, 0.125, 8), (0.0, 1.0, 0.3, 4),
                                                 (0.0, 0.9, 0.3, 3), (1.0, 0.0, 0.1, 0),
                                                 (2.0, 2.0, 0.5, 0)])
def test_steps_to_reach(start, end, step, n):
    assert lt.steps_to_reach(start, end, step) == n


def _array(values):
    return np.array(values, dtype=float)


def test_a_step_within_the_time_tolerance_of_the_end_reaches_it():
    # 4 steps of 0.25 end 1.0, the same instant as 1.0 + tolerance: no fifth step
    end = 1.0 + time_tolerance(0.25, 1.0)
    assert end > 1.0 and lt.steps_to_reach(0.0, end, 0.25) == 4
    assert lt.steps_to_reach(0.0, np.nextafter(end, 2.0), 0.25) == 5


@pytest.mark.parametrize("ends, dt, step", [
    # each step of the first interval's length (0.5 s) reaches one end: (0, 0.5], (0.5, 1],
    # (1, 1.5]; the replay keeps that step although the intervals vary
    ([0.5, 0.75, 1.125], [0.5, 0.25, 0.375], 0.5),
    # steps of the first length (0.25 s) reach 0.25, then none, then 0.75: not one end each,
    # so the replay steps at the shortest interval
    ([0.25, 0.75, 1.25], [0.25, 0.5, 0.5], 0.25),
])
def test_replay_step_counts_from_the_first_interval(ends, dt, step):
    assert lt.replay_step(_array(ends), _array(dt)) == step


def _grid_with_two_slips(start, n, last_shift):
    """Ends every 0.25 s from ``start``, the sixth 1e-10 s early and the last ``last_shift``
    late, with the intervals they make (the shortest 0.25 - 1e-10)."""
    ends = start + 0.25 * np.arange(1, n + 1)
    ends[5] -= 1e-10
    ends[-1] += last_shift
    return ends, np.diff(np.concatenate([[start], ends]))


def test_the_replay_tolerance_is_that_of_the_last_end():
    # 4096 s into the log the time tolerance of a 0.25 s step is 2.5e-10 + 8 ulp(4096) =
    # 2.573e-10: an end 2.555e-10 late is still on the grid (one end a step), so the replay
    # keeps the first interval; with the tolerance near t = 0 (2.5e-10) it would not
    ends, dt = _grid_with_two_slips(0.0, 16384, 2.555e-10)
    assert 2.555e-10 < time_tolerance(0.25, 4096.0) and lt.replay_step(ends, dt) == 0.25


def test_an_end_beyond_the_tolerance_leaves_the_grid():
    # 1e-7 s late is beyond the tolerance (2.5e-10 + ULPs, whatever the time of the log):
    # the replay steps at the shortest interval
    ends, dt = _grid_with_two_slips(1000.0, 16, 1e-7)
    assert lt.replay_step(ends, dt) == dt.min() < 0.25


def test_replay_step_of_a_single_interval():
    assert lt.replay_step(_array([0.25]), _array([0.25])) == 0.25
