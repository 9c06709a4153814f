"""navcore.filters.recovery: the covariance inflation against its closed form, the bounded R, and
the rejection-run bookkeeping; the filters' use of them on a scenario: test_outage_recovery."""
import math

import numpy as np
import pytest

from navcore.filters.recovery import (MAX_INFLATION, RecoveryGuard, bounded_r,
                                      inflate_navigation, inflation_factor)


def test_inflation_factor_matches_the_scalar_closed_form():
    # v^2 / (lambda a + r) = k  ->  lambda = (v^2 / k - r) / a
    for v, a, r, k in ((30.0, 2.0, 1.5, 1.0), (-7.0, 0.3, 4.0, 1.0), (100.0, 1e-2, 1.0, 1.0)):
        lam = inflation_factor(np.array([v]), np.array([[a]]), np.array([[r]]), k)
        assert lam == pytest.approx((v * v / k - r) / a, rel=1e-9)


def test_inflation_factor_of_a_diagonal_case_against_the_scalar_root():
    """Equal whitened variances: sum_i c_i^2 / (lambda mu + 1) = k has the root
    lambda = (|c|^2 / k - 1) / mu (a textbook case the eigen-solution must reproduce)."""
    R = np.diag([4.0, 1.0, 9.0])
    A = 0.5 * R                                   # mu = 0.5 for every axis
    v = np.array([20.0, -5.0, 30.0])
    c2 = float(v @ np.linalg.solve(R, v))
    lam = inflation_factor(v, A, R, 3.0)
    assert lam == pytest.approx((c2 / 3.0 - 1.0) / 0.5, rel=1e-9)


def test_inflation_factor_is_one_for_a_consistent_innovation_and_capped():
    R, A = np.eye(3), np.eye(3)
    assert inflation_factor(np.array([0.5, 0.5, 0.5]), A, R, 3.0) == 1.0
    assert inflation_factor(np.array([1e9, 0.0, 0.0]), A, R, 3.0) == MAX_INFLATION


def test_inflate_navigation_scales_the_navigation_block_and_keeps_p_definite():
    rng = np.random.default_rng(1)
    M = rng.standard_normal((15, 15))
    P = M @ M.T + 15 * np.eye(15)
    roomy = np.full(15, 1e9)                 # an initial covariance that caps nothing
    Q = inflate_navigation(P, 100.0, roomy)
    assert np.allclose(Q[:9, :9], 100.0 * P[:9, :9])
    assert np.allclose(Q[:9, 9:], 10.0 * P[:9, 9:]) and np.array_equal(Q[9:, 9:], P[9:, 9:])
    np.linalg.cholesky(Q)
    assert inflate_navigation(P, 1.0, roomy) is P
    # attitude stops at its initial variance (distinct per axis); position and velocity not
    p0_var = np.full(15, 1e9)
    p0_var[6:9] = np.diag(P)[6:9] * np.array([2.0, 50.0, 400.0])
    Q = inflate_navigation(P, 100.0, p0_var)
    np.testing.assert_allclose(np.diag(Q)[6:9], np.diag(P)[6:9] * [2.0, 50.0, 100.0])
    np.testing.assert_allclose(np.diag(Q)[:6], 100.0 * np.diag(P)[:6])
    np.linalg.cholesky(Q)


def test_bounded_r_caps_the_variances_of_a_diagonal_r_and_leaves_a_small_one():
    r_max = np.array([4.0, 4.0, 1.0])
    assert np.allclose(bounded_r(np.diag([9.0, 2.0, 5.0]), r_max), np.diag([4.0, 2.0, 1.0]))
    R = np.diag([1.0, 2.0, 0.5])
    assert bounded_r(R, r_max) is R


def test_bounded_r_keeps_correlations_and_the_bound():
    R = np.array([[10.0, 6.0], [6.0, 10.0]])
    B = bounded_r(R, np.array([4.0, 4.0]))
    assert np.all(np.linalg.eigvalsh(np.diag([4.0, 4.0]) - B) >= -1e-12)
    assert B[0, 1] > 0 and math.isclose(B[0, 0], B[1, 1])


def _epoch(guard, gap, flagged):
    guard.advance(gap)
    guard.open_epoch()
    due = guard.due(np.array(flagged))
    guard.close_epoch(~np.array(flagged) | due)
    return due.tolist()


def test_a_run_of_rejections_and_an_outage_count_alike():
    guard = RecoveryGuard(2, recovery=True, recovery_epochs=3)
    assert _epoch(guard, 1.0, [False, False]) == [False, False]
    # an isolated rejection, and one every other epoch, are the law's
    assert _epoch(guard, 1.0, [True, False]) == [False, False]
    assert _epoch(guard, 1.0, [False, False]) == [False, False]
    # component 0 rejected three epochs in a row: re-acquired at the third
    assert [_epoch(guard, 1.0, [True, False]) for _ in range(3)] == [
        [False, False], [False, False], [True, False]]
    # after a 3 s outage the first fix the law rejects is re-acquired at once
    assert _epoch(guard, 3.0, [True, True]) == [True, True]
    assert guard.n_reacquired == 0          # counted by reacquisition(), not by due()


def test_the_guard_off_never_reacquires():
    guard = RecoveryGuard(3, recovery=False, recovery_epochs=1)
    for gap in (1.0, 100.0, 1.0):
        assert _epoch(guard, gap, [True, True, True]) == [False, False, False]
