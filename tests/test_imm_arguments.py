"""The IMM machinery (navcore.filters.imm) at the edges of its arguments, by hand: transition
matrices and probabilities at their bounds, an unreachable model, zero likelihoods (without a
divide warning), the probability floor, and refusals that name what they refuse."""

from __future__ import annotations

import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from navcore.core.component import InputError, ParameterError
from navcore.filters.imm import (ImmBank, check_transition_matrix, imm_mix,
                                 imm_update_probabilities, log_likelihood)


def _filters(*xs):
    """Stand-ins with the ``x`` and ``P`` the bank reads and writes."""
    return [SimpleNamespace(x=np.array([x], dtype=float), P=np.eye(1)) for x in xs]


def test_identity_and_zero_entries_are_valid_transitions():
    np.testing.assert_array_equal(check_transition_matrix([[1, 0], [0, 1]]), np.eye(2))


@pytest.mark.parametrize("Pi, message", [
    (np.full(2, 0.5), "must be square"),
    (np.full((2, 3), 1.0 / 3.0), "must be square"),
    (np.array([[np.nan, 1.0], [0.0, 1.0]]), "entries must be finite and in"),
    (np.array([[1.0 + 1e-10, 0.0], [0.0, 1.0]]), "entries must be finite and in"),
])
def test_bad_transition_matrices_are_refused(Pi, message):
    """Among them an entry 1e-10 above 1 in a row whose sum is within the 1e-9 tolerance."""
    with pytest.raises(ParameterError, match=message):
        check_transition_matrix(Pi)


def test_the_wanted_size_is_named():
    with pytest.raises(ParameterError, match="must be 3x3"):
        check_transition_matrix(np.eye(2), 3)


def test_a_refused_likelihood_names_the_function():
    with pytest.raises(InputError, match="^log_likelihood"):
        log_likelihood(np.ones(2), -np.eye(2))


def test_mixing_refusals_name_their_argument():
    with pytest.raises(InputError, match="^IMM: 'mu' must be a probability vector"):
        imm_mix(np.array([0.5, 0.6]), np.eye(2), [np.zeros(1)] * 2, [np.eye(1)] * 2)
    with pytest.raises(InputError, match="^imm_mix: 2 probabilities but 3 states"):
        imm_mix(np.array([0.5, 0.5]), np.eye(2), [np.zeros(1)] * 3, [np.eye(1)] * 2)


def test_an_unreachable_model_is_mixed_with_the_probabilities():
    """Pi = [[1, 0], [1, 0]]: nothing reaches model 1 (c_bar = [1, 0]).  Model 0 mixes with
    mu_{i|0} = Pi_i0 mu_i / 1 = mu, model 1 with mu as documented: both get
    x0 = 0.3 * 1 + 0.7 * 3 = 2.4, P0 = 0.3 (1 + 1.4^2) + 0.7 (2 + 0.6^2) = 2.54."""
    xs, Ps, c_bar = imm_mix(np.array([0.3, 0.7]), np.array([[1.0, 0.0], [1.0, 0.0]]),
                            [np.array([1.0]), np.array([3.0])],
                            [np.array([[1.0]]), np.array([[2.0]])])
    np.testing.assert_array_equal(c_bar, [1.0, 0.0])
    for x, P in zip(xs, Ps):
        np.testing.assert_allclose(x, [2.4], rtol=1e-15)
        np.testing.assert_allclose(P, [[2.54]], rtol=1e-14)


def test_zero_likelihoods_and_probabilities_give_zero_without_a_warning():
    """Bayes' rule with zeros, floor 0: c_bar = [0.6, 0.4, 0], Lambda = [0, 2, 1] gives
    mu proportional to [0, 0.8, 0] = [0, 1, 0]; log(0) is taken as -inf silently."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mu = imm_update_probabilities(np.array([0.6, 0.4, 0.0]), np.array([0.0, 2.0, 1.0]),
                                      floor=0.0)
    np.testing.assert_array_equal(mu, [0.0, 1.0, 0.0])


def test_equal_likelihoods_without_floor_keep_the_prediction():
    mu = imm_update_probabilities(np.array([0.5, 0.5]), np.array([1.0, 1.0]), floor=0.0)
    np.testing.assert_array_equal(mu, [0.5, 0.5])


def test_no_information_normalizes_the_prediction():
    """Every likelihood zero: mu = c_bar / sum c_bar (c_bar is only proportional), with the
    floor's renormalization and without."""
    for floor in (1e-12, 0.0):
        mu = imm_update_probabilities(np.array([0.2, 0.6]), np.full(2, -np.inf), log=True,
                                      floor=floor)
        np.testing.assert_allclose(mu, [0.25, 0.75], rtol=1e-15)


def test_an_unreachable_model_keeps_the_floor():
    """c_bar = [1, 0]: model 1 gets probability 0, raised to the floor f and renormalized:
    [1, f] / (1 + f)."""
    f = 1e-3
    mu = imm_update_probabilities(np.array([1.0, 0.0]), np.array([0.0, 0.0]), log=True, floor=f)
    np.testing.assert_allclose(mu, [1.0 / (1.0 + f), f / (1.0 + f)], rtol=1e-15)


@pytest.mark.parametrize("floor", [0.5, -1e-3])
def test_the_floor_is_below_one_over_the_number_of_models(floor):
    with pytest.raises(ParameterError, match="'floor' must be in"):
        imm_update_probabilities(np.array([0.5, 0.5]), np.array([1.0, 1.0]), floor=floor)
    with pytest.raises(ParameterError, match="'floor' must be in"):
        ImmBank(_filters(0.0, 1.0), np.eye(2), floor=floor)


def test_a_bank_may_start_in_one_model_without_a_floor():
    bank = ImmBank(_filters(0.0, 1.0), np.eye(2), mu0=[1, 0], floor=0.0)
    assert bank.mu.dtype == np.float64
    np.testing.assert_array_equal(bank.mu, [1.0, 0.0])
    with pytest.raises(ParameterError, match="'mu0' must be a probability vector"):
        ImmBank(_filters(0.0, 1.0), np.eye(2), mu0=[0.5, 0.6])


def test_the_predicted_probabilities_sum_to_one():
    """Rows of Pi summing to 1 - 5e-10 (within the tolerance): c_bar = Pi^T mu sums to
    1 - 5e-10, the bank's predicted probabilities to 1."""
    Pi = np.diag([1.0 - 5e-10, 1.0 - 5e-10])
    bank = ImmBank(_filters(0.0, 1.0), Pi)
    bank.predict(lambda flt, j: None)
    np.testing.assert_allclose(bank.mu, [0.5, 0.5], rtol=0.0, atol=1e-15)


def test_the_update_passes_each_model_its_index_and_uses_the_bank_floor():
    """Log-likelihoods 0 and -1000 for models 0 and 1 from mu = [0.5, 0.5], Pi = I: Bayes gives
    [1, e^-1000] = [1, 0]; the bank's floor 0.1 makes it [1, 0.1] / 1.1."""
    bank = ImmBank(_filters(0.0, 1.0), np.eye(2), floor=0.1)
    log_liks = bank.update(lambda flt, j: (0.0, -1000.0)[j])
    np.testing.assert_array_equal(log_liks, [0.0, -1000.0])
    np.testing.assert_allclose(bank.mu, [1.0 / 1.1, 0.1 / 1.1], rtol=1e-15)
    assert math.isclose(bank.x[0], 0.1 / 1.1, rel_tol=1e-14)


def test_transition_rows_must_sum_to_one_within_1e_9():
    check_transition_matrix(np.array([[1.0 - 0.5e-9, 0.0], [0.0, 1.0]]))
    with pytest.raises(ParameterError, match="rows must sum to 1"):
        check_transition_matrix(np.array([[1.0 - 2e-9, 0.0], [0.0, 1.0]]))


def test_a_bank_of_one_filter_is_that_filter():
    bank = ImmBank(_filters(2.0), np.eye(1))
    np.testing.assert_array_equal(bank.mu, [1.0])
    np.testing.assert_array_equal(bank.x, [2.0])
