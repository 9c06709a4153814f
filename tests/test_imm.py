"""Component verification of the IMM machinery (paper 000's IMM-UKF baseline, ref. [14])."""
import copy

import numpy as np
import pytest
from scipy.stats import multivariate_normal
from linear_kalman import LinearKalmanFilter as TextbookKalmanFilter

from navcore.core.component import InputError, ParameterError
from navcore.filters.imm import (ImmBank, imm_combine, imm_combine_rows, imm_mix,
                                 imm_update_probabilities, log_likelihood, mix_banks)
from navcore.filters.unscented import UnscentedKalmanFilter


class LinearKalmanFilter(TextbookKalmanFilter):
    """The textbook KF whose update returns the log-likelihood, as the bank needs."""

    def update(self, z, H, R):
        v, S, _ = super().update(z, H, R)
        return log_likelihood(v, S)


# 1-D constant-velocity target, position measured, white-acceleration process noise
DT = 1.0
F = np.array([[1.0, DT], [0.0, 1.0]])
G = np.array([[0.5 * DT ** 2], [DT]])
H = np.array([[1.0, 0.0]])
R = np.array([[1.0]])
Q_LOW, Q_HIGH = 0.01, 10.0          # acceleration variances of the two regimes, (m/s^2)^2
QS = [Q_LOW * G @ G.T, Q_HIGH * G @ G.T]
STICKY = np.array([[0.97, 0.03], [0.03, 0.97]])
REGIME = 150                        # samples per regime: low, high, low, high
SETTLE = 15                         # samples after each switch excluded from the score


def simulate_switching_target(seed, n_steps=4 * REGIME):
    rng = np.random.default_rng(seed)
    mode = (np.arange(n_steps) // REGIME) % 2
    x = np.zeros(2)
    truth, zs = [], []
    for k in range(n_steps):
        x = F @ x + G[:, 0] * rng.normal() * np.sqrt((Q_LOW, Q_HIGH)[mode[k]])
        truth.append(x.copy())
        zs.append(H @ x + rng.normal(size=1) * np.sqrt(R[0, 0]))
    return mode, np.array(truth), zs


def run_bank(bank, zs, Qs):
    mus, xs = [], []
    for z in zs:
        bank.predict(lambda flt, j: flt.predict(F, Qs[j]))
        bank.update(lambda flt, j: flt.update(z, H, R))
        assert abs(bank.mu.sum() - 1.0) < 1e-12 and np.all((bank.mu >= 0) & (bank.mu <= 1))
        mus.append(bank.mu.copy())
        xs.append(bank.x.copy())
    return np.array(mus), np.array(xs)


def test_likelihoods_match_scipy():
    rng = np.random.default_rng(31)
    A = rng.normal(size=(3, 3))
    S = A @ A.T + np.eye(3)
    v = rng.normal(size=3)
    expected = multivariate_normal(mean=np.zeros(3), cov=S).logpdf(v)
    assert log_likelihood(v, S) == pytest.approx(expected, rel=1e-12)
    with pytest.raises(InputError, match="positive definite"):
        log_likelihood(v, -S)


def test_mixing_matches_definition():
    rng = np.random.default_rng(32)
    r, n = 3, 4
    mu = np.array([0.2, 0.5, 0.3])
    Pi = np.array([[0.9, 0.05, 0.05], [0.1, 0.8, 0.1], [0.0, 0.3, 0.7]])
    xs = [rng.normal(size=n) for _ in range(r)]
    Ps = [np.eye(n) * (j + 1) + 0.1 * np.ones((n, n)) for j in range(r)]
    mixed_xs, mixed_Ps, c_bar = imm_mix(mu, Pi, xs, Ps)
    assert np.allclose(c_bar, Pi.T @ mu, rtol=1e-15)
    for j in range(r):
        w = np.array([Pi[i, j] * mu[i] / c_bar[j] for i in range(r)])
        assert w.sum() == pytest.approx(1.0, abs=1e-15)
        x0 = sum(w[i] * xs[i] for i in range(r))
        P0 = sum(w[i] * (Ps[i] + np.outer(xs[i] - x0, xs[i] - x0)) for i in range(r))
        assert np.allclose(mixed_xs[j], x0, rtol=1e-13) and np.allclose(mixed_Ps[j], P0, rtol=1e-13)
    x, P = imm_combine(mu, xs, Ps)
    assert np.allclose(x, sum(m * xi for m, xi in zip(mu, xs)), rtol=1e-14)
    assert np.all(np.linalg.eigvalsh(P) > 0)


def test_probability_update_sums_to_one_without_underflow():
    rng = np.random.default_rng(33)
    for _ in range(1000):
        r = rng.integers(2, 6)
        c_bar = rng.dirichlet(np.ones(r))
        log_lik = rng.normal(scale=1e4, size=r)          # likelihood ratios of e^(1e4)
        mu = imm_update_probabilities(c_bar, log_lik, log=True)
        assert abs(mu.sum() - 1.0) < 1e-12 and np.all((mu >= 0.0) & (mu <= 1.0))
        assert np.argmax(mu) == np.argmax(np.log(c_bar) + log_lik)
        assert mu.min() > 0.0                            # floored: no model locked out
    # linear likelihoods that underflowed to zero are handled in log space too
    mu = imm_update_probabilities(np.array([0.5, 0.5]), np.array([0.0, 1e-300]))
    assert mu[1] == pytest.approx(1.0, abs=1e-11) and mu[0] > 0.0
    # no information at all: keep the predicted probabilities
    c_bar = np.array([0.3, 0.7])
    assert np.allclose(imm_update_probabilities(c_bar, np.zeros(2)), c_bar)
    assert np.allclose(imm_update_probabilities(c_bar, np.full(2, -np.inf), log=True), c_bar)
    # equal likelihoods leave the prediction unchanged; Bayes' rule otherwise
    assert np.allclose(imm_update_probabilities(c_bar, np.array([2.0, 2.0])), c_bar, rtol=1e-15)
    assert np.allclose(imm_update_probabilities(c_bar, np.array([1.0, 3.0])),
                       np.array([0.3, 2.1]) / 2.4, rtol=1e-14)
    with pytest.raises(InputError):
        imm_update_probabilities(c_bar, np.array([np.nan, 1.0]))


def test_two_mode_switching_target_probabilities_follow_the_true_mode():
    mode, truth, zs = simulate_switching_target(seed=1)
    filters = [LinearKalmanFilter(np.zeros(2), 100.0 * np.eye(2)) for _ in range(2)]
    mus, xs = run_bank(ImmBank(filters, STICKY), zs, QS)
    p_true = mus[np.arange(len(mode)), mode]
    fractions = [(p_true[s * REGIME + SETTLE:(s + 1) * REGIME] > 0.5).mean() for s in range(4)]
    # measured with seed 1: [1.0, 0.94, 0.99, 0.94]
    assert min(fractions) >= 0.8, fractions
    # the blended estimate beats the single low-Q model (which lags in the high-Q regimes)
    single = LinearKalmanFilter(np.zeros(2), 100.0 * np.eye(2))
    single_x = []
    for z in zs:
        single.predict(F, QS[0])
        single.update(z, H, R)
        single_x.append(single.x.copy())
    rms_imm = np.sqrt(np.mean((xs[:, 0] - truth[:, 0]) ** 2))
    rms_low = np.sqrt(np.mean((np.array(single_x)[:, 0] - truth[:, 0]) ** 2))
    assert rms_imm < 0.9 * rms_low, (rms_imm, rms_low)     # measured 0.82 m vs 6.16 m


def test_identical_models_keep_stationary_probabilities_and_equal_single_kf():
    _, _, zs = simulate_switching_target(seed=2, n_steps=100)
    Pi = np.array([[0.9, 0.1], [0.3, 0.7]])
    stationary = np.array([0.75, 0.25])                  # solves pi = Pi^T pi
    assert np.allclose(Pi.T @ stationary, stationary)
    Q = 0.5 * G @ G.T
    bank = ImmBank(
        [LinearKalmanFilter(np.zeros(2), 10.0 * np.eye(2)) for _ in range(2)], Pi, stationary
    )
    single = LinearKalmanFilter(np.zeros(2), 10.0 * np.eye(2))
    for z in zs:
        bank.predict(lambda flt, j: flt.predict(F, Q))
        single.predict(F, Q)
        bank.update(lambda flt, j: flt.update(z, H, R))
        single.update(z, H, R)
        assert np.allclose(bank.mu, stationary, rtol=0, atol=1e-12)
        assert np.allclose(bank.x, single.x, rtol=1e-12, atol=1e-12)
        assert np.allclose(bank.P, single.P, rtol=1e-12, atol=1e-14)


def test_bank_of_ukfs_equals_bank_of_linear_kfs():
    _, _, zs = simulate_switching_target(seed=3, n_steps=200)
    kfs = ImmBank([LinearKalmanFilter(np.zeros(2), 100.0 * np.eye(2)) for _ in range(2)], STICKY)
    ukfs = ImmBank(
        [UnscentedKalmanFilter(2, x0=np.zeros(2), P0=100.0 * np.eye(2)) for _ in range(2)], STICKY
    )
    for z in zs:
        kfs.predict(lambda flt, j: flt.predict(F, QS[j]))
        ukfs.predict(lambda flt, j: flt.predict(lambda x: F @ x, QS[j]))
        kfs.update(lambda flt, j: flt.update(z, H, R))
        ukfs.update(lambda flt, j: flt.update(z, lambda x: H @ x, R))      # returns the info dict
        assert np.allclose(ukfs.mu, kfs.mu, rtol=0, atol=1e-9)
        assert np.allclose(ukfs.x, kfs.x, rtol=1e-8, atol=1e-9)
        assert np.allclose(ukfs.P, kfs.P, rtol=1e-8, atol=1e-12)


def test_mixing_once_per_measurement_interval_and_feedback():
    filters = [UnscentedKalmanFilter(2, x0=np.array([0.0, 1.0]), P0=np.eye(2)) for _ in range(2)]
    bank = ImmBank(filters, STICKY, mu0=np.array([0.9, 0.1]))
    bank.predict(lambda flt, j: flt.predict(lambda x: F @ x, QS[j]))
    mu_after_first = bank.mu.copy()
    assert np.allclose(mu_after_first, STICKY.T @ np.array([0.9, 0.1]))
    for _ in range(9):                                   # e.g. 10 IMU steps per GNSS fix
        bank.predict(lambda flt, j: flt.predict(lambda x: F @ x, QS[j] / 10))
    assert np.array_equal(bank.mu, mu_after_first)       # no re-mixing between measurements
    bank.update(lambda flt, j: flt.update(np.array([5.0]), lambda x: x[:1], R))
    assert bank.needs_mixing
    snapshot = copy.deepcopy(bank)
    x_combined = bank.x.copy()
    bank.subtract_from_states(x_combined)
    assert np.allclose(bank.x, 0.0, atol=1e-12)
    assert np.allclose(
        imm_combine(bank.mu, [f.x for f in bank.filters], [f.P for f in bank.filters])[0],
        0.0,
        atol=1e-12,
    )
    assert np.allclose(snapshot.x, x_combined)


def test_bank_rejects_bad_parameters():
    filters = [LinearKalmanFilter(np.zeros(2), np.eye(2)) for _ in range(2)]
    with pytest.raises(ParameterError, match="rows must sum to 1"):
        ImmBank(filters, np.array([[0.9, 0.2], [0.1, 0.9]]))
    with pytest.raises(ParameterError, match="2x2"):
        ImmBank(filters, np.eye(3))
    with pytest.raises(ParameterError, match="mu0"):
        ImmBank(filters, STICKY, mu0=np.array([0.5, 0.6]))


def test_combination_against_the_textbook_by_hand():
    """Bar-Shalom, Li & Kirubarajan (2001) eqs. 11.6.6-20/21: x = sum mu_j x_j and
    P = sum mu_j (P_j + (x_j - x)(x_j - x)^T), worked by hand for two models:
    x = 0.3 [1, 2] + 0.7 [3, -1] = [2.4, -0.1]; the mean of the P_j is [[1.3, 0.15], [0.15, 2.4]];
    the spread of the means 0.3 d1 d1^T + 0.7 d2 d2^T with d1 = [-1.4, 2.1], d2 = [0.6, -0.9]
    is [[0.84, -1.26], [-1.26, 1.89]]."""
    x, P = imm_combine(np.array([0.3, 0.7]), [np.array([1.0, 2.0]), np.array([3.0, -1.0])],
                       [np.array([[2.0, 0.5], [0.5, 1.0]]), np.array([[1.0, 0.0], [0.0, 3.0]])])
    np.testing.assert_allclose(x, [2.4, -0.1], atol=1e-15)
    np.testing.assert_allclose(P, [[2.14, -1.11], [-1.11, 4.29]], atol=1e-14)


def test_the_bank_reports_the_spread_of_its_models():
    """After an update in which the two models disagree, the bank's covariance exceeds the
    probability-weighted mean of the models' covariances by exactly the spread of their means
    (a combined P without that term would be overconfident)."""
    bank = ImmBank([LinearKalmanFilter(np.zeros(2), 10.0 * np.eye(2)) for _ in range(2)],
                   STICKY, np.array([0.5, 0.5]))
    for z in (np.array([0.0]), np.array([5.0]), np.array([12.0])):
        bank.predict(lambda flt, j: flt.predict(F, QS[j]))
        bank.update(lambda flt, j: flt.update(z, H, R))
    xs = [f.x for f in bank.filters]
    assert np.abs(xs[0] - xs[1]).max() > 0.5            # the models really disagree
    mean_P = sum(m * f.P for m, f in zip(bank.mu, bank.filters))
    spread = sum(m * np.outer(x - bank.x, x - bank.x) for m, x in zip(bank.mu, xs))
    np.testing.assert_allclose(bank.P - mean_P, spread, rtol=1e-10, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(spread) >= -1e-12) and np.trace(spread) > 1e-3


def _random_banks(rng, count, r, n=15):
    banks = []
    for _ in range(count):
        filters = []
        for _ in range(r):
            A = rng.normal(0, 1, (n, n)) * np.logspace(-4, 0, n)
            filters.append(UnscentedKalmanFilter(n, x0=rng.normal(0, 1e-2, n),
                                                 P0=0.5 * (A @ A.T + (A @ A.T).T)))
        Pi = rng.dirichlet(np.ones(r), r)
        bank = ImmBank(filters, Pi, mu0=rng.dirichlet(np.ones(r)))
        banks.append(bank)
    return banks


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


@pytest.mark.parametrize("r", [2, 3])
def test_banks_mix_and_combine_together_as_each_bank_alone(r):
    """mix_banks and imm_combine_rows of several banks against each bank's own mix and
    imm_combine, bit for bit; a bank whose probabilities are not a distribution keeps its
    state and gets its own error, the others mix."""
    banks = _random_banks(np.random.default_rng(40 + r), 5, r)
    alone = copy.deepcopy(banks)
    banks[2].mu = banks[2].mu * 2.0
    errors = mix_banks(banks)
    with pytest.raises(InputError) as own:
        copy.deepcopy(banks[2]).mix()
    assert str(errors[2]) == str(own.value) and banks[2].needs_mixing
    assert all(e is None for k, e in enumerate(errors) if k != 2)
    for k, (bank, own_bank) in enumerate(zip(banks, alone)):
        if k == 2:
            continue
        own_bank.mix()
        assert np.array_equal(_bits(bank.mu), _bits(own_bank.mu)) and not bank.needs_mixing
        for flt, own_flt in zip(bank.filters, own_bank.filters):
            assert np.array_equal(_bits(flt.x), _bits(own_flt.x))
            assert np.array_equal(_bits(flt.P), _bits(own_flt.P))
    mixed = [bank for k, bank in enumerate(banks) if k != 2]
    x, P = imm_combine_rows(np.stack([bank.mu for bank in mixed]),
                            np.stack([[f.x for f in bank.filters] for bank in mixed]),
                            np.stack([[f.P for f in bank.filters] for bank in mixed]))
    for k, bank in enumerate(mixed):
        own_x, own_P = imm_combine(bank.mu, [f.x for f in bank.filters],
                                   [f.P for f in bank.filters])
        assert np.array_equal(_bits(x[k]), _bits(own_x))
        assert np.array_equal(_bits(P[k]), _bits(own_P))


@pytest.mark.parametrize("r", [2, 3])
def test_banks_that_all_pass_their_checks_mix_as_each_bank_alone(r):
    """mix_banks of banks whose every probability vector is a distribution (the inputs of
    all banks stacked and checked at once) against each bank's own mix, bit for bit."""
    banks = _random_banks(np.random.default_rng(50 + r), 6, r)
    alone = copy.deepcopy(banks)
    assert mix_banks(banks) == [None] * 6
    for bank, own_bank in zip(banks, alone):
        own_bank.mix()
        assert np.array_equal(_bits(bank.mu), _bits(own_bank.mu)) and not bank.needs_mixing
        for flt, own_flt in zip(bank.filters, own_bank.filters):
            assert np.array_equal(_bits(flt.x), _bits(own_flt.x))
            assert np.array_equal(_bits(flt.P), _bits(own_flt.P))
