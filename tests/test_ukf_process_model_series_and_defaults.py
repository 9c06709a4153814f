"""The UKF process model's small-angle series, bias defaults and a large bias error.

Near a zero attitude error the Rodrigues coefficients and the rotation vector's kinematic
coefficient are taken from their Taylor series (``sin t / t = 1 - t^2/6 + t^4/120``, ``(1 -
cos t) / t^2 = 1/2 - t^2/24 + t^4/720``, ``c(t) = 1/12 + t^2/720 + t^4/30240``), written out here
to one more term; the centre point after feedback is exactly zero and must not warn.
"""
from __future__ import annotations


import numpy as np
import pytest
from test_ukf_process_model import TAU_A, TAU_G, points, reference_derivative  # noqa: F401

from navcore.filters.ukf_time_update import (_inverse_jacobian_apply, _rodrigues_coefficients,
                                             error_dynamics, propagate_points)


def test_rodrigues_coefficients_by_their_series():
    assert _rodrigues_coefficients(0.0) == (1.0, 0.5)       # 0 / 0 is not evaluated
    a, b = _rodrigues_coefficients(9e-13)
    assert a == pytest.approx(1.0 - 9e-13 / 6.0 + 81e-26 / 120.0, rel=2e-16, abs=0)
    assert b == pytest.approx(0.5 - 9e-13 / 24.0 + 81e-26 / 720.0, rel=4e-16, abs=0)


def test_inverse_jacobian_by_its_series():
    # w perpendicular to phi: phi x (phi x w) = -|phi|^2 w, so J^-1 w = w - phi x w / 2 - c t^2 w
    phi = np.array([6e-5, -3e-5, 6e-5])                     # |phi|^2 = 8.1e-9
    w = np.array([1.0, 4.0, 1.0])
    t2 = float(np.sum(phi ** 2))
    c = 1.0 / 12.0 + t2 / 720.0 + t2 ** 2 / 30240.0
    expected = w - 0.5 * np.cross(phi, w) - c * t2 * w
    got = _inverse_jacobian_apply(*phi, *w, t2)
    at_zero = _inverse_jacobian_apply(0.0, 0.0, 0.0, *w, 0.0)   # 0 / 0 is not evaluated
    np.testing.assert_allclose(got, expected, rtol=2e-16, atol=0)
    assert at_zero == tuple(w)


def test_bias_errors_are_random_constants_by_default(points):
    X, nom = points
    Xdot = error_dynamics(X, nom)
    assert np.array_equal(Xdot[:, 9:15], np.zeros((31, 6)))
    Y = propagate_points(X, nom)
    assert np.array_equal(Y[:, 9:15], X[:, 9:15])


def test_bias_errors_of_short_correlation_times(points):
    X, nom = points
    Xdot = error_dynamics(X, nom, 0.5, 0.25)
    np.testing.assert_allclose(Xdot[:, 9:12], -X[:, 9:12] / 0.5, rtol=1e-15)
    np.testing.assert_allclose(Xdot[:, 12:15], -X[:, 12:15] / 0.25, rtol=1e-15)


def test_a_large_gyro_bias_error_is_no_attitude_error(points):
    # 0.05 rad/s of gyro bias error on a point without attitude error: the velocity rows
    # see no rotation of the specific force
    X, nom = points
    X = X[:4].copy()
    X[:, 9:12] = [0.05, -0.04, 0.03]
    X[3, 6:9] = 0.0
    Xdot = error_dynamics(X, nom, TAU_G, TAU_A)
    ref = np.array([reference_derivative(x, nom) for x in X])
    np.testing.assert_allclose(Xdot[:, 0:6], ref[:, 0:6], rtol=1e-9, atol=1e-15)
