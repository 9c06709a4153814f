"""Component verification of the unscented Kalman filter core (paper 000 eqs. 11-23)."""
import copy

import numpy as np
import pytest
from linear_kalman import LinearKalmanFilter

from navcore.core.component import InputError, ParameterError
from navcore.filters.unscented import (
    UnscentedKalmanFilter,
    matrix_sqrt,
    sigma_points,
    sigma_weights,
    unscented_transform,
)

# (alpha, beta, kappa): the default, and a set with a negative centre weight (lambda < 0)
PARAMETER_SETS = [(1.0, 2.0, 0.0), (0.5, 2.0, -1.0)]


def random_spd(rng, n, scale=1.0):
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + n * np.eye(n))


def linear_model(seed):
    """4-state constant-velocity model (2-D) with random perturbations of F (rescaled to spectral
    radius <= 0.99), random H, Q, R."""
    rng = np.random.default_rng(seed)
    dt = 0.5
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    F = F + 0.05 * rng.normal(size=(4, 4))
    F *= 0.99 / max(0.99, np.abs(np.linalg.eigvals(F)).max())   # stable: long runs stay bounded
    H = np.hstack([np.eye(2), np.zeros((2, 2))]) + 0.1 * rng.normal(size=(2, 4))
    Q = random_spd(rng, 4, 0.01)
    R = random_spd(rng, 2, 0.5)
    return rng, F, H, Q, R


@pytest.mark.parametrize("alpha,beta,kappa", PARAMETER_SETS + [(1e-3, 2.0, 0.0)])
def test_sigma_weights_sums_and_lambda(alpha, beta, kappa):
    n = 15
    Wm, Wc, lam = sigma_weights(n, alpha, beta, kappa)
    assert lam == pytest.approx(alpha ** 2 * (n + kappa) - n, rel=1e-14)
    assert Wm.shape == Wc.shape == (2 * n + 1,)
    assert Wm.sum() == pytest.approx(1.0, abs=1e-9)
    assert Wc.sum() == pytest.approx(2.0 + beta - alpha ** 2, abs=1e-9)
    assert np.all(Wm[1:] == 0.5 / (n + lam)) and np.all(Wc[1:] == Wm[1:])


def test_default_weights_are_positive_for_15_states():
    Wm, Wc, lam = sigma_weights(15)          # alpha=1, beta=2, kappa=0
    assert lam == 0.0 and Wm[0] == 0.0 and Wc[0] == 2.0
    assert np.all(Wc > 0.0) and np.allclose(Wm[1:], 1.0 / 30.0)


@pytest.mark.parametrize("kwargs", [dict(n=0), dict(n=3, alpha=0.0), dict(n=3, kappa=-3.0),
                                    dict(n=3, beta=float("nan"))])
def test_sigma_weights_reject_bad_parameters(kwargs):
    with pytest.raises(ParameterError):
        sigma_weights(**kwargs)


@pytest.mark.parametrize("alpha,beta,kappa", PARAMETER_SETS)
def test_sigma_points_reproduce_mean_and_covariance(alpha, beta, kappa):
    rng = np.random.default_rng(3)
    n = 15
    x = rng.normal(size=n)
    P = random_spd(rng, n, 1e-3)
    Wm, Wc, lam = sigma_weights(n, alpha, beta, kappa)
    X = sigma_points(x, P, lam)
    assert X.shape == (2 * n + 1, n)
    mean, cov = unscented_transform(X, Wm, Wc)
    assert np.allclose(mean, x, rtol=0, atol=1e-13)
    # centre point contributes nothing to the spread, so beta/alpha do not bias the covariance
    assert np.allclose(cov, P, rtol=1e-11, atol=1e-17)


def test_matrix_sqrt_fallback_for_singular_and_slightly_indefinite():
    rng = np.random.default_rng(4)
    B = rng.normal(size=(6, 3))
    P_singular = B @ B.T                        # rank 3: Cholesky fails
    L, used_fallback = matrix_sqrt(P_singular)
    assert used_fallback
    assert np.allclose(L @ L.T, P_singular, atol=1e-12)
    V = np.linalg.qr(rng.normal(size=(4, 4)))[0]
    P_indefinite = (
        V @ np.diag([1.0, 0.5, 1e-3, -1e-15]) @ V.T
    )  # round-off-sized negative eigenvalue
    L, used_fallback = matrix_sqrt(P_indefinite)
    assert used_fallback and np.isfinite(L).all()
    assert np.allclose(L @ L.T, V @ np.diag([1.0, 0.5, 1e-3, 0.0]) @ V.T, atol=1e-12)
    _, used_fallback = matrix_sqrt(np.eye(3))
    assert not used_fallback


def test_unscented_transform_mean_exact_for_quadratic():
    # E[x^T A x] = tr(A P) + mu^T A mu for any distribution; the UT mean is exact up to 2nd order
    rng = np.random.default_rng(5)
    n = 5
    mu = rng.normal(size=n)
    P = random_spd(rng, n, 0.1)
    A = random_spd(rng, n)
    for alpha, beta, kappa in PARAMETER_SETS:
        Wm, Wc, lam = sigma_weights(n, alpha, beta, kappa)
        Y = np.array([[x @ A @ x] for x in sigma_points(mu, P, lam)])
        mean, _ = unscented_transform(Y, Wm, Wc)
        assert mean[0] == pytest.approx(np.trace(A @ P) + mu @ A @ mu, rel=1e-12)


# alpha = 1e-3 (weights ~1e6 of both signs) still agrees, to ~3e-10 instead of ~1e-15
@pytest.mark.parametrize("alpha,beta,kappa", PARAMETER_SETS + [(1e-3, 2.0, 0.0)])
def test_ukf_matches_linear_kf(alpha, beta, kappa):
    rng, F, H, Q, R = linear_model(seed=11)
    x0 = np.array([1.0, -2.0, 0.3, 0.1])
    P0 = np.diag([4.0, 4.0, 1.0, 1.0])
    kf = LinearKalmanFilter(x0, P0)
    ukf = UnscentedKalmanFilter(4, alpha, beta, kappa, x0=x0, P0=P0)
    truth = x0.copy()
    worst_x = worst_P = 0.0
    for k in range(50):
        truth = F @ truth + rng.multivariate_normal(np.zeros(4), Q)
        z = H @ truth + rng.multivariate_normal(np.zeros(2), R)
        kf.predict(F, Q)
        ukf.predict(lambda x: F @ x, Q)
        v, S, nis = kf.update(z, H, R)
        info = ukf.update(z, lambda x: H @ x, R)
        assert np.allclose(info["innovation"], v, rtol=0, atol=1e-8 * np.abs(v).max())
        assert np.allclose(info["S"], S, rtol=1e-8)
        assert info["nis"] == pytest.approx(nis, rel=1e-8)
        worst_x = max(worst_x, np.abs(ukf.x - kf.x).max() / np.abs(kf.x).max())
        worst_P = max(worst_P, np.abs(ukf.P - kf.P).max() / np.abs(kf.P).max())
        assert np.array_equal(ukf.P, ukf.P.T)
    assert worst_x < 1e-8 and worst_P < 1e-8


def test_vectorized_and_pointwise_models_agree():
    rng, F, H, Q, R = linear_model(seed=12)
    a = UnscentedKalmanFilter(4, x0=np.ones(4), P0=np.eye(4))
    b = copy.deepcopy(a)
    f = lambda x, dt: F @ x + dt * np.sin(x)           # noqa: E731 - nonlinear, extra argument
    f_vec = lambda X, dt: X @ F.T + dt * np.sin(X)     # noqa: E731
    h = lambda x: H @ x + 0.1 * x[:2] ** 2             # noqa: E731
    h_vec = lambda X: X @ H.T + 0.1 * X[:, :2] ** 2    # noqa: E731
    for _ in range(5):
        z = rng.normal(size=2)
        a.predict(f, Q, 0.1)
        b.predict(f_vec, Q, 0.1, vectorized=True)
        ia = a.update(z, h, R)
        ib = b.update(z, h_vec, R, vectorized=True)
        assert ia["nis"] == pytest.approx(ib["nis"], rel=1e-12)
    assert np.allclose(a.x, b.x, rtol=1e-12) and np.allclose(a.P, b.P, rtol=1e-12)


def test_scale_arguments_equal_scaled_matrices_and_split_update():
    rng, F, H, Q, R = linear_model(seed=13)
    a = UnscentedKalmanFilter(4, x0=np.ones(4), P0=np.eye(4))
    b = copy.deepcopy(a)
    c = copy.deepcopy(a)
    z = rng.normal(size=2)
    a.predict(lambda x: F @ x, Q, q_scale=3.0)
    b.predict(lambda x: F @ x, 3.0 * Q)
    c.predict(lambda x: F @ x, 3.0 * Q)
    ia = a.update(z, lambda x: H @ x, R, r_scale=0.5)
    ib = b.update(z, lambda x: H @ x, 0.5 * R)
    pred = c.predict_measurement(lambda x: H @ x)
    ic = c.correct(z, pred, 0.5 * R)
    for key in ("innovation", "S", "K"):
        assert np.allclose(ia[key], ib[key], rtol=1e-13) and np.allclose(
            ic[key], ib[key], rtol=1e-13
        )
    assert np.allclose(a.P, b.P, rtol=1e-13) and np.allclose(c.P, b.P, rtol=1e-13)


def test_predict_measurement_does_not_change_filter():
    ukf = UnscentedKalmanFilter(3, x0=np.array([1.0, 2.0, 3.0]), P0=np.diag([1.0, 2.0, 3.0]))
    x, P = ukf.x.copy(), ukf.P.copy()
    ukf.predict_measurement(lambda x: x[:2])
    assert np.array_equal(ukf.x, x) and np.array_equal(ukf.P, P)


def test_nis_of_consistent_model_averages_measurement_dimension():
    rng, F, H, Q, R = linear_model(seed=14)
    m, steps = 2, 2000
    x0 = np.zeros(4)
    P0 = np.eye(4)
    ukf = UnscentedKalmanFilter(4, x0=x0, P0=P0)
    truth = rng.multivariate_normal(x0, P0)
    nis = np.empty(steps)
    for k in range(steps):
        truth = F @ truth + rng.multivariate_normal(np.zeros(4), Q)
        z = H @ truth + rng.multivariate_normal(np.zeros(2), R)
        ukf.predict(lambda x: F @ x, Q)
        nis[k] = ukf.update(z, lambda x: H @ x, R)["nis"]
    # mean of chi2(m) is m, std of the mean sqrt(2m/steps) = 0.032; measured 2.031 with this seed
    assert nis.mean() == pytest.approx(m, abs=0.12)
    assert ukf.last_nis == nis[-1]
    assert np.isfinite(ukf.last_log_likelihood)


def test_log_likelihood_matches_gaussian_density():
    from scipy.stats import multivariate_normal
    rng, F, H, Q, R = linear_model(seed=15)
    ukf = UnscentedKalmanFilter(4, x0=np.zeros(4), P0=np.eye(4))
    info = ukf.update(np.array([0.7, -1.2]), lambda x: H @ x, R)
    expected = multivariate_normal(mean=np.zeros(2), cov=info["S"]).logpdf(info["innovation"])
    assert info["log_likelihood"] == pytest.approx(expected, rel=1e-12)


def test_bad_inputs_raise_clear_errors():
    ukf = UnscentedKalmanFilter(2)
    with pytest.raises(InputError, match="'z'"):
        ukf.update(np.array([np.nan, 0.0]), lambda x: x, np.eye(2))
    with pytest.raises(InputError, match="positive definite"):
        ukf.update(np.zeros(2), lambda x: x, -10.0 * np.eye(2))
    with pytest.raises(InputError, match="'Q'"):
        ukf.predict(lambda x: x, np.eye(3))
    with pytest.raises(InputError, match="'R'"):
        ukf.update(np.zeros(2), lambda x: x, np.eye(3))
    with pytest.raises(InputError, match="predicted by f"):
        ukf.predict(lambda x: x * np.nan, np.eye(2))
    with pytest.raises(ParameterError, match="'P0'"):
        UnscentedKalmanFilter(2, P0=np.eye(3))
    # the filter is unchanged after a rejected step
    assert np.array_equal(ukf.x, np.zeros(2)) and np.array_equal(ukf.P, np.eye(2))


def test_state_is_deep_copyable_and_deterministic():
    rng, F, H, Q, R = linear_model(seed=16)
    a = UnscentedKalmanFilter(4, x0=np.ones(4), P0=np.eye(4))
    a.predict(lambda x: F @ x, Q)
    snapshot = copy.deepcopy(a)
    z = rng.normal(size=2)
    a.update(z, lambda x: H @ x, R)
    snapshot.update(z, lambda x: H @ x, R)
    assert np.array_equal(a.x, snapshot.x) and np.array_equal(a.P, snapshot.P)


def test_filter_with_singular_covariance_uses_fallback_and_matches_kf():
    # a state with exactly zero variance (not excited): Cholesky fails, eigen fallback works
    rng, F, H, Q, R = linear_model(seed=17)
    Q = np.diag([1e-2, 1e-2, 1e-3, 0.0])
    F = np.diag([1.0, 1.0, 0.9, 1.0])
    F[0, 2] = 0.5
    P0 = np.diag([1.0, 1.0, 0.1, 0.0])
    x0 = np.array([0.0, 0.0, 0.0, 0.2])
    ukf = UnscentedKalmanFilter(4, x0=x0, P0=P0)
    kf = LinearKalmanFilter(x0, P0)
    for _ in range(10):
        z = rng.normal(size=2)
        ukf.predict(lambda x: F @ x, Q)
        kf.predict(F, Q)
        ukf.update(z, lambda x: H @ x, R)
        kf.update(z, H, R)
    assert ukf.sqrt_fallbacks >= 10
    assert np.allclose(ukf.x, kf.x, rtol=1e-9, atol=1e-12)
    assert np.allclose(ukf.P, kf.P, rtol=1e-9, atol=1e-12)
    assert ukf.x[3] == pytest.approx(0.2, abs=1e-12) and abs(ukf.P[3, 3]) < 1e-12


def test_caller_set_covariance_is_symmetrized_before_use():
    ukf = UnscentedKalmanFilter(2)
    ukf.P = np.array([[2.0, 0.3], [0.1, 1.0]])          # asymmetric by a caller
    X = ukf.sigma_points()
    _, cov = unscented_transform(X, ukf.Wm, ukf.Wc)
    assert np.allclose(cov, [[2.0, 0.2], [0.2, 1.0]], rtol=1e-13)
    ukf.P = np.array([[1.0, np.nan], [np.nan, 1.0]])
    with pytest.raises(InputError, match="'P'"):
        ukf.predict(lambda x: x, np.eye(2))
