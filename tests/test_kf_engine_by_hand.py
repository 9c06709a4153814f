"""navcore.filters.ins_gnss_kf on a few steps against formulas written out by hand.

* propagation: the two accumulated parts ``Phi_acc P Phi_acc' + Q_acc`` against ``P``
  propagated directly, step by step, ``P <- Phi P Phi' + diag(q) dt`` with the densities of
  the configuration written out (``q = arw^2, vrw^2, 2 sigma^2 / tau``);
* the update: against the textbook Joseph-form filter of ``tests/linear_kalman.py`` with
  ``H = [I 0]``, then the feedback into a strapdown corrected by hand;
* the measurement ``z = INS - GNSS``: the WGS-84 radii, the fix age and the lever arm terms
  written out by hand.
"""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from navcore.core import state
from navcore.filters.ins_gnss_kf import MEASUREMENTS, KfConfig, KfEngine, UpdateResult
from navcore.ins.error_model import N_STATES, transition_matrix
from navcore.ins.strapdown import Strapdown

from linear_kalman import LinearKalmanFilter

ARW, VRW = 2e-4, 3e-3
GYRO_SIGMA, GYRO_TAU, ACCEL_SIGMA, ACCEL_TAU = 1e-5, 300.0, 2e-3, 50.0
P0 = np.array([3.0, 4.0, 5.0, 0.1, 0.2, 0.3, 1e-2, 2e-2, 3e-2,
               1e-5, 2e-5, 3e-5, 1e-3, 2e-3, 3e-3])
R_SIGMA = np.array([2.0, 3.0, 4.0, 0.1, 0.2, 0.3])
DT = 0.02
WGS84_A, WGS84_E2, OMEGA_IE = 6378137.0, 6.69437999014e-3, 7.292115e-5


def config(measurement="position_velocity", lever_arm=None):
    m = MEASUREMENTS[measurement]
    return KfConfig(p0=P0, gyro_arw=ARW, accel_vrw=VRW, gyro_bias_sigma=GYRO_SIGMA,
                    gyro_bias_tau=GYRO_TAU, accel_bias_sigma=ACCEL_SIGMA,
                    accel_bias_tau=ACCEL_TAU, r_sigma=R_SIGMA[:m], measurement=measurement,
                    lever_arm=lever_arm)


def strapdown():
    return Strapdown.from_euler(0.7, 2.0, 350.0, np.array([40.0, -30.0, 2.0]), 0.1, -0.05, 1.2)


def increments(k):
    """Body increments of IMU step k: a gentle turn with some acceleration."""
    dtheta = np.array([1e-3 + 1e-4 * k, -2e-3, 5e-3]) * DT
    dvel = np.array([0.8, 0.3 - 0.05 * k, -9.7]) * DT
    return dtheta, dvel


def hand_densities():
    q = np.zeros(N_STATES)
    q[3:6] = VRW ** 2
    q[6:9] = ARW ** 2
    q[9:12] = 2.0 * GYRO_SIGMA ** 2 / GYRO_TAU
    q[12:15] = 2.0 * ACCEL_SIGMA ** 2 / ACCEL_TAU
    return q


def propagated_engine(steps=4, gyro_bias=(0.0, 0.0, 0.0), accel_bias=(0.0, 0.0, 0.0)):
    """(engine, reference strapdown, P propagated directly) after ``steps`` IMU steps."""
    kf = KfEngine(config(), strapdown())
    kf.gyro_bias, kf.accel_bias = np.array(gyro_bias), np.array(accel_bias)
    nav = strapdown()
    P = np.diag(P0 ** 2)
    q = hand_densities()
    for k in range(steps):
        dtheta, dvel = increments(k)
        kf.propagate(dtheta, dvel, DT)
        dtheta_c = dtheta - np.array(gyro_bias) * DT
        dvel_c = dvel - np.array(accel_bias) * DT
        C_before = nav.C_bn.copy()
        nav.update(dtheta_c, dvel_c, DT)
        phi = transition_matrix(nav.lat, nav.h, nav.v_ned, nav.C_bn, C_before @ dvel_c / DT,
                                DT, GYRO_TAU, ACCEL_TAU)
        P = phi @ P @ phi.T + np.diag(q * DT)
    return kf, nav, P


def check_feedback(engine, nav_before, biases_before, dx, P):
    """The engine's state after an update against the textbook dx and P: the strapdown
    ``nav_before`` corrected by hand with dx, the biases plus dx, the covariance P."""
    nav_before.correct(dx[0:3], dx[3:6], dx[6:9])
    assert engine.nav.lat == pytest.approx(nav_before.lat, abs=1e-14)
    assert engine.nav.lon == pytest.approx(nav_before.lon, abs=1e-14)
    assert engine.nav.h == pytest.approx(nav_before.h, abs=1e-8)
    np.testing.assert_allclose(engine.nav.v_ned, nav_before.v_ned, rtol=0, atol=1e-9)
    np.testing.assert_allclose(engine.nav.C_bn, nav_before.C_bn, rtol=0, atol=1e-11)
    np.testing.assert_allclose(engine.gyro_bias, biases_before[0] + dx[9:12], rtol=1e-8,
                               atol=1e-20)
    np.testing.assert_allclose(engine.accel_bias, biases_before[1] + dx[12:15], rtol=1e-8,
                               atol=1e-20)
    np.testing.assert_allclose(engine.P, P, rtol=1e-8, atol=1e-18)


def test_initial_covariance_noise_and_measurement_matrix():
    kf = KfEngine(config(), strapdown())
    np.testing.assert_array_equal(kf.P, np.diag(P0 ** 2))
    np.testing.assert_allclose(kf.q_density, hand_densities(), rtol=1e-15)
    np.testing.assert_array_equal(kf.R0, np.diag(R_SIGMA ** 2))
    assert kf.m == 6 and kf.H.shape == (6, N_STATES)
    np.testing.assert_array_equal(kf.H, np.hstack([np.eye(6), np.zeros((6, 9))]))
    np.testing.assert_array_equal(kf.phi_acc, np.eye(N_STATES))
    np.testing.assert_array_equal(kf.q_acc, np.zeros((N_STATES, N_STATES)))
    assert kf.n_updates == 0 and kf.last is None
    np.testing.assert_array_equal(kf.gyro_bias, np.zeros(3))
    np.testing.assert_array_equal(kf.accel_bias, np.zeros(3))
    np.testing.assert_array_equal(kf.rate_ib, np.zeros(3))
    position_only = KfEngine(config("position"), strapdown())
    assert position_only.m == 3
    np.testing.assert_array_equal(position_only.H, np.hstack([np.eye(3), np.zeros((3, 12))]))


def test_defaults_of_the_configuration_and_of_an_update_result():
    cfg = KfConfig(p0=P0, gyro_arw=ARW, accel_vrw=VRW, gyro_bias_sigma=0.0, gyro_bias_tau=0.0,
                   accel_bias_sigma=0.0, accel_bias_tau=0.0, r_sigma=R_SIGMA)
    assert cfg.measurement == "position_velocity" and cfg.lever_arm is None
    result = UpdateResult(np.zeros(3), np.eye(3), 0.5)
    # an update without adaptation: unit scales, no fading, no outlier
    assert (result.q_scale, result.r_scale, result.fading_factor) == (1.0, 1.0, 1.0)
    assert result.outlier is False


def test_propagation_in_two_parts_equals_the_direct_covariance_propagation():
    gyro_bias, accel_bias = (2e-4, -1e-4, 3e-4), (0.02, -0.01, 0.03)
    kf, nav, P = propagated_engine(4, gyro_bias, accel_bias)
    # the mechanization ran on the bias-compensated increments
    assert (kf.nav.lat, kf.nav.lon, kf.nav.h) == (nav.lat, nav.lon, nav.h)
    np.testing.assert_array_equal(kf.nav.v_ned, nav.v_ned)
    np.testing.assert_array_equal(kf.nav.C_bn, nav.C_bn)
    dtheta, _ = increments(3)
    np.testing.assert_allclose(kf.rate_ib, (dtheta - np.array(gyro_bias) * DT) / DT,
                               rtol=1e-14)
    np.testing.assert_allclose(kf.covariance(), P, rtol=1e-10, atol=1e-22)
    np.testing.assert_allclose(kf.covariance_diagonal(), np.diagonal(P), rtol=1e-10,
                               atol=1e-22)
    p_prop, q_acc = kf.predicted_parts()
    np.testing.assert_allclose(p_prop + q_acc, P, rtol=1e-10, atol=1e-22)
    # the parts alone: Q_acc is P propagated from zero, Phi_acc P0 Phi_acc' the rest
    assert q_acc[5, 5] > 0.0 and np.all(np.diagonal(q_acc) > 0.0)
    np.testing.assert_allclose(p_prop, kf.phi_acc @ np.diag(P0 ** 2) @ kf.phi_acc.T,
                               rtol=1e-14)


def test_q_accumulated_from_zero_is_the_process_noise_alone():
    kf = KfEngine(config(), strapdown())
    kf.P = np.zeros((N_STATES, N_STATES))
    nav = strapdown()
    Q = np.zeros((N_STATES, N_STATES))
    for k in range(3):
        dtheta, dvel = increments(k)
        C_before = nav.C_bn.copy()
        nav.update(dtheta, dvel, DT)
        phi = transition_matrix(nav.lat, nav.h, nav.v_ned, nav.C_bn, C_before @ dvel / DT,
                                DT, GYRO_TAU, ACCEL_TAU)
        Q = phi @ Q @ phi.T + np.diag(hand_densities() * DT)
        kf.propagate(dtheta, dvel, DT)
    _, q_acc = kf.predicted_parts()
    np.testing.assert_allclose(q_acc, Q, rtol=1e-12, atol=1e-30)
    # the first step's noise on the diagonal: q dt, the bias states decayed by (1 - dt/tau)^2
    np.testing.assert_allclose(q_acc[14, 14], 2.0 * ACCEL_SIGMA ** 2 / ACCEL_TAU * DT
                               * sum((1.0 - DT / ACCEL_TAU) ** (2 * j) for j in range(3)),
                               rtol=1e-12)


def test_close_prediction_symmetrizes_and_restarts_the_accumulators():
    kf, _, _ = propagated_engine(2)
    A = np.arange(N_STATES * N_STATES, dtype=float).reshape(N_STATES, N_STATES)
    kf.close_prediction(A)
    np.testing.assert_array_equal(kf.P, 0.5 * (A + A.T))
    np.testing.assert_array_equal(kf.phi_acc, np.eye(N_STATES))
    np.testing.assert_array_equal(kf.q_acc, np.zeros((N_STATES, N_STATES)))
    np.testing.assert_array_equal(kf.covariance(), 0.5 * (A + A.T))


def test_predicted_innovation_adds_r_to_the_leading_block():
    kf, _, P = propagated_engine(3)
    P_pred, S = kf.predicted_innovation()
    np.testing.assert_allclose(P_pred, P, rtol=1e-10, atol=1e-22)
    np.testing.assert_allclose(S, P[:6, :6] + np.diag(R_SIGMA ** 2), rtol=1e-10)
    R = np.diag([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    _, S_given = kf.predicted_innovation(R)
    np.testing.assert_allclose(S_given, P[:6, :6] + R, rtol=1e-10)


@pytest.mark.parametrize("measurement", ["position", "position_velocity"])
def test_kalman_update_is_the_textbook_joseph_update(measurement):
    kf = KfEngine(config(measurement), strapdown())
    m = kf.m
    rng = np.random.default_rng(7)
    M = rng.standard_normal((N_STATES, N_STATES))
    P = M @ M.T + np.diag(P0 ** 2)
    z = rng.standard_normal(m) * R_SIGMA[:m] * 3.0
    R = np.diag(R_SIGMA[:m] ** 2) + 0.1 * np.ones((m, m))     # a correlated R
    textbook = LinearKalmanFilter(np.zeros(N_STATES), P)
    H = np.hstack([np.eye(m), np.zeros((m, N_STATES - m))])
    v_ref, S_ref, _ = textbook.update(z, H, R)
    dx, P_new, v, S, K = kf.kalman_update(P, z, R)
    np.testing.assert_allclose(dx, textbook.x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P_new, textbook.P, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(P_new, P_new.T)
    np.testing.assert_array_equal(v, v_ref)
    np.testing.assert_allclose(S, S_ref, rtol=1e-14)
    np.testing.assert_allclose(K, P @ H.T @ np.linalg.inv(S_ref), rtol=1e-9, atol=1e-12)


def test_update_feeds_the_textbook_estimate_back():
    gyro_bias, accel_bias = (1e-4, 2e-4, -3e-4), (0.01, 0.02, -0.03)
    kf, _, P = propagated_engine(3, gyro_bias, accel_bias)
    before = copy.deepcopy(kf.nav)
    z = np.array([6.0, -4.0, 3.0, 0.5, -0.3, 0.2])
    R0 = np.diag(R_SIGMA ** 2)
    textbook = LinearKalmanFilter(np.zeros(N_STATES), P)
    v_ref, S_ref, nis_ref = textbook.update(z, np.hstack([np.eye(6), np.zeros((6, 9))]), R0)
    result = kf.update(z)
    dx = textbook.x
    # closed loop: lat -= dn / (R_N + h), lon -= de / ((R_E + h) cos lat), h += dd, v -= dv
    check_feedback(kf, before, (np.array(gyro_bias), np.array(accel_bias)), dx, textbook.P)
    np.testing.assert_array_equal(kf.phi_acc, np.eye(N_STATES))
    np.testing.assert_array_equal(kf.q_acc, np.zeros((N_STATES, N_STATES)))
    assert kf.n_updates == 1
    np.testing.assert_array_equal(result.innovation, v_ref)
    np.testing.assert_allclose(result.S, S_ref, rtol=1e-12)
    assert result.nis == pytest.approx(nis_ref, rel=1e-9)
    assert (result.r_scale, result.fading_factor, result.outlier) == (1.0, 1.0, False)
    kf.update(np.zeros(6))
    assert kf.n_updates == 2


def hand_radii(lat):
    w = 1.0 - WGS84_E2 * math.sin(lat) ** 2
    return WGS84_A * (1.0 - WGS84_E2) / w ** 1.5, WGS84_A / math.sqrt(w)


def test_measurement_is_ins_minus_gnss_taken_back_to_the_fix_time():
    kf = KfEngine(config(), strapdown())
    nav = kf.nav
    rn, re = hand_radii(nav.lat)
    fix_lat, fix_lon, fix_h = nav.lat - 3.0 / rn, nav.lon + 2.0 / (re * math.cos(nav.lat)), 351.5
    fix_v = np.array([39.0, -29.5, 2.5])
    age = 0.25
    z = kf.measurement(fix_lat, fix_lon, fix_h, fix_v, age)
    v = nav.v_ned
    expected = [(nav.lat - fix_lat) * (rn + nav.h) - v[0] * age,
                (nav.lon - fix_lon) * (re + nav.h) * math.cos(nav.lat) - v[1] * age,
                -(nav.h - fix_h) - v[2] * age]
    np.testing.assert_allclose(z[:3], expected, rtol=1e-9)
    assert z[0] == pytest.approx(3.0 * (rn + 350.0) / rn - 10.0, rel=1e-9)
    np.testing.assert_allclose(z[3:], v - fix_v, rtol=1e-14)
    position_only = KfEngine(config("position"), strapdown())
    z3 = position_only.measurement(fix_lat, fix_lon, fix_h, fix_v, age)
    assert z3.shape == (3,)
    np.testing.assert_allclose(z3, expected, rtol=1e-9)


@pytest.mark.parametrize("measurement", ["position", "position_velocity"])
def test_measurement_carries_the_ins_to_the_antenna(measurement):
    lever = np.array([1.5, -0.4, -0.8])
    plain = KfEngine(config(measurement), strapdown())
    kf = KfEngine(config(measurement, lever), strapdown())
    for engine in (plain, kf):
        engine.propagate(*increments(0), DT)
    fix = (kf.nav.lat - 1e-6, kf.nav.lon + 1e-6, 349.0, np.array([40.5, -30.5, 1.5]), 0.1)
    offset = kf.measurement(*fix) - plain.measurement(*fix)
    C, lat = kf.nav.C_bn, kf.nav.lat
    rate = increments(0)[0] / DT
    earth_rate = np.array([OMEGA_IE * math.cos(lat), 0.0, -OMEGA_IE * math.sin(lat)])
    np.testing.assert_allclose(offset[:3], C @ lever, rtol=1e-9, atol=1e-12)
    if kf.m == 6:
        expected_v = C @ np.cross(rate, lever) - np.cross(earth_rate, C @ lever)
        np.testing.assert_allclose(offset[3:], expected_v, rtol=1e-6, atol=1e-15)


def test_a_captured_state_continues_identically():
    kf, _, _ = propagated_engine(2, (1e-4, 0.0, 0.0), (0.0, 0.01, 0.0))
    kf.update(np.array([1.0, 2.0, -1.0, 0.1, 0.0, -0.1]))
    kf.propagate(*increments(2), DT)
    tree = state.capture(kf)
    assert set(tree) == set(KfEngine.state_fields)
    fresh = KfEngine(config(), strapdown())
    state.restore(fresh, tree)
    z = np.array([0.5, -0.5, 0.3, 0.0, 0.05, 0.0])
    for engine in (kf, fresh):
        engine.propagate(*increments(3), DT)
        engine.last = engine.update(z)
    np.testing.assert_array_equal(fresh.P, kf.P)
    np.testing.assert_array_equal(fresh.nav.C_bn, kf.nav.C_bn)
    np.testing.assert_array_equal(fresh.gyro_bias, kf.gyro_bias)
    assert fresh.n_updates == kf.n_updates == 2


def test_integer_sigmas_give_float_covariances_that_a_state_restores_into():
    """A configuration written with integers (p0 = 1 m, R = 2 m): P and R0 are float64, so
    the state of an updated engine (float P) restores into a fresh build of the same
    configuration, and the adaptive engines' copy of R0 is float too."""
    cfg = KfConfig(p0=[1] * N_STATES, gyro_arw=0, accel_vrw=0, gyro_bias_sigma=0,
                   gyro_bias_tau=0, accel_bias_sigma=0, accel_bias_tau=0, r_sigma=[2, 2, 2],
                   measurement="position")
    kf = KfEngine(cfg, strapdown())
    assert kf.P.dtype == np.float64 and kf.R0.dtype == np.float64
    np.testing.assert_array_equal(kf.R0, 4.0 * np.eye(3))
    kf.propagate(*increments(0), DT)
    kf.update(np.array([1.0, 0.0, 0.0]))
    fresh = KfEngine(cfg, strapdown())
    state.restore(fresh, state.capture(kf))
    np.testing.assert_array_equal(fresh.P, kf.P)
