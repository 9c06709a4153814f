"""The AHRS engine (navcore.filters.ahrs) piece by piece against references written out here:
the Hamilton product and rotation-vector quaternions by hand and through scipy's Rotation, one
UKF time update and one measurement update against filterpy's UKF with the process and
measurement models of the module docstring written with scipy, the MRP shadow switch with its
Jacobian by hand, the Euler 1-sigma against the linearized covariance, and the fuzzy R
adaptation (paper 003 eqs. 15-19, 25) on a window of two worked out by hand."""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from filterpy.kalman import MerweScaledSigmaPoints
from filterpy.kalman import UnscentedKalmanFilter as FilterpyUkf
from scipy.spatial.transform import Rotation

from navcore.core.state import capture, restore
from navcore.errors import InputError, StateError
from navcore.filters import ahrs
from navcore.filters.ahrs import FuzzyAdaptiveR, UkfAhrsEngine, quat_euler, triad_attitude

G, H, INCL = 9.8, 5.0e-5, math.radians(60.0)
R_ACCEL, R_MAG = 0.05, 2.0e-7
ARW, BIAS_RW = 2.0e-3, 1.0e-4
ALPHA, BETA, KAPPA = 0.5, 2.0, 1.0           # point 0 weighted: lambda = 0.25 * 7 - 6 < 0


def _engine(adaptive=None, p0_att=0.05, p0_bias=2e-3):
    return UkfAhrsEngine(G, H, INCL, ARW, BIAS_RW, R_ACCEL, R_MAG, p0_att, p0_bias,
                         ALPHA, BETA, KAPPA, adaptive=adaptive)


def _scalar_first(rotation):
    x, y, z, w = rotation.as_quat()
    return np.array([w, x, y, z]) * (1.0 if w >= 0 else -1.0)


def _same_rotation(q, rotation, atol=1e-12):
    q = np.asarray(q) * (1.0 if q[0] >= 0 else -1.0)
    np.testing.assert_allclose(q, _scalar_first(rotation), atol=atol)


# -- quaternions ---------------------------------------------------------------------------
def test_hamilton_products_by_hand():
    """(1 + 2i + 3j + 4k)(5 + 6i + 7j + 8k) = -60 + 12i + 30j + 24k; i j = k, j i = -k."""
    assert ahrs._qmul((1.0, 2.0, 3.0, 4.0), (5.0, 6.0, 7.0, 8.0)) == (-60.0, 12.0, 30.0, 24.0)
    assert ahrs._qmul((0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0)) == (0.0, 0.0, 0.0, 1.0)
    assert ahrs._qmul((0.0, 0.0, 1.0, 0.0), (0.0, 1.0, 0.0, 0.0)) == (0.0, 0.0, 0.0, -1.0)


def _sin_half_over_t(t):
    """sin(t/2)/t from its Taylor series in exact fractions (three terms: enough below 1e-6)."""
    x = Fraction(t) / 2
    return float((1 - x * x / 6 + x ** 4 / 120) / 2)


def test_rotation_vector_quaternions_against_scipy_and_the_series():
    for vector in ([0.0, 0.0, math.pi / 2], [0.3, -0.4, 1.2], [2e-6, 0.0, 0.0]):
        _same_rotation(ahrs._rotvec_quat(*vector), Rotation.from_rotvec(vector), atol=1e-16)
    assert ahrs._rotvec_quat(0.0, 0.0, 0.0) == (1.0, 0.0, 0.0, 0.0)
    # below 1e-6 rad the series: sin(t/2)/t correctly rounded (half of 2**-54 below 0.5)
    t = 2.0 ** -20
    assert abs(ahrs._rotvec_quat(t, 0.0, 0.0)[1] / t - _sin_half_over_t(t)) <= 2.0 ** -55
    assert abs(ahrs._rotvec_quat(0.0, 0.0, -t)[3] / -t - _sin_half_over_t(t)) <= 2.0 ** -55
    # at 1e-6 rad too (|(6e-7, 8e-7, 0)| = 1e-6 exactly), where sin(t/2)/t in floats is off
    # by 0.7 of 2**-54 and the vector part would be another float
    s = _sin_half_over_t(1e-6)
    assert ahrs._rotvec_quat(6e-7, 8e-7, 0.0)[1:] == (s * 6e-7, s * 8e-7, 0.0)


def test_bias_quaternions_are_those_of_minus_b_t():
    """The bias rotation of the time update (propagate_points: the quaternion of -b T)."""
    T = 0.5
    b = np.array([[0.4, -0.8, 2.0], [1e-3, 2e-3, -3e-3], [0.0, 0.0, 0.0],
                  [2.0 ** -19, 0.0, 0.0], [0.0, 1.5, 0.0], [1.2e-6, 1.6e-6, 0.0]])
    q = np.array([ahrs._rotvec_quat(*(-row * T)) for row in b])
    for row, quat in zip(b, q):
        _same_rotation(quat, Rotation.from_rotvec(-row * T), atol=1e-16)
    # |b T| of rows 3 and 5, 2**-20 and 1e-6 (as above): the series, correctly rounded
    assert abs(q[3, 1] / -2.0 ** -20 - _sin_half_over_t(2.0 ** -20)) <= 2.0 ** -55
    s = _sin_half_over_t(1e-6)
    assert q[5, 1:].tolist() == [s * -6e-7, s * -8e-7, 0.0]
    assert q[2].tolist() == [1.0, 0.0, 0.0, 0.0]


def test_euler_angles_of_quaternions():
    rotation = Rotation.from_euler("ZYX", [2.0, -0.5, 0.7])
    q = _scalar_first(rotation)
    np.testing.assert_allclose(quat_euler(tuple(q)), [0.7, -0.5, 2.0], atol=1e-14)
    np.testing.assert_allclose(quat_euler(tuple(3.0 * q)), [0.7, -0.5, 2.0], atol=1e-14)
    # a yaw of 180 deg whose atan2 gives -pi (w z + x y = -0.0, as a -0.0 component makes
    # it) is reported as +pi, as one with +0.0 is
    assert quat_euler((0.0, -0.0, 0.0, -1.0))[2] == math.pi
    assert quat_euler((0.0, 0.0, 0.0, 1.0)) == (0.0, 0.0, math.pi)


def test_triad_takes_directions_only():
    """TRIAD uses the directions of the two vectors: a specific force of any size (here
    0.5 m/s^2) gives the attitude of the same direction."""
    C_bn = Rotation.from_euler("ZYX", [-1.0, 0.3, -0.6]).as_matrix()
    f_b = C_bn.T @ [0.0, 0.0, -0.5]
    m_b = C_bn.T @ [H * math.cos(INCL), 0.0, H * math.sin(INCL)]
    np.testing.assert_allclose(triad_attitude(f_b, m_b, INCL), C_bn, atol=1e-12)


def test_triad_refuses_a_zero_or_parallel_pair():
    with pytest.raises(InputError, match="zero or parallel"), np.errstate(invalid="ignore"):
        triad_attitude([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], INCL)
    with pytest.raises(InputError, match="zero or parallel"):
        triad_attitude([0.0, 0.0, -9.8], [0.0, 0.0, 3e-5], INCL)


# -- the UKF against filterpy --------------------------------------------------------------
def _mrp(rotation):
    return rotation.as_mrp()


def _process_by_hand(x, T, increments):
    """Module docstring: q(sigma+) = q(sigma) (x) dq (x) q(-b T), b+ = b, with scipy."""
    rotation = Rotation.from_mrp(x[:3])
    for dtheta in increments:
        rotation = rotation * Rotation.from_rotvec(dtheta)
    rotation = rotation * Rotation.from_rotvec(-x[3:] * T)
    return np.concatenate((_mrp(rotation), x[3:]))


def _measurement_by_hand(x):
    """Module docstring: z = [C_bn^T (0, 0, -g), C_bn^T (cos I, 0, sin I)]."""
    C_bn = Rotation.from_mrp(x[:3]).as_matrix()
    return np.concatenate((C_bn.T @ [0.0, 0.0, -G], C_bn.T @ [math.cos(INCL), 0.0,
                                                             math.sin(INCL)]))


def _filterpy(x, P):
    ukf = FilterpyUkf(dim_x=6, dim_z=6, dt=1.0, hx=_measurement_by_hand, fx=None,
                      points=MerweScaledSigmaPoints(6, ALPHA, BETA, KAPPA))
    ukf.x, ukf.P = x.copy(), P.copy()
    return ukf


START = Rotation.from_euler("ZYX", [2.0, -0.2, 0.3])
BIAS = np.array([1e-3, -2e-3, 5e-4])
INCREMENTS = [np.array([0.01, -0.02, 0.03]), np.array([0.015, 0.0, -0.01]),
              np.array([-0.005, 0.02, 0.02])]


def _started(**kwargs):
    engine = _engine(**kwargs)
    engine.start(START.as_matrix())
    engine.ukf.x[3:] = BIAS
    return engine


def test_start_takes_the_mrp_of_the_attitude_and_the_initial_sigmas():
    engine = _engine(p0_att=0.04, p0_bias=1e-3)
    engine.start(START.as_matrix())
    np.testing.assert_allclose(engine.ukf.x, np.concatenate((_mrp(START), np.zeros(3))),
                               atol=1e-15)
    # an MRP is tan(angle / 4) along the axis: a 1-sigma angle of 0.04 rad is 0.01 in sigma
    np.testing.assert_allclose(engine.ukf.P, np.diag([1e-4] * 3 + [1e-6] * 3), rtol=1e-15)
    assert engine.started


def test_time_update_against_filterpy_with_the_process_written_out():
    engine = _started()
    x0, P0 = engine.ukf.x.copy(), engine.ukf.P.copy()
    for dtheta in INCREMENTS:
        engine.accumulate(dtheta, 0.01)
    T = 0.03
    assert engine.interval == pytest.approx(T, rel=1e-15)
    _same_rotation(engine.current_quat(), Rotation.from_mrp(
        _process_by_hand(x0, T, INCREMENTS)[:3]))       # the pending update, not applied yet
    engine.predict()
    reference = _filterpy(x0, P0)
    s = x0[:3] @ x0[:3]
    reference.Q = np.diag([ARW ** 2 * T * (1 + s) ** 2 / 16] * 3 + [BIAS_RW ** 2 * T] * 3)
    reference.predict(dt=T, fx=lambda x, dt: _process_by_hand(x, dt, INCREMENTS))
    np.testing.assert_allclose(engine.ukf.x, reference.x, rtol=0, atol=1e-14)
    np.testing.assert_allclose(engine.ukf.P, reference.P, rtol=1e-10, atol=1e-17)
    assert engine.dq == (1.0, 0.0, 0.0, 0.0) and engine.interval == 0.0
    # with nothing accumulated the time update leaves the filter as it is, to the bit
    x1, P1 = engine.ukf.x.copy(), engine.ukf.P.copy()
    engine.predict()
    assert np.array_equal(engine.ukf.x, x1) and np.array_equal(engine.ukf.P, P1)
    _same_rotation(engine.current_quat(), Rotation.from_mrp(x1[:3]), atol=1e-15)


def test_a_wide_spread_of_points_is_continued_in_the_set_of_the_prior_mean():
    """An attitude known to some 110 deg (sigma 0.49 in MRP): the points reach |sigma| = 0.66,
    whose shadows lie nearer a neighbouring point than their own set does; each propagated
    point is kept in the set nearest the prior mean, here the one inside the unit sphere
    that scipy's as_mrp gives."""
    engine = _engine(p0_att=4.0 * math.sqrt(0.24), p0_bias=1e-4)
    engine.start(Rotation.from_euler("ZYX", [0.1, 0.05, -0.05]).as_matrix())
    x0, P0 = engine.ukf.x.copy(), engine.ukf.P.copy()
    for dtheta in INCREMENTS:
        engine.accumulate(dtheta, 0.01)
    engine.predict()
    reference = _filterpy(x0, P0)
    s = x0[:3] @ x0[:3]
    reference.Q = np.diag([ARW ** 2 * 0.03 * (1 + s) ** 2 / 16] * 3 + [BIAS_RW ** 2 * 0.03] * 3)
    reference.predict(dt=0.03, fx=lambda x, dt: _process_by_hand(x, dt, INCREMENTS))
    np.testing.assert_allclose(engine.ukf.x, reference.x, rtol=0, atol=1e-13)
    np.testing.assert_allclose(engine.ukf.P, reference.P, rtol=1e-9, atol=1e-15)


def _measured(attitude_error_deg=(1.0, -2.0, 3.0)):
    truth = START * Rotation.from_euler("xyz", attitude_error_deg, degrees=True)
    C_bn = truth.as_matrix()
    f_b = C_bn.T @ [0.0, 0.0, -G] + [0.01, -0.02, 0.0]
    m_b = H * (C_bn.T @ [math.cos(INCL), 0.0, math.sin(INCL)]) + [1e-7, 0.0, -2e-7]
    return f_b, m_b


def _reference_update(engine, f_b, m_b, r_scale):
    x, P = engine.ukf.x.copy(), engine.ukf.P.copy()
    reference = _filterpy(x, P)
    reference.sigmas_f = reference.points_fn.sigma_points(x, P)
    R = np.diag([R_ACCEL ** 2 * r_scale[0]] * 3 + [(R_MAG / H) ** 2 * r_scale[1]] * 3)
    reference.update(np.concatenate((f_b, m_b / H)), R=R)
    return reference, R


@pytest.mark.parametrize("r_scale", [(1.0, 1.0), (2.0, 0.5)])
def test_measurement_update_against_filterpy_with_the_measurement_written_out(r_scale):
    """R = diag(r_a^2 I, (r_m / H)^2 I), each block times its scale; z = [f_b, m_b / H]."""
    engine = _started()
    engine.r_scale = np.array(r_scale)
    f_b, m_b = _measured()
    reference, _ = _reference_update(engine, f_b, m_b, r_scale)
    innovation = engine.update(f_b, m_b)
    np.testing.assert_allclose(innovation, reference.y, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(engine.ukf.x, reference.x, rtol=0, atol=1e-13)
    np.testing.assert_allclose(engine.ukf.P, reference.P, rtol=1e-9, atol=1e-18)
    nis = reference.y @ np.linalg.solve(reference.S, reference.y)
    assert engine.last_nis == pytest.approx(nis, rel=1e-10)
    assert engine.shadow_switches == 0


class _ScalesGiven:
    """A stand-in adaptation: records what it is given and returns fixed block scales."""

    def __init__(self, scales):
        self.scales, self.calls = np.array(scales), []

    def step(self, innovation, Pzz, R0, r_scale):
        self.calls.append((innovation.copy(), Pzz.copy(), R0.copy(), np.array(r_scale)))
        return self.scales


def test_the_adapted_scales_are_used_in_the_same_update():
    adaptive = _ScalesGiven([3.0, 0.25])
    engine = _started(adaptive=adaptive)
    f_b, m_b = _measured()
    reference, R = _reference_update(engine, f_b, m_b, (3.0, 0.25))
    engine.update(f_b, m_b)
    np.testing.assert_allclose(engine.ukf.x, reference.x, rtol=0, atol=1e-13)
    assert engine.r_scale.tolist() == [3.0, 0.25]
    (innovation, Pzz, R0, before), = adaptive.calls
    np.testing.assert_allclose(innovation, reference.y, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Pzz, reference.S - R, rtol=1e-9, atol=1e-18)
    assert np.array_equal(R0, np.diag([R_ACCEL ** 2] * 3 + [(R_MAG / H) ** 2] * 3))
    assert before.tolist() == [1.0, 1.0]


def test_measurement_model_of_the_points():
    X = np.zeros((3, 6))
    X[:, :3] = [_mrp(START), [0.0, 0.0, 0.0], [0.2, -0.5, 0.4]]
    expected = np.array([_measurement_by_hand(x) for x in X])
    np.testing.assert_allclose(_engine()._measure(X), expected, rtol=0, atol=1e-14)


# -- the shadow set ------------------------------------------------------------------------
P_SHADOW = np.diag([1e-4, 2e-4, 3e-4, 1e-6, 2e-6, 3e-6]) + 5e-5 * (np.eye(6, k=1) + np.eye(6, k=-1))


def test_a_state_outside_the_unit_sphere_switches_to_its_shadow():
    engine = _engine()
    sigma = np.array([0.6, -0.8, 0.5])                 # |sigma|^2 = 1.25
    engine.ukf.x = np.concatenate((sigma, BIAS))
    engine.ukf.P = P_SHADOW.copy()
    engine._switch_to_shadow()
    s = 1.25
    np.testing.assert_allclose(engine.ukf.x[:3], -sigma / s, rtol=1e-15)
    assert engine.ukf.x[3:].tolist() == BIAS.tolist()
    J = np.eye(6)
    J[:3, :3] = (2.0 * np.outer(sigma, sigma) - s * np.eye(3)) / s ** 2   # d(-sigma/s)/dsigma
    np.testing.assert_allclose(engine.ukf.P, J @ P_SHADOW @ J.T, rtol=1e-13, atol=1e-22)
    assert engine.shadow_switches == 1
    np.testing.assert_allclose(Rotation.from_mrp(engine.ukf.x[:3]).as_matrix(),
                               Rotation.from_mrp(sigma).as_matrix(), atol=1e-15)
    engine.ukf.x[:3] = [0.0, 0.0, -1.5]
    engine._switch_to_shadow()
    assert engine.shadow_switches == 2                  # a count of the switches


@pytest.mark.parametrize("sigma", [[0.0, 0.0, 1.0], [0.3, 0.4, -0.5]])
def test_a_state_on_or_inside_the_unit_sphere_stays(sigma):
    engine = _engine()
    engine.ukf.x = np.concatenate((sigma, BIAS))
    engine.ukf.P = P_SHADOW.copy()
    engine._switch_to_shadow()
    assert engine.ukf.x[:3].tolist() == sigma and np.array_equal(engine.ukf.P, P_SHADOW)
    assert engine.shadow_switches == 0


def test_a_time_update_across_180_degrees_ends_in_the_shadow_set():
    """From 178 deg about down, +4 deg: the points continue past |sigma| = 1 (nearest set) and
    the mean switches to the shadow, the attitude that of the rotations composed."""
    engine = _engine(p0_att=1e-4, p0_bias=1e-7)
    start = Rotation.from_rotvec([0.0, 0.0, math.radians(178.0)])
    engine.start(start.as_matrix())
    engine.accumulate([0.0, 0.0, math.radians(4.0)], 0.1)
    engine.predict()
    assert engine.shadow_switches == 1 and engine.ukf.x[:3] @ engine.ukf.x[:3] < 1.0
    _same_rotation(engine.current_quat(),
                   start * Rotation.from_rotvec([0.0, 0.0, math.radians(4.0)]), atol=1e-9)
    assert np.all(np.linalg.eigvalsh(engine.ukf.P) > 0)


# -- Euler angles and their sigmas ---------------------------------------------------------
def _euler_sigma_linearized(sigma, P_sigma):
    """sqrt(diag(J P J^T)) with J = d(roll, pitch, yaw)/d sigma by central differences."""
    def euler(s):
        return Rotation.from_mrp(s).as_euler("ZYX")[::-1]
    h = 1e-6
    J = np.empty((3, 3))
    for i in range(3):
        step = np.zeros(3)
        step[i] = h
        d = euler(sigma + step) - euler(sigma - step)
        J[:, i] = np.angle(np.exp(1j * d)) / (2 * h)
    return np.sqrt(np.diag(J @ P_sigma @ J.T))


@pytest.mark.parametrize("yaw_deg", [115.0, 179.9999])
def test_euler_sigma_is_the_linearized_spread(yaw_deg):
    """Small attitude sigmas: the spread of the points' Euler angles is J P J^T; near yaw 180
    deg the points straddle +-pi and their angles are taken relative to point 0."""
    engine = _engine()
    engine.start(Rotation.from_euler("ZYX", [yaw_deg, -10.0, 20.0], degrees=True).as_matrix())
    P_sigma = np.array([[4e-10, 1e-10, 0.0], [1e-10, 9e-10, -2e-10], [0.0, -2e-10, 1e-9]])
    engine.ukf.P[:3, :3] = P_sigma
    np.testing.assert_allclose(engine.euler_sigma(),
                               _euler_sigma_linearized(engine.ukf.x[:3], P_sigma), rtol=1e-4)
    np.testing.assert_allclose(engine.euler(), np.radians([20.0, -10.0, yaw_deg]), atol=1e-12)
    assert engine.gyro_bias.tolist() == [0.0, 0.0, 0.0]


def test_euler_sigma_of_a_wide_roll_spread_by_hand():
    """Roll only, widely spread: sigma_x = 0.2 +- 0.5, the points at 4 atan(0.7) and
    4 atan(-0.3) (139.9 and -66.8 deg about x, from 45.2 deg): deviations from point 0,
    their weighted mean and spread with the weights of alpha, beta, kappa written out (paper
    000 eqs. 12-13)."""
    n, lam = 6, ALPHA ** 2 * (6 + KAPPA) - 6
    wm0, wc0, wi = lam / (n + lam), lam / (n + lam) + 1 + BETA - ALPHA ** 2, 0.5 / (n + lam)
    engine = _engine()
    engine.ukf.x = np.array([0.2, 0.0, 0.0, 0.0, 0.0, 0.0])
    engine.ukf.P = np.diag([0.25 / (n + lam)] + [1e-14] * 5)
    roll0 = 4 * math.atan(0.2)
    d_plus, d_minus = 4 * math.atan(0.7) - roll0, 4 * math.atan(-0.3) - roll0
    mean = wi * (d_plus + d_minus)                    # the other 10 points deviate by ~0
    spread = wc0 * mean ** 2 + wi * ((d_plus - mean) ** 2 + (d_minus - mean) ** 2
                                     + 10 * mean ** 2)
    assert wm0 + 12 * wi == pytest.approx(1.0, abs=1e-15)
    sigmas = engine.euler_sigma()
    assert sigmas[0] == pytest.approx(math.sqrt(spread), rel=1e-9)
    assert sigmas[0] > 1.3 and np.all(sigmas[1:] < 1e-5)


def test_restoring_a_state_checks_the_kinds_of_the_fields():
    """A saved engine restores into a fresh one; a state whose 'started' is not a bool or
    whose 'last_nis' is not a number is refused naming the field."""
    engine = _started()
    engine.accumulate(INCREMENTS[0], 0.01)
    engine.update(*_measured())
    fresh = _engine()
    restore(fresh, capture(engine))
    assert np.array_equal(fresh.ukf.x, engine.ukf.x) and fresh.started is True
    assert fresh.last_nis == engine.last_nis
    for field, value, message in (("started", 1, "expected bool, got a value of kind int"),
                                  ("last_nis", [0.5], "expected float, got a value of kind "
                                                      "list")):
        tree = capture(engine)
        tree[field] = value
        with pytest.raises(StateError) as exc:
            restore(_engine(), tree)
        assert str(exc.value) == f"UkfAhrsEngine.{field}: {message}"


# -- fuzzy adaptive R ----------------------------------------------------------------------
class _Inference:
    """A stand-in rule base: records (e, de) and returns the next factor of a list, for each
    block its stacked form is called with."""

    def __init__(self, factors):
        self.factors, self.calls = list(factors), []

    def stacked(self, copies):
        return self

    def __call__(self, e, de):
        self.calls += list(zip(e.tolist(), de.tolist()))
        return np.array([self.factors.pop(0) for _ in e.tolist()])


PZZ = np.diag([1.0, 1.0, 1.0, 4.0, 4.0, 4.0]) + 0.3 * (np.eye(6, k=1) + np.eye(6, k=-1))
R0 = np.diag([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])


def test_fuzzy_adaptation_on_a_window_of_two_by_hand():
    inference = _Inference([0.8, 4.0, 0.1, 0.9])
    adaptive = FuzzyAdaptiveR(inference, window=2, r_scale_min=0.5, r_scale_max=2.0)
    one = np.array([1.0, 1.0])
    # first innovation: the window is not full, the scales stay
    assert adaptive.step(np.array([2.0, 0, 0, 0, 0, 0]), PZZ, R0, one) is one
    assert inference.calls == []
    # second: C_z = mean of r^2 = (2, 2, 0, 4.5, 4.5, 0), P_z = (2, 2, 2, 6, 6, 6)
    new = adaptive.step(np.array([0.0, 2, 0, 3, 3, 0]), PZZ, R0, one)
    assert inference.calls == [(pytest.approx(-1 / 3, abs=1e-15), 0.0),
                               (pytest.approx(-1 / 2, abs=1e-15), 0.0)]
    assert new.tolist() == [0.8, 2.0]                  # 1 * 0.8; 1 * 4.0 clipped at 2
    # third replaces the first: C_z = (0, 2, 4.5, 4.5, 4.5, 8), P_z = (1.8 x 3, 8 x 3)
    inference.calls.clear()
    newer = adaptive.step(np.array([0.0, 0, 3, 0, 0, 4]), PZZ, R0, new)
    (e_acc, de_acc), (e_mag, de_mag) = inference.calls
    assert (e_acc, de_acc) == (pytest.approx(11 / 54, abs=1e-15),
                               pytest.approx(11 / 54 + 1 / 3, abs=1e-15))
    assert (e_mag, de_mag) == (pytest.approx(-7 / 24, abs=1e-15),
                               pytest.approx(-7 / 24 + 1 / 2, abs=1e-15))
    assert newer.tolist() == [0.5, pytest.approx(1.8, abs=1e-15)]   # 0.08 clipped at 0.5
    np.testing.assert_allclose(adaptive.e, [11 / 54, -7 / 24], atol=1e-15)
    assert new.tolist() == [0.8, 2.0]                  # the scales given are not changed
