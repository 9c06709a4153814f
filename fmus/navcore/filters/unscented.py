"""Generic unscented Kalman filter core (paper 000, Yang et al. 2018, eqs. 11-23).

This module is plain numpy: the model is given as callables ``f(x, *args)`` (process) and
``h(x, *args)`` (measurement) over numpy arrays, so the same core serves the 15-state INS/GNSS
error filter of paper 000 (nonlinear large-misalignment attitude error propagation, paper 000 eq. 1,
position measurement paper 000 eqs. 3-4), the AHRS filters and the tests' linear models.

Scaled unscented transform (paper 000 eqs. 11-13, after Julier 2002, ref. [17])
------------------------------------------------------------------------------
For a state of dimension ``n`` with mean ``x`` and covariance ``P``::

    lambda = alpha^2 (n + kappa) - n
    chi_0      = x
    chi_i      = x + (sqrt((n + lambda) P))_i          i = 1..n
    chi_{n+i}  = x - (sqrt((n + lambda) P))_i          i = 1..n        (paper 000 eq. 11)
    Wm_0 = lambda / (n + lambda),  Wm_i = 1 / (2 (n + lambda))          (paper 000 eq. 12)
    Wc_0 = lambda / (n + lambda) + 1 + beta - alpha^2,  Wc_i = Wm_i     (paper 000 eq. 13)

``(sqrt(A))_i`` is the i-th *column* of a matrix square root ``L`` with ``L L^T = A`` (the paper's
text says "i-th diagonal element", a slip: the columns are what makes the transform reproduce
``P``).  The paper also writes ``n = 2(n_x + n_v + n_xi)`` and sums paper 000 eqs. 15-20 over ``i =
0..n``; the scaled UT uses ``n = n_x + n_v + n_xi`` (augmented dimension) and ``2n + 1`` points,
which is what is implemented here.

Parameters alpha, beta, kappa
-----------------------------
Paper 000 gives no values; it only states ``0 <= alpha <= 1``, that beta tunes the accuracy of
the covariance (beta = 2 is optimal for Gaussian priors) and that kappa should keep the
posterior covariance positive semi-definite.  The classic choice ``alpha = 1e-3`` puts the points
at ``1e-3 sqrt(n)`` sigma and gives weights of order ``1/alpha^2 = 1e6`` with opposite signs: for a
15-state error filter whose states span nine orders of magnitude (m, m/s, rad, rad/s, m/s^2) that
costs ~6 significant digits in the covariance sums.  ``kappa = 3 - n`` (Julier's fourth-moment
match) gives ``Wm_0 = (3 - n)/3 = -4`` for n = 15, a negative weight that can make the predicted
covariance indefinite.  The default here is therefore ``alpha = 1, beta = 2, kappa = 0``:
``lambda = 0``, all covariance weights positive (``Wc_0 = 2``, ``Wc_i = 1/(2n)``), points at
``sqrt(n)`` sigma (3.9 sigma for n = 15), so the predicted covariance is a positive combination
of outer products, PSD by construction.  Any other set with ``n + lambda > 0`` can be passed.

Additive versus augmented noise
-------------------------------
The paper augments the state with process and measurement noise (paper 000 eqs. 9-10) so that noise
may enter ``f`` and ``h`` nonlinearly.  This core uses the additive form ``x_{k+1} = f(x_k) +
w_k``, ``z_k = h(x_k) + xi_k``: the predicted covariance is the transformed covariance plus ``Q``
and the innovation covariance is the transformed one plus ``R``.  The two forms give identical
first and second moments whenever the noise enters the discrete model linearly and additively
(``f(x, w) = f(x) + G w`` with ``G Q G^T`` passed as ``Q``), which is the case of the paper's error
model (paper 000 eq. 1: the sensor noises enter through ``C delta f^b`` and ``C delta omega^b``,
linear in the noise for a given attitude; paper 000 eq. 3: ``z = H x + xi``).  When noise enters
nonlinearly (e.g. multiplied by an attitude error state) the augmented form additionally captures
the state-noise cross terms, which are of higher order in the (small) noise; the additive form
drops them and costs ``2 n_x + 1`` instead of ``2 (n_x + n_v + n_xi) + 1`` model evaluations (31
instead of 67 for the paper's 15 + 15 + 3 dimensions).

Prediction and update
---------------------
``predict`` draws sigma points from ``(x, P)``, propagates them through ``f`` (paper 000 eq. 14)
and forms the mean and covariance (paper 000 eqs. 15-16) plus ``Q``.  ``update`` draws a fresh set
of points from the predicted ``(x, P)`` (needed because with additive noise the propagated points
do not carry ``Q``, and because several predictions may run between two measurements), maps them
through ``h`` (paper 000 eq. 17) and applies paper 000 eqs. 18-23 with ``P_zz`` including ``R``.
It returns the innovation, its covariance ``S`` and the normalized innovation squared ``NIS = v^T
S^-1 v`` (the paper's chi-square statistic, paper 000 eq. 24) and the Gaussian log-likelihood of
the innovation (for IMM).
"""
from __future__ import annotations

import math
from typing import Any, Callable, Dict, List, NamedTuple, Optional, Tuple

import numpy as np
from scipy.linalg import lapack

from navcore.errors import InputError, ParameterError
from navcore.filters.unscented_rows import (correct_rows, correction_error, eigen_sqrt,
                                            measurement_moments_rows, points_from_sqrt_rows,
                                            predicted_moments_rows, predicted_state_error,
                                            state_error)


# ---------------------------------------------------------------------------------------
# Scaled unscented transform
# ---------------------------------------------------------------------------------------
def sigma_weights(n: int, alpha: float = 1.0, beta: float = 2.0,
                  kappa: float = 0.0) -> Tuple[np.ndarray, np.ndarray, float]:
    """Weights of the scaled unscented transform, paper 000 eqs. 12-13.

    Returns ``(Wm, Wc, lambda_)`` with ``Wm``, ``Wc`` of length ``2n + 1`` and
    ``lambda_ = alpha^2 (n + kappa) - n`` (paper 000 eq. 11).  ``Wm`` sums to 1; ``Wc`` sums to
    ``2 + beta - alpha^2``.  Raises :class:`ParameterError` unless ``n >= 1``, ``alpha > 0`` and
    ``n + lambda_ > 0`` (the points are spread by ``sqrt(n + lambda_)``).
    """
    if int(n) != n or n < 1:
        raise ParameterError(
            f"sigma_weights: state dimension 'n' must be a positive integer, got {n}"
        )
    n = int(n)
    for name, value in (("alpha", alpha), ("beta", beta), ("kappa", kappa)):
        if not math.isfinite(value):
            raise ParameterError(f"sigma_weights: parameter '{name}' must be finite, got {value}")
    if alpha <= 0.0:
        raise ParameterError(f"sigma_weights: parameter 'alpha' must be > 0, got {alpha}")
    lambda_ = alpha * alpha * (n + kappa) - n
    if n + lambda_ <= 0.0:
        raise ParameterError(
            f"sigma_weights: n + lambda = alpha^2 (n + kappa) = {n + lambda_} must be > 0 "
            f"(n={n}, alpha={alpha}, kappa={kappa}); increase 'kappa'")
    Wm = np.full(2 * n + 1, 0.5 / (n + lambda_))
    Wc = Wm.copy()
    Wm[0] = lambda_ / (n + lambda_)
    Wc[0] = lambda_ / (n + lambda_) + 1.0 + beta - alpha * alpha
    return Wm, Wc, float(lambda_)


def matrix_sqrt(A: np.ndarray) -> Tuple[np.ndarray, bool]:
    """Square root ``L`` with ``L L^T = A`` of a symmetric PSD matrix; ``(L, used_fallback)``.

    The matrix is symmetrized first (round-off makes covariances slightly asymmetric).  The
    lower Cholesky factor is used when it exists.  When it does not (a covariance that lost
    positive definiteness by round-off, or a singular one with exact zero variances, e.g. a
    state that is not excited), the eigen-decomposition ``A = V D V^T`` is used with the
    eigenvalues floored at 0 and ``L = V sqrt(D)``: the nearest PSD matrix in Frobenius norm,
    so the points still reproduce every non-negative direction of ``A``.  ``A`` must be finite.
    """
    return _sqrt_symmetric(0.5 * (A + A.T))


def _sqrt_symmetric(A: np.ndarray) -> Tuple[np.ndarray, bool]:
    # LAPACK dpotrf reads only the lower triangle of an already symmetric A; called directly
    # it costs ~2.5 us for n = 15 against ~6.5 us for numpy.linalg.cholesky (sigma_points_rows
    # calls the same routine from a kernel for many matrices)
    L, info = lapack.dpotrf(A, lower=1, clean=1)
    if info == 0:
        return L, False
    return eigen_sqrt(A), True


def sigma_points(x: np.ndarray, P: np.ndarray, lambda_: float) -> np.ndarray:
    """Sigma points of paper 000 eq. 11 as an array of shape ``(2n + 1, n)`` (one point per row).

    Row 0 is ``x``; rows ``1..n`` are ``x + L[:, i]`` and rows ``n+1..2n`` are ``x - L[:, i]``
    with ``L L^T = (n + lambda_) P`` (Cholesky, eigen-decomposition fallback: see
    :func:`matrix_sqrt`).  Raises :class:`InputError` on non-finite ``x``/``P`` or mismatched
    shapes.
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    n = x.shape[0]
    if x.ndim != 1 or P.shape != (n, n):
        raise InputError(
            f"sigma_points: 'x' must be (n,) and 'P' (n, n); got {x.shape} and {P.shape}"
        )
    _require_finite("x", x, "sigma_points")
    _require_finite("P", P, "sigma_points")
    if n + lambda_ <= 0.0:
        raise ParameterError(f"sigma_points: n + lambda must be > 0, got {n + lambda_}")
    L, _ = matrix_sqrt(P)
    return _points_from_sqrt(x, L * math.sqrt(n + lambda_))


def _points_from_sqrt(x: np.ndarray, L: np.ndarray) -> np.ndarray:
    return points_from_sqrt_rows(x[None], L[None])[0]


def unscented_transform(points: np.ndarray, Wm: np.ndarray, Wc: np.ndarray,
                        noise_cov: Optional[np.ndarray] = None) -> Tuple[np.ndarray, np.ndarray]:
    """Weighted mean and covariance of transformed sigma points (paper 000 eqs. 15-16, 18-19).

    ``points`` has shape ``(2n + 1, m)`` (one transformed point per row).  Returns
    ``(mean, cov)`` with ``cov = sum_i Wc_i (Y_i - mean)(Y_i - mean)^T + noise_cov``
    (the additive noise covariance, if given), symmetrized.
    """
    points = np.asarray(points, dtype=float)
    mean = Wm @ points
    dev = points - mean
    cov = (dev.T * Wc) @ dev
    if noise_cov is not None:
        cov = cov + noise_cov
    return mean, 0.5 * (cov + cov.T)


def _require_finite(name: str, value: np.ndarray, where: str) -> None:
    if not np.isfinite(value).all():
        raise InputError(f"{where}: '{name}' contains NaN or inf")


def _apply_model(func: Callable, X: np.ndarray, args: tuple, vectorized: bool) -> np.ndarray:
    """Evaluate ``func`` on every sigma point (rows of ``X``)."""
    if vectorized:
        Y = np.asarray(func(X, *args), dtype=float)
        if Y.ndim != 2 or Y.shape[0] != X.shape[0]:
            raise InputError(
                f"vectorized model must return one row per sigma point, shape ({X.shape[0]}, m); "
                f"got {Y.shape}")
        return Y
    return np.array([np.atleast_1d(func(xi, *args)) for xi in X], dtype=float)


# ---------------------------------------------------------------------------------------
# Filter
# ---------------------------------------------------------------------------------------
class MeasurementPrediction(NamedTuple):
    """Predicted measurement of :meth:`UnscentedKalmanFilter.predict_measurement` (paper 000
    eqs. 17-20).

    ``Pzz`` is the transformed spread only, *without* R, so that the caller can pick or scale
    R after seeing the prediction; ``S = Pzz + R`` is formed in ``correct``.
    """

    z_pred: np.ndarray
    Pzz: np.ndarray
    Pxz: np.ndarray


class UnscentedKalmanFilter:
    """Additive-noise unscented Kalman filter (paper 000 eqs. 11-23, see module docstring).

    State lives in the plain attributes ``x`` (shape ``(n,)``) and ``P`` (``(n, n)``), which the
    caller may read, overwrite (e.g. reset the error state to zero after feedback to the INS)
    and deep-copy.  After each update ``last_nis`` and ``last_log_likelihood`` hold the chi-square
    statistic (paper 000 eq. 24) and the Gaussian log-likelihood of that innovation (for IMM; both 0
    before the first update);
    ``sqrt_fallbacks`` counts the square roots that needed the eigenvalue fallback.

    Parameters
    ----------
    n : state dimension.
    alpha, beta, kappa : scaled UT parameters (paper 000 eqs. 11-13).  Default ``1, 2, 0``: why,
    in the
        module docstring (the paper gives no values).
    x0, P0 : initial state and covariance (default zeros and identity).
    """

    state_fields = ("x", "P", "last_nis", "last_log_likelihood", "sqrt_fallbacks")
    derived_fields = ("Wm", "Wc", "lambda_", "n", "alpha", "beta", "kappa", "_spread")

    def __init__(self, n: int, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0,
                 x0: Optional[np.ndarray] = None, P0: Optional[np.ndarray] = None):
        self.Wm, self.Wc, self.lambda_ = sigma_weights(n, alpha, beta, kappa)
        self.n = int(n)
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)
        self._spread = math.sqrt(self.n + self.lambda_)
        self.x = np.zeros(self.n) if x0 is None else np.array(x0, dtype=float)
        self.P = np.eye(self.n) if P0 is None else np.array(P0, dtype=float)
        if self.x.shape != (self.n,):
            raise ParameterError(
                f"UnscentedKalmanFilter: 'x0' must have shape ({n},), got {self.x.shape}"
            )
        if self.P.shape != (self.n, self.n):
            raise ParameterError(
                f"UnscentedKalmanFilter: 'P0' must have shape ({n}, {n}), got {self.P.shape}")
        _require_finite("x0", self.x, "UnscentedKalmanFilter")
        _require_finite("P0", self.P, "UnscentedKalmanFilter")
        # 0 until the first update, so a diagnostic output is never NaN
        self.last_nis = 0.0
        self.last_log_likelihood = 0.0
        self.sqrt_fallbacks = 0

    # -- helpers --------------------------------------------------------------------------
    def sigma_points(self) -> np.ndarray:
        """Sigma points (paper 000 eq. 11) of the current ``(x, P)``, shape ``(2n + 1, n)``.

        ``P`` is symmetrized here only if the caller replaced it by a non-symmetric matrix
        (``predict``/``correct`` always store it symmetric).
        """
        L, fallback = _sqrt_symmetric(self.checked_covariance())
        self.sqrt_fallbacks += fallback
        return _points_from_sqrt(self.x, L * self._spread)

    def checked_covariance(self) -> np.ndarray:
        """``P``, symmetrized if the caller replaced it by a non-symmetric matrix, after the
        checks of :meth:`sigma_points` on ``x`` and ``P`` (shapes, finite values)."""
        x, P = self.x, self.P
        if x.shape != (self.n,) or P.shape != (self.n, self.n):
            raise InputError(
                f"UnscentedKalmanFilter: 'x' must be ({self.n},) and 'P' ({self.n}, {self.n}), "
                f"got {x.shape} and {P.shape}"
            )
        error = state_error(x, P)
        if error is not None:
            raise error
        if not (P == P.T).all():
            P = 0.5 * (P + P.T)
        return P

    # -- time update ----------------------------------------------------------------------
    def predict(self, f: Callable, Q: np.ndarray, *args: Any, q_scale: float = 1.0,
                vectorized: bool = False) -> None:
        """Time update, paper 000 eqs. 14-16 with additive process noise.

        ``f(x, *args) -> x_next`` maps one state (shape ``(n,)``); with ``vectorized=True`` it
        maps all points at once, ``f(X, *args)`` with ``X`` of shape ``(2n + 1, n)``, one point
        per row, returning the same shape (much cheaper in Python for n = 15).  ``Q`` is the
        discrete process noise covariance of the step; ``q_scale`` multiplies it (adaptive
        schemes; CTFA instead passes its scheduled ``Q`` directly, paper 000 eq. 25).
        """
        X = self.sigma_points()
        self.predict_points(_apply_model(f, X, args, vectorized), Q, q_scale=q_scale)

    def predict_points(self, Y: np.ndarray, Q: np.ndarray, q_scale: float = 1.0) -> None:
        """Time update, paper 000 eqs. 15-16, from the points of :meth:`sigma_points` mapped
        through the process model (``Y``, shape ``(2n + 1, n)``; one row per point).

        For a caller that propagates several filters' points in one call of the model (an IMM
        bank); :meth:`predict` is ``sigma_points``, the model, then this.
        """
        Y = np.asarray(Y, dtype=float)
        if Y.shape != (2 * self.n + 1, self.n):
            raise InputError(
                f"UnscentedKalmanFilter.predict: f must return shape ({self.n},) per point, "
                f"got {Y.shape[1:]}"
            )
        if np.shape(Q) != (self.n, self.n):
            raise InputError(
                f"UnscentedKalmanFilter.predict: 'Q' must have shape ({self.n}, {self.n}), "
                f"got {np.shape(Q)}"
            )
        x, P, finite = predicted_moments_rows(Y[None], self.Wm, self.Wc,
                                              np.asarray(Q, dtype=float)[None],
                                              np.full(1, float(q_scale)))
        if not finite[0]:
            raise predicted_state_error()
        self.x = x[0]
        self.P = P[0]

    # -- measurement update ---------------------------------------------------------------
    def predict_measurement(self, h: Callable, *args: Any,
                            vectorized: bool = False) -> MeasurementPrediction:
        """Predicted measurement, its spread ``Pzz`` (without R) and ``Pxz``, paper 000 eqs. 17-20.

        ``h(x, *args) -> z`` (shape ``(m,)``), or with ``vectorized=True`` ``h(X, *args)`` over
        the ``(2n + 1, n)`` points returning ``(2n + 1, m)``.  Does not change the filter.
        """
        X = self.sigma_points()
        Y = _apply_model(h, X, args, vectorized)
        z_pred, Pzz, Pxz = measurement_moments_rows(X[None], Y[None], self.x[None], self.Wm,
                                                    self.Wc)
        return MeasurementPrediction(z_pred[0], Pzz[0], Pxz[0])

    def correct(self, z: np.ndarray, prediction: MeasurementPrediction, R: np.ndarray,
                r_scale: float = 1.0) -> Dict[str, Any]:
        """Apply eqs. 21-23 with a measurement prediction from :meth:`predict_measurement`.

        ``S = Pzz + r_scale R``; ``K = Pxz S^-1``; ``x += K v``; ``P -= K S K^T``, computed as
        ``K Pxz^T`` (the same matrix, ``Pxz S^-1 Pxz^T``) and symmetrized so round-off never
        leaves an asymmetric ``P``.
        Returns a dict with ``innovation`` (``v = z - z_pred``), ``S``, ``nis`` (``v^T S^-1 v``,
        paper 000 eq. 24), ``log_likelihood`` (``log N(v; 0, S)``), ``K`` and ``z_pred``.
        Raises :class:`InputError` if ``z`` is not finite or ``S`` is not positive definite.
        """
        z = np.asarray(z, dtype=float)
        z_pred, Pzz, Pxz = prediction
        if z.shape != z_pred.shape:
            raise InputError(f"UnscentedKalmanFilter.correct: measurement 'z' has shape {z.shape}, "
                             f"h gives {z_pred.shape}")
        _require_finite("z", z, "UnscentedKalmanFilter.correct")
        if np.shape(R) != Pzz.shape:
            raise InputError(f"UnscentedKalmanFilter.correct: 'R' must have shape {Pzz.shape}, "
                             f"got {np.shape(R)}")
        S = Pzz + (R if r_scale == 1.0 else r_scale * np.asarray(R))
        rows = correct_rows(self.x[None], self.P[None], z[None], z_pred[None], S[None],
                            Pxz[None])
        if rows.status[0]:
            raise correction_error(rows.status[0])
        self.x, self.P = rows.x[0], rows.P[0]
        self.last_nis = nis = float(rows.nis[0])
        self.last_log_likelihood = log_likelihood = float(rows.log_likelihood[0])
        return {"innovation": rows.v[0], "S": rows.S[0], "nis": nis,
                "log_likelihood": log_likelihood, "K": rows.K[0], "z_pred": z_pred}

    def update(self, z: np.ndarray, h: Callable, R: np.ndarray, *args: Any, r_scale: float = 1.0,
               vectorized: bool = False) -> Dict[str, Any]:
        """Measurement update, paper 000 eqs. 17-23: :meth:`predict_measurement` then
        :meth:`correct`.

        Returns ``dict(innovation, S, nis, log_likelihood, K, z_pred)``; ``nis`` is the
        chi-square statistic of paper 000 eq. 24 (``v^T S^-1 v``).
        """
        return self.correct(
            z, self.predict_measurement(h, *args, vectorized=vectorized), R, r_scale
        )
