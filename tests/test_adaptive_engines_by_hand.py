"""navcore.filters.adaptive_filters: one or a few updates of each engine against its paper's
equations written out by hand, on the textbook Joseph-form filter of tests/linear_kalman.py
(H = [I 0], the components kept).

* Sage-Husa + fading (paper 001 eqs. 9-12): eq. 11's test, eq. 12's factor on the propagated
  part only, eq. 9 with d_k = (1 - b) / (1 - b^(k+1)), k counting updates from 1;
* IAKF (eqs. 13-14): tau = v' G^-1 v on the unfaded prediction, Y = sqrt(C / tau) above the
  chi2(6) quantile C (printed table: 15.033 at alpha = 0.02), then the above with Y v;
* Newton robust KF (paper 004): r_i = v_i^2 / S_ii against 6.635, the replacement
  3 f_N - 3 f_{N-1} + f_{N-2} from three stored (feedback-corrected) samples with 19 R_ii;
* IGG-III: u_i = v_i / sqrt(S_ii), w = (k0 / u) ((k1 - u) / (k1 - k0))^2, R_ii / w_i;
* INS only: the innovation and nothing else.
"""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from navcore.core import state
from navcore.core.component import ParameterError
from navcore.filters.adaptive_filters import (IakfEngine, InsOnlyEngine, SageHusaFadingEngine,
                                              masked_update)
from navcore.filters.robust_filters import (UNUSABLE_VARIANCE_FACTOR, Igg3RobustKfEngine,
                                            NewtonRobustKfEngine)
from navcore.filters.innovation_stats import chi2_gate
from navcore.filters.recovery import bounded_r, inflate_navigation, inflation_factor
from navcore.ins.error_model import N_STATES

from linear_kalman import LinearKalmanFilter
from test_kf_engine_by_hand import DT, R_SIGMA, check_feedback, config, increments, strapdown

R0 = np.diag(R_SIGMA ** 2)
#: upper 2 % quantile of chi2(6) (printed tables)
CHI2_98_6DOF = 15.033


def textbook(P_pred, z, R, keep=None):
    """(dx, P, K, S) of the Joseph-form update with the components ``keep``."""
    keep = np.ones(len(z), dtype=bool) if keep is None else keep
    idx = np.flatnonzero(keep)
    H = np.eye(N_STATES)[idx]
    kf = LinearKalmanFilter(np.zeros(N_STATES), P_pred)
    R_kept = R[np.ix_(idx, idx)]
    _, S, _ = kf.update(z[idx], H, R_kept)
    K = P_pred @ H.T @ np.linalg.inv(S)
    return kf.x, kf.P, K, S


def stepped(engine, k=0):
    engine.propagate(*increments(k), DT)
    return engine


def after_first_update(engine):
    """``engine`` stepped, updated with a clean fix and stepped again: the time before a
    filter's first update is no fix interval, so its recovery guard counts from there."""
    stepped(engine).update(CLEAN[0])
    assert not engine.guard.due(np.ones(engine.m, dtype=bool)).any()
    return stepped(engine, 1)


def before(engine):
    return copy.deepcopy(engine.nav), (engine.gyro_bias.copy(), engine.accel_bias.copy())


# ------------------------------------------------------------------------------------------
# masked update
# ------------------------------------------------------------------------------------------
def test_masked_update_is_the_textbook_update_of_the_kept_components():
    rng = np.random.default_rng(11)
    M = rng.standard_normal((N_STATES, N_STATES))
    P = M @ M.T + np.eye(N_STATES)
    z = rng.standard_normal(6)
    R = R0 + 0.01 * np.ones((6, 6))
    keep = np.array([True, False, True, False, False, True])
    dx, P_new = masked_update(P, z, R, keep)
    dx_ref, P_ref, _, _ = textbook(P, z, R, keep)
    np.testing.assert_allclose(dx, dx_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P_new, P_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(P_new, P_new.T)
    one = np.array([False, False, False, True, False, False])
    dx1, P1 = masked_update(P, z, R, one)
    dx1_ref, P1_ref, _, _ = textbook(P, z, R, one)
    np.testing.assert_allclose(dx1, dx1_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P1, P1_ref, rtol=1e-9, atol=1e-12)
    # nothing kept: no correction, the prediction (symmetrized)
    A = P + np.triu(np.ones((N_STATES, N_STATES)), 1)
    dx0, P0 = masked_update(A, z, R, np.zeros(6, dtype=bool))
    np.testing.assert_array_equal(dx0, np.zeros(N_STATES))
    np.testing.assert_array_equal(P0, 0.5 * (A + A.T))


# ------------------------------------------------------------------------------------------
# Sage-Husa + fading
# ------------------------------------------------------------------------------------------
SHF = dict(forgetting_factor=0.9, reserve_gamma=2.0, r_floor_fraction=0.04,
           max_fading_factor=None, r_max_scale=4.0, recovery=False, recovery_epochs=5,
           r_floor_nominal=False)


def shf_by_hand(engine, v, b, gamma, cap=None, r_max=None):
    """Paper 001 eqs. 9-12 on the engine's prediction parts and R_hat."""
    p_prop, q_acc = engine.predicted_parts()
    R = engine.R.copy()
    k = engine.sage_husa_index + 1
    HQH, HP0H = q_acc[:6, :6], p_prop[:6, :6]
    if v @ v <= gamma * (np.trace(HP0H) + np.trace(HQH) + np.trace(R)):     # eq. 11
        lam = 1.0
    else:                                                                     # eq. 12
        lam = max(1.0, (v @ v - np.trace(HQH) - np.trace(R)) / np.trace(HP0H))
        lam = lam if cap is None else min(lam, cap)
    P_pred = lam * p_prop + q_acc                                             # eq. 10
    if r_max is not None:       # the guard on: attitude and biases faded up to their p0 only
        p0_var = np.asarray(engine.config.p0) ** 2
        lam_i = [lam if i < 6 else min(lam, max(1.0, p0_var[i] / p_prop[i, i]))
                 for i in range(N_STATES)]
        P_pred = np.sqrt(np.outer(lam_i, lam_i)) * p_prop + q_acc
    dx, P, K, S = textbook(P_pred, v, R)
    d = (1.0 - b) / (1.0 - b ** (k + 1))
    e = v - (K @ v)[:6]
    R_new = (1.0 - d) * R + d * (np.outer(e, e) + P[:6, :6])                 # eq. 9
    R_new = 0.5 * (R_new + R_new.T)
    if r_max is not None:
        R_new = bounded_r(R_new, r_max)
    return dict(lam=lam, dx=dx, P=P, S=S, R_used=R, R_new=R_new)


def test_sage_husa_fading_two_updates_by_hand():
    kf = stepped(SageHusaFadingEngine(config(), strapdown(), **SHF))
    np.testing.assert_array_equal(kf.R, R0)
    np.testing.assert_allclose(kf.r_min, 0.04 * R_SIGMA ** 2, rtol=1e-15)
    assert kf.r_max is None and kf.sage_husa_index == 0
    for k, z in enumerate((np.array([40.0, -30.0, 20.0, 2.0, -1.0, 0.5]),     # diverging
                           np.array([1.0, 0.5, -0.5, 0.05, 0.0, -0.05]))):    # normal
        if k:
            stepped(kf, k)
        nav, biases = before(kf)
        ref = shf_by_hand(kf, z, 0.9, 2.0)
        result = kf.update(z)
        assert (ref["lam"] > 1.0) == (k == 0)
        assert result.fading_factor == pytest.approx(ref["lam"], rel=1e-12)
        check_feedback(kf, nav, biases, ref["dx"], ref["P"])
        np.testing.assert_allclose(kf.R, ref["R_new"], rtol=1e-8)
        assert kf.sage_husa_index == k + 1
        np.testing.assert_allclose(result.S, ref["S"], rtol=1e-10)
        assert result.nis == pytest.approx(z @ np.linalg.solve(ref["S"], z), rel=1e-9)
        assert result.r_scale == pytest.approx(np.trace(ref["R_used"]) / np.trace(R0),
                                               rel=1e-12)
        np.testing.assert_array_equal(result.innovation, z)
        assert result.outlier is False
    np.testing.assert_allclose(kf.r_sigma_estimate(), np.sqrt(np.diag(ref["R_new"])),
                               rtol=1e-8)
    assert kf.n_updates == 2


def test_sage_husa_fading_factor_cap_and_bounded_r_with_recovery():
    """With the guard, the fading factor acts at a re-acquisition (here: one fix interval
    without a fix, recovery_epochs = 1), capped, on attitude and biases up to p0."""
    options = dict(SHF, max_fading_factor=3.0, recovery=True, recovery_epochs=1)
    kf = after_first_update(SageHusaFadingEngine(config(), strapdown(), **options))
    np.testing.assert_allclose(kf.r_max, 4.0 * R_SIGMA ** 2, rtol=1e-15)
    z = np.array([60.0, -50.0, 40.0, 3.0, -2.0, 1.0])
    assert kf.fading_allowed()
    nav, biases = before(kf)
    ref = shf_by_hand(kf, z, 0.9, 2.0, cap=3.0, r_max=4.0 * R_SIGMA ** 2)
    result = kf.update(z)
    assert result.fading_factor == 3.0
    check_feedback(kf, nav, biases, ref["dx"], ref["P"])
    np.testing.assert_allclose(kf.R, ref["R_new"], rtol=1e-8)
    assert np.all(np.diag(kf.R) <= 4.0 * R_SIGMA ** 2 * (1 + 1e-12))
    # without the guard the estimate is not bounded
    free = stepped(SageHusaFadingEngine(config(), strapdown(), **dict(SHF, reserve_gamma=1e9)))
    free.update(z)
    assert free.R[0, 0] > 4.0 * R0[0, 0]


def test_sage_husa_r_floor_binds_on_a_quiet_stretch():
    """Zero innovations and a tiny P: eq. 9 drives R_hat below 4 % of R0, the guard holds it
    at the floor (diagonal case: R_hat = max(R_hat, floor) per axis)."""
    kf = SageHusaFadingEngine(config(), strapdown(), **dict(SHF, forgetting_factor=0.5))
    kf.P = np.diag(np.full(N_STATES, 1e-12))
    for _ in range(12):
        kf.update(np.zeros(6))
    np.testing.assert_allclose(np.diag(kf.R), 0.04 * R_SIGMA ** 2, rtol=1e-6)


# ------------------------------------------------------------------------------------------
# IAKF
# ------------------------------------------------------------------------------------------
IAKF = dict(SHF, outlier_alpha=0.02)


def test_iakf_compresses_an_outlier_onto_the_gate():
    kf = stepped(IakfEngine(config(), strapdown(), **IAKF))
    assert (kf.compression, kf.tau, kf.outlier_alpha) == (1.0, 0.0, 0.02)
    z = np.array([30.0, -20.0, 10.0, 1.0, -0.5, 0.2])
    p_prop, q_acc = kf.predicted_parts()
    G = (p_prop + q_acc)[:6, :6] + R0
    tau = z @ np.linalg.solve(G, z)
    gate = chi2_gate(0.02, 6)                   # the quantile to all digits
    assert gate == pytest.approx(CHI2_98_6DOF, abs=5e-4)
    Y = math.sqrt(gate / tau)
    assert Y < 0.5
    nav, biases = before(kf)
    ref = shf_by_hand(kf, Y * z, 0.9, 2.0)
    result = kf.update(z)
    assert kf.compression == pytest.approx(Y, rel=1e-12)
    assert kf.tau == pytest.approx(tau, rel=1e-9) and result.nis == kf.tau
    ref = shf_by_hand_with(kf, nav, biases, ref, result)
    np.testing.assert_array_equal(result.innovation, z)
    np.testing.assert_allclose(result.S, G, rtol=1e-12)
    assert result.outlier is True
    assert kf.guard.n_reacquired == 0


def shf_by_hand_with(kf, nav, biases, ref, result):
    """Checks an IAKF update against the Sage-Husa + fading reference of its innovation."""
    assert result.fading_factor == pytest.approx(ref["lam"], rel=1e-6)
    check_feedback(kf, nav, biases, ref["dx"], ref["P"])
    np.testing.assert_allclose(kf.R, ref["R_new"], rtol=1e-6)
    assert result.r_scale == pytest.approx(np.trace(ref["R_used"]) / np.trace(R0), rel=1e-12)
    return ref


def test_iakf_below_the_gate_is_sage_husa_fading():
    kf = stepped(IakfEngine(config(), strapdown(), **IAKF))
    z = np.array([2.0, -1.0, 1.5, 0.1, -0.05, 0.02])
    nav, biases = before(kf)
    ref = shf_by_hand(kf, z, 0.9, 2.0)
    result = kf.update(z)
    assert kf.compression == 1.0 and result.outlier is False
    shf_by_hand_with(kf, nav, biases, ref, result)
    # an innovation whose tau is just above the gate is compressed (Y a little below 1)
    stepped(kf, 1)
    p_prop, q_acc = kf.predicted_parts()
    G = (p_prop + q_acc)[:6, :6] + kf.R
    u = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    z = u * math.sqrt(CHI2_98_6DOF * 1.01 / (u @ np.linalg.solve(G, u)))
    kf.update(z)
    assert kf.compression == pytest.approx(math.sqrt(1.0 / 1.01), rel=1e-4)


def test_iakf_takes_a_second_compressed_epoch_uncompressed_with_recovery():
    kf = IakfEngine(config(), strapdown(), **dict(IAKF, recovery=True, recovery_epochs=2))
    z = np.array([30.0, -20.0, 10.0, 1.0, -0.5, 0.2])
    stepped(kf).update(z)
    assert kf.compression < 1.0 and kf.guard.n_reacquired == 0
    stepped(kf, 1)
    nav, biases = before(kf)
    ref = shf_by_hand(kf, z, 0.9, 2.0, r_max=4.0 * R_SIGMA ** 2)
    result = kf.update(z)
    assert kf.compression == 1.0 and kf.guard.n_reacquired == 1
    assert result.outlier is False
    shf_by_hand_with(kf, nav, biases, ref, result)
    np.testing.assert_array_equal(kf.guard.since_accepted, np.zeros(6))


def test_iakf_refuses_a_significance_outside_zero_one():
    with pytest.raises(ParameterError, match="alpha"):
        IakfEngine(config(), strapdown(), **dict(IAKF, outlier_alpha=1.5))


# ------------------------------------------------------------------------------------------
# Newton robust KF
# ------------------------------------------------------------------------------------------
NEWTON = dict(chi2_threshold=6.635, newton_order=4, replacement_variance="propagated",
              recovery=False, recovery_epochs=5)
CLEAN = [np.array([1.0, -0.5, 0.3, 0.02, -0.01, 0.01]),
         np.array([1.2, -0.4, 0.2, 0.03, -0.02, 0.0]),
         np.array([1.1, -0.6, 0.4, 0.01, 0.0, 0.02])]


def newton_by_hand(kf, z, hist, R_faulted=None, faults=None):
    """One Newton update by hand; ``hist`` (list of stored samples) is updated in place."""
    P_pred = kf.covariance()
    S = P_pred[:6, :6] + R0
    chi2 = z ** 2 / np.diag(S)
    faults = chi2 > 6.635 if faults is None else faults
    z_used, R = z.copy(), R0.copy()
    if faults.any():
        f = np.array(hist)
        replacement = (3.0 * f[-1] - 3.0 * f[-2] + f[-3]) if len(f) >= 3 else f[-1]
        z_used = np.where(faults, replacement, z)
        R = np.diag(np.where(faults, 19.0 * R_SIGMA ** 2, R_SIGMA ** 2)) \
            if R_faulted is None else R_faulted
    dx, P, _, _ = textbook(P_pred, z_used, R)
    hist.append(z_used.copy())
    for sample in hist:
        sample -= dx[:6]
    return dict(dx=dx, P=P, S=S, chi2=chi2, faults=faults, z_used=z_used)


def run_newton(kf, zs, hist, **kwargs):
    for k, z in enumerate(zs):
        stepped(kf, k)
        nav, biases = before(kf)
        ref = newton_by_hand(kf, z, hist, **kwargs)
        result = kf.update(z)
        check_feedback(kf, nav, biases, ref["dx"], ref["P"])
    return ref, result


def test_newton_replaces_a_failed_component_by_the_extrapolation_of_three_samples():
    kf = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    hist = []
    run_newton(kf, CLEAN, hist)
    assert kf.n_rejected == 0 and not kf.rejected.any()
    np.testing.assert_allclose(kf.history.samples(), np.array(hist), rtol=1e-9, atol=1e-12)
    z = np.array([80.0, -0.5, 0.3, 0.02, -0.01, 3.0])          # north and down velocity fail
    ref, result = run_newton(kf, [z], hist)
    assert kf.rejected.tolist() == [True, False, False, False, False, True]
    assert kf.n_rejected == 2 and result.outlier is True
    np.testing.assert_allclose(kf.chi2_values, ref["chi2"], rtol=1e-12)
    assert kf.chi2_max == pytest.approx(ref["chi2"].max(), rel=1e-12)
    np.testing.assert_allclose(result.S, ref["S"], rtol=1e-12)
    np.testing.assert_array_equal(result.innovation, z)
    assert result.nis == pytest.approx(z @ np.linalg.solve(ref["S"], z), rel=1e-9)
    np.testing.assert_allclose(kf.sample_variances[-1],
                               np.where(kf.rejected, 19.0, 1.0) * R_SIGMA ** 2, rtol=1e-15)
    assert len(kf.sample_variances) == len(kf.history) == 4
    np.testing.assert_allclose(kf.history.samples(), np.array(hist), rtol=1e-9, atol=1e-12)


def test_newton_nominal_replacement_variance_keeps_r():
    kf = NewtonRobustKfEngine(config(), strapdown(),
                              **dict(NEWTON, replacement_variance="nominal"))
    hist = []
    run_newton(kf, CLEAN, hist)
    z = np.array([80.0, -0.5, 0.3, 0.02, -0.01, 0.0])
    run_newton(kf, [z], hist, R_faulted=R0)
    assert kf.n_rejected == 1


def test_newton_history_is_cleared_by_a_missed_fix_and_a_lone_fault_is_left_out():
    kf = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    hist = []
    run_newton(kf, CLEAN[:2], hist)
    assert kf.update_interval == pytest.approx(DT) and kf.history_epoch == 1
    for k in range(3):                         # three IMU steps: a fix was missed
        stepped(kf, k)
    assert kf.time == pytest.approx(5 * DT)
    z = np.array([80.0, -0.5, 0.3, 0.02, -0.01, 0.0])
    P_pred = kf.covariance()
    nav, biases = before(kf)
    result = kf.update(z)
    assert kf.history_epoch == 4 and len(kf.history) == 1 and kf.rejected[0]
    # nothing to extrapolate from: the component is left out, its variance capped
    dx, P, _, _ = textbook(P_pred, z, R0, keep=~kf.rejected)
    check_feedback(kf, nav, biases, dx, P)
    assert kf.sample_variances[-1][0] == UNUSABLE_VARIANCE_FACTOR * R_SIGMA[0] ** 2
    assert len(kf.sample_variances) == 1
    assert result.outlier is True
    # the history grows again from the fix after the outage, at the engine's epochs
    for k, z in enumerate(CLEAN[:2]):
        stepped(kf, k).update(z)
    assert kf.history_epoch == kf.history.last_epoch == 6 and len(kf.history) == 3
    assert len(kf.sample_variances) == 3


def test_newton_epochs_of_updates_without_imu_time():
    kf = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    kf.update(CLEAN[0])
    kf.update(CLEAN[1])                         # the same time: the interval is 0
    kf.update(CLEAN[2])
    assert kf.update_interval == 0.0 and kf.history_epoch == 2 and len(kf.history) == 3


def test_newton_extrapolated_variance_of_a_replaced_sample():
    """Order 4 from five samples of which the newest is a replacement with 19 R: the weights
    5, 10, 10, 5, 1 give 25 * 19 + 100 + 100 + 25 + 1 = 701 times R."""
    kf = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    r0 = R_SIGMA ** 2
    for factor in (1.0, 1.0, 1.0, 1.0, 19.0):
        kf.sample_variances.append(factor * r0)
    np.testing.assert_allclose(kf._extrapolated_variance(), 701.0 * r0, rtol=1e-14)
    kf.sample_variances.clear()
    kf.sample_variances.append(r0)
    kf.sample_variances.append(2.0 * r0)       # order 1: 2^2 * 2 + 1 = 9
    np.testing.assert_allclose(kf._extrapolated_variance(), 9.0 * r0, rtol=1e-14)


def test_newton_reacquires_a_fault_after_an_outage_with_recovery():
    """A clean first update (the time before it is no fix interval), then a fault one
    interval later: re-acquired (recovery_epochs = 1)."""
    kf = after_first_update(NewtonRobustKfEngine(
        config(), strapdown(), **dict(NEWTON, recovery=True, recovery_epochs=1)))
    assert kf.guard.interval == 0.0 and not kf.rejected.any()
    z = np.array([80.0, -0.5, 0.3, 0.02, -0.01, 0.0])
    P_pred = kf.covariance()
    due = np.array([True, False, False, False, False, False])
    lam = inflation_factor(z[:1], P_pred[:1, :1], R0[:1, :1], 1)
    P_inflated = inflate_navigation(P_pred, lam, kf.p0_var)
    nav, biases = before(kf)
    result = kf.update(z)
    assert kf.guard.n_reacquired == 1 and not kf.rejected.any()
    dx, P, _, _ = textbook(P_inflated, z, R0)
    check_feedback(kf, nav, biases, dx, P)
    np.testing.assert_allclose(result.S, P_inflated[:6, :6] + R0, rtol=1e-12)
    chi2 = z ** 2 / np.diag(P_inflated[:6, :6] + R0)
    np.testing.assert_allclose(kf.chi2_values, chi2, rtol=1e-12)
    assert chi2[0] == pytest.approx(1.0, rel=1e-6) and due[0]


def test_newton_state_restores_into_a_fresh_engine():
    kf = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    run_newton(kf, CLEAN, [])
    fresh = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    state.restore(fresh, state.capture(kf))
    z = np.array([80.0, -0.5, 0.3, 0.02, -0.01, 0.0])
    for engine in (kf, fresh):
        stepped(engine, 3).update(z)
    np.testing.assert_array_equal(fresh.P, kf.P)
    np.testing.assert_array_equal(fresh.history.samples(), kf.history.samples())


# ------------------------------------------------------------------------------------------
# IGG-III
# ------------------------------------------------------------------------------------------
IGG = dict(igg_k0=1.5, igg_k1=3.0, recovery=False, recovery_epochs=5)


def igg_z(kf, u):
    """The innovation with standardized components ``u`` against the current prediction."""
    S = kf.covariance()[:6, :6] + R0
    return np.asarray(u) * np.sqrt(np.diag(S)), S


def igg3_by_hand(u, k0, k1):
    u = abs(u)
    return 1.0 if u <= k0 else (k0 / u) * ((k1 - u) / (k1 - k0)) ** 2 if u <= k1 else 0.0


@pytest.mark.parametrize("k0, k1, n_rejected", [(1.5, 3.0, 1), (1.0, 2.5, 2)])
def test_igg3_weights_down_weights_and_drops_by_hand(k0, k1, n_rejected):
    kf = stepped(Igg3RobustKfEngine(config(), strapdown(), **dict(IGG, igg_k0=k0, igg_k1=k1)))
    assert kf.weights.tolist() == [1.0] * 6 and kf.n_rejected == 0
    u = [1.0, 2.0, 4.0, -2.6, 0.5, -1.5]
    z, S = igg_z(kf, u)
    w = np.array([igg3_by_hand(x, k0, k1) for x in u])
    P_pred = kf.covariance()
    nav, biases = before(kf)
    result = kf.update(z)
    np.testing.assert_allclose(kf.weights, w, rtol=1e-9, atol=1e-15)
    assert kf.n_rejected == n_rejected and result.outlier is True
    np.testing.assert_array_equal(result.innovation, z)
    keep = w > 0
    R = np.diag(np.where(keep, R_SIGMA ** 2 / np.where(keep, w, 1.0), 1.0))
    dx, P, _, _ = textbook(P_pred, z, R, keep)
    check_feedback(kf, nav, biases, dx, P)
    r0 = R_SIGMA ** 2
    assert result.r_scale == pytest.approx(np.sum(r0[keep] / w[keep]) / np.sum(r0[keep]),
                                           rel=1e-9)
    np.testing.assert_allclose(result.S, S, rtol=1e-12)
    assert result.nis == pytest.approx(z @ np.linalg.solve(S, z), rel=1e-9)


def test_igg3_keeps_everything_below_k0():
    kf = stepped(Igg3RobustKfEngine(config(), strapdown(), **IGG))
    z, _ = igg_z(kf, [1.0, -1.4, 0.5, 0.0, 1.2, -0.3])
    P_pred = kf.covariance()
    nav, biases = before(kf)
    result = kf.update(z)
    dx, P, _, _ = textbook(P_pred, z, R0)
    check_feedback(kf, nav, biases, dx, P)
    assert result.r_scale == 1.0 and result.outlier is False and kf.n_rejected == 0


def test_igg3_with_every_component_dropped_only_predicts():
    kf = stepped(Igg3RobustKfEngine(config(), strapdown(), **IGG))
    z, _ = igg_z(kf, [5.0] * 6)
    P_pred = kf.covariance()
    lat = kf.nav.lat
    result = kf.update(z)
    assert kf.n_rejected == 6 and result.r_scale == 1.0
    assert kf.nav.lat == lat
    np.testing.assert_allclose(kf.P, P_pred, rtol=1e-12)


def test_igg3_reacquires_a_rejected_component_with_full_weight():
    kf = after_first_update(Igg3RobustKfEngine(config(), strapdown(),
                                               **dict(IGG, recovery=True, recovery_epochs=1)))
    z, _ = igg_z(kf, [20.0, 0.5, 0.0, 0.0, 0.0, 0.0])
    P_pred = kf.covariance()
    lam = inflation_factor(z[:1], P_pred[:1, :1], R0[:1, :1], 1)
    P_inflated = inflate_navigation(P_pred, lam, kf.p0_var)
    u = z / np.sqrt(np.diag(P_inflated[:6, :6] + R0))
    assert abs(u[0]) == pytest.approx(1.0, rel=1e-6) and abs(u[1]) < 1.5
    nav, biases = before(kf)
    kf.update(z)
    assert kf.guard.n_reacquired == 1 and kf.weights.tolist() == [1.0] * 6
    dx, P, _, _ = textbook(P_inflated, z, R0)
    check_feedback(kf, nav, biases, dx, P)
    # the re-acquired component keeps at least full weight though above k0 after inflation
    kf2 = after_first_update(Igg3RobustKfEngine(config(), strapdown(), **dict(
        IGG, recovery=True, recovery_epochs=1, igg_k0=0.5, igg_k1=0.9)))
    z2, _ = igg_z(kf2, [20.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    kf2.update(z2)
    assert kf2.weights[0] == 1.0


# ------------------------------------------------------------------------------------------
# INS only
# ------------------------------------------------------------------------------------------
def test_ins_only_evaluates_the_innovation_and_changes_nothing():
    kf = stepped(InsOnlyEngine(config(), strapdown()))
    P_pred = kf.covariance()
    nav = copy.deepcopy(kf.nav)
    z = [3.0, -2.0, 1.0, 0.1, 0.0, -0.1]
    result = kf.update(z)
    S = P_pred[:6, :6] + R0
    np.testing.assert_allclose(result.S, S, rtol=1e-14)
    assert result.nis == pytest.approx(np.array(z) @ np.linalg.solve(S, z), rel=1e-12)
    assert result.innovation.dtype == np.float64
    np.testing.assert_array_equal(result.innovation, z)
    np.testing.assert_array_equal(kf.covariance(), P_pred)
    assert (kf.nav.lat, kf.nav.h) == (nav.lat, nav.h) and kf.n_updates == 0


# ------------------------------------------------------------------------------------------
# what every engine shares: float innovations, diagnostics before the first fix
# ------------------------------------------------------------------------------------------
ENGINES = [(SageHusaFadingEngine, SHF), (IakfEngine, IAKF), (NewtonRobustKfEngine, NEWTON),
           (Igg3RobustKfEngine, IGG), (InsOnlyEngine, {})]


@pytest.mark.parametrize("cls, options", ENGINES, ids=lambda c: getattr(c, "__name__", ""))
def test_an_integer_measurement_is_taken_as_floats(cls, options):
    z_int = [3, -2, 1, 0, 1, 0]
    a = stepped(cls(config(), strapdown(), **options))
    b = stepped(cls(config(), strapdown(), **options))
    result = a.update(z_int)
    reference = b.update(np.array(z_int, dtype=float))
    assert result.innovation.dtype == np.float64
    np.testing.assert_array_equal(result.innovation, reference.innovation)
    np.testing.assert_array_equal(a.covariance(), b.covariance())
    assert result.nis == reference.nis


def test_newton_reports_no_rejection_before_the_first_fix():
    kf = NewtonRobustKfEngine(config(), strapdown(), **NEWTON)
    assert kf.chi2_max == 0.0 and type(kf.chi2_max) is float
    assert kf.n_rejected == 0 and type(kf.n_rejected) is int
    np.testing.assert_array_equal(kf.chi2_values, np.zeros(6))
    assert kf.rejected.dtype == bool and not kf.rejected.any() and kf.rejected.shape == (6,)


def test_iakf_counts_each_reacquisition_and_never_a_clean_epoch():
    kf = IakfEngine(config(), strapdown(), **dict(IAKF, recovery=True, recovery_epochs=1))
    stepped(kf).update(np.array([2.0, -1.0, 1.5, 0.1, -0.05, 0.02]))     # below the gate
    assert kf.guard.n_reacquired == 0 and kf.compression == 1.0
    z = np.array([30.0, -20.0, 10.0, 1.0, -0.5, 0.2])
    stepped(kf, 1).update(z)
    stepped(kf, 2).update(z * 20.0)
    assert kf.guard.n_reacquired == 2 and kf.compression == 1.0


def at_threshold(s, threshold=6.635):
    """A value v with v * v / s == threshold in floating point (the statistic at the gate)."""
    v = math.sqrt(threshold * s)
    for _ in range(64):
        ratio = v * v / s
        if ratio == threshold:
            return v
        v = np.nextafter(v, math.inf if ratio < threshold else 0.0)
    pytest.skip("no double reaches the threshold exactly")


def test_newton_statistic_at_the_threshold_passes():
    """Paper 004: an observation fails when r_i *exceeds* the threshold."""
    kf = stepped(NewtonRobustKfEngine(config(), strapdown(), **NEWTON))
    _, S = kf.predicted_innovation()
    z = np.zeros(6)
    z[2] = at_threshold(S[2, 2])
    kf.update(z)
    assert kf.chi2_values[2] == 6.635 and not kf.rejected.any()


def test_newton_reacquires_one_component_and_tests_the_others_on_the_inflated_prediction():
    """Recovery after 2 intervals.  Epoch 1: north position rejected (nothing to replace it
    with), the rest accepted.  Epoch 2: north fails again and is due, so the prediction is
    inflated for it; down velocity (accepted at epoch 1) still fails on the inflated
    prediction and is replaced by the epoch-1 sample; east velocity lands on the threshold
    exactly there and is accepted."""
    kf = NewtonRobustKfEngine(config(), strapdown(), **dict(NEWTON, recovery=True,
                                                             recovery_epochs=2))
    hist = []
    z1 = np.array([80.0, -0.5, 0.3, 0.02, -0.01, 0.01])
    stepped(kf)
    P_pred = kf.covariance()
    dx1, _, _, _ = textbook(P_pred, z1, R0, keep=np.arange(6) > 0)
    kf.update(z1)
    hist.append(z1 - dx1[:6])
    np.testing.assert_allclose(kf.guard.since_accepted, [DT, 0, 0, 0, 0, 0], rtol=1e-12)
    stepped(kf, 1)
    P_pred = kf.covariance()
    z2 = np.array([80.0, -0.5, 0.3, 0.02, 0.0, 100.0])
    lam = inflation_factor(z2[:1], P_pred[:1, :1], R0[:1, :1], 1)
    P_inflated = inflate_navigation(P_pred, lam, kf.p0_var)
    S = P_inflated[:6, :6] + R0
    z2[4] = at_threshold(S[4, 4])
    assert z2[4] ** 2 / (P_pred[4, 4] + R0[4, 4]) > 6.635       # failed before inflation
    z_used = np.where(np.arange(6) == 5, hist[-1], z2)
    dx, P, _, _ = textbook(P_inflated, z_used, R0)
    nav, biases = before(kf)
    result = kf.update(z2)
    assert kf.rejected.tolist() == [False, False, False, False, False, True]
    assert kf.guard.n_reacquired == 1
    check_feedback(kf, nav, biases, dx, P)
    np.testing.assert_allclose(result.S, S, rtol=1e-12)
    np.testing.assert_allclose(kf.guard.since_accepted, [0, 0, 0, 0, 0, DT], rtol=1e-12)


def test_igg3_reacquires_one_component_and_weighs_the_others_on_the_inflated_prediction():
    """As the Newton case with k0 = 1, k1 = 2: at epoch 2 north position is due; east
    position, rejected before the inflation, has u = 1.5 after it and the weight
    (1 / 1.5) (0.5 / 1)^2 = 1/6."""
    options = dict(IGG, igg_k0=1.0, igg_k1=2.0, recovery=True, recovery_epochs=2)
    kf = stepped(Igg3RobustKfEngine(config(), strapdown(), **options))
    z1, _ = igg_z(kf, [20.0, 0.5, 0.0, 0.0, 0.0, 0.0])
    kf.update(z1)
    assert kf.weights[0] == 0.0 and kf.n_rejected == 1
    np.testing.assert_allclose(kf.guard.since_accepted, [DT, 0, 0, 0, 0, 0], rtol=1e-12)
    stepped(kf, 1)
    P_pred = kf.covariance()
    z2, S_before = igg_z(kf, [20.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    lam = inflation_factor(z2[:1], P_pred[:1, :1], R0[:1, :1], 1)
    P_inflated = inflate_navigation(P_pred, lam, kf.p0_var)
    S = P_inflated[:6, :6] + R0
    z2[1] = 1.5 * math.sqrt(S[1, 1])
    assert z2[1] / math.sqrt(S_before[1, 1]) > 2.0                 # rejected before
    w = np.array([1.0, 1.0 / 6.0, 1.0, 1.0, 1.0, 1.0])
    dx, P, _, _ = textbook(P_inflated, z2, np.diag(R_SIGMA ** 2 / w))
    nav, biases = before(kf)
    result = kf.update(z2)
    np.testing.assert_allclose(kf.weights, w, rtol=1e-9)
    check_feedback(kf, nav, biases, dx, P)
    np.testing.assert_allclose(result.S, S, rtol=1e-12)
    np.testing.assert_array_equal(result.innovation, z2)
    assert result.outlier is True
    np.testing.assert_array_equal(kf.guard.since_accepted, np.zeros(6))
    # east position was down-weighted, not taken at full weight: its down-weighting run goes on
    assert kf.short_weight_fixes.tolist() == [0, 1, 0, 0, 0, 0]


def test_igg3_reacquires_a_run_of_down_weighted_fixes():
    """A component down-weighted (0 < w < 1) at ``recovery_epochs`` fixes in a row is
    re-acquired as a rejected one is: the prediction inflated for it, full weight.  A fix at
    full weight in between starts the run again; a fix beyond k1 (an outlier) at the end of a
    down-weighting run stays rejected (only a run of rejections re-acquires it); time without
    fixes is no run (one down-weighted fix after an outage is the law's); with ``recovery``
    off the weights are the law's at every fix."""
    options = dict(IGG, recovery=True, recovery_epochs=2)
    kf = after_first_update(Igg3RobustKfEngine(config(), strapdown(), **options))
    z1, _ = igg_z(kf, [2.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    kf.update(z1)
    assert 0.0 < kf.weights[0] < 1.0 and kf.guard.n_reacquired == 0
    np.testing.assert_array_equal(kf.guard.since_accepted, np.zeros(6))
    assert kf.short_weight_fixes.tolist() == [1, 0, 0, 0, 0, 0]
    stepped(kf, 2)
    P_pred = kf.covariance()
    z2, S_before = igg_z(kf, [2.5, 0.0, 0.0, 0.0, 0.0, 0.0])
    lam = inflation_factor(z2[:1], P_pred[:1, :1], R0[:1, :1], 1)
    assert lam > 1.0
    P_inflated = inflate_navigation(P_pred, lam, kf.p0_var)
    nav, biases = before(kf)
    result = kf.update(z2)
    assert kf.guard.n_reacquired == 1 and kf.weights.tolist() == [1.0] * 6
    dx, P, _, _ = textbook(P_inflated, z2, R0)
    check_feedback(kf, nav, biases, dx, P)
    np.testing.assert_allclose(result.S, P_inflated[:6, :6] + R0, rtol=1e-12)
    assert kf.short_weight_fixes.tolist() == [0] * 6
    # a full-weight fix between two down-weighted ones, an outlier after a down-weighted
    # one: no re-acquisition, the law's weights
    for recovery, sequence in ((True, [2.0, 1.0, 2.5]), (True, [2.0, 20.0]),
                               (False, [2.0, 1.0, 2.5])):
        kf = after_first_update(Igg3RobustKfEngine(config(), strapdown(),
                                                   **dict(options, recovery=recovery)))
        for k, u in enumerate(sequence):
            z, _ = igg_z(kf, [u, 0.0, 0.0, 0.0, 0.0, 0.0])
            kf.update(z)
            assert kf.weights[0] == pytest.approx(igg3_by_hand(u, 1.5, 3.0), rel=1e-12)
            stepped(kf, 3 + k)
        assert kf.guard.n_reacquired == 0
    kf = after_first_update(Igg3RobustKfEngine(config(), strapdown(), **options))
    kf.update(igg_z(kf, [0.0] * 6)[0])                     # the fix interval: one step
    for k in range(10):                                   # ten fix intervals without a fix
        stepped(kf, 2 + k)
    z, _ = igg_z(kf, [2.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    kf.update(z)
    assert kf.weights[0] == pytest.approx(igg3_by_hand(2.0, 1.5, 3.0), rel=1e-12)
    assert kf.guard.n_reacquired == 0 and kf.short_weight_fixes.tolist() == [1, 0, 0, 0, 0, 0]


def receiver_r(engine, std):
    """What the component does with ``r_from_receiver``: the receiver's position sigmas
    ``std`` (N, E, D) as the position part of the engine's nominal R."""
    R = engine.R0.copy()
    R[[0, 1, 2], [0, 1, 2]] = np.asarray(std) ** 2
    engine.R0 = R


@pytest.mark.parametrize("engine_class, options", [(SageHusaFadingEngine, SHF),
                                                   (IakfEngine, IAKF)])
def test_the_r_bound_follows_the_receivers_sigmas_per_axis(engine_class, options):
    """The failing case of a real drive: 1-cm RTK fixes with ``r_from_receiver`` and an INS
    that drifts off by decimetres.  R_hat stays within ``r_max_scale`` times the receiver's
    variance of each axis (N, E, D distinct), not 4 x r_pos^2; the floor follows it too."""
    kf = stepped(engine_class(config(), strapdown(), **dict(options, recovery=True)))
    std = np.array([0.01, 0.02, 0.04])
    bound = 4.0 * np.concatenate([std ** 2, R_SIGMA[3:] ** 2])
    for k in range(5):                  # the sigmas change from fix to fix; the last: std
        receiver_r(kf, std * (1.0 + 0.1 * (k % 2)))
        kf.update(np.array([0.6, -0.9, 1.2, 0.02, -0.01, 0.03]))
        stepped(kf, k + 1)
    np.testing.assert_allclose(kf.r_max, 4.0 * np.diag(kf.R0), rtol=1e-15)
    np.testing.assert_allclose(kf.r_min, options["r_floor_fraction"] * np.diag(kf.R0),
                               rtol=1e-15)
    np.testing.assert_allclose(kf.r_max, bound, rtol=1e-15)
    r_hat = np.diag(kf.R)
    assert np.all(r_hat <= bound * (1.0 + 1e-12)), r_hat / bound
    # the innovations are tens of receiver sigmas: R_hat sits at its bound on the position axes
    assert np.all(r_hat[:3] >= 0.5 * bound[:3]), r_hat[:3] / bound[:3]


def test_with_the_guard_the_fading_factor_waits_for_a_re_acquisition():
    """Fixes every interval, each beyond its predicted covariance (a receiver whose sigma is
    too small): paper 001's eq. 12 fades at every one; with the guard (recovery_epochs = 2)
    the factor stays 1 until two fix intervals pass without a fix, then fades once."""
    z = np.array([9.0, -8.0, 7.0, 0.3, -0.2, 0.1])
    factors = []
    for options in (SHF, dict(SHF, recovery=True, recovery_epochs=2)):
        kf = SageHusaFadingEngine(config(), strapdown(), **options)
        row = []
        for k in range(4):
            stepped(kf, k)
            if k == 3:                      # one fix missing: two intervals
                stepped(kf, k)
            row.append((kf.fading_allowed(), kf.update(z).fading_factor))
        factors.append(row)
    law, guarded = factors
    assert all(allowed and fading > 1.0 for allowed, fading in law), law
    assert [allowed for allowed, _ in guarded] == [False, False, False, True]
    assert [fading for _, fading in guarded[:3]] == [1.0, 1.0, 1.0] and guarded[3][1] > 1.0
