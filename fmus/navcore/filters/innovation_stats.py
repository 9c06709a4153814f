"""Innovation statistics of the filters and the chi-square quantiles and gates they meet.

One definition of each:

* :func:`nis` -- the normalized innovation squared ``v' S^-1 v`` by one linear solve (the
  error-state KF family, the IMM mixture); :func:`nis_from_cholesky` the same statistic as
  ``|L^-1 v|^2`` from a Cholesky factor ``S = L L'`` a filter already has (the UKF update,
  paper 001's compression test), with :func:`log_det_from_cholesky` and
  :func:`gaussian_log_likelihood` for the Gaussian likelihood (the IMM weights);
  :func:`checked_cholesky` factors a checked innovation covariance, and
  :func:`chi_square_statistic` is the checked statistic (paper 000 eq. 24).  Each filter keeps
  the arithmetic it has always used, so its outputs stay the same to the last bit.
* :func:`chi_square_per_observation` -- ``v_i^2 / S_ii``, paper 004's single-observation test.
* :func:`chi2_lower_quantile` / :func:`chi2_upper_quantile` -- the chi-square quantiles, and
  :func:`chi2_gate` the checked, cached upper quantile at significance alpha; the gates the
  papers print (:data:`CHI2_THRESHOLD_PAPER_004`, :data:`CTFA_THRESHOLDS_PAPER_000`).

The quantiles come from ``scipy.special`` instead of ``scipy.stats``.  For a probability
strictly inside (0, 1) ``2 gammaincinv(dof/2, p)`` and ``chdtri(dof, alpha)`` are the special
functions ``scipy.stats.chi2.ppf`` and ``.isf`` evaluate, so the numbers are bit for bit those
of ``scipy.stats.chi2`` (tests/test_innovation_stats.py).  Why not ``scipy.stats`` itself:
everything navcore imports ends up inside the FMUs, and ``scipy.stats`` loads ``scipy.fft`` and
the C++ extension ``scipy._lib._uarray``, which keeps Python references in C++ objects of
static storage duration.  A native FMI host that ends with ``exit()`` runs those static
destructors first and only then pythonfmu's teardown of the embedded interpreter
(``Py_FinalizeEx``), which releases the same references a second time and frees live
objects: a crash at exit in about half of all native-host runs.  Keep ``scipy.stats`` (and
``scipy.fft``) out of navcore; ``tests/test_chost.py`` checks the import chain of every FMU.
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import Tuple

import numpy as np
from scipy import special
from scipy.linalg import lapack

from .array_checks import square
from ..errors import InputError, ParameterError

#: paper 004's per-observation chi-square gate (section 2.1): chi2(1) upper quantile at
#: significance 0.01 (6.6349), as the paper prints it
CHI2_THRESHOLD_PAPER_004 = 6.635
#: paper 000's thresholds (T1, T2) of eq. 25 for its 3-dimensional GPS position measurement:
#: chi2(3) quantiles at 90 % and 99 % (6.2514, 11.3449), as the paper prints them
CTFA_THRESHOLDS_PAPER_000 = (6.25, 11.35)

_LOG_2PI = math.log(2.0 * math.pi)


# ----------------------------------------------------------------------------------------
# the statistic v' S^-1 v
# ----------------------------------------------------------------------------------------
def nis(v: np.ndarray, S: np.ndarray) -> float:
    """Normalized innovation squared ``v' S^-1 v`` by one linear solve (no checks)."""
    return float(nis_rows(v[None], S[None])[0])


def nis_rows(v: np.ndarray, S: np.ndarray) -> np.ndarray:
    """:func:`nis` of every run: ``v`` (B, m), ``S`` (B, m, m); (B,).  numpy solves each
    slice as one run's call (one LAPACK ``dgesv``)."""
    return dot_rows(v, np.linalg.solve(S, v[..., None])[..., 0])


def dot_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a_i' b_i`` of every run (B, m each): (B,), each numpy's 1-D ``a @ b`` of that run
    (the stacked product of a 1 x m by an m x 1 slice is the same BLAS dot)."""
    return (a[..., None, :] @ b[..., :, None])[..., 0, 0]


def trace_rows(X: np.ndarray) -> np.ndarray:
    """``np.trace`` of every run's (m, m) slice of ``X`` (B, m, m): (B,)."""
    return np.trace(X, axis1=-2, axis2=-1)


def nis_from_cholesky(L: np.ndarray, v: np.ndarray, general_solve: bool = False) -> float:
    """``v' S^-1 v = |L^-1 v|^2`` for the lower Cholesky factor ``L`` of ``S``: one
    triangular solve (LAPACK ``dtrtrs``), or with ``general_solve`` numpy's LU solve of the
    same system, the arithmetic paper 001's compression factor keeps (equal to round-off)."""
    if general_solve:
        return float(cholesky_nis_rows(L[None], v[None])[0])
    else:
        u, _ = lapack.dtrtrs(L, v, lower=1)
    return float(u @ u)


def cholesky_nis_rows(L: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``|L^-1 v|^2`` of every run by numpy's LU solve (``L`` (B, m, m), ``v`` (B, m)):
    :func:`nis_from_cholesky` with ``general_solve``, (B,)."""
    u = np.linalg.solve(L, v[..., None])[..., 0]
    return dot_rows(u, u)


def log_det_from_cholesky(L: np.ndarray) -> float:
    """``log det S = 2 sum log L_ii`` for the lower Cholesky factor ``L`` of ``S``."""
    return 2.0 * sum(math.log(L[i, i]) for i in range(L.shape[0]))


def gaussian_log_likelihood(nis_value: float, log_det: float, m: int) -> float:
    """``log N(v; 0, S) = -(v' S^-1 v + log det S + m log 2 pi) / 2`` from the NIS, ``log det S``
    and the dimension ``m``."""
    return -0.5 * (nis_value + log_det + m * _LOG_2PI)


def checked_cholesky(innovation, S, where: str,
                     numpy_factor: bool = False) -> Tuple[np.ndarray, np.ndarray]:
    """``(v, L)``: the innovation as a float vector and the lower Cholesky factor of the
    symmetrized ``S`` (LAPACK ``dpotrf``; with ``numpy_factor`` numpy's ``cholesky``, the
    factorization paper 001's compression factor keeps: the two libraries' factors agree to
    round-off, not always to the bit).  Raises :class:`InputError` naming ``where`` if the
    shapes disagree, a value is not finite or ``S`` is not positive definite."""
    v = np.atleast_1d(np.asarray(innovation, dtype=float))
    S = np.atleast_2d(np.asarray(S, dtype=float))
    if S.shape != (v.shape[0], v.shape[0]):
        raise InputError(f"{where}: 'S' must be {v.shape[0]}x{v.shape[0]}, got {S.shape}")
    if not (np.isfinite(v).all() and np.isfinite(S).all()):
        raise InputError(f"{where}: 'innovation' and 'S' must be finite")
    if numpy_factor:
        try:
            return v, np.linalg.cholesky(0.5 * (S + S.T))
        except np.linalg.LinAlgError:
            raise InputError(f"{where}: innovation covariance 'S' is not positive "
                             "definite") from None
    L, info = lapack.dpotrf(0.5 * (S + S.T), lower=1, clean=1)
    if info != 0:
        raise InputError(f"{where}: innovation covariance 'S' is not positive definite")
    return v, L


def chi_square_statistic(innovation, S) -> float:
    """Chi-square statistic ``v' S^-1 v`` of an innovation, checked (paper 000 eq. 24; the
    NIS).  ``S`` is the innovation covariance (``P_zz`` of paper 000
    eq. 19 including R); solved through its Cholesky factor.  Raises :class:`InputError` if
    ``S`` is not positive definite or the inputs are not finite."""
    v, L = checked_cholesky(innovation, S, "chi_square_statistic")
    return nis_from_cholesky(L, v)


def chi_square_per_observation(innovation, S) -> np.ndarray:
    """Per-observation chi-square statistics r_i = v_i^2 / S_ii (paper 004, section 2.1).

    The paper's "single observation chi-square test" (当前时刻单个观测值的卡方检验): each
    component of the innovation is tested on its own, so a fault is located in the
    observation that carries it and only that one is replaced.  With v ~ N(0, S) each r_i is
    chi2(1) (one degree of freedom), whatever the correlations between components.

    ``innovation`` (m,) -- or (N, m), a batch of N epochs; ``S`` = H P_{k,k-1} H' + R
    (m, m), only its diagonal is used.  Returns an array of the shape of ``innovation``.
    """
    v = np.asarray(innovation, dtype=float)
    if v.ndim == 0:
        v = v.reshape(1)
    if v.ndim not in (1, 2):
        raise InputError(f"innovation: expected shape (m,) or (N, m), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InputError("innovation: contains NaN or inf")
    m = v.shape[-1]
    s = np.diag(square("S", S, m))
    if np.any(s <= 0.0):
        raise InputError(f"S: diagonal must be > 0, got {s}")
    return v * v / s


# ----------------------------------------------------------------------------------------
# chi-square quantiles and gates
# ----------------------------------------------------------------------------------------
def chi2_lower_quantile(p, dof):
    """The x with P(X <= x) = p for X ~ chi2(dof), 0 < p < 1 (``scipy.stats.chi2.ppf``)."""
    return 2.0 * special.gammaincinv(dof / 2, p)


def chi2_upper_quantile(alpha, dof):
    """The x with P(X > x) = alpha for X ~ chi2(dof), 0 < alpha < 1 (``scipy.stats.chi2.isf``)."""
    return special.chdtri(dof, alpha)


def chi2_gate(alpha: float, dof: int = 1) -> float:
    """Upper alpha quantile of chi2(dof): the gate a chi-square test at significance alpha
    compares its statistic with (``chi2_gate(0.01, 1)`` = 6.6349, paper 004's 6.635)."""
    if not (0.0 < alpha < 1.0):
        raise ParameterError(f"alpha (significance level) must be in (0, 1), got {alpha}")
    if int(dof) != dof or dof < 1:
        raise ParameterError(f"dof (degrees of freedom) must be an integer >= 1, got {dof}")
    return _cached_upper_quantile(float(alpha), int(dof))


@lru_cache(maxsize=64)
def _cached_upper_quantile(alpha: float, dof: int) -> float:
    # cached: the quantile costs ~0.3 ms, and a filter asks for the same gate every update
    return float(chi2_upper_quantile(alpha, dof))
