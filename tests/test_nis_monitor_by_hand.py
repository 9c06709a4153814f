"""navcore.filters.nis_monitor on sequences worked out by hand: the band edge of a textbook
chi-square table, which updates a window holds at its ends, the counts and the time at which
it first may warn, and the numbers its message gives."""
from __future__ import annotations

import pytest

from navcore.filters.innovation_stats import chi2_gate
from navcore.filters.nis_monitor import NisMonitor

#: chi2 upper 1 % points (a printed table, e.g. Abramowitz & Stegun table 26.8): dof 3, 6
EDGE_3, EDGE_6 = 11.345, 16.812


def _feed(monitor, values, dof=3, dt=1.0):
    """Observe ``values`` at t = 0, dt, 2 dt, ...; the (t, message) of every warning."""
    out = []
    for k, x in enumerate(values):
        message = monitor.observe(k * dt, x, dof)
        if message is not None:
            out.append((k * dt, message))
    return out


def test_the_band_edge_is_the_tables_99_percent_point_of_the_updates_dof():
    for nis, dof, warns in ((EDGE_3 * 1.001, 3, True), (EDGE_3 * 0.999, 3, False),
                            (12.0, 3, True), (12.0, 6, False), (EDGE_6 * 1.001, 6, True)):
        assert bool(_feed(NisMonitor(10.0), [nis] * 30, dof)) is warns, (nis, dof)


def test_an_nis_exactly_at_its_edge_is_not_above_it():
    edge = chi2_gate(0.01, 3)
    assert edge == pytest.approx(EDGE_3, abs=1e-3)
    assert _feed(NisMonitor(10.0), [edge] * 40) == []


def test_the_first_warning_comes_once_a_whole_window_of_ten_updates_is_seen():
    # updates every second from t = 0, all above: at t = 10 the window (0, 10] holds 10
    warned = _feed(NisMonitor(10.0), [100.0] * 30)
    assert [t for t, _ in warned] == [10.0]
    # a window of 9.5 s holds 10 updates a second apart, one of 8.5 s never does
    assert [t for t, _ in _feed(NisMonitor(9.5), [100.0] * 30)] == [10.0]
    assert _feed(NisMonitor(8.5), [100.0] * 60) == []
    # started at t = 5: the first whole window ends at 15
    monitor = NisMonitor(10.0)
    assert [t for t in range(5, 40) if monitor.observe(float(t), 100.0, 3)] == [15]


def test_the_window_drops_the_update_exactly_one_span_old():
    # t = 0 above, t = 1..5 above, 6..10 below: at t = 10 the window (0, 10] has 5 of 10 above,
    # not more than half; with the update at t = 0 it would be 6 of 11
    values = [100.0] * 6 + [1.0] * 5 + [1.0] * 20
    assert _feed(NisMonitor(10.0), values) == []


def test_more_than_half_above_warns_and_half_does_not():
    # a 20 s window of 1 s updates holds 20: 10 above is half, 11 (t = 10 ... 20) more
    half = [1.0, 100.0] * 15
    assert _feed(NisMonitor(20.0), half) == []
    more = [1.0] * 10 + [100.0] * 11
    assert [t for t, _ in _feed(NisMonitor(20.0), more)] == [20.0]


def test_the_message_counts_the_window_and_gives_the_median_ratio():
    # at t = 10 the window holds the ten ratios 1.1 ... 2.0 of the edge (the update at t = 0
    # has left it): the median of the sorted list (its 6th) is 1.6
    values = [EDGE_3 * r for r in (1.0, 2.0, 1.1, 1.9, 1.2, 1.8, 1.3, 1.7, 1.4, 1.6, 1.5)]
    monitor = NisMonitor(10.0)
    warned = _feed(monitor, values)
    assert len(warned) == 1
    t, text = warned[0]
    assert t == 10.0
    assert text == ("at t = 10 s 10 of the last 10 updates (10 s) have an NIS above their "
                    "99 % chi-square band (median 1.6 times its edge): the filter's covariance "
                    "and the sigmas it reports understate its real errors (its Q, R or initial "
                    "state do not match the sensors); warned once.  Q too small for a real "
                    "IMU: try imu_noise_factor = 7 (now 1); GNSS errors correlated from fix to "
                    "fix: set gnss_corr_time (docs/guide/your_real_log.md)")
    # the factor: the median NIS per dof, 11.345 * 1.6 / 3 = 6.05, rounded up to one digit;
    # from a factor of 10 in use, 60.5 -> 70
    warned = _feed(NisMonitor(10.0, noise_factor=10.0), values)
    assert "try imu_noise_factor = 70 (now 10)" in warned[0][1]


def test_after_its_warning_the_monitor_is_silent_and_keeps_no_window():
    monitor = NisMonitor(10.0)
    assert len(_feed(monitor, [100.0] * 11)) == 1
    assert monitor.warned and len(monitor.window) == 0
    assert all(monitor.observe(float(t), 100.0, 3) is None for t in range(11, 100))
    assert len(monitor.window) == 0


def test_a_window_of_a_second_or_less_still_warns():
    # 20 updates a second for 1 s, all above: the first warning at t = 1 s (the window
    # (0, 1] then holds the 20 updates after the first)
    warned = _feed(NisMonitor(1.0), [100.0] * 40, dt=0.05)
    assert len(warned) == 1 and warned[0][0] == pytest.approx(1.0)
