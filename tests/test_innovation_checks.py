"""The checks of navcore.filters.innovation_stats at their edges, on values worked out by hand:
the per-observation statistic and its inputs, the gate's parameters, the Cholesky factor's
refusals, the log-determinant and the Gaussian log-likelihood.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.errors import InputError, ParameterError
from navcore.filters import innovation_stats as ist
from lapack_cases import case_where_the_solves_differ


def test_per_observation_statistic_of_one_epoch_a_batch_and_a_scalar():
    S = np.diag([4.0, 0.25])
    assert ist.chi_square_per_observation([2.0, 1.0], S).tolist() == [1.0, 4.0]
    batch = ist.chi_square_per_observation([[2.0, 1.0], [0.0, 0.5]], S)
    assert batch.tolist() == [[1.0, 4.0], [0.0, 1.0]]
    assert ist.chi_square_per_observation(3.0, 9.0).tolist() == [1.0]


@pytest.mark.parametrize("innovation, S, message", [
    ([[[1.0]]], np.eye(1), r"^innovation: expected shape \(m,\) or \(N, m\)"),
    ([1.0, math.nan], np.eye(2), r"^innovation: contains NaN"),
    ([1.0, 1.0], np.eye(3), r"^S: expected shape \(2, 2\)"),
    ([1.0, 1.0], np.diag([1.0, 0.0]), r"^S: diagonal must be > 0"),
    ([1.0, 1.0], np.diag([1.0, -1.0]), r"^S: diagonal must be > 0"),
])
def test_per_observation_inputs_are_named(innovation, S, message):
    with pytest.raises(InputError, match=message):
        ist.chi_square_per_observation(innovation, S)


def test_gate_parameters_and_default_dof():
    assert ist.chi2_gate(0.01) == pytest.approx(6.6349, abs=1e-4)     # printed chi2(1) table
    assert ist.chi2_gate(0.05, 2) == pytest.approx(5.9915, abs=1e-4)   # chi2(2): -2 ln 0.05
    for alpha in (0.0, 1.0, -0.1):
        with pytest.raises(ParameterError, match=r"^alpha "):
            ist.chi2_gate(alpha)
    for dof in (0, 1.5, -1):
        with pytest.raises(ParameterError, match=r"^dof "):
            ist.chi2_gate(0.05, dof)


def test_chi2_quantiles_of_two_degrees_of_freedom_by_hand():
    # chi2(2) is exponential with mean 2: P(X <= x) = 1 - exp(-x / 2)
    assert ist.chi2_lower_quantile(0.5, 2) == pytest.approx(2.0 * math.log(2.0))
    assert ist.chi2_upper_quantile(0.25, 2) == pytest.approx(-2.0 * math.log(0.25))


@pytest.mark.parametrize("numpy_factor", [False, True])
def test_cholesky_factor_and_its_refusals(numpy_factor):
    S = np.array([[4.0, 2.0], [2.0, 5.0]])           # L = [[2, 0], [1, 2]]
    v, L = ist.checked_cholesky([1.0, 2.0], S, "here", numpy_factor=numpy_factor)
    assert v.tolist() == [1.0, 2.0] and L == pytest.approx(np.array([[2.0, 0.0], [1.0, 2.0]]))
    with pytest.raises(InputError, match=r"^here: innovation covariance 'S' is not positive"):
        ist.checked_cholesky([1.0, 1.0], np.diag([1.0, -1.0]), "here", numpy_factor)
    with pytest.raises(InputError, match=r"^here: 'S' must be 2x2, got \(1, 1\)"):
        ist.checked_cholesky([1.0, 1.0], 3.0, "here", numpy_factor)
    with pytest.raises(InputError, match=r"^here: 'innovation' and 'S' must be finite"):
        ist.checked_cholesky([1.0, 1.0], np.diag([1.0, math.inf]), "here", numpy_factor)


def test_log_det_nis_and_likelihood_by_hand():
    L = np.array([[2.0, 0.0], [1.0, 2.0]])           # S = [[4, 2], [2, 5]], det 16
    assert ist.log_det_from_cholesky(L) == pytest.approx(math.log(16.0))
    # u = L^-1 v for v = (2, 3): u = (1, 1), |u|^2 = 2
    assert ist.nis_from_cholesky(L, np.array([2.0, 3.0])) == pytest.approx(2.0)
    assert ist.nis_from_cholesky(L, np.array([2.0, 3.0]), general_solve=True) == pytest.approx(2.0)
    assert ist.chi_square_statistic([2.0, 3.0], L @ L.T) == pytest.approx(2.0)
    assert ist.nis(np.array([2.0, 3.0]), L @ L.T) == pytest.approx(2.0)
    expected = -0.5 * (2.0 + math.log(16.0) + 2 * math.log(2 * math.pi))
    assert ist.gaussian_log_likelihood(2.0, math.log(16.0), 2) == pytest.approx(expected)


def test_the_checked_statistic_names_itself():
    with pytest.raises(InputError, match=r"^chi_square_statistic: innovation covariance 'S'"):
        ist.chi_square_statistic([1.0, 1.0], -np.eye(2))


def test_the_nis_of_a_factor_is_a_triangular_solve_by_default():
    """One triangular solve (LAPACK dtrtrs), bit for bit; numpy's LU solve only on request
    (a case where the two differ in the last bit)."""
    S, v, nis_triangular, nis_lu = case_where_the_solves_differ()
    L = np.linalg.cholesky(S)
    assert ist.nis_from_cholesky(L, v) == nis_triangular
    assert ist.nis_from_cholesky(L, v, general_solve=True) == nis_lu
