"""The unscented INS/GNSS engines (navcore.filters.ukf_filters) step by step against references
written out from the module docstring, without a scenario.

The reference mechanizes its own strapdown on the bias-compensated increments, forms the interval
means by the trapezoidal rule (``f`` from the summed ``C_bn dvel``), predicts an
:class:`UnscentedKalmanFilter` with ``propagate_points`` and the discrete process noise written
out (``q T``, the velocity noise integrated into position: ``q_v T^3/3`` and ``q_v T^2/2``),
updates it with ``H = [I_m 0]`` and feeds the estimate back.  The CTFA schedule of paper 000
eq. 25 and the textbook IMM cycle (mixing, model-matched prediction and update, probabilities
from the likelihoods, combination) are written out the same way.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from navcore.filters.ins_gnss_kf import KfConfig
from navcore.filters.ukf_filters import CtfaUkfEngine, ImmUkfEngine, UkfEngine
from navcore.filters.ukf_time_update import (NominalInterval, discrete_process_noise,
                                             propagate_points)
from navcore.filters.unscented import UnscentedKalmanFilter
from navcore.ins.strapdown import Strapdown

DT = 0.02
P0_SIGMA = np.array([3.0] * 3 + [0.1] * 3 + [2e-3] * 3 + [1e-5] * 3 + [1e-3] * 3)
ARW, VRW = 2e-4, 3e-3
BG_SIGMA, BG_TAU, BA_SIGMA, BA_TAU = 2e-5, 300.0, 2e-3, 200.0
R_SIGMA = np.array([2.0, 3.0, 4.0, 0.1, 0.2, 0.3])
UT = dict(predict_interval=0.1, alpha=1.0, beta=2.0, kappa=0.0)
GYRO_BIAS = np.array([1e-4, -2e-4, 5e-5])
ACCEL_BIAS = np.array([0.01, -0.02, 0.03])
#: the spectral density of the error model: none on position, VRW^2, ARW^2, 2 sigma^2 / tau
Q_DENSITY = np.array([0.0] * 3 + [VRW ** 2] * 3 + [ARW ** 2] * 3
                     + [2.0 * BG_SIGMA ** 2 / BG_TAU] * 3 + [2.0 * BA_SIGMA ** 2 / BA_TAU] * 3)


def kf_config(m=3):
    return KfConfig(p0=P0_SIGMA, gyro_arw=ARW, accel_vrw=VRW, gyro_bias_sigma=BG_SIGMA,
                    gyro_bias_tau=BG_TAU, accel_bias_sigma=BA_SIGMA, accel_bias_tau=BA_TAU,
                    r_sigma=R_SIGMA[:m], measurement={3: "position", 6: "position_velocity"}[m])


def strapdown():
    return Strapdown.from_euler(0.6, 1.9, 500.0, [20.0, 10.0, -1.0], 0.1, -0.05, 1.2)


def increments(k):
    """IMU increments of step k: a turn at a growing rate, a growing forward force."""
    return (np.array([1e-3, -2e-3, 0.05 + 0.01 * k]) * DT,
            np.array([0.5 + 0.1 * k, -0.2, -9.8]) * DT)


def process_noise_by_hand(T):
    Q = np.diag(Q_DENSITY * T)
    for i in range(3):
        qv = Q_DENSITY[3 + i]
        Q[i, i] = qv * T ** 3 / 3.0
        Q[i, 3 + i] = Q[3 + i, i] = qv * T ** 2 / 2.0
    return Q


class Reference:
    """The engine of the module docstring written out; ``predict`` is called by the test."""

    def __init__(self, m=3, q_scales=(1.0,)):
        self.m = m
        self.nav = strapdown()
        self.filters = [UnscentedKalmanFilter(15, x0=np.zeros(15), P0=np.diag(P0_SIGMA ** 2))
                        for _ in q_scales]
        self.q_scales = list(q_scales)
        self.gyro_bias = np.zeros(3)
        self.accel_bias = np.zeros(3)
        self.samples = []

    @property
    def ukf(self):
        return self.filters[0]

    def step(self, dtheta, dvel):
        dtheta = dtheta - self.gyro_bias * DT
        dvel = dvel - self.accel_bias * DT
        nav = self.nav
        before = (nav.lat, nav.h, nav.v_ned.copy(), nav.C_bn.copy())
        force = nav.C_bn @ dvel
        nav.update(dtheta, dvel, DT)
        self.samples.append((before, (nav.lat, nav.h, nav.v_ned.copy(), nav.C_bn.copy()), force))

    def pending(self):
        return len(self.samples) * DT

    def nominal(self):
        """The interval means (trapezoid) of lat, h, v, C_bn and the mean specific force."""
        T = self.pending()
        means = [sum(0.5 * DT * (a[i] + b[i]) for a, b, _ in self.samples) / T for i in range(4)]
        force = sum(f for _, _, f in self.samples) / T
        return T, means, force

    def predict(self):
        T, (lat, h, v, C), force = self.nominal()
        nom = NominalInterval(T, lat, h, v, C, force)
        for flt, scale in zip(self.filters, self.q_scales):
            flt.predict(propagate_points, scale * process_noise_by_hand(T), nom, BG_TAU, BA_TAU,
                        vectorized=True)
        self.samples = []

    def feed_back(self, dx):
        self.nav.correct(dx[0:3], dx[3:6], dx[6:9])
        self.gyro_bias = self.gyro_bias + dx[9:12]
        self.accel_bias = self.accel_bias + dx[12:15]

    def update(self, z, P=None):
        """One UKF's update (from the prior ``P`` if given) and the feedback."""
        if P is not None:
            self.ukf.P = P
        info = self.ukf.update(z, lambda x: x[:self.m], np.diag(R_SIGMA[:self.m] ** 2))
        self.feed_back(self.ukf.x)
        self.ukf.x = np.zeros(15)
        return info


def run(engine, reference, steps, first=0, predict_every=5):
    """Steps ``first``.. of both; the reference predicts after every ``predict_every``."""
    for k in range(first, first + steps):
        engine.propagate(*increments(k), DT)
        reference.step(*increments(k))
        if predict_every and (k - first + 1) % predict_every == 0:
            reference.predict()


def assert_same_covariance(P, P_ref, tol=1e-9):
    """Equal to ``tol`` in units of the reference's standard deviations (correlations)."""
    sd = np.sqrt(np.diagonal(P_ref))
    np.testing.assert_allclose(P / np.outer(sd, sd), P_ref / np.outer(sd, sd), atol=tol)


def assert_same_navigation(nav, nav_ref):
    assert nav.lat == pytest.approx(nav_ref.lat, abs=1e-14)
    assert nav.lon == pytest.approx(nav_ref.lon, abs=1e-14)
    assert nav.h == pytest.approx(nav_ref.h, abs=1e-8)
    np.testing.assert_allclose(nav.v_ned, nav_ref.v_ned, rtol=0, atol=1e-10)
    np.testing.assert_allclose(nav.C_bn, nav_ref.C_bn, rtol=0, atol=1e-12)


def biased(engine, reference):
    engine.gyro_bias, engine.accel_bias = GYRO_BIAS.copy(), ACCEL_BIAS.copy()
    reference.gyro_bias, reference.accel_bias = GYRO_BIAS.copy(), ACCEL_BIAS.copy()


def test_discrete_process_noise_by_hand():
    q = np.arange(15.0)                      # velocity densities 3, 4, 5
    Q = discrete_process_noise(q, 0.5)
    assert Q[3, 3] == 1.5 and Q[9, 9] == 4.5 and Q[14, 14] == 7.0
    assert Q[0, 0] == pytest.approx(3.0 / 24.0, rel=1e-15)           # q_v T^3 / 3
    assert Q[2, 5] == Q[5, 2] == pytest.approx(5.0 / 8.0, rel=1e-15)  # q_v T^2 / 2
    assert np.count_nonzero(Q) == 15 + 6     # the diagonal and the position-velocity terms


@pytest.mark.parametrize("interval, every", [(0.1, 5), (0.06, 3), (0.0, 1)])
def test_the_prediction_runs_every_interval_on_its_nominal_means(interval, every):
    engine = UkfEngine(kf_config(), strapdown(), **dict(UT, predict_interval=interval))
    reference = Reference()
    biased(engine, reference)
    for k in range(12):
        run(engine, reference, 1, first=k, predict_every=0)
        if (k + 1) % every == 0:
            reference.predict()
        assert_same_covariance(engine.ukf.P, reference.ukf.P)
        np.testing.assert_allclose(engine.ukf.x, reference.ukf.x, rtol=0,
                                   atol=1e-9 * P0_SIGMA.min())
        expected = np.diagonal(reference.ukf.P) + Q_DENSITY * reference.pending()
        np.testing.assert_allclose(engine.covariance_diagonal(), expected, rtol=1e-9, atol=0)
    assert_same_navigation(engine.nav, reference.nav)
    dtheta, _ = increments(11)
    np.testing.assert_allclose(engine.rate_ib, dtheta / DT - GYRO_BIAS, rtol=1e-13)
    P = engine.covariance()
    P[0, 0] = -1.0                           # a copy: the engine's covariance is untouched
    assert engine.ukf.P[0, 0] > 0.0


def test_an_interval_short_by_more_than_a_nanosecond_waits_for_the_next_step():
    engine = UkfEngine(kf_config(), strapdown(), **UT)
    dt = (0.1 - 5e-9) / 5
    for k in range(5):
        engine.propagate(*increments(k), dt)
    assert np.array_equal(engine.ukf.P, np.diag(P0_SIGMA ** 2))
    engine.propagate(*increments(5), dt)
    assert not np.array_equal(engine.ukf.P, np.diag(P0_SIGMA ** 2))


def test_an_interval_short_by_a_nanosecond_is_complete():
    engine = UkfEngine(kf_config(), strapdown(), **UT)
    engine.propagate(*increments(0), 0.1 - 1e-9)
    assert not np.array_equal(engine.ukf.P, np.diag(P0_SIGMA ** 2))


def test_the_unscented_parameters_reach_the_filters():
    # n = 15, alpha = 0.5, kappa = 1: lambda = 0.25 * 16 - 15 = -11, Wm_0 = -11 / 4
    options = dict(UT, alpha=0.5, beta=3.0, kappa=1.0)
    ukf = UkfEngine(kf_config(), strapdown(), **options).ukf
    imm = ImmUkfEngine(kf_config(), strapdown(), q_scales=[1.0, 2.0], p_stay=0.9,
                       recovery=False, recovery_epochs=5, **options)
    for flt in [ukf] + imm.bank.filters:
        assert flt.lambda_ == -11.0 and flt.Wm[0] == -2.75
        assert flt.Wc[0] == -2.75 + 1.0 + 3.0 - 0.25
        assert np.array_equal(flt.x, np.zeros(15))


def test_a_q_scale_set_on_the_plain_ukf_scales_the_prediction():
    engine = UkfEngine(kf_config(), strapdown(), **UT)
    engine.q_scale = 3.0
    reference = Reference(q_scales=(3.0,))
    run(engine, reference, 7)
    assert_same_covariance(engine.ukf.P, reference.ukf.P)
    result = engine.update(np.array([1.0, 2.0, 3.0]))
    assert result.q_scale == 3.0


@pytest.mark.parametrize("m", [3, 6])
def test_an_update_predicts_the_pending_steps_then_feeds_back(m):
    engine = UkfEngine(kf_config(m), strapdown(), **UT)
    reference = Reference(m)
    biased(engine, reference)
    run(engine, reference, 7)                # one prediction, 2 steps pending
    z = np.array([1.5, -2.0, 0.7, 0.05, -0.03, 0.02])[:m]
    np.testing.assert_allclose(engine.process_noise(0.1), process_noise_by_hand(0.1),
                               rtol=1e-15, atol=0)
    result = engine.update(z)
    reference.predict()
    expected = reference.update(z)
    np.testing.assert_allclose(result.innovation, expected["innovation"], rtol=1e-9)
    np.testing.assert_allclose(result.S, expected["S"], rtol=1e-9)
    assert result.nis == pytest.approx(expected["nis"], rel=1e-9)
    assert result.q_scale == 1.0 and engine.n_updates == 1
    assert np.array_equal(engine.ukf.x, np.zeros(15))
    assert_same_covariance(engine.ukf.P, reference.ukf.P)
    assert_same_navigation(engine.nav, reference.nav)
    np.testing.assert_allclose(engine.gyro_bias - GYRO_BIAS, reference.gyro_bias - GYRO_BIAS,
                               rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(engine.accel_bias - ACCEL_BIAS, reference.accel_bias - ACCEL_BIAS,
                               rtol=1e-9, atol=1e-13)
    run(engine, reference, 5, first=7)       # the next interval on the corrected biases
    assert_same_covariance(engine.ukf.P, reference.ukf.P)
    assert_same_navigation(engine.nav, reference.nav)


def ctfa_engine(m=3, t1=0.0, t2=0.0, pass_decay=1.0, recovery=False, epochs=5):
    return CtfaUkfEngine(kf_config(m), strapdown(), q_max_scale=100.0, t1=t1, t2=t2,
                         pass_decay=pass_decay, recovery=recovery, recovery_epochs=epochs, **UT)


@pytest.mark.parametrize("m, t1, t2, T1, T2", [
    (3, 0.0, 0.0, 6.25, 11.35),              # the paper's
    (6, 0.0, 0.0, 10.645, 16.812),           # chi2(6) at 90 % and 99 % (printed tables)
    (3, 4.0, 9.0, 4.0, 9.0), (6, 4.0, 9.0, 4.0, 9.0), (3, 0.5, 1.0, 0.5, 1.0)])
def test_ctfa_thresholds(m, t1, t2, T1, T2):
    engine = ctfa_engine(m, t1, t2)
    assert engine.schedule.T1 == pytest.approx(T1, abs=5e-4)
    assert engine.schedule.T2 == pytest.approx(T2, abs=5e-4)
    assert engine.q_max_scale == 100.0 and engine.chi2 == 0.0 and engine.q_scale == 1.0


def fix_with_nis(engine, nis_value, direction=(1.0, -0.5, 0.3)):
    """A position fix whose innovation against the current prediction has the given NIS."""
    d = np.array(direction)
    S = engine.ukf.P[:3, :3] + engine.R0
    return engine.ukf.x[:3] + d * np.sqrt(nis_value / (d @ np.linalg.solve(S, d)))


@pytest.mark.parametrize("pass_decay, after_pass", [(1.0, 50.5), (0.0, 1.0)])
def test_ctfa_q_follows_eq25(pass_decay, after_pass):
    engine = ctfa_engine(pass_decay=pass_decay)
    reference = Reference()
    run(engine, reference, 5)
    # (6.25 + 11.35) / 2: halfway between Qmin and Qmax = 100 Qmin
    z = fix_with_nis(engine, 8.8)
    result = engine.update(z)
    assert result.nis == pytest.approx(8.8, rel=1e-9) and engine.chi2 == result.nis
    assert engine.q_scale == pytest.approx(50.5, rel=1e-9) and result.q_scale == engine.q_scale
    reference.update(z)
    reference.q_scales = [engine.q_scale]
    run(engine, reference, 7, first=5)
    assert_same_covariance(engine.ukf.P, reference.ukf.P)
    expected = np.diagonal(reference.ukf.P) + 50.5 * Q_DENSITY * 2 * DT
    np.testing.assert_allclose(engine.covariance_diagonal(), expected, rtol=1e-9)
    engine.update(fix_with_nis(engine, 1.0))                 # passes the test
    assert engine.q_scale == pytest.approx(after_pass, rel=1e-9)


def inflation_by_hand(v, HPH, R, target):
    """lambda with v' (lambda HPH + R)^-1 v = target."""
    return brentq(lambda lam: v @ np.linalg.solve(lam * HPH + R, v) - target, 1.0, 1e6,
                  xtol=1e-14, rtol=1e-14)


def inflated_by_hand(P, lam):
    """Position and velocity times lam, attitude times lam but at most up to its initial
    variance P0_SIGMA^2, biases unchanged (cross terms by the square roots)."""
    att = [min(lam, max(1.0, P0_SIGMA[i] ** 2 / P[i, i])) for i in range(6, 9)]
    d = np.sqrt(np.array([lam] * 6 + att + [1.0] * 6))
    return P * np.outer(d, d)


@pytest.mark.parametrize("recovery", [True, False])
def test_ctfa_reacquires_the_first_fix_after_an_outage(recovery):
    # fixes at 1 s and 2 s set the fix interval; none for 3 s (> 2 intervals) then a far one
    engine = ctfa_engine(recovery=recovery, epochs=2)
    reference = Reference()
    for second in range(2):
        run(engine, reference, 50, first=50 * second)
        z = engine.ukf.x[:3] + np.array([0.5, -0.4, 0.3])
        engine.update(z)
        reference.update(z)
    run(engine, reference, 150, first=100)   # ends on a prediction: nothing pending
    P, x = engine.ukf.P.copy(), engine.ukf.x.copy()
    assert_same_covariance(P, reference.ukf.P)
    z = x[:3] + np.array([40.0, -30.0, 20.0])
    result = engine.update(z)
    v, R = z - x[:3], engine.R0
    if recovery:
        # inflated until the NIS of the fix is the measurement dimension
        lam = inflation_by_hand(v, P[:3, :3], R, 3.0)
        assert lam > 10.0 and engine.guard.n_reacquired == 1
        assert result.nis == pytest.approx(3.0, rel=1e-9)
        expected = reference.update(z, P=inflated_by_hand(reference.ukf.P, lam))
    else:
        assert engine.guard.n_reacquired == 0
        assert result.nis == pytest.approx(v @ np.linalg.solve(P[:3, :3] + R, v), rel=1e-9)
        expected = reference.update(z)
    assert result.nis == pytest.approx(expected["nis"], rel=1e-9)
    assert_same_covariance(engine.ukf.P, reference.ukf.P)


def test_regular_fixes_are_not_reacquired():
    # fixes every second for 4 s, then a far one a second later: no outage, nothing inflated
    engine = ctfa_engine(recovery=True, epochs=2)
    for second in range(5):
        for k in range(50):
            engine.propagate(*increments(k), DT)
        x, P = engine.ukf.x.copy(), engine.ukf.P.copy()
        v = np.array([40.0, -30.0, 20.0]) if second == 4 else np.zeros(3)
        result = engine.update(x[:3] + v)
    assert engine.guard.n_reacquired == 0
    assert result.nis == pytest.approx(v @ np.linalg.solve(P[:3, :3] + engine.R0, v), rel=1e-9)


def test_reacquire_returns_one_when_the_guard_is_off():
    engine = ctfa_engine(recovery=False)
    x, P = engine.ukf.x, engine.ukf.P
    assert engine.reacquire(np.array([40.0, -30.0, 20.0]), x, P, (engine.ukf,)) == 1.0


def test_a_close_fix_after_an_outage_is_not_reacquired():
    engine = ctfa_engine(recovery=True, epochs=2)
    for second in range(2):
        for k in range(50):
            engine.propagate(*increments(k), DT)
        engine.update(engine.ukf.x[:3])
    for k in range(150):
        engine.propagate(*increments(k), DT)
    P = engine.ukf.P.copy()
    z = fix_with_nis(engine, 11.0)           # inside the 99 % gate of chi2(3), 11.34
    result = engine.update(z)
    assert engine.guard.n_reacquired == 0
    assert result.nis == pytest.approx(11.0, rel=1e-9)
    assert P[0, 0] > engine.ukf.P[0, 0]


@pytest.mark.parametrize("q_scales, p_stay, Pi, q_scale", [
    ([1.0], 0.9, [[1.0]], 1.0),
    ([1.0, 100.0], 0.9, [[0.9, 0.1], [0.1, 0.9]], 50.5),
    ([1.0, 10.0, 100.0], 0.8, [[0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]], 37.0)])
def test_imm_bank_of_the_q_scales(q_scales, p_stay, Pi, q_scale):
    engine = imm_engine(q_scales, p_stay)
    np.testing.assert_allclose(engine.bank.Pi, Pi, rtol=1e-15)
    assert engine.q_scales.tolist() == q_scales and engine.ukf is None
    assert engine.q_scale == pytest.approx(q_scale, rel=1e-15)
    assert engine.model_probabilities is engine.bank.mu
    for flt in engine.bank.filters:
        assert np.array_equal(flt.P, np.diag(P0_SIGMA ** 2)) and flt.n == 15


def imm_engine(q_scales, p_stay=0.9, recovery=False, epochs=5):
    return ImmUkfEngine(kf_config(), strapdown(), q_scales=q_scales, p_stay=p_stay,
                        recovery=recovery, recovery_epochs=epochs, **UT)


def combined(mu, filters):
    x = sum(c * f.x for c, f in zip(mu, filters))
    P = sum(c * (f.P + np.outer(f.x - x, f.x - x)) for c, f in zip(mu, filters))
    return x, P


def mix(mu, Pi, filters):
    """The IMM interaction: each model starts from the mixture its predecessors give it."""
    c_bar = Pi.T @ mu
    weights = Pi * mu[:, None] / c_bar[None, :]             # mu_{i|j}
    starts = [combined(weights[:, j], filters) for j in range(len(filters))]
    for flt, (x, P) in zip(filters, starts):
        flt.x, flt.P = x, P
    return c_bar


def imm_update(reference, mu, z, R):
    """Every model updated, probabilities from the likelihoods, combined estimate fed back."""
    likelihood = np.exp([f.update(z, lambda x: x[:3], R)["log_likelihood"]
                         for f in reference.filters])
    mu = mu * likelihood / (mu @ likelihood)
    dx, _ = combined(mu, reference.filters)
    reference.feed_back(dx)
    for f in reference.filters:
        f.x = f.x - dx
    return mu


def test_imm_cycles_by_hand():
    Pi = np.array([[0.9, 0.1], [0.1, 0.9]])
    engine = imm_engine([1.0, 1e5])
    reference = Reference(q_scales=(1.0, 1e5))
    R = engine.R0
    mu = np.array([0.5, 0.5])
    for cycle, z in enumerate(([2.0, -1.0, 0.5], [-3.0, 4.0, 1.0], [0.5, 0.5, -6.0])):
        mu = mix(mu, Pi, reference.filters)
        run(engine, reference, 10, first=10 * cycle)
        x, P = combined(mu, reference.filters)
        v = np.array(z) - x[:3]
        result = engine.update(np.array(z))
        assert result.nis == pytest.approx(v @ np.linalg.solve(P[:3, :3] + R, v), rel=1e-9)
        np.testing.assert_allclose(result.innovation, v, rtol=1e-9)
        np.testing.assert_allclose(result.S, P[:3, :3] + R, rtol=1e-9)
        mu = imm_update(reference, mu, np.array(z), R)
        np.testing.assert_allclose(engine.model_probabilities, mu, rtol=1e-9)
        assert engine.q_scale == pytest.approx(mu @ [1.0, 1e5], rel=1e-9)
        assert result.q_scale == engine.q_scale
        for flt, ref in zip(engine.bank.filters, reference.filters):
            np.testing.assert_allclose(flt.x, ref.x, rtol=0, atol=1e-9 * P0_SIGMA.min())
            assert_same_covariance(flt.P, ref.P)
        assert_same_navigation(engine.nav, reference.nav)
    assert engine.n_updates == 3
    assert abs(mu[0] - 0.5) > 5e-4           # the likelihoods moved the probabilities
    assert_same_covariance(engine.covariance(), combined(mu, reference.filters)[1])
    engine.propagate(*increments(30), DT)
    expected = np.diagonal(combined(mu, reference.filters)[1]) + engine.q_scale * Q_DENSITY * DT
    np.testing.assert_allclose(engine.covariance_diagonal(), expected, rtol=1e-9)


def test_imm_of_one_model_is_the_ukf():
    engine, ukf = imm_engine([1.0]), UkfEngine(kf_config(), strapdown(), **UT)
    for k in range(7):
        engine.propagate(*increments(k), DT)
        ukf.propagate(*increments(k), DT)
    z = np.array([2.0, -1.0, 0.5])
    a, b = engine.update(z), ukf.update(z)
    assert a.nis == pytest.approx(b.nis, rel=1e-9)
    assert_same_covariance(engine.covariance(), ukf.covariance())


def test_imm_reacquisition_inflates_every_model_and_recombines():
    engine = imm_engine([1.0, 1e5], recovery=True, epochs=2)
    for second in range(2):
        for k in range(50):
            engine.propagate(*increments(50 * second + k), DT)
        engine.update(engine.bank.x[:3])
    for k in range(150):
        engine.propagate(*increments(100 + k), DT)
    bank = engine.bank
    mu = bank.mu.copy()
    x, P = combined(mu, bank.filters)
    z = x[:3] + np.array([40.0, -30.0, 20.0])
    lam = inflation_by_hand(z - x[:3], P[:3, :3], engine.R0, 3.0)
    inflated = [UnscentedKalmanFilter(15, x0=f.x, P0=inflated_by_hand(f.P, lam))
                for f in bank.filters]
    x, P = combined(mu, inflated)
    v = z - x[:3]
    result = engine.update(z)
    assert engine.guard.n_reacquired == 1
    assert result.nis == pytest.approx(v @ np.linalg.solve(P[:3, :3] + engine.R0, v), rel=1e-9)
    # the models' spread is not inflated, so the NIS of the mixture is a little over 3
    assert 3.0 < result.nis < 3.1


def test_repeated_reacquisitions_keep_the_attitude_within_its_initial_sigma():
    """The failing case behind 'the state predicted by f or Q contains NaN': CtfaUkf with
    the guard re-acquiring at every fix (recovery_epochs = 1, fixes 10 intervals apart, each
    30 m off).  Each re-acquisition multiplied the attitude variance by lambda and no fix
    brought it back: 1e30 rad after 36 of them, then NaN.  Now the attitude stays near its
    initial sigma and every update is finite."""
    engine = CtfaUkfEngine(kf_config(6), strapdown(), q_max_scale=1.0, t1=0.0, t2=0.0,
                           pass_decay=1.0, recovery=True, recovery_epochs=1, **UT)
    z = np.array([30.0, -20.0, 25.0, 3.0, -2.0, 1.0])
    for k in range(40):
        for j in range(10):
            engine.propagate(*increments(j), DT)
        engine.update(z if k % 2 else -z)
        sigma = np.sqrt(np.diag(engine.covariance()))
        # the inflation stops at the initial sigma (Q held at its configured value by
        # q_max_scale = 1: the process noise adds 4 % over the 40 s)
        assert np.all(sigma[6:9] <= 1.1 * P0_SIGMA[6:9]), (k, sigma[6:9])
        assert np.isfinite(engine.covariance()).all()
    assert engine.guard.n_reacquired >= 36
