"""Tests of navcore.filters.adaptive_laws and navcore.filters.robust_laws: the adaptation laws of
papers 001
and 004 (and the chi-square gate and per-observation statistic they use)."""

import copy
import math
import pickle
from math import comb

import numpy as np
import pytest
from scipy.stats import chi2

from navcore.filters.adaptive_laws import (
    compression_factor,
    divergence_test,
    fading_factor,
    fading_predict,
    guard_positive_definite,
    r_floor_from_initial,
    sage_husa_r_update,
    sage_husa_weight,
)
from navcore.filters.innovation_stats import (CHI2_THRESHOLD_PAPER_004, chi2_gate,
    chi_square_per_observation)
from navcore.filters.robust_laws import (
    ObservationHistory,
    chi_square_faults,
    igg3_weight,
    newton_forward_extrapolate,
)
from navcore.core.component import InputError, ParameterError


# ----------------------------------------------------------------------------------------
# Sage-Husa (paper 001 eq. 9)
# ----------------------------------------------------------------------------------------
def test_sage_husa_weight_values():
    assert sage_husa_weight(0, 0.99) == pytest.approx(1.0, rel=1e-14)
    assert sage_husa_weight(1, 0.99) == pytest.approx(1.0 / 1.99, rel=1e-14)
    assert sage_husa_weight(5, 0.95) == pytest.approx(0.05 / (1 - 0.95 ** 6), rel=1e-14)
    assert sage_husa_weight(10_000, 0.99) == pytest.approx(0.01, rel=1e-12)
    assert sage_husa_weight(9, 1.0) == pytest.approx(0.1, rel=1e-15)
    with pytest.raises(ParameterError, match="b"):
        sage_husa_weight(1, 1.2)
    with pytest.raises(InputError, match="k"):
        sage_husa_weight(-1, 0.99)


def test_sage_husa_recursion_is_exponentially_weighted_mean():
    """R_k = sum_i b^(k-i) S_i / sum_i b^(k-i), with R_0 as sample S_0."""
    rng = np.random.default_rng(7)
    m, n, b = 2, 4, 0.95
    R0 = np.diag([2.0, 3.0])
    R = R0.copy()
    samples = [R0]
    for k in range(1, 30):
        v = rng.standard_normal(m)
        H = rng.standard_normal((m, n))
        K = rng.standard_normal((n, m)) * 0.1
        A = rng.standard_normal((n, n))
        P = A @ A.T * 0.01
        e = (np.eye(m) - H @ K) @ v
        samples.append(np.outer(e, e) + H @ P @ H.T)
        R = sage_husa_r_update(R, v, H, K, P, k, b)
        weights = b ** np.arange(k, -1, -1.0)
        expected = np.tensordot(weights, np.array(samples), axes=1) / weights.sum()
        np.testing.assert_allclose(R, expected, rtol=1e-12, atol=1e-14)
        assert np.array_equal(R, R.T)


def _run_adaptive_kf(R_true, R0, b, steps, seed, include_hph=True):
    """Random-walk state (H = I, Q = 0.1 diag(R_true)) tracked by a KF whose R comes from
    the Sage-Husa estimator; returns the history of the estimated R."""
    rng = np.random.default_rng(seed)
    m = R_true.shape[0]
    H = np.eye(m)
    q_sigma = np.sqrt(0.1 * np.diag(R_true))
    Q = np.diag(q_sigma ** 2)
    L = np.linalg.cholesky(R_true)
    x_true = np.zeros(m)
    x = np.zeros(m)
    P = 10.0 * np.eye(m)
    R = R0.copy()
    history = np.empty((steps, m, m))
    for k in range(1, steps + 1):
        x_true = x_true + q_sigma * rng.standard_normal(m)
        z = x_true + L @ rng.standard_normal(m)
        P_pred = P + Q
        v = z - H @ x
        K = P_pred @ H.T @ np.linalg.inv(H @ P_pred @ H.T + R)
        x = x + K @ v
        P = (np.eye(m) - K @ H) @ P_pred
        if include_hph:
            R = sage_husa_r_update(R, v, H, K, P, k, b)
        else:  # eq. 9 without its H P_k H' term (for the sensitivity check)
            d = sage_husa_weight(k, b)
            e = v - H @ K @ v
            R = (1 - d) * R + d * np.outer(e, e)
        history[k - 1] = R
    return history


@pytest.mark.parametrize("R0_factor", [10.0, 0.1])
def test_sage_husa_scalar_converges_to_true_R(R0_factor):
    R_true = np.array([[4.0]])
    hist = _run_adaptive_kf(R_true, R0_factor * R_true, b=0.999, steps=5000, seed=1)
    ratio = hist[:, 0, 0] / 4.0
    # memory ~1000 updates: one-sigma scatter of the estimate ~3 %
    assert abs(ratio[-1] - 1.0) < 0.05          # measured 0.4 % (R0 x10), 0.1 % (R0 /10)
    assert abs(ratio[-3000:].mean() - 1.0) < 0.03
    assert np.all(np.abs(ratio[1500:] - 1.0) < 0.15)  # measured max 3.7 % / 8.2 %


def test_sage_husa_short_memory_b099_unbiased_on_average():
    R_true = np.array([[4.0]])
    hist = _run_adaptive_kf(R_true, 10 * R_true, b=0.99, steps=5000, seed=1)
    ratio = hist[:, 0, 0] / 4.0
    assert abs(ratio[-3000:].mean() - 1.0) < 0.03   # measured 0.9 %
    assert 0.05 < ratio[-3000:].std() < 0.15        # ~ sqrt(2 (1-b)/(1+b)) = 0.10


def test_sage_husa_needs_the_hph_term():
    """Without H P_k H' the estimate is biased low by far more than its scatter."""
    R_true = np.array([[4.0]])
    hist = _run_adaptive_kf(R_true, 10 * R_true, b=0.999, steps=5000, seed=1, include_hph=False)
    assert hist[-1, 0, 0] / 4.0 < 0.75              # measured 0.62


def test_sage_husa_3d_correlated_converges():
    A = np.array([[1.0, 0.3, 0.0], [0.3, 2.0, 0.5], [0.0, 0.5, 0.5]])
    R_true = A @ A.T
    hist = _run_adaptive_kf(R_true, 10 * np.diag(np.diag(R_true)), b=0.999, steps=5000, seed=1)
    R_end = hist[-1]
    rel_frob = np.linalg.norm(R_end - R_true) / np.linalg.norm(R_true)
    assert rel_frob < 0.05                          # measured 2.1 %
    np.testing.assert_allclose(np.diag(R_end), np.diag(R_true), rtol=0.05)  # measured <= 1.3 %
    assert np.all(np.linalg.eigvalsh(R_end) > 0)


def test_sage_husa_shape_and_value_errors():
    with pytest.raises(InputError, match="innovation"):
        sage_husa_r_update(np.eye(2), [np.nan, 0.0], np.eye(2), np.eye(2), np.eye(2), 1, 0.99)
    with pytest.raises(InputError, match="K"):
        sage_husa_r_update(np.eye(2), [1.0, 0.0], np.eye(2), np.eye(3), np.eye(2), 1, 0.99)
    with pytest.raises(InputError, match="R_prev"):
        sage_husa_r_update(np.eye(3), [1.0, 0.0], np.eye(2), np.eye(2), np.eye(2), 1, 0.99)


# ----------------------------------------------------------------------------------------
# positive-definiteness guard
# ----------------------------------------------------------------------------------------
def test_guard_floors_eigenvalues_scalar_floor():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((4, 4))
    R = A + A.T                                     # indefinite
    assert np.linalg.eigvalsh(R)[0] < 0
    floor = 0.2
    R_g = guard_positive_definite(R, floor)
    assert np.array_equal(R_g, R_g.T)
    assert np.linalg.eigvalsh(R_g)[0] >= floor * (1 - 1e-12)
    # eigenvalues above the floor are kept
    w, w_g = np.linalg.eigvalsh(R), np.linalg.eigvalsh(R_g)
    np.testing.assert_allclose(w_g[w > floor], w[w > floor], rtol=1e-12)


def test_guard_per_axis_floor_and_identity_on_healthy_R():
    R_min = np.array([1e-2, 4.0, 1e-10])            # mixed units: m^2, (m/s)^2, rad^2
    R_bad = np.array([[0.5, 0.9, 0.0], [0.9, 1.0, 0.0], [0.0, 0.0, 0.0]])
    R_g = guard_positive_definite(R_bad, R_min)
    assert np.linalg.eigvalsh(R_g - np.diag(R_min))[0] >= -1e-12 * np.abs(R_g).max()
    assert np.all(np.diag(R_g) >= R_min * (1 - 1e-12))
    assert np.linalg.eigvalsh(R_g)[0] >= R_min.min() * (1 - 1e-9)
    R_ok = np.diag([1.0, 9.0, 1e-8]) + 0.1 * np.array([[0, 1, 0], [1, 0, 0], [0, 0, 0]])
    np.testing.assert_allclose(guard_positive_definite(R_ok, R_min), R_ok, rtol=1e-14)
    R_asym = R_ok + np.array([[0, 1e-3, 0], [0, 0, 0], [0, 0, 0]])
    np.testing.assert_allclose(guard_positive_definite(R_asym, R_min), 0.5 * (R_asym + R_asym.T))


def test_guard_repairs_sage_husa_first_update_collapse():
    """k = 0 (d = 1) with a confident filter leaves a rank-one R; the guard restores it."""
    R0 = np.diag([25.0, 0.09])
    v = np.array([3.0, 0.2])
    R1 = sage_husa_r_update(R0, v, np.eye(2), np.zeros((2, 2)), np.zeros((2, 2)), 0, 0.99)
    assert np.linalg.eigvalsh(R1)[0] < 1e-12 * np.abs(R1).max()
    floor = r_floor_from_initial(R0)
    np.testing.assert_allclose(floor, [0.25, 0.0009])
    R1g = sage_husa_r_update(R0, v, np.eye(2), np.zeros((2, 2)), np.zeros((2, 2)), 0, 0.99,
                             R_min=floor)
    assert np.linalg.eigvalsh(R1g - np.diag(floor))[0] >= -1e-12


def test_guard_rejects_bad_floor():
    with pytest.raises(ParameterError, match="R_min"):
        guard_positive_definite(np.eye(2), [1.0, 0.0])
    with pytest.raises(ParameterError, match="R_min"):
        guard_positive_definite(np.eye(2), [1.0, 1.0, 1.0])


# ----------------------------------------------------------------------------------------
# fading-memory filter (paper 001 eqs. 10-12)
# ----------------------------------------------------------------------------------------
def _fading_setup():
    Phi = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.9]])
    P = np.diag([2.0, 0.5, 1.0])
    GQG = np.diag([0.01, 0.02, 0.03])
    H = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    R = np.diag([1.0, 0.5])
    HPH0 = H @ Phi @ P @ Phi.T @ H.T
    HQH = H @ GQG @ H.T
    return Phi, P, GQG, H, R, HPH0, HQH


def test_divergence_test_boundary():
    _, _, _, _, R, HPH0, HQH = _fading_setup()
    trace_E = np.trace(HPH0 + HQH + R)              # 2.5 + 0.81 + 0.04 + 1.5 = 4.85
    v_edge = np.array([math.sqrt(trace_E), 0.0])
    assert divergence_test(v_edge * (1 - 1e-9), HPH0 + HQH, R, 1.0)
    assert not divergence_test(v_edge * (1 + 1e-9), HPH0 + HQH, R, 1.0)
    assert divergence_test(v_edge * 1.4, HPH0 + HQH, R, 2.0)
    with pytest.raises(ParameterError, match="gamma"):
        divergence_test(v_edge, HPH0, R, 0.0)


def test_fading_factor_is_one_while_test_passes():
    _, _, _, _, R, HPH0, HQH = _fading_setup()
    rng = np.random.default_rng(11)
    trace_E = np.trace(HPH0 + HQH + R)
    for _ in range(200):
        v = rng.standard_normal(2)
        v *= rng.uniform(0, 1) * math.sqrt(trace_E) / np.linalg.norm(v)
        assert divergence_test(v, HPH0 + HQH, R, 1.0)
        assert fading_factor(v, HQH, R, HPH0, gamma=1.0) == 1.0
    # an innovation that fails gamma = 1 but passes gamma = 3 gives exactly 1 with gamma = 3
    v = np.array([3.0, 0.0])                        # v'v = 9 > 4.85, < 14.55
    assert fading_factor(v, HQH, R, HPH0, gamma=3.0) == 1.0


def test_fading_factor_equals_eq12_when_test_fails():
    Phi, P, GQG, H, R, HPH0, HQH = _fading_setup()
    v = np.array([3.0, -2.0])                       # v'v = 13 > 4.85
    lam = fading_factor(v, HQH, R, HPH0, gamma=1.0)
    # eq. 12 by hand: (13 - (0.01 + 0.03 + 1.5)) / (tr(H Phi P Phi' H') = 2.5 + 0.81)
    expected = (13.0 - 1.54) / 3.31
    assert lam == pytest.approx(expected, rel=1e-14)
    assert lam > 1.0
    # the faded prediction (eq. 10) makes eq. 11 with gamma = 1 hold with equality
    P_pred = fading_predict(Phi @ P @ Phi.T, GQG, lam)
    assert np.trace(H @ P_pred @ H.T + R) == pytest.approx(v @ v, rel=1e-13)
    assert fading_factor(v, HQH, R, HPH0, max_factor=2.0) == 2.0


def test_fading_factor_clipped_to_one_for_gamma_below_one():
    _, _, _, _, R, HPH0, HQH = _fading_setup()
    v = np.array([2.0, 0.0])                        # v'v = 4 < 4.85 but > 0.5 * 4.85
    assert not divergence_test(v, HPH0 + HQH, R, 0.5)
    assert (4.0 - 1.54) / 3.31 < 1.0                # eq. 12 alone would shrink P
    assert fading_factor(v, HQH, R, HPH0, gamma=0.5) == 1.0


def test_fading_factor_zero_denominator_raises():
    with pytest.raises(InputError, match="HPpredH_no_Q"):
        fading_factor([10.0], [[0.0]], [[1.0]], [[0.0]])


def test_fading_predict_standard_and_faded():
    Phi, P, GQG, _, _, _, _ = _fading_setup()
    p_prop = Phi @ P @ Phi.T
    np.testing.assert_allclose(fading_predict(p_prop, GQG, 1.0), Phi @ P @ Phi.T + GQG,
                               rtol=1e-15)
    # lambda = 1 is the standard prediction (eq. 6) exactly, as the filter relies on
    assert np.array_equal(fading_predict(p_prop, GQG, 1.0), p_prop + GQG)
    P2 = fading_predict(p_prop, GQG, 2.5)
    np.testing.assert_allclose(P2, Phi @ (2.5 * P) @ Phi.T + GQG, rtol=1e-15)
    np.testing.assert_allclose(P2, P2.T, rtol=1e-15)
    with pytest.raises(InputError, match="lam"):
        fading_predict(p_prop, GQG, 0.0)
    with pytest.raises(InputError, match="GQG"):
        fading_predict(p_prop, GQG[:1, :1], 2.0)


# ----------------------------------------------------------------------------------------
# outlier compression (paper 001 eqs. 13-14)
# ----------------------------------------------------------------------------------------
def _compression_setup():
    P_pred = np.array([[4.0, 0.5, 0.2, 0.0], [0.5, 3.0, 0.0, 0.1],
                       [0.2, 0.0, 1.0, 0.0], [0.0, 0.1, 0.0, 0.5]])
    H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    R = np.diag([1.0, 2.0, 0.25])
    G = H @ P_pred @ H.T + R
    K = P_pred @ H.T @ np.linalg.inv(G)
    return G, K


def test_compression_is_one_at_and_below_gate():
    G, K = _compression_setup()
    C = chi2.ppf(0.95, 3)                           # 7.8147
    L = np.linalg.cholesky(G)
    direction = np.array([0.3, -0.8, 0.52])
    direction /= np.linalg.norm(direction)
    for tau_target in (0.0, 1.0, 5.0, C * (1 - 1e-12)):
        v = L @ direction * math.sqrt(tau_target)
        Y, tau, gate = compression_factor(v, G, K, alpha=0.05)
        assert Y == 1.0
        assert tau == pytest.approx(tau_target, rel=1e-12, abs=1e-15)
        assert gate == pytest.approx(C, rel=1e-12)


def test_compression_follows_eq14_above_gate():
    G, K = _compression_setup()
    v = np.array([12.0, -9.0, 4.0])
    Y, tau, gate = compression_factor(v, G, K, alpha=0.05)
    # eq. 14 by hand with the paper's threshold D = sqrt(lambda C)
    tau_hand = v @ np.linalg.solve(G, v)
    lam = np.linalg.eigvalsh(K @ G @ K.T).max()
    C = chi2.ppf(1 - 0.05, 3)
    D = math.sqrt(lam * C)
    assert tau_hand > D ** 2 / lam
    assert tau == pytest.approx(tau_hand, rel=1e-12)
    assert Y == pytest.approx(D / math.sqrt(tau_hand * lam), rel=1e-12)
    assert Y == pytest.approx(math.sqrt(C / tau_hand), rel=1e-12)   # lambda cancels
    assert 0 < Y < 1
    # the compressed innovation lies on the gate
    vc = Y * v
    assert vc @ np.linalg.solve(G, vc) == pytest.approx(C, rel=1e-12)
    # alpha = 0.02 gate is wider
    assert compression_factor(v, G, K, alpha=0.02)[2] == pytest.approx(chi2.ppf(0.98, 3))


def test_compression_with_constant_threshold_D():
    G, K = _compression_setup()
    lam = np.linalg.eigvalsh(K @ G @ K.T).max()
    v = np.array([12.0, -9.0, 4.0])
    D = 2.0
    Y, tau, gate = compression_factor(v, G, K, D=D)
    assert gate == pytest.approx(D ** 2 / lam, rel=1e-12)
    assert Y == pytest.approx(D / math.sqrt(tau * lam), rel=1e-12)
    # D bounds the state correction of the compressed innovation
    assert np.linalg.norm(K @ (Y * v)) <= D * (1 + 1e-12)
    v_small = v * 0.01
    assert compression_factor(v_small, G, K, D=D)[0] == 1.0
    # zero gain: nothing to compress
    assert compression_factor(v, G, np.zeros_like(K), D=D)[0] == 1.0


def test_compression_rejects_non_pd_G():
    with pytest.raises(InputError, match="G"):
        compression_factor([1.0, 1.0], [[1.0, 2.0], [2.0, 1.0]], np.eye(2))


# ----------------------------------------------------------------------------------------
# per-observation chi-square test (paper 004)
# ----------------------------------------------------------------------------------------
def test_chi2_threshold_matches_paper_004():
    assert chi2_gate(0.01, 1) == pytest.approx(6.6349, abs=1e-4)
    assert abs(chi2_gate(0.01, 1) - CHI2_THRESHOLD_PAPER_004) < 2e-4
    assert chi2_gate(0.025, 1) == pytest.approx(5.0239, abs=1e-4)
    assert chi2_gate(0.05, 3) == pytest.approx(7.8147, abs=1e-4)
    with pytest.raises(ParameterError, match="alpha"):
        chi2_gate(1.5, 1)
    with pytest.raises(ParameterError, match="dof"):
        chi2_gate(0.01, 0)


def test_per_observation_false_alarm_rate_is_alpha():
    rng = np.random.default_rng(2024)
    A = np.array([[2.0, 0.0, 0.0], [1.0, 0.5, 0.0], [0.3, -0.2, 0.1]])
    S = A @ A.T                                     # correlated innovation covariance
    v = rng.standard_normal((100_000, 3)) @ A.T
    r = chi_square_per_observation(v, S)
    assert r.shape == (100_000, 3)
    np.testing.assert_allclose(r.mean(axis=0), 1.0, atol=0.02)
    rate = (r > CHI2_THRESHOLD_PAPER_004).mean(axis=0)
    assert np.all(np.abs(rate - 0.01) < 0.002)      # binomial sigma 0.0003
    faults = chi_square_faults(v[:5], S)
    np.testing.assert_array_equal(faults, r[:5] > 6.635)


def test_per_observation_statistic_single_epoch():
    S = np.array([[4.0, 1.0], [1.0, 0.25]])
    r = chi_square_per_observation([4.0, 1.5], S)
    np.testing.assert_allclose(r, [4.0, 9.0])
    np.testing.assert_array_equal(chi_square_faults([4.0, 1.5], S), [False, True])
    with pytest.raises(InputError, match="S"):
        chi_square_per_observation([1.0, 1.0], np.diag([1.0, 0.0]))


# ----------------------------------------------------------------------------------------
# Newton extrapolation (paper 004)
# ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("degree", [0, 1, 2, 3, 4])
def test_newton_order4_exact_for_polynomials_up_to_degree4(degree):
    rng = np.random.default_rng(degree)
    coeffs = rng.uniform(-2, 2, degree + 1)
    h, t0 = 0.7, 3.1
    t = t0 + h * np.arange(8)                       # 7 past samples, predict the 8th
    f = np.polyval(coeffs, t)
    predicted = newton_forward_extrapolate(f[:7], order=4)
    assert predicted == pytest.approx(f[7], rel=1e-9, abs=1e-9 * np.abs(f).max())


def test_newton_order4_not_exact_for_degree5_error_is_fifth_difference():
    a5, h = 0.5, 0.7
    t = h * np.arange(6)
    f = a5 * t ** 5 + 2.0 * t ** 2
    predicted = newton_forward_extrapolate(f[:5], order=4)
    error = f[5] - predicted
    assert error == pytest.approx(120 * a5 * h ** 5, rel=1e-9)   # nabla^5 f = 5! a5 h^5
    assert abs(error) > 1e-3 * abs(f[5])


def test_newton_closed_form_weights_and_vector_samples():
    rng = np.random.default_rng(5)
    samples = rng.standard_normal((9, 3))
    for p in range(5):
        weights = np.array([(-1) ** j * comb(p + 1, j + 1) for j in range(p + 1)])
        expected = weights @ samples[::-1][: p + 1]
        np.testing.assert_allclose(newton_forward_extrapolate(samples, order=p), expected,
                                   rtol=1e-12, atol=1e-12)
    # noise amplification of the order-4 weights: sqrt(251) = 15.84
    w4 = np.array([5, -10, 10, -5, 1])
    assert math.sqrt(w4 @ w4) == pytest.approx(math.sqrt(comb(10, 5) - 1))


def test_newton_short_histories():
    assert newton_forward_extrapolate([2.5]) == 2.5
    assert newton_forward_extrapolate([1.0, 3.0]) == pytest.approx(5.0)          # linear
    assert newton_forward_extrapolate([1.0, 4.0, 9.0]) == pytest.approx(16.0)    # quadratic
    np.testing.assert_allclose(newton_forward_extrapolate([[1.0, 2.0]]), [1.0, 2.0])
    with pytest.raises(ValueError, match="samples"):
        newton_forward_extrapolate([])
    with pytest.raises(ParameterError, match="order"):
        newton_forward_extrapolate([1.0, 2.0], order=-1)


def test_observation_history_window_gap_correction_and_copy():
    hist = ObservationHistory(maxlen=5)
    with pytest.raises(InputError):
        hist.predict_next()
    t = np.arange(8.0)
    for k in range(8):
        hist.append([t[k] ** 2, 3.0 - t[k]], epoch=k)
    assert len(hist) == 5
    np.testing.assert_allclose(hist.samples()[:, 0], t[3:] ** 2)
    np.testing.assert_allclose(hist.predict_next(), [64.0, -5.0], rtol=1e-12)

    snapshot = copy.deepcopy(hist)
    restored = pickle.loads(pickle.dumps(hist))
    hist.apply_correction([1.0, -1.0])              # closed-loop INS reset shifts z
    np.testing.assert_allclose(hist.predict_next(), [63.0, -4.0], rtol=1e-12)
    np.testing.assert_allclose(snapshot.predict_next(), [64.0, -5.0], rtol=1e-12)
    np.testing.assert_allclose(restored.samples(), snapshot.samples())
    assert snapshot.last_epoch == 7

    hist.append([0.0, 0.0], epoch=10)               # outage: spacing lost, start over
    assert len(hist) == 1 and hist.last_epoch == 10
    hist.append([1.0, 1.0])                         # default epoch = last + 1
    assert hist.last_epoch == 11
    with pytest.raises(InputError, match="epoch"):
        hist.append([2.0, 2.0], epoch=11)
    with pytest.raises(InputError, match="z"):
        hist.append([1.0, 2.0, 3.0])
    with pytest.raises(ParameterError, match="maxlen"):
        ObservationHistory(maxlen=0)


# ----------------------------------------------------------------------------------------
# IGG-III
# ----------------------------------------------------------------------------------------
def test_igg3_weight_regions():
    k0, k1 = 1.5, 3.0
    assert igg3_weight(0.0) == 1.0
    assert igg3_weight(-1.5) == 1.0
    assert igg3_weight(2.0, k0, k1) == pytest.approx((1.5 / 2.0) * (1.0 / 1.5) ** 2)
    assert igg3_weight(-2.0, k0, k1) == igg3_weight(2.0, k0, k1)
    assert igg3_weight(3.0, k0, k1) == 0.0
    assert igg3_weight(10.0, k0, k1) == 0.0
    u = np.linspace(0, 5, 501)
    w = igg3_weight(u, 1.0, 4.5)
    assert w.shape == u.shape
    assert np.all(np.diff(w) <= 1e-15) and w[0] == 1.0 and w[-1] == 0.0
    assert igg3_weight(1.0 + 1e-9, 1.0, 4.5) == pytest.approx(1.0, abs=1e-8)     # continuous
    with pytest.raises(ParameterError, match="k0"):
        igg3_weight(1.0, 3.0, 1.5)
    with pytest.raises(InputError, match="standardized_residual"):
        igg3_weight(np.nan)
