"""navcore.filters.recovery piece by piece with hand numbers: the guard's interval and outage
bookkeeping step by step, the factor of a re-acquisition of some components, the bounds at
their edges, the gate of filters without their own (chi-square quantiles from printed
tables) and the guarded engine's IMU time."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.filters.innovation_stats import chi2_gate
from navcore.filters.ins_gnss_kf import KfConfig, KfEngine
from navcore.filters.recovery import (MAX_INFLATION, GuardedEngine, RecoveryGuard, bounded_r,
                                      flag_by_gate, inflate_navigation, inflation_factor,
                                      recovery_options)
from navcore.ins.strapdown import Strapdown

#: upper 1 % quantiles of chi2(3) and chi2(6) (printed tables)
CHI2_99_3DOF, CHI2_99_6DOF = 11.345, 16.812


def test_recovery_options_are_typed_engine_arguments():
    options = recovery_options({"recovery": 1, "recovery_epochs": 7.0, "other": 3})
    assert options == {"recovery": True, "recovery_epochs": 7}
    assert type(options["recovery"]) is bool and type(options["recovery_epochs"]) is int
    assert recovery_options({"recovery": 0, "recovery_epochs": 2})["recovery"] is False


def test_a_new_guard_has_no_interval_and_nothing_elapsed():
    guard = RecoveryGuard(3, recovery=1, recovery_epochs=4.0)
    assert guard.enabled is True and guard.epochs == 4 and type(guard.epochs) is int
    assert (guard.elapsed, guard.interval, guard.n_reacquired) == (0.0, 0.0, 0)
    np.testing.assert_array_equal(guard.since_accepted, np.zeros(3))
    # no interval seen yet: nothing is due, however long a component has waited
    guard.since_accepted[:] = 100.0
    assert not guard.may_reacquire()
    assert guard.due(np.ones(3, dtype=bool)).tolist() == [False, False, False]


def _first_update(guard, gap=0.005):
    """The filter's first update ``gap`` after its start: a gap that is no fix interval."""
    guard.advance(gap)
    guard.open_epoch()
    assert guard.interval == 0.0 and guard.opened
    guard.close_epoch(np.ones(guard.since_accepted.shape, dtype=bool))


def test_the_interval_is_the_smallest_gap_seen_and_a_zero_gap_is_none():
    guard = RecoveryGuard(2, recovery=True, recovery_epochs=3)
    _first_update(guard)
    guard.advance(0.5)
    guard.advance(0.75)
    assert guard.elapsed == 1.25
    guard.open_epoch()
    assert (guard.elapsed, guard.interval) == (0.0, 1.25)
    np.testing.assert_array_equal(guard.since_accepted, [1.25, 1.25])
    guard.close_epoch(np.array([True, False]))
    np.testing.assert_array_equal(guard.since_accepted, [0.0, 1.25])
    guard.advance(2.0)
    guard.open_epoch()                      # a longer gap (an outage) keeps the interval
    assert guard.interval == 1.25
    np.testing.assert_array_equal(guard.since_accepted, [2.0, 3.25])
    guard.open_epoch()                      # two updates at the same time: no interval
    assert guard.interval == 1.25
    np.testing.assert_array_equal(guard.since_accepted, [2.0, 3.25])
    guard.advance(1.0)
    guard.open_epoch()                      # a shorter gap becomes the interval
    assert guard.interval == 1.0
    np.testing.assert_array_equal(guard.since_accepted, [3.0, 4.25])


def test_may_reacquire_and_due_after_recovery_epochs_intervals():
    guard = RecoveryGuard(2, recovery=True, recovery_epochs=3)
    guard.advance(1.0)
    guard.open_epoch()
    guard.close_epoch(np.array([True, True]))
    for _ in range(2):
        guard.advance(1.0)
        guard.open_epoch()
    # 2 intervals without an accepted value: not yet
    assert not guard.may_reacquire()
    assert guard.due(np.array([True, True])).tolist() == [False, False]
    guard.close_epoch(np.array([False, True]))
    guard.advance(1.0 - 1e-9)               # the third interval, a little short (jitter)
    guard.open_epoch()
    assert guard.may_reacquire()
    assert guard.due(np.array([True, True])).tolist() == [True, False]
    assert guard.due(np.array([False, True])).tolist() == [False, False]
    assert guard.due([0, 0]).dtype == bool and not guard.due([0, 0]).any()
    guard.close_epoch(np.array([True, True]))
    guard.advance(3.0 - 1e-5)                # 1e-5 s short of 3 intervals: beyond the jitter
    guard.open_epoch()
    assert guard.interval == 1.0 - 1e-9
    assert not guard.may_reacquire()
    assert guard.due(np.array([True, True])).tolist() == [False, False]


def test_a_gap_a_little_short_of_the_intervals_still_counts_them():
    """Fix times with clock jitter: one interval of 1 s, then 2 s less 1e-7 s: 3 intervals
    within the relative tolerance 1e-6."""
    guard = RecoveryGuard(1, recovery=True, recovery_epochs=3)
    for gap, accepted in ((1.0, True), (1.0, False), (2.0 - 1e-7, False)):
        guard.advance(gap)
        guard.open_epoch()
        if accepted:
            guard.close_epoch(np.array([True]))
    assert guard.interval == 1.0 and guard.since_accepted[0] == pytest.approx(3.0 - 1e-7)
    assert guard.may_reacquire()
    assert guard.due(np.array([True])).tolist() == [True]


def test_a_disabled_guard_never_may_reacquire():
    guard = RecoveryGuard(1, recovery=False, recovery_epochs=1)
    for gap in (1.0, 50.0):
        guard.advance(gap)
        guard.open_epoch()
        assert not guard.may_reacquire()


def test_reacquisition_of_one_component_uses_its_own_variances():
    """Component 1 of three due: lambda = (v1^2 / 1 - r1) / a1 (the scalar closed form), the
    other components' numbers play no part."""
    guard = RecoveryGuard(3, recovery=True, recovery_epochs=2)
    v = np.array([50.0, 40.0, -70.0])
    HPH = np.array([[3.0, 0.5, 0.2], [0.5, 2.0, 0.1], [0.2, 0.1, 5.0]])
    R = np.diag([1.0, 4.0, 9.0])
    lam = guard.reacquisition(v, HPH, R, np.array([False, True, False]))
    assert lam == pytest.approx((40.0 ** 2 - 4.0) / 2.0, rel=1e-9)
    assert guard.n_reacquired == 1
    # two due: the NIS of the pair at lambda is 2
    lam2 = guard.reacquisition(v, HPH, R, np.array([True, False, True]))
    idx = [0, 2]
    S = lam2 * HPH[np.ix_(idx, idx)] + R[np.ix_(idx, idx)]
    assert float(v[idx] @ np.linalg.solve(S, v[idx])) == pytest.approx(2.0, rel=1e-9)
    assert guard.n_reacquired == 2


def test_inflation_factor_of_a_correlated_case_and_a_direction_without_variance():
    # the NIS at the factor is the target, computed the textbook way
    v = np.array([30.0, -10.0])
    A = np.array([[2.0, 0.8], [0.8, 1.0]])
    R = np.array([[1.0, 0.3], [0.3, 2.0]])
    lam = inflation_factor(v, A, R, 2.0)
    nis = float(v @ np.linalg.solve(lam * A + R, v))
    assert nis == pytest.approx(2.0, rel=1e-9)
    assert lam > 1.0
    # a direction of HPH with no variance keeps its whitened c^2 (here 3^2 = 9 of axis 1):
    # 60^2 / (4 lambda + 1) + 9 = 10 -> lambda = (3600 - 1) / 4
    lam = inflation_factor(np.array([60.0, 3.0]), np.diag([4.0, 0.0]), np.eye(2), 10.0)
    assert lam == pytest.approx(3599.0 / 4.0, rel=1e-9)
    # rounding below zero of that eigenvalue is read as zero, not as a negative variance
    lam = inflation_factor(np.array([60.0, 3.0]), np.diag([4.0, -1e-3]), np.eye(2), 10.0)
    assert lam == pytest.approx(3599.0 / 4.0, rel=1e-9)


def test_inflation_factor_at_the_target_and_at_the_cap():
    # NIS at lambda = 1 exactly the target: no inflation
    assert inflation_factor(np.array([2.0]), np.eye(1), np.eye(1), 2.0) == 1.0
    # a root just below the cap is found, one above it gives the cap (a 1e6-fold variance)
    a = 1.0
    v_below = math.sqrt(0.5e6 * a + 1.0)
    assert inflation_factor(np.array([v_below]), np.eye(1), np.eye(1), 1.0) == pytest.approx(
        0.5e6, rel=1e-9)
    assert inflation_factor(np.array([3e3]), np.eye(1), np.eye(1), 1.0) == 1e6 == MAX_INFLATION


def test_inflate_navigation_by_hand_on_a_small_covariance():
    P = np.full((15, 15), 2.0) + np.eye(15)
    Q = inflate_navigation(P, 4.0, np.full(15, 100.0))
    assert Q[0, 0] == 12.0 and Q[8, 8] == 12.0 and Q[0, 8] == 8.0       # times 4
    assert Q[0, 9] == 4.0 and Q[14, 3] == 4.0                             # times 2
    assert Q[9, 9] == 3.0 and Q[14, 9] == 2.0                             # unchanged


def test_bounded_r_at_the_bound_and_with_unequal_bounds():
    r_max = np.array([4.0, 9.0])
    at_bound = np.diag([4.0, 1.0])
    assert bounded_r(at_bound, r_max) is at_bound
    capped = bounded_r(np.diag([1.0, 25.0]), r_max)
    np.testing.assert_allclose(capped, np.diag([1.0, 9.0]), rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(capped, capped.T)
    # correlated: whitened by the bounds, S = [[1, 0.5], [0.5, 1]] * 2 has eigenvalues 3 and 1;
    # the 3 is capped at 1 along (1, 1)/sqrt 2: S' = I, so R' = diag(r_max)
    R = np.array([[8.0, 6.0], [6.0, 18.0]])
    np.testing.assert_allclose(bounded_r(R, r_max), np.diag(r_max), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("m, gate", [(3, CHI2_99_3DOF), (6, CHI2_99_6DOF)])
def test_flag_by_gate_at_the_99_percent_quantile(m, gate):
    assert flag_by_gate(gate * 1.001, m).tolist() == [True] * m
    assert flag_by_gate(gate * 0.999, m).tolist() == [False] * m


class _GuardedKf(GuardedEngine, KfEngine):
    def __init__(self, config, nav, **options):
        super().__init__(config, nav)
        self.init_guard(**options)


def test_a_guarded_engine_counts_the_imu_time_for_its_guard():
    config = KfConfig(p0=np.ones(15), gyro_arw=0.0, accel_vrw=0.0, gyro_bias_sigma=0.0,
                      gyro_bias_tau=0.0, accel_bias_sigma=0.0, accel_bias_tau=0.0,
                      r_sigma=np.ones(3), measurement="position")
    nav = Strapdown.from_euler(0.7, 2.0, 0.0, np.zeros(3), 0.0, 0.0, 0.0)
    kf = _GuardedKf(config, nav, recovery=True, recovery_epochs=2)
    assert kf.guard.since_accepted.shape == (3,) and kf.guard.epochs == 2 and kf.guard.enabled
    for _ in range(3):
        kf.propagate(np.zeros(3), np.array([0.0, 0.0, -9.8]) * 0.25, 0.25)
    assert kf.guard.elapsed == 0.75
    assert kf.phi_acc[0, 3] == pytest.approx(0.75)       # the engine's own propagation ran


def test_an_outage_of_exactly_the_limit_counts_and_the_interval_is_half_a_second():
    """Fixes at 2 Hz, recovery after 2 intervals: an outage of exactly 2 x 0.5 s less the
    relative tolerance 1e-6 reaches the limit (inclusive)."""
    guard = RecoveryGuard(1, recovery=True, recovery_epochs=2)
    _first_update(guard, 0.25)
    guard.advance(0.5)
    guard.open_epoch()
    guard.close_epoch(np.array([True]))
    guard.advance(2 * 0.5 * (1.0 - 1e-6))
    guard.open_epoch()
    assert guard.interval == 0.5
    assert guard.may_reacquire()
    assert guard.due(np.array([True])).tolist() == [True]


def test_inflation_factor_between_one_and_e():
    # v^2 / (lambda + 1) = 1 with v^2 = 2.5: lambda = 1.5
    lam = inflation_factor(np.array([math.sqrt(2.5)]), np.eye(1), np.eye(1), 1.0)
    assert lam == pytest.approx(1.5, rel=1e-9)


def test_bounded_r_caps_only_the_axis_above_its_bound():
    r_max = np.array([4.0, 4.0, 4.0])
    # one variance 9 above the bound, two below: whitened eigenvalues 0.25, 0.25, 2.25
    np.testing.assert_allclose(bounded_r(np.diag([1.0, 1.0, 9.0]), r_max),
                               np.diag([1.0, 1.0, 4.0]), rtol=1e-12, atol=1e-14)
    # 1.5 times the bound
    np.testing.assert_allclose(bounded_r(np.diag([6.0, 1.0, 1.0]), r_max),
                               np.diag([4.0, 1.0, 1.0]), rtol=1e-12, atol=1e-14)


def test_a_nis_at_the_gate_itself_is_not_flagged():
    # flagged when the NIS *exceeds* the 99 % quantile
    for m in (3, 6):
        assert not flag_by_gate(chi2_gate(0.01, m), m).any()


def test_the_time_before_the_first_update_is_no_fix_interval():
    """The failing case of a real log: the first fix 5 ms after the filter's start, then 4 Hz
    fixes.  Before, 5 ms became the interval, so two rejected fixes in a row (0.5 s > 5 x
    5 ms) were a re-acquisition; now the interval is 0.25 s and only five intervals without
    an accepted value (1.25 s) are."""
    guard = RecoveryGuard(3, recovery=True, recovery_epochs=5)
    _first_update(guard, 0.005)
    flagged = np.array([True, False, True])
    for k in range(5):
        guard.advance(0.25)
        guard.open_epoch()
        assert guard.interval == 0.25
        due = guard.due(flagged)
        assert due.tolist() == ([True, False, True] if k == 4 else [False, False, False]), k
        guard.close_epoch(~flagged)
    np.testing.assert_allclose(guard.since_accepted, [1.25, 0.0, 1.25])
