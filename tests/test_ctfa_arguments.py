"""The arguments of the CTFA schedule (navcore.filters.ctfa, paper 000 eq. 25): which thresholds,
probabilities and Q bounds are accepted at their boundaries, that a refusal names the function
or matrix it is about, and that a reset goes back to Q_0 = Q_min."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.core.component import InputError, ParameterError
from navcore.filters.ctfa import CtfaQSchedule, ctfa_q_scale, ctfa_thresholds

QMIN, QMAX = np.diag([1.0, 2.0]), np.diag([5.0, 6.0])


@pytest.mark.parametrize("p_low, p_high", [(0.0, 0.99), (0.9, 0.9), (0.9, 1.0)])
def test_threshold_probabilities_must_be_strictly_inside_and_ordered(p_low, p_high):
    with pytest.raises(ParameterError, match="^ctfa_thresholds: need 0 < p_low < p_high < 1"):
        ctfa_thresholds(3, p_low, p_high)


@pytest.mark.parametrize("T1, T2", [(math.nan, 10.0), (1.0, math.inf), (-0.5, 10.0),
                                    (4.0, 4.0), (5.0, 4.0)])
def test_thresholds_must_be_finite_with_0_le_t1_lt_t2(T1, T2):
    with pytest.raises(ParameterError, match="^ctfa_q_scale: thresholds must satisfy"):
        ctfa_q_scale(3.0, T1, T2)
    with pytest.raises(ParameterError, match="^CtfaQSchedule: thresholds must satisfy"):
        CtfaQSchedule(QMIN, QMAX, T1, T2)


def test_a_zero_lower_threshold_is_allowed():
    # T1 = 0, T2 = 5: the weight rises linearly from 0: stat 1 gives 1 / 5
    assert ctfa_q_scale(1.0, 0.0, 5.0) == pytest.approx(0.2, rel=1e-15)
    assert ctfa_q_scale(0.0, 0.0, 5.0) == 0.0


def test_a_bad_statistic_is_refused_by_name():
    with pytest.raises(InputError, match="^ctfa_q_scale: chi-square statistic 'stat'"):
        ctfa_q_scale(-1.0)


@pytest.mark.parametrize("which", ["Qmin", "Qmax"])
@pytest.mark.parametrize("bad", [np.ones(2), np.ones((2, 3)), np.ones((2, 2, 2))],
                         ids=["vector", "2x3", "3d"])
def test_q_bounds_must_be_square_matrices(which, bad):
    args = {"Qmin": QMIN, "Qmax": QMAX, which: bad}
    with pytest.raises(ParameterError, match=f"^CtfaQSchedule: '{which}' must be a square"):
        CtfaQSchedule(args["Qmin"], args["Qmax"])


@pytest.mark.parametrize("which", ["Qmin", "Qmax"])
def test_q_bounds_must_be_symmetric_to_1e_12(which):
    """An asymmetry of 1e-9 relative is refused: the tolerance is 1e-12 relative, with no
    absolute one (Q entries are often far below 1)."""
    base = {"Qmin": np.array([[1.0, 0.5], [0.5, 2.0]]), "Qmax": np.array([[5.0, 0.5], [0.5, 6.0]])}
    base[which] = base[which].copy()
    base[which][0, 1] += 0.5e-9
    with pytest.raises(ParameterError, match=f"^CtfaQSchedule: '{which}' must be symmetric"):
        CtfaQSchedule(base["Qmin"], base["Qmax"])


@pytest.mark.parametrize("scale", [4.0, 1e-6])
def test_qmax_minus_qmin_may_be_negative_by_round_off_only(scale):
    """The span Qmax - Qmin is refused when its smallest eigenvalue is below -1e-12 max|Qmax|:
    exactly at that bound it is accepted, at twice it refused (here Qmin = 0, the span diagonal,
    so its eigenvalues are the diagonal exactly)."""
    zero = np.zeros((2, 2))
    CtfaQSchedule(zero, np.diag([scale, -1e-12 * scale]))
    with pytest.raises(ParameterError, match="^CtfaQSchedule: 'Qmax - Qmin' must be positive"):
        CtfaQSchedule(zero, np.diag([scale, -2e-12 * scale]))


def test_the_matrices_are_floats_whatever_the_input():
    """Integer bounds give float64 matrices (a Q is written to float outputs and states)."""
    sched = CtfaQSchedule([[1, 0], [0, 2]], [[5, 0], [0, 6]])
    for Q in (sched.Qmin, sched.Qmax, sched.Q):
        assert Q.dtype == np.float64


def test_reset_goes_back_to_qmin():
    """After an exceedance above T2 (weight 1, Q = Qmax), reset gives Q_0 = Qmin, and with the
    paper's hold a passing test then keeps Qmin."""
    sched = CtfaQSchedule(QMIN, QMAX)
    np.testing.assert_array_equal(sched.update(20.0), QMAX)
    sched.reset()
    assert sched.weight == 0.0
    np.testing.assert_array_equal(sched.Q, QMIN)
    np.testing.assert_array_equal(sched.update(1.0), QMIN)
