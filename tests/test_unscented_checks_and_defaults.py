"""The unscented core's argument checks, defaults and scale branches, with hand numbers.

Weights of the scaled unscented transform written out for small n (paper 000 eqs. 11-13:
``lambda = alpha^2 (n + kappa) - n``, ``Wm_0 = lambda / (n + lambda)``, ``Wc_0 = Wm_0 + 1 +
beta - alpha^2``, ``W_i = 1 / (2 (n + lambda))``), one-state filters whose predict and update
are worked out by hand, and the messages, which start with the place and name the argument.
"""
import numpy as np
import pytest

from navcore.core.component import InputError, ParameterError
from navcore.filters.unscented import (UnscentedKalmanFilter, sigma_points, sigma_weights,
                                       unscented_transform)


def test_weights_of_one_state():
    # n = 1, alpha = 1, kappa = 0: lambda = 0, points at x and x +- 1 sigma
    Wm, Wc, lam = sigma_weights(1)
    assert lam == 0.0
    assert Wm.tolist() == [0.0, 0.5, 0.5] and Wc.tolist() == [2.0, 0.5, 0.5]


def test_filter_defaults_and_its_beta_and_kappa():
    ukf = UnscentedKalmanFilter(2)
    assert ukf.lambda_ == 0.0 and ukf.Wc[0] == 2.0           # beta = 2: 0 + 1 + 2 - 1
    # n = 2, beta = 5, kappa = 1: lambda = 3 - 2 = 1, Wm_0 = 1/3, Wc_0 = 1/3 + 1 + 5 - 1
    ukf = UnscentedKalmanFilter(2, beta=5.0, kappa=1.0)
    assert ukf.lambda_ == 1.0
    assert ukf.Wm[0] == pytest.approx(1.0 / 3.0, rel=1e-15)
    assert ukf.Wc[0] == pytest.approx(1.0 / 3.0 + 5.0, rel=1e-15)
    assert ukf.Wm[1:] == pytest.approx([1.0 / 6.0] * 4, rel=1e-15)


def test_fresh_filter_diagnostics_are_zero():
    ukf = UnscentedKalmanFilter(3)
    assert ukf.last_nis == 0.0 and ukf.last_log_likelihood == 0.0
    assert ukf.sqrt_fallbacks == 0
    ukf.P = np.diag([1.0, 1.0, 0.0])                         # one state not excited
    ukf.sigma_points()
    assert ukf.sqrt_fallbacks == 1


def test_integer_initial_values_give_a_float_state():
    # the caller may overwrite the state in place: an integer array would truncate
    ukf = UnscentedKalmanFilter(2, x0=[1, 2], P0=[[2, 0], [0, 1]])
    ukf.x[0] += 0.25
    ukf.P[0, 0] += 0.5
    assert ukf.x.tolist() == [1.25, 2.0] and ukf.P[0, 0] == 2.5


@pytest.mark.parametrize("n", [0, 2.5])
def test_state_dimension_must_be_a_positive_integer(n):
    with pytest.raises(ParameterError, match="^sigma_weights: state dimension 'n'"):
        sigma_weights(n, kappa=1.0)


@pytest.mark.parametrize("name", ["alpha", "beta", "kappa"])
def test_a_non_finite_parameter_is_named(name):
    with pytest.raises(ParameterError, match=f"^sigma_weights: parameter '{name}' must be finite"):
        sigma_weights(3, **{name: float("nan")})


def test_alpha_zero_is_refused_as_alpha():
    with pytest.raises(ParameterError, match="^sigma_weights: parameter 'alpha' must be > 0"):
        sigma_weights(3, alpha=0.0, kappa=1.0)


@pytest.mark.parametrize("lam", [-2.0, -3.0])
def test_sigma_points_need_a_positive_spread(lam):
    # n = 2: n + lambda = 0 and -1 are refused
    with pytest.raises(ParameterError, match="^sigma_points: n \\+ lambda must be > 0"):
        sigma_points(np.zeros(2), np.eye(2), lam)


def test_sigma_points_spread_by_n_plus_lambda():
    # n = 1, lambda = 3: points at x +- sqrt(4 * 0.25) = x +- 1
    points = sigma_points(np.array([2.0]), np.array([[0.25]]), 3.0)
    assert points.ravel().tolist() == [2.0, 3.0, 1.0]


@pytest.mark.parametrize("name", ["x", "P"])
def test_sigma_points_name_a_non_finite_argument(name):
    args = {"x": np.zeros(2), "P": np.eye(2)}
    args[name] = args[name] * np.nan
    with pytest.raises(InputError, match=f"^sigma_points: '{name}' contains NaN or inf"):
        sigma_points(args["x"], args["P"], 0.0)


def test_sigma_points_refuse_a_state_that_is_not_a_vector():
    with pytest.raises(InputError, match="^sigma_points: 'x' must be"):
        sigma_points(np.zeros((2, 2)), np.eye(2), 0.0)


@pytest.mark.parametrize("name, value", [("x0", [0.0, np.inf]),
                                         ("P0", np.full((2, 2), np.inf))])
def test_filter_names_a_non_finite_initial_value(name, value):
    with pytest.raises(InputError, match=f"^UnscentedKalmanFilter: '{name}' contains NaN or inf"):
        UnscentedKalmanFilter(2, **{name: value})


def test_transform_adds_the_noise_covariance():
    Wm, Wc, _ = sigma_weights(1)
    mean, cov = unscented_transform([[0.0], [1.0], [-1.0]], Wm, Wc, noise_cov=[[0.25]])
    assert mean.tolist() == [0.0] and cov.tolist() == [[1.25]]


def test_vectorized_model_must_give_one_row_per_point():
    ukf = UnscentedKalmanFilter(2)
    with pytest.raises(InputError, match="^vectorized model must return one row per sigma point"):
        ukf.predict(lambda X: X[:, 0], np.eye(2), vectorized=True)


def test_a_state_of_the_wrong_shape_is_refused():
    ukf = UnscentedKalmanFilter(2)
    ukf.x = np.zeros(3)
    with pytest.raises(InputError, match="^UnscentedKalmanFilter: 'x' must be"):
        ukf.sigma_points()


def test_a_symmetric_covariance_is_used_as_it_is():
    # 0.5 (P + P') of a variance near the float range's top would overflow
    ukf = UnscentedKalmanFilter(1, P0=[[1.5e308]])
    points = ukf.sigma_points()
    assert points[1, 0] == pytest.approx(np.sqrt(1.5e308), rel=1e-15)


def one_state_filter():
    """x = 1, P = 4 (n = 1, default weights): points 1, 3, -1."""
    return UnscentedKalmanFilter(1, x0=[1.0], P0=[[4.0]])


@pytest.mark.parametrize("q_scale", [1.0, 2.0])
def test_predict_of_one_state_by_hand(q_scale):
    # x+ = 3 x, Q = 0.5: mean 3, covariance 9 * 4 + q_scale * 0.5
    ukf = one_state_filter()
    ukf.predict(lambda x: 3.0 * x, np.array([[0.5]]), q_scale=q_scale)
    assert ukf.x.tolist() == [3.0] and ukf.P.tolist() == [[36.0 + 0.5 * q_scale]]


def test_predict_points_adds_q_once_by_default():
    ukf = one_state_filter()
    ukf.predict_points(3.0 * ukf.sigma_points(), np.array([[0.5]]))
    assert ukf.P.tolist() == [[36.5]]


@pytest.mark.parametrize("r_scale", [1.0, 2.0])
def test_update_of_one_state_by_hand(r_scale):
    # z = x + offset (offset an extra argument of h), R = 2: S = 4 + 2 r_scale, K = 4 / S
    ukf = one_state_filter()
    info = ukf.update(np.array([4.5]), lambda x, offset: x + offset, np.array([[2.0]]), 0.5,
                      r_scale=r_scale)
    S = 4.0 + 2.0 * r_scale
    assert info["z_pred"].tolist() == [1.5] and info["innovation"].tolist() == [3.0]
    assert info["S"][0, 0] == pytest.approx(S, rel=1e-15)
    assert info["K"][0, 0] == pytest.approx(4.0 / S, rel=1e-15)
    assert info["nis"] == pytest.approx(9.0 / S, rel=1e-15)
    assert ukf.x[0] == pytest.approx(1.0 + 12.0 / S, rel=1e-15)
    assert ukf.P[0, 0] == pytest.approx(4.0 - 16.0 / S, rel=1e-15)


def test_correct_names_a_non_finite_measurement():
    ukf = one_state_filter()
    with pytest.raises(InputError, match="^UnscentedKalmanFilter.correct: 'z' contains NaN"):
        ukf.update(np.array([np.nan]), lambda x: x, np.eye(1))


def test_correct_refuses_a_non_finite_r():
    ukf = one_state_filter()
    with pytest.raises(InputError, match="predicted by h or 'R' contains NaN or inf"):
        ukf.update(np.array([1.0]), lambda x: x, np.array([[np.nan]]))
