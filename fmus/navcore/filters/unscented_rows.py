"""The unscented filter's arithmetic for many filters at once: each function takes B filters
along a leading axis, and a single filter (:class:`~navcore.filters.unscented.
UnscentedKalmanFilter`, the UKF engines, the AHRS filters) calls it with one row, so a batch
of runs and a run alone compute with the same code (paper 000 eqs. 11-23; the transform and
its notation: :mod:`navcore.filters.unscented`).

numpy's stacked products give every filter the floats of its own 2-D product, and the
Cholesky factors are LAPACK's, called from kernels on the Fortran copies scipy's wrappers
would make (:mod:`navcore.core.lapack_kernels`), so a filter's row is what it computes alone.
"""
from __future__ import annotations

import math
from typing import List, NamedTuple, Optional, Tuple

import numpy as np

from navcore.core.kernels import kernel
from navcore.core.lapack_kernels import potrf_lower, potrs_lower, trtrs_lower
from navcore.errors import InputError
from navcore.filters.innovation_stats import gaussian_log_likelihood

def eigen_sqrt(A: np.ndarray) -> np.ndarray:
    """The square root of :func:`matrix_sqrt` where the Cholesky factor does not exist."""
    eigval, eigvec = np.linalg.eigh(A)
    return eigvec * np.sqrt(np.maximum(eigval, 0.0))


def points_from_sqrt_rows(x: np.ndarray, L: np.ndarray) -> np.ndarray:
    """Sigma points of B filters at once: ``x`` (B, n), scaled square roots ``L`` (B, n, n);
    returns (B, 2n + 1, n), each filter's points as :func:`sigma_points` lays them out."""
    runs, n = x.shape
    X = np.empty((runs, 2 * n + 1, n))
    X[:, 0] = x
    Lt = L.transpose(0, 2, 1)
    np.add(x[:, None, :], Lt, out=X[:, 1:n + 1])          # row i is x + column i of L
    np.subtract(x[:, None, :], Lt, out=X[:, n + 1:])
    return X


def sigma_points_rows(x: np.ndarray, P: np.ndarray,
                      spread: float) -> Tuple[np.ndarray, np.ndarray]:
    """The sigma points (B, 2n + 1, n) of B filters from their states ``x`` (B, n) and
    covariances ``P`` (B, n, n), each as its :meth:`UnscentedKalmanFilter.sigma_points` draws
    them (``P`` symmetrized where it is not symmetric, its lower Cholesky factor by one LAPACK
    ``dpotrf`` per matrix, called from a kernel (:mod:`navcore.core.lapack_kernels`) on the
    Fortran copy scipy's wrapper would make, so each root is the one a filter alone gets:
    numpy's stacked Cholesky rounds otherwise; scaled by ``spread``), and which filters needed
    the eigenvalue fallback (B,)."""
    x = np.ascontiguousarray(x, dtype=float)
    P = np.ascontiguousarray(P, dtype=float)
    runs, n = x.shape
    X = np.empty((runs, 2 * n + 1, n))
    info = np.empty(runs, dtype=np.int64)
    _points_rows(x, P, float(spread), np.empty((n, n), order="F"), X, info)
    fallback = info != 0
    if fallback.any():
        for b in np.flatnonzero(fallback).tolist():
            A = P[b] if (P[b] == P[b].T).all() else 0.5 * (P[b] + P[b].T)
            X[b] = points_from_sqrt_rows(x[b:b + 1], eigen_sqrt(A)[None] * spread)[0]
    return X, fallback


@kernel
def _points_rows(x, P, spread, factor, X, info):
    """:func:`sigma_points_rows` of every filter whose Cholesky factor exists (LAPACK's info
    of each into ``info``; the points of the others are left to the caller)."""
    n = x.shape[1]
    for b in range(x.shape[0]):
        symmetric = True
        for i in range(n):
            for j in range(i + 1):
                if not P[b, i, j] == P[b, j, i]:
                    symmetric = False
        for i in range(n):
            for j in range(n):
                factor[i, j] = P[b, i, j] if symmetric else 0.5 * (P[b, i, j] + P[b, j, i])
        info[b] = potrf_lower(factor)
        if info[b] != 0:
            continue
        for k in range(n):
            X[b, 0, k] = x[b, k]
        for i in range(n):                      # row 1 + i is x + column i of the root
            for k in range(n):
                root = (factor[k, i] if i <= k else 0.0) * spread
                X[b, 1 + i, k] = x[b, k] + root
                X[b, 1 + n + i, k] = x[b, k] - root


def predicted_moments_rows(Y: np.ndarray, Wm: np.ndarray, Wc: np.ndarray, Q: np.ndarray,
                           q_scale: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Paper 000 eqs. 15-16 for B filters at once: their mapped points ``Y`` (B, 2n + 1, n),
    process noises ``Q`` (B, n, n) times ``q_scale`` (B,).  Returns the means (B, n), the
    symmetrized covariances (B, n, n) and whether each is finite (B,).  numpy's stacked
    products give each filter the floats of its own 2-D product (``tests/test_kf_batch.py``)."""
    x = Wm @ Y
    dev = Y - x[:, None, :]
    P = (dev.transpose(0, 2, 1) * Wc) @ dev
    P += q_scale[:, None, None] * Q               # 1.0 * Q is Q exactly
    # a NaN/inf anywhere in f's output or Q propagates into P, so one check covers all
    finite = np.isfinite(P).all(axis=(1, 2))
    return x, 0.5 * (P + P.transpose(0, 2, 1)), finite


def checked_covariances(filters) -> Tuple[np.ndarray, np.ndarray, np.ndarray,
                                          List[Optional[Exception]]]:
    """:meth:`UnscentedKalmanFilter.checked_covariance` of every filter of ``filters`` (one
    state dimension): the states (F, n), the covariances as given (F, n, n), the checked
    ones (the given ones, but symmetrized where a filter's own check symmetrized them) and,
    per filter, the error its own check raised (None if none; its rows are then not
    meaningful).  The covariances and states of every filter are checked for finite values
    and symmetry by stacked comparisons (a single filter's update calls this too; a batch
    checks its filters before each prediction by :func:`finite_symmetric_rows`); a filter
    that fails them runs its own check, which symmetrizes or raises."""
    n = filters[0].n
    count = len(filters)
    if all(f.x.shape == (n,) and f.P.shape == (n, n) for f in filters):
        x = np.stack([f.x for f in filters])
        P = np.stack([f.P for f in filters])
        passed = (np.isfinite(P).all(axis=(1, 2)) & np.isfinite(x).all(axis=1)
                  & (P == P.transpose(0, 2, 1)).all(axis=(1, 2)))
    else:
        x, P = np.zeros((count, n)), np.zeros((count, n, n))
        passed = np.zeros(count, dtype=bool)
    checked = P
    errors: List[Optional[Exception]] = [None] * count
    for j in np.flatnonzero(~passed).tolist():
        flt = filters[j]
        try:
            P_checked = flt.checked_covariance()
        except Exception as exc:       # the filter's own error (InputError)
            errors[j] = exc
            continue
        if checked is P:
            checked = P.copy()
        x[j], P[j], checked[j] = flt.x, flt.P, P_checked
    return x, P, checked, errors


@kernel
def finite_symmetric_rows(x, P, passed):
    """Whether each filter's state ``x[b]`` and covariance ``P[b]`` are finite and ``P[b]``
    is symmetric (equal to its transpose, element for element), into ``passed``: the
    checks of :func:`checked_covariances` as one kernel, for a batch's filters at every
    prediction."""
    n = x.shape[1]
    for b in range(x.shape[0]):
        ok = True
        for i in range(n):
            if not math.isfinite(x[b, i]):
                ok = False
            for j in range(n):
                if not (math.isfinite(P[b, i, j]) and P[b, i, j] == P[b, j, i]):
                    ok = False
        passed[b] = ok


def state_error(x: np.ndarray, P: np.ndarray) -> Optional[InputError]:
    """The error of a filter whose ``P`` or ``x`` is not finite (None: both are)."""
    if not np.isfinite(P).all():
        return InputError("UnscentedKalmanFilter: 'P' contains NaN or inf")
    if not np.isfinite(x).all():
        return InputError("UnscentedKalmanFilter: 'x' contains NaN or inf")
    return None


def predicted_state_error() -> InputError:
    """The error of a prediction whose moments are not finite (:func:`predicted_moments_rows`)."""
    return InputError("UnscentedKalmanFilter.predict: the state predicted by f or 'Q' "
                      "contains NaN or inf")


def measurement_moments_rows(X: np.ndarray, Y: np.ndarray, x: np.ndarray, Wm: np.ndarray,
                             Wc: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Paper 000 eqs. 18-20 for B filters at once: their points ``X`` (B, 2n + 1, n) with
    means ``x`` (B, n), mapped through h to ``Y`` (B, 2n + 1, m).  Returns ``z_pred`` (B, m),
    ``Pzz`` (B, m, m, without R) and ``Pxz`` (B, n, m)."""
    z_pred = Wm @ Y
    dY = Y - z_pred[:, None, :]
    wdY = dY * Wc[:, None]
    Pzz = dY.transpose(0, 2, 1) @ wdY
    Pxz = (X - x[:, None, :]).transpose(0, 2, 1) @ wdY
    return z_pred, Pzz, Pxz


class CorrectedRows(NamedTuple):
    """:func:`correct_rows`' results, one row per filter; ``status`` 0 where the filter was
    corrected, else the code :func:`correction_error` turns into its error (that filter's
    other rows are then not meaningful)."""

    x: np.ndarray
    P: np.ndarray
    v: np.ndarray
    S: np.ndarray
    K: np.ndarray
    nis: np.ndarray
    log_likelihood: np.ndarray
    status: np.ndarray


#: :func:`correct_rows` status codes
_NOT_FINITE, _NOT_POSITIVE = 1, 2


def correct_rows(x: np.ndarray, P: np.ndarray, z: np.ndarray, z_pred: np.ndarray,
                 S: np.ndarray, Pxz: np.ndarray) -> CorrectedRows:
    """Paper 000 eqs. 21-23 for B filters at once (:meth:`UnscentedKalmanFilter.correct`):
    states ``x`` (B, n), ``P`` (B, n, n), measurements ``z`` and predictions ``z_pred``
    (B, m), innovation covariances ``S = Pzz + R`` (B, m, m, symmetrized here), ``Pxz``
    (B, n, m).  One Cholesky factor per filter (LAPACK, as one filter alone calls it) serves
    the PD check, the gain, the NIS and log det S."""
    S = 0.5 * (S + S.transpose(0, 2, 1))
    v = z - z_pred
    runs, m = z.shape
    if math.isfinite(S.sum() + v.sum()):          # NaN and inf propagate into a sum
        status = np.zeros(runs, dtype=np.int64)
    else:
        status = np.where(np.isfinite(S).all(axis=(1, 2)) & np.isfinite(v).all(axis=1), 0,
                          _NOT_FINITE)
    K = np.zeros(Pxz.shape)
    u, log_det = np.zeros((runs, m)), np.zeros(runs)
    n = Pxz.shape[1]
    _cholesky_solves(np.ascontiguousarray(S), np.ascontiguousarray(Pxz), v, status, K, u,
                     log_det, np.empty((m, m), order="F"), np.empty((m, n), order="F"),
                     np.empty((m, 1), order="F"))
    # |u|^2 of every filter: numpy's stacked (1, m) x (m, 1) products are each slice's 1-D
    # dot, one filter's float(u @ u); the log-likelihood's arithmetic is elementwise
    corrected = status == 0
    nis = np.where(corrected, np.matmul(u[:, None, :], u[:, :, None])[:, 0, 0], 0.0)
    log_likelihood = np.where(corrected, gaussian_log_likelihood(nis, log_det, m), 0.0)
    # a filter not corrected has K = 0 and may have a v that is not finite
    used = np.where(status[:, None] == 0, v, 0.0) if status.any() else v
    x = x + (K @ used[:, :, None])[:, :, 0]
    P = P - K @ Pxz.transpose(0, 2, 1)
    return CorrectedRows(x, 0.5 * (P + P.transpose(0, 2, 1)), v, S, K, nis, log_likelihood,
                         status)


@kernel
def _cholesky_solves(S, Pxz, v, status, K, u, log_det, factor, gain, solved):
    """For every filter b with ``status[b]`` 0: the lower Cholesky factor of ``S[b]``
    (``status[b]`` set to not positive definite where it does not exist), the gain ``K[b] =
    Pxz[b] S[b]^-1`` (``dpotrs``), ``u[b] = L^-1 v[b]`` (``dtrtrs``: the NIS is ``|u|^2``)
    and ``log det S[b] = 2 sum log L_ii`` (the sum from the first term, as Python's ``sum``).
    ``factor`` (m, m), ``gain`` (m, n), ``solved`` (m, 1): Fortran-ordered work matrices
    holding what scipy's wrappers would hand to LAPACK."""
    m, n = S.shape[1], Pxz.shape[1]
    for b in range(S.shape[0]):
        if status[b]:
            continue
        for i in range(m):
            for j in range(m):
                factor[i, j] = S[b, i, j]
        if potrf_lower(factor) != 0:
            status[b] = _NOT_POSITIVE
            continue
        for i in range(m):
            for j in range(n):
                gain[i, j] = Pxz[b, j, i]
            solved[i, 0] = v[b, i]
        potrs_lower(factor, gain)
        trtrs_lower(factor, solved)
        total = 0.0
        for i in range(m):
            for j in range(n):
                K[b, j, i] = gain[i, j]
            u[b, i] = solved[i, 0]
            total += math.log(factor[i, i])
        log_det[b] = 2.0 * total


def correction_error(status: int) -> InputError:
    """The error of a filter :func:`correct_rows` could not correct."""
    if status == _NOT_FINITE:
        return InputError("UnscentedKalmanFilter.correct: the measurement predicted by h or "
                          "'R' contains NaN or inf")
    return InputError("UnscentedKalmanFilter.correct: innovation covariance S = Pzz + R is "
                      "not positive definite (check R)")


class Correction(NamedTuple):
    """A filter's measurement update by :func:`update_filters`: its innovation ``v``, ``S``,
    the NIS and the Gaussian log-likelihood of ``v`` (what
    :meth:`UnscentedKalmanFilter.correct` returns of them)."""

    v: np.ndarray
    S: np.ndarray
    nis: float
    log_likelihood: float


def update_filters(filters, z: np.ndarray, R: np.ndarray, h, checked=None,
                   ) -> Tuple[List[Optional[Correction]], List[Optional[Exception]]]:
    """The measurement update (paper 000 eqs. 17-23) of every filter of ``filters`` (one
    transform: the same n, weights and spread) with its measurement ``z[i]`` (F, m) and noise
    ``R[i]`` (F, m, m), through ``h`` mapping the points of all filters at once
    ((F, 2n + 1, n) to (F, 2n + 1, m)): each filter's checks, sigma points, measurement
    moments and correction as :meth:`UnscentedKalmanFilter.update` computes them, in one
    call of each row function.  Each filter updated takes its new ``x``, ``P``,
    ``last_nis``, ``last_log_likelihood`` and square-root fallbacks; returns per filter its
    :class:`Correction` and the error its own update raises (None if none; the filter is
    then not corrected).  ``checked``: the filters' states and covariances stacked, when
    the caller knows them finite and symmetric (else None: checked here)."""
    if checked is None:
        # the covariances as given: the sigma points symmetrize what is not symmetric
        x, P, _, errors = checked_covariances(filters)
    else:
        (x, P), errors = checked, [None] * len(filters)
    for i in np.flatnonzero(~np.isfinite(z).all(axis=1)).tolist():
        if errors[i] is None:
            errors[i] = InputError("UnscentedKalmanFilter.correct: 'z' contains NaN or inf")
    done = [i for i, error in enumerate(errors) if error is None]
    corrections: List[Optional[Correction]] = [None] * len(filters)
    if not done:
        return corrections, errors
    updated = [filters[i] for i in done]
    if len(done) < len(filters):
        x, P, z, R = x[done], P[done], z[done], R[done]
    first = updated[0]
    X, fallback = sigma_points_rows(x, P, first._spread)
    z_pred, Pzz, Pxz = measurement_moments_rows(X, h(X), x, first.Wm, first.Wc)
    rows = correct_rows(x, P, z, z_pred, Pzz + R, Pxz)
    for k, (i, flt) in enumerate(zip(done, updated)):
        flt.sqrt_fallbacks += bool(fallback[k])
        if rows.status[k]:
            errors[i] = correction_error(rows.status[k])
            continue
        flt.x, flt.P = rows.x[k], rows.P[k]
        flt.last_nis = nis = float(rows.nis[k])
        flt.last_log_likelihood = log_likelihood = float(rows.log_likelihood[k])
        corrections[i] = Correction(rows.v[k], rows.S[k], nis, log_likelihood)
    return corrections, errors
