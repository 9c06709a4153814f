"""The UKF's process model over all sigma points (navcore.filters.ukf_time_update.error_dynamics)
against a
point-by-point reference written independently: scipy rotations for exp([phi x]), numpy
cross products, textbook earth and transport rates, and the rotation vector's rate taken by
central differences of exp(eps w_s) exp([phi x]) (so the kinematics' convention is checked,
not only its algebra).  The UKF on that model against filterpy's UKF."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navcore.ins import earth
from navcore.filters.ukf_time_update import (NominalInterval, discrete_process_noise,
                                             error_dynamics, propagate_points)
from navcore.filters.unscented import UnscentedKalmanFilter

TAU_G, TAU_A = 3600.0, 1800.0


def nav_rates(lat, h, v, rn, re):
    """(w_ie + w_en, 2 w_ie + w_en) in NED (Groves 5.41, 5.44) with the radii given."""
    w_ie = earth.earth_rate_ned(lat)
    w_en = np.array([v[1] / (re + h), -v[0] / (rn + h), -v[1] * np.tan(lat) / (re + h)])
    return w_ie + w_en, 2.0 * w_ie + w_en


def rotation_vector_rate(phi, w_s, step=1e-5):
    """d(phi)/dt of R = exp([phi x]) turning with spatial rate w_s (dR/dt = [w_s x] R), by
    central differences over a turn of ``step`` rad."""
    norm = np.linalg.norm(w_s)
    if norm == 0.0:
        return np.zeros(3)
    eps = step / norm
    R = Rotation.from_rotvec(phi)
    ahead = (Rotation.from_rotvec(eps * w_s) * R).as_rotvec()
    behind = (Rotation.from_rotvec(-eps * w_s) * R).as_rotvec()
    return (ahead - behind) / (2.0 * eps)


def reference_derivative(x, nom):
    """Module docstring of navcore.filters.ukf_time_update, one point; radii at the computed
    latitude."""
    dr, dv, phi, dbg, dba = x[0:3], x[3:6], x[6:9], x[9:12], x[12:15]
    rn, re = earth.radii(nom.lat)
    w_in_c, w_cor_c = nav_rates(nom.lat, nom.h, nom.v, rn, re)
    v_t = nom.v - dv
    w_in_t, w_cor_t = nav_rates(nom.lat - dr[0] / (rn + nom.h), nom.h + dr[2], v_t, rn, re)
    R = Rotation.from_rotvec(phi).as_matrix()
    w_s = R @ (w_in_c - nom.C @ dbg) - w_in_t
    ddv = (
        (nom.f - R @ nom.f)
        + R @ (nom.C @ dba)
        - (np.cross(w_cor_c, nom.v) - np.cross(w_cor_t, v_t))
    )
    ddv[2] += 2.0 * earth.gravity(nom.lat, nom.h) / np.sqrt(rn * re) * dr[2]
    return np.concatenate([dv, ddv, rotation_vector_rate(phi, w_s), -dbg / TAU_G, -dba / TAU_A])


@pytest.fixture(scope="module")
def points():
    rng = np.random.default_rng(7)
    scale = np.array([5.0] * 3 + [0.2] * 3 + [3e-3] * 3 + [2e-5] * 3 + [2e-3] * 3)
    X = rng.standard_normal((31, 15)) * scale
    X[0] = 0.0                                    # the centre point after feedback
    X[1, 6:9] = [0.2, -0.3, 0.1]                  # a large attitude error (0.37 rad)
    X[2, 6:9] = [3e-9, 0.0, -1e-9]                # inside the series branches
    C = Rotation.from_euler("ZYX", [2.1, 0.05, -0.2]).as_matrix()
    nom = NominalInterval(0.1, 0.61, 850.0, np.array([42.0, -17.0, 1.5]), C,
                          np.array([0.8, -1.1, -9.6]))
    return X, nom


def test_process_model_matches_pointwise_reference(points):
    X, nom = points
    Xdot = error_dynamics(X, nom, TAU_G, TAU_A)
    ref = np.array([reference_derivative(x, nom) for x in X])
    # position, velocity and bias rows: the same formulas in another form, rounding level
    for rows in (slice(0, 6), slice(9, 15)):
        np.testing.assert_allclose(Xdot[:, rows], ref[:, rows], rtol=1e-9, atol=1e-15)
    # attitude rows: central differences, truncation ~step^2 = 1e-10, rounding ~1e-16/step
    for got, want in zip(Xdot[1:, 6:9], ref[1:, 6:9]):
        assert np.linalg.norm(got - want) <= 1e-8 * np.linalg.norm(want), (got, want)


def test_propagated_points_are_one_step_with_second_order_position(points):
    X, nom = points
    Xdot = np.array([reference_derivative(x, nom) for x in X])
    T = nom.T
    expected = X + T * Xdot
    expected[:, 0:3] += 0.5 * T * T * Xdot[:, 3:6]
    np.testing.assert_allclose(propagate_points(X, nom, TAU_G, TAU_A), expected,
                               rtol=1e-9, atol=1e-12)


def test_points_of_several_filters_in_one_call_propagate_as_alone(points):
    """What the IMM bank relies on when it propagates all models' points in one call: each
    row's result depends on that row only, bit for bit."""
    X, nom = points
    rng = np.random.default_rng(8)
    other = X[::-1] * rng.uniform(0.5, 2.0, size=X.shape)
    together = propagate_points(np.concatenate([X, other]), nom, TAU_G, TAU_A)
    assert np.array_equal(together[:31], propagate_points(X, nom, TAU_G, TAU_A))
    assert np.array_equal(together[31:], propagate_points(other, nom, TAU_G, TAU_A))


def test_ukf_on_the_error_model_matches_filterpy(points):
    """Ours (all points through the model at once, fresh points for every update) against
    filterpy's UKF (the model point by point; its update points redrawn from the predicted
    mean and covariance, as ours): paper 000's sensors, 2 s of 10 Hz predictions, 1 Hz fixes."""
    from filterpy.kalman import MerweScaledSigmaPoints
    from filterpy.kalman import UnscentedKalmanFilter as FilterpyUkf

    _, nom = points
    deg_h, ug = np.radians(1.0) / 3600.0, 9.80665e-6
    q_density = np.array([0.0] * 3 + [(10.0 * ug) ** 2] * 3 + [(np.radians(0.06) / 60.0) ** 2] * 3
                         + [(0.5 * deg_h) ** 2 / 1800.0] * 3 + [(10.0 * ug) ** 2 / 900.0] * 3)
    Q = discrete_process_noise(q_density, nom.T)
    R = np.diag([2.56, 4.42, 3.43]) ** 2
    P0 = np.diag(np.array([3.0] * 3 + [0.02, 0.02, 0.01] + [1e-4, 1e-4, 1e-3]
                          + [5.0 * deg_h] * 3 + [100.0 * ug] * 3) ** 2)
    ours = UnscentedKalmanFilter(15, x0=np.zeros(15), P0=P0)
    ref = FilterpyUkf(dim_x=15, dim_z=3, dt=nom.T, hx=lambda x: x[:3],
                      fx=lambda x, dt: propagate_points(x[None, :], nom, TAU_G, TAU_A)[0],
                      points=MerweScaledSigmaPoints(15, alpha=1.0, beta=2.0, kappa=0.0))
    ref.x, ref.P, ref.Q, ref.R = np.zeros(15), P0.copy(), Q, R
    rng = np.random.default_rng(9)
    for k in range(20):
        ours.predict(propagate_points, Q, nom, TAU_G, TAU_A, vectorized=True)
        ref.predict()
        if k % 10 == 9:
            z = rng.normal(size=3) * np.array([2.56, 4.42, 3.43])
            ours.update(z, lambda X: X[:, :3], R, vectorized=True)
            ref.compute_process_sigmas(nom.T, fx=lambda x, dt: x)
            ref.update(z)
    sd = np.sqrt(np.diagonal(ref.P))
    assert np.all(np.abs(ours.x - ref.x) <= 1e-12 * sd)
    np.testing.assert_allclose(ours.P / np.outer(sd, sd), ref.P / np.outer(sd, sd), atol=1e-12)
