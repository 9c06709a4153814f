"""Adaptation laws of paper 001's adaptive Kalman filters (Sage-Husa, fading memory, compression).

Pure functions over numpy arrays, called by an INS/GNSS error-state Kalman filter in its
prediction and update steps; no filter state lives here.  Paper 004's robust laws are in
:mod:`navcore.filters.robust_laws`, the innovation statistics and chi-square gates in
:mod:`navcore.filters.innovation_stats`.

Shapes used throughout (m = measurement dimension, n = state dimension):

=============================  ==========  ===================================================
name                           shape       meaning
=============================  ==========  ===================================================
``innovation``                 (m,)        v_k = z_k - H_k x_{k,k-1}  (paper 001 eq. 5)
``H``                          (m, n)      measurement matrix
``K``                          (n, m)      Kalman gain (paper 001 eq. 7)
``P`` / ``P_post``             (n, n)      state covariance P_{k-1} / P_k (paper 001 eq. 8)
``R``                          (m, m)      measurement noise covariance
``G`` / ``S``                  (m, m)      innovation covariance H P_{k,k-1} H' + R
``Phi``                        (n, n)      state transition matrix Phi_{k,k-1}
``GQG``                        (n, n)      Gamma_k Q_k Gamma_k'
=============================  ==========  ===================================================

Paper 001 (Yuan et al., *Improved adaptive Kalman filter in GPS/SINS*, 2015)
----------------------------------------------------------------------------
* :func:`sage_husa_r_update` -- simplified Sage-Husa R estimator, paper 001 eq. 9, with
  :func:`sage_husa_weight` d_k = (1 - b) / (1 - b^(k+1)) and the positive-definiteness guard
  :func:`guard_positive_definite` (+ :func:`r_floor_from_initial` for its floor).
* :func:`divergence_test` (paper 001 eq. 11), :func:`fading_factor` (paper 001 eq. 12) and
  :func:`fading_predict` (paper 001 eq. 10) -- the fading-memory filter.
* :func:`compression_factor` -- outlier compression of the innovation, paper 001 eqs. 13-14.

Order of the calls in one IAKF cycle (paper 001, section 2.2; its equations)::

    x_pred = Phi @ x                                   # eq. 3, does not need P
    v = z - H @ x_pred                                 # eq. 5
    HPH0 = H @ Phi @ P @ Phi.T @ H.T                   # H Phi P_{k-1} Phi' H'
    HQH = H @ GQG @ H.T                                # H Gamma Q Gamma' H'
    lam = fading_factor(v, HQH, R, HPH0, gamma)        # eqs. 11-12 (1 while eq. 11 holds)
    P_pred = fading_predict(Phi @ P @ Phi.T, GQG, lam) # eq. 10
    G = H @ P_pred @ H.T + R
    K = P_pred @ H.T @ inv(G)                          # eq. 7
    Y, tau, gate = compression_factor(v, G, K)         # eqs. 13-14
    v = Y * v                                          # compressed innovation
    x = x_pred + K @ v;  P = (I - K H) P_pred          # eqs. 4, 8
    R = sage_husa_r_update(R, v, H, K, P, k, b, R_min) # eq. 9 with the guard
"""
from __future__ import annotations

import math
from typing import Optional, Tuple, Union

import numpy as np

from .array_checks import matrix, square, symmetrize, vector
from ..errors import InputError, ParameterError
from .innovation_stats import (checked_cholesky, chi2_gate, cholesky_nis_rows, dot_rows,
    nis_from_cholesky, trace_rows)

ArrayLike = Union[np.ndarray, float, list]

#: Default fraction of the initial R diagonal used as the variance floor of the guard
#: (see :func:`r_floor_from_initial`): a floor of 1 % of the variance, i.e. 10 % of the
#: standard deviation, never binds while the estimator behaves, and keeps R invertible
#: and the gain bounded when it does not.
DEFAULT_R_FLOOR_FRACTION = 0.01


# ----------------------------------------------------------------------------------------
# paper 001, section 1.1: simplified Sage-Husa measurement-noise estimator
# ----------------------------------------------------------------------------------------
def sage_husa_weight(k: int, b: float) -> float:
    """Weight d_k = (1 - b) / (1 - b^(k+1)) of the Sage-Husa estimator (paper 001, eq. 9).

    ``b`` is the forgetting factor, 0 < b <= 1 (paper: 0.95-0.99); ``k`` >= 0 the index of
    the update.  With these weights the recursion of paper 001 eq. 9 is exactly the exponentially
    weighted mean ``sum_i b^(k-i) S_i / sum_i b^(k-i)`` of the bracketed samples S_1..S_k,
    where the initial R_0 counts as sample S_0.  Hence:

    * k = 1 for the first measurement update keeps R_0 as one sample (weight b/(1+b) at
      the first update, decaying); k = 0 gives d = 1 and throws R_0 away entirely.
    * the memory length is about 1/(1 - b) updates once b^k is small (100 for b = 0.99).
    * b = 1 is the limit d_k = 1/(k+1): the plain arithmetic mean (no forgetting).
    """
    if not (0.0 < b <= 1.0) or not math.isfinite(b):
        raise ParameterError(f"b (Sage-Husa forgetting factor) must be in (0, 1], got {b}")
    if int(k) != k or k < 0:
        raise InputError(f"k (Sage-Husa update index) must be an integer >= 0, got {k}")
    k = int(k)
    if b == 1.0:
        return 1.0 / (k + 1)
    # -expm1((k+1) log b) = 1 - b^(k+1) without cancellation for b close to 1
    return (1.0 - b) / -math.expm1((k + 1) * math.log(b))


def sage_husa_r_update(R_prev, innovation, H, K, P_post, k: int, b: float,
                       R_min: Optional[ArrayLike] = None) -> np.ndarray:
    """Simplified Sage-Husa measurement-noise estimate, paper 001 eq. 9.

    ``R_k = (1 - d_k) R_{k-1} + d_k [ (I - H K) v v' (I - H K)' + H P_k H' ]``

    with d_k from :func:`sage_husa_weight` (``k``, ``b``).  ``(I - H K) v = z - H x_k`` is
    the post-fit residual e_k; for a filter run with the true R, E[e e'] = R - H P_k H', so
    the bracket is an unbiased one-sample estimate of R.  Only R is estimated: the paper
    keeps Q fixed because estimating both at once makes Sage-Husa diverge (section 1.1).

    Arguments (see module table): ``R_prev`` (m, m); ``innovation`` v_k (m,) -- the one used
    in the state update, i.e. already compressed by paper 001 eq. 13 in the IAKF; ``H`` (m, n);
    ``K`` (n, m); ``P_post`` P_k (n, n) after the update (paper 001 eq. 8).  ``R_min`` (optional,
    scalar or (m,)): if given, the result goes through :func:`guard_positive_definite`.

    The result is symmetrized (round-off makes H P_k H' slightly asymmetric).
    """
    v = vector("innovation", innovation)
    m = v.shape[0]
    R_prev = square("R_prev", R_prev, m)
    H = matrix("H", H, rows=m)
    n = H.shape[1]
    K = matrix("K", K, rows=n, cols=m)
    P_post = square("P_post", P_post, n)
    d = sage_husa_weight(k, b)
    R_new = sage_husa_r_rows(R_prev[None], v[None], H, K[None], P_post[None], np.array([d]))[0]
    if R_min is not None:
        R_new = guard_positive_definite(R_new, R_min)
    return R_new


def sage_husa_r_rows(R_prev, innovation, H, K, P_post, d) -> np.ndarray:
    """:func:`sage_husa_r_update` before its guard, for every run (no checks): ``R_prev``
    (B, m, m), ``innovation`` (B, m), ``H`` (m, n) shared, ``K`` (B, n, m), ``P_post``
    (B, n, n) and the weights ``d`` (B,); (B, m, m).  numpy's stacked products give each
    run its own 2-D product's floats."""
    v = innovation
    residual = v - (H @ (K @ v[..., None]))[..., 0]   # (I - H K) v without forming I - H K
    sample = residual[..., :, None] * residual[..., None, :] + H @ P_post @ H.T
    d = d[:, None, None]
    return symmetric_rows((1.0 - d) * R_prev + d * sample)


def symmetric_rows(a: np.ndarray) -> np.ndarray:
    """``(a + a') / 2`` of every run's slice of ``a`` (B, m, m)."""
    return 0.5 * (a + a.swapaxes(-1, -2))


def r_floor_from_initial(R0, fraction: float = DEFAULT_R_FLOOR_FRACTION) -> np.ndarray:
    """Variance floor for :func:`guard_positive_definite`: ``fraction * diag(R0)``, shape (m,).

    ``R0`` is the filter's initial (datasheet) R, (m, m) or its diagonal (m,).  Per-axis
    floors keep units consistent when z mixes positions and velocities (or rad^2 and m^2).
    """
    if not (fraction > 0.0) or not math.isfinite(fraction):
        raise ParameterError(f"fraction (R floor fraction) must be > 0, got {fraction}")
    a = np.asarray(R0, dtype=float)
    diag = np.diag(a) if a.ndim == 2 else a.reshape(-1)
    if not np.all(np.isfinite(diag)) or np.any(diag <= 0.0):
        raise ParameterError(f"R0: diagonal must be finite and > 0, got {diag}")
    return fraction * diag


def guard_positive_definite(R, R_min: ArrayLike) -> np.ndarray:
    """Keep an estimated R symmetric positive definite, with a variance floor.

    Method: symmetrize, scale by D = diag(sqrt(R_min)) to S = D^-1 R D^-1, floor the
    eigenvalues of S at 1, scale back.  The result R_g satisfies R_g - diag(R_min) >= 0
    (positive semidefinite), so every eigenvalue of R_g is >= min(R_min) and every diagonal
    element R_g[i, i] >= R_min[i].  A scalar ``R_min`` is a plain eigenvalue floor.  An R
    that already satisfies R - diag(R_min) >= 0 comes back unchanged (up to round-off);
    eigenvectors of S are kept, so correlations survive the guard.  Scaling first makes the
    floor per axis, which keeps units consistent when z mixes m^2, (m/s)^2 and rad^2.

    Why a guard although paper 001 eq. 9 is a convex combination of PSD terms: other
    Sage-Husa forms (innovation-based, ``v v' - H P_{k,k-1} H'``) subtract a covariance and
    lose definiteness outright; the simplified form only keeps it in exact arithmetic and
    with a PD R_{k-1}.  What can still go wrong:

    * small k: d_k is large (d_0 = 1, d_1 ~ 0.5), so R is one or two rank-one samples
      e e' plus H P_k H', which is nearly singular once the filter is confident;
    * round-off: P_k from (I - K H) P_{k,k-1} (paper 001 eq. 8, not Joseph form) loses symmetry and
      can get slightly negative eigenvalues, and so can H P_k H';
    * compressed innovations (paper 001 eqs. 13-14): during an outlier patch each innovation is
      shrunk onto the gate, so the samples under-estimate R and R decays geometrically
      towards H P_k H'; the gain then grows and the filter trusts the bad data more;
    * small true noise / long quiet periods with b < 1 drive R towards zero, and a nearly
      singular G = H P H' + R makes the gain and the chi-square statistics ill-conditioned.

    ``R_min``: scalar or (m,) of variance floors, > 0 (default choice in a filter:
    :func:`r_floor_from_initial`, 1 % of the initial R diagonal).
    """
    R = square("R", R)
    m = R.shape[0]
    floor = np.asarray(R_min, dtype=float)
    if floor.ndim == 0:
        floor = np.full(m, float(floor))
    if floor.shape != (m,):
        raise ParameterError(f"R_min: expected a scalar or shape ({m},), got {floor.shape}")
    if not np.all(np.isfinite(floor)) or np.any(floor <= 0.0):
        raise ParameterError(f"R_min: floors must be finite and > 0, got {floor}")
    return guard_positive_definite_rows(R[None], floor[None])[0]


def guard_positive_definite_rows(R, floor) -> np.ndarray:
    """:func:`guard_positive_definite` of every run (no checks): ``R`` (B, m, m), the
    floors ``floor`` (B, m); (B, m, m).  One stacked Cholesky test finds whether any run
    needs a repair; only then is each run tested and repaired alone."""
    R = symmetric_rows(R)
    floors = np.zeros_like(R)
    diagonal = np.arange(R.shape[-1])
    floors[:, diagonal, diagonal] = floor
    try:  # fast path (a few us): R - diag(R_min) positive definite, nothing to repair
        np.linalg.cholesky(R - floors)
        return R
    except np.linalg.LinAlgError:
        pass
    R = R.copy()
    for b in range(len(R)):
        try:
            np.linalg.cholesky(R[b] - floors[b])
        except np.linalg.LinAlgError:
            R[b] = _eigenvalues_floored(R[b], floor[b])
    return R


def _eigenvalues_floored(R, floor) -> np.ndarray:
    """One run's repair of :func:`guard_positive_definite`: the eigenvalues of R scaled by
    the floors raised to 1."""
    scale = np.sqrt(floor)
    S = R / np.outer(scale, scale)
    w, V = np.linalg.eigh(S)
    S_g = (V * np.maximum(w, 1.0)) @ V.T
    return symmetrize(S_g * np.outer(scale, scale))


# ----------------------------------------------------------------------------------------
# paper 001, section 1.2: fading-memory filter
# ----------------------------------------------------------------------------------------
def divergence_test(innovation, HPH_prior, R, gamma: float = 1.0) -> bool:
    """Divergence criterion of paper 001, eq. 11: True while the filter works normally.

    ``v'v <= gamma * tr(E[v v'])`` with ``E[v v'] = H P_{k,k-1} H' + R`` (the innovation
    covariance of the *unfaded* prediction, paper 001 eq. 6).  ``HPH_prior`` = H P_{k,k-1} H' (m,
    m), ``R`` (m, m).  ``gamma`` is the paper's reserve coefficient: gamma = 1 is the strictest
    criterion the paper considers; larger gamma tolerates larger innovations before the
    fading factor is engaged.  gamma < 1 is allowed but stricter than the paper's strictest.
    Returns False when the criterion fails (filter diverging -> apply paper 001 eq. 12).
    """
    if not (gamma > 0.0) or not math.isfinite(gamma):
        raise ParameterError(f"gamma (divergence reserve coefficient) must be > 0, got {gamma}")
    v = vector("innovation", innovation)
    m = v.shape[0]
    HPH = square("HPH_prior", HPH_prior, m)
    R = square("R", R, m)
    return bool(divergence_test_rows(dot_rows(v, v), HPH, R, gamma))


def divergence_test_rows(vv, HPH_prior, R, gamma):
    """:func:`divergence_test` of every run (no checks) from ``v'v`` (B,), ``HPH_prior`` and
    ``R`` (B, m, m) and ``gamma`` (a number or (B,))."""
    return vv <= gamma * (trace_rows(HPH_prior) + trace_rows(R))


def fading_factor(innovation, HQH, R, HPpredH_no_Q, gamma: float = 1.0,
                  max_factor: Optional[float] = None) -> float:
    """Fading factor lambda_k of paper 001, eqs. 11-12.

    ``lambda_k = (v'v - tr(H Gamma Q Gamma' H' + R)) / tr(H Phi P_{k-1} Phi' H')``
    (paper 001 eq. 12)

    (the paper prints the numerator as Z Z', meaning the scalar v'v).  It is the factor for
    which the faded prediction of paper 001 eq. 10 makes the strictest criterion hold with equality:
    ``tr(H (Phi lambda P_{k-1} Phi' + Gamma Q Gamma') H' + R) = v'v``.

    Arguments, all matrices a filter has before its covariance prediction:

    * ``innovation`` v_k (m,) = z_k - H Phi x_{k-1} (x can be predicted before P);
    * ``HQH`` = H Gamma Q Gamma' H' (m, m);
    * ``R`` (m, m), the R the filter uses in this update;
    * ``HPpredH_no_Q`` = H Phi P_{k-1} Phi' H' (m, m), the predicted covariance without Q.

    Returns 1.0 exactly while :func:`divergence_test` (paper 001 eq. 11, with ``gamma`` and
    H P_{k,k-1} H' = HPpredH_no_Q + HQH) passes: the paper only estimates lambda when the
    test fails.  When it fails with gamma >= 1, v'v > tr(HPpredH_no_Q + HQH + R), hence
    paper 001 eq. 12 gives lambda > 1 by itself; the result is nevertheless clipped to >= 1
    (relevant for gamma < 1), because lambda < 1 would shrink P_{k-1} -- the opposite of what the
    fading memory is for.  ``max_factor`` (optional, >= 1) caps lambda against a single wild
    innovation inflating P by orders of magnitude; the paper has no cap (default None).

    Raises InputError if the test fails while tr(HPpredH_no_Q) <= 0 (no state uncertainty
    projects on the measurement, so no fading factor can explain the innovation).
    """
    if max_factor is not None and (not (max_factor >= 1.0) or not math.isfinite(max_factor)):
        raise ParameterError(f"max_factor (fading factor cap) must be >= 1, got {max_factor}")
    v = vector("innovation", innovation)
    m = v.shape[0]
    HQH = square("HQH", HQH, m)
    R = square("R", R, m)
    HPH0 = square("HPpredH_no_Q", HPpredH_no_Q, m)
    if not (gamma > 0.0) or not math.isfinite(gamma):
        raise ParameterError(f"gamma (divergence reserve coefficient) must be > 0, got {gamma}")
    lam, refused = fading_factor_rows(dot_rows(v, v)[None], HQH[None], R[None], HPH0[None],
                                      gamma, math.inf if max_factor is None else max_factor)
    if refused[0]:
        raise_no_fading_factor(np.trace(HPH0))
    return float(lam[0])


def fading_factor_rows(vv, HQH, R, HPH0, gamma, max_factor):
    """:func:`fading_factor` of every run (no checks) from ``v'v`` (B,) and ``HQH``, ``R``,
    ``HPH0`` (B, m, m), with ``gamma`` and ``max_factor`` (numbers or (B,); inf for no
    cap).  Returns (lambda (B,), refused (B,)): ``refused`` marks the runs whose test fails
    with tr(HPH0) <= 0, for which :func:`fading_factor` raises
    (:func:`raise_no_fading_factor`)."""
    holds = divergence_test_rows(vv, HPH0 + HQH, R, gamma)
    denominator = trace_rows(HPH0)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (vv - trace_rows(HQH) - trace_rows(R)) / denominator
    lam = np.where(lam > 1.0, lam, 1.0)                  # Python's max(1.0, lam): NaN gives 1
    lam = np.where(max_factor < lam, max_factor, lam)    # and min(lam, max_factor)
    return np.where(holds, 1.0, lam), ~holds & ~(denominator > 0.0)


def raise_no_fading_factor(denominator):
    """The error of :func:`fading_factor` when no fading factor explains the innovation."""
    raise InputError(
        "HPpredH_no_Q: trace must be > 0 to compute a fading factor (paper 001 eq. 12), got "
        f"{denominator}")


def fading_predict(P_propagated, GQG, lam: float) -> np.ndarray:
    """Fading-memory covariance prediction, paper 001 eq. 10.

    ``P_{k,k-1} = Phi (lam P_{k-1}) Phi' + Gamma Q Gamma' = lam P_propagated + GQG`` -- the
    factor multiplies P_{k-1} before propagation, not the process noise.  ``P_propagated`` =
    Phi P_{k-1} Phi' (n, n) (a filter accumulates Phi over its IMU steps), ``GQG`` = Gamma Q
    Gamma' (n, n), ``lam`` > 0 (from :func:`fading_factor`; 1 gives the standard prediction,
    paper 001 eq. 6, exactly).  The caller symmetrizes the covariance it adopts.
    """
    if not (lam > 0.0) or not math.isfinite(lam):
        raise InputError(f"lam (fading factor) must be finite and > 0, got {lam}")
    P_propagated = square("P_propagated", P_propagated)
    GQG = square("GQG", GQG, P_propagated.shape[0])
    return fading_predict_rows(P_propagated[None], GQG[None], np.array([lam]))[0]


def fading_predict_rows(P_propagated, GQG, lam) -> np.ndarray:
    """:func:`fading_predict` of every run (no checks): (B, n, n) each, ``lam`` (B,)."""
    return lam[:, None, None] * P_propagated + GQG


# ----------------------------------------------------------------------------------------
# paper 001, section 2.1: outlier compression of the innovation
# ----------------------------------------------------------------------------------------
def compression_factor(innovation, G, K, alpha: float = 0.05,
                       D: Optional[float] = None) -> Tuple[float, float, float]:
    """Outlier compression factor Y_k of paper 001, eqs. 13-14.

    ``tau = v' G^-1 v`` with ``G = H P_{k,k-1} H' + R`` (m, m), the innovation covariance
    (paper 001 eq. 13), and

    ``Y = 1`` if ``tau <= D^2 / lambda``, else ``Y = D / sqrt(tau lambda)``  (paper 001 eq. 14)

    where lambda is the largest eigenvalue of K G K' (``K`` the gain, (n, m)) and D the
    threshold.  The compressed innovation is ``Y v`` (paper 001 eq. 13); the IAKF uses it for the
    state update and for the Sage-Husa R estimate.

    Threshold.  The paper's recommended value is D = sqrt(lambda C) with C the upper
    alpha quantile of chi2(n), n = m the measurement dimension (``D=None``, the default;
    ``alpha`` 0.05 or 0.02 in the paper).  Then **lambda cancels**:

    * the gate D^2/lambda = C, so the test "tau <= D^2/lambda" is the ordinary chi-square
      test of the normalized innovation squared tau ~ chi2(m) at significance alpha;
    * above the gate Y = sqrt(lambda C) / sqrt(tau lambda) = sqrt(C / tau) < 1, so the
      compressed innovation has (Y v)' G^-1 (Y v) = Y^2 tau = C: an outlier is shrunk
      radially onto the gate (Huber-like), keeping its direction.

    With a constant ``D`` chosen by experience (the paper allows it), lambda matters:
    sqrt(tau lambda) bounds the state correction, ||K v|| <= sqrt(lambda tau) (lambda is also
    the largest eigenvalue of G^1/2 K' K G^1/2), so D is a limit on the norm of the state
    correction K Y v, in state units.  If lambda = 0 (zero gain) nothing is compressed.

    Returns ``(Y, tau, gate)`` with gate = D^2/lambda (= C for the default threshold).
    Y = 1 exactly at and below the gate.
    """
    v = vector("innovation", innovation)
    m = v.shape[0]
    G = square("G", G, m)
    K = matrix("K", K, cols=m)
    v, L = checked_cholesky(v, G, "G", numpy_factor=True)  # G = L L', tau = |L^-1 v|^2
    tau = nis_from_cholesky(L, v, general_solve=True)
    if D is None:
        gate = chi2_gate(alpha, m)
        return float(compression_rows(np.array([tau]), gate)[0]), tau, gate
    if not (D > 0.0) or not math.isfinite(D):
        raise ParameterError(f"D (compression threshold) must be finite and > 0, got {D}")
    lam = float(np.linalg.eigvalsh(symmetrize(K @ G @ K.T))[-1])
    if lam <= 0.0:
        return 1.0, tau, math.inf
    gate = D * D / lam
    Y = 1.0 if tau <= gate else D / math.sqrt(tau * lam)
    return Y, tau, gate


def compression_statistic_rows(innovation, G) -> np.ndarray:
    """The statistic ``tau = v' G^-1 v`` of :func:`compression_factor` for every run (no
    checks: ``innovation`` (B, m) and ``G`` (B, m, m) finite): numpy's Cholesky factor of
    the symmetrized G and its LU solve, as there.  Raises numpy's LinAlgError when a G is
    not positive definite."""
    L = np.linalg.cholesky(symmetric_rows(G))
    return cholesky_nis_rows(L, innovation)


def compression_rows(tau, gate) -> np.ndarray:
    """The factor Y of :func:`compression_factor` with the default threshold from the
    statistics ``tau`` (B,) and the chi-square gates ``gate`` (a number or (B,)): 1 at and
    below the gate, ``sqrt(gate / tau)`` above."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(tau <= gate, 1.0, np.sqrt(gate / tau))
