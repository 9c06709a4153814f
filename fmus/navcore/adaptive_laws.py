"""Adaptation laws of the adaptive / robust Kalman filters of papers 001 and 004.

Pure functions over numpy arrays, called by an INS/GNSS error-state Kalman filter in its
prediction and update steps.  No filter state lives here except the small observation
history of paper 004 (:class:`ObservationHistory`).

Shapes used throughout (m = measurement dimension, n = state dimension):

=============================  ==========  ===================================================
name                           shape       meaning
=============================  ==========  ===================================================
``innovation``                 (m,)        v_k = z_k - H_k x_{k,k-1}  (paper 001 eq. 5)
``H``                          (m, n)      measurement matrix
``K``                          (n, m)      Kalman gain (eq. 7)
``P`` / ``P_post``             (n, n)      state covariance P_{k-1} / P_k (eq. 8)
``R``                          (m, m)      measurement noise covariance
``G`` / ``S``                  (m, m)      innovation covariance H P_{k,k-1} H' + R
``Phi``                        (n, n)      state transition matrix Phi_{k,k-1}
``GQG``                        (n, n)      Gamma_k Q_k Gamma_k'
=============================  ==========  ===================================================

Paper 001 (Yuan et al., *Improved adaptive Kalman filter in GPS/SINS*, 2015)
----------------------------------------------------------------------------
* :func:`sage_husa_r_update` -- simplified Sage-Husa R estimator, eq. 9, with
  :func:`sage_husa_weight` d_k = (1 - b) / (1 - b^(k+1)) and the positive-definiteness guard
  :func:`guard_positive_definite` (+ :func:`r_floor_from_initial` for its floor).
* :func:`divergence_test` (eq. 11), :func:`fading_factor` (eq. 12) and
  :func:`fading_predict` (eq. 10) -- the fading-memory filter.
* :func:`compression_factor` -- outlier compression of the innovation, eqs. 13-14.

Order of the calls in one IAKF cycle (paper 001, section 2.2)::

    x_pred = Phi @ x                                   # eq. 3, does not need P
    v = z - H @ x_pred                                 # eq. 5
    HPH0 = H @ Phi @ P @ Phi.T @ H.T                   # H Phi P_{k-1} Phi' H'
    HQH = H @ GQG @ H.T                                # H Gamma Q Gamma' H'
    lam = fading_factor(v, HQH, R, HPH0, gamma)        # eqs. 11-12 (1 while eq. 11 holds)
    P_pred = fading_predict(Phi, P, GQG, lam)          # eq. 10
    G = H @ P_pred @ H.T + R
    K = P_pred @ H.T @ inv(G)                          # eq. 7
    Y, tau, gate = compression_factor(v, G, K)         # eqs. 13-14
    v = Y * v                                          # compressed innovation
    x = x_pred + K @ v;  P = (I - K H) P_pred          # eqs. 4, 8
    R = sage_husa_r_update(R, v, H, K, P, k, b, R_min) # eq. 9 with the guard

Paper 004 (Cai et al., *Robust Kalman filtering algorithm using Newton interpolation*, 2020)
-------------------------------------------------------------------------------------------
The copy of paper 004 we have lost its numbered equations; what is implemented follows its
text (sections 2.1 and 2.2):

* :func:`chi_square_per_observation` -- the "single observation chi-square test" statistic
  v_i^2 / S_ii, one degree of freedom per observation; :func:`chi_square_faults` compares it
  with the paper's threshold 6.635 (:data:`CHI2_THRESHOLD_PAPER_004`, chi2(1) at
  alpha = 0.01); :func:`chi2_threshold` gives the threshold for any alpha and dof.
* :func:`newton_forward_extrapolate` -- one-step extrapolation of the previous observations
  by the equally spaced Newton interpolation polynomial (4th order in the paper).
* :class:`ObservationHistory` -- the previous observations the extrapolation uses.

Robust-filter extra (not from the four papers): :func:`igg3_weight`, the IGG-III equivalent
weight factor of Yang Yuanxi's robust estimation, which paper 004 lists as the other common
robust method ("等价权函数法", section 1.2).
"""
from __future__ import annotations

import math
from collections import deque
from functools import lru_cache
from typing import Optional, Tuple, Union

import numpy as np
from navcore.chisquare import chi2 as _chi2

from navcore.component import InputError, ParameterError

ArrayLike = Union[np.ndarray, float, list]

#: Threshold of paper 004's per-observation chi-square test (section 2.1): chi2(1) upper
#: quantile at significance 0.01 (scipy gives 6.6349).
CHI2_THRESHOLD_PAPER_004 = 6.635

#: Default fraction of the initial R diagonal used as the variance floor of the guard
#: (see :func:`r_floor_from_initial`): a floor of 1 % of the variance, i.e. 10 % of the
#: standard deviation, never binds while the estimator behaves, and keeps R invertible
#: and the gain bounded when it does not.
DEFAULT_R_FLOOR_FRACTION = 0.01


# ----------------------------------------------------------------------------------------
# input checking (cheap: these functions run once per filter update)
# ----------------------------------------------------------------------------------------
def _vector(name: str, x) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise InputError(f"{name}: expected a vector of shape (m,), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf: {a}")
    return a


def _matrix(name: str, x, shape: Tuple[int, int]) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 and shape == (1, 1):
        a = a.reshape(1, 1)
    if a.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf")
    return a


def _square(name: str, x, m: Optional[int] = None) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise InputError(f"{name}: expected a square matrix, got shape {a.shape}")
    if m is not None and a.shape[0] != m:
        raise InputError(f"{name}: expected shape ({m}, {m}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf")
    return a


def _symmetrize(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + a.T)


# ----------------------------------------------------------------------------------------
# paper 001, section 1.1: simplified Sage-Husa measurement-noise estimator
# ----------------------------------------------------------------------------------------
def sage_husa_weight(k: int, b: float) -> float:
    """Weight d_k = (1 - b) / (1 - b^(k+1)) of the Sage-Husa estimator (paper 001, eq. 9).

    ``b`` is the forgetting factor, 0 < b <= 1 (paper: 0.95-0.99); ``k`` >= 0 the index of
    the update.  With these weights the recursion of eq. 9 is exactly the exponentially
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
    in the state update, i.e. already compressed by eq. 13 in the IAKF; ``H`` (m, n);
    ``K`` (n, m); ``P_post`` P_k (n, n) after the update (eq. 8).  ``R_min`` (optional,
    scalar or (m,)): if given, the result goes through :func:`guard_positive_definite`.

    The result is symmetrized (round-off makes H P_k H' slightly asymmetric).
    """
    v = _vector("innovation", innovation)
    m = v.shape[0]
    R_prev = _square("R_prev", R_prev, m)
    H = np.asarray(H, dtype=float)
    if H.ndim != 2 or H.shape[0] != m:
        raise InputError(f"H: expected shape ({m}, n), got {H.shape}")
    n = H.shape[1]
    H = _matrix("H", H, (m, n))
    K = _matrix("K", K, (n, m))
    P_post = _square("P_post", P_post, n)
    d = sage_husa_weight(k, b)

    residual = v - H @ (K @ v)                 # (I - H K) v without forming I - H K
    sample = np.outer(residual, residual) + H @ P_post @ H.T
    R_new = _symmetrize((1.0 - d) * R_prev + d * sample)
    if R_min is not None:
        R_new = guard_positive_definite(R_new, R_min)
    return R_new


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

    Why a guard although eq. 9 of paper 001 is a convex combination of PSD terms: other
    Sage-Husa forms (innovation-based, ``v v' - H P_{k,k-1} H'``) subtract a covariance and
    lose definiteness outright; the simplified form only keeps it in exact arithmetic and
    with a PD R_{k-1}.  What can still go wrong:

    * small k: d_k is large (d_0 = 1, d_1 ~ 0.5), so R is one or two rank-one samples
      e e' plus H P_k H', which is nearly singular once the filter is confident;
    * round-off: P_k from (I - K H) P_{k,k-1} (eq. 8, not Joseph form) loses symmetry and
      can get slightly negative eigenvalues, and so can H P_k H';
    * compressed innovations (eqs. 13-14): during an outlier patch each innovation is
      shrunk onto the gate, so the samples under-estimate R and R decays geometrically
      towards H P_k H'; the gain then grows and the filter trusts the bad data more;
    * small true noise / long quiet periods with b < 1 drive R towards zero, and a nearly
      singular G = H P H' + R makes the gain and the chi-square statistics ill-conditioned.

    ``R_min``: scalar or (m,) of variance floors, > 0 (default choice in a filter:
    :func:`r_floor_from_initial`, 1 % of the initial R diagonal).
    """
    R = _square("R", R)
    m = R.shape[0]
    floor = np.asarray(R_min, dtype=float)
    if floor.ndim == 0:
        floor = np.full(m, float(floor))
    if floor.shape != (m,):
        raise ParameterError(f"R_min: expected a scalar or shape ({m},), got {floor.shape}")
    if not np.all(np.isfinite(floor)) or np.any(floor <= 0.0):
        raise ParameterError(f"R_min: floors must be finite and > 0, got {floor}")
    R = _symmetrize(R)
    try:  # fast path (a few us): R - diag(R_min) positive definite, nothing to repair
        np.linalg.cholesky(R - np.diag(floor))
        return R
    except np.linalg.LinAlgError:
        pass
    scale = np.sqrt(floor)
    S = R / np.outer(scale, scale)
    w, V = np.linalg.eigh(S)
    S_g = (V * np.maximum(w, 1.0)) @ V.T
    return _symmetrize(S_g * np.outer(scale, scale))


# ----------------------------------------------------------------------------------------
# paper 001, section 1.2: fading-memory filter
# ----------------------------------------------------------------------------------------
def divergence_test(innovation, HPH_prior, R, gamma: float = 1.0) -> bool:
    """Divergence criterion of paper 001, eq. 11: True while the filter works normally.

    ``v'v <= gamma * tr(E[v v'])`` with ``E[v v'] = H P_{k,k-1} H' + R`` (the innovation
    covariance of the *unfaded* prediction, eq. 6).  ``HPH_prior`` = H P_{k,k-1} H' (m, m),
    ``R`` (m, m).  ``gamma`` is the paper's reserve coefficient: gamma = 1 is the strictest
    criterion the paper considers; larger gamma tolerates larger innovations before the
    fading factor is engaged.  gamma < 1 is allowed but stricter than the paper's strictest.
    Returns False when the criterion fails (filter diverging -> apply eq. 12).
    """
    if not (gamma > 0.0) or not math.isfinite(gamma):
        raise ParameterError(f"gamma (divergence reserve coefficient) must be > 0, got {gamma}")
    v = _vector("innovation", innovation)
    m = v.shape[0]
    HPH = _square("HPH_prior", HPH_prior, m)
    R = _square("R", R, m)
    return bool(v @ v <= gamma * (np.trace(HPH) + np.trace(R)))


def fading_factor(innovation, HQH, R, HPpredH_no_Q, gamma: float = 1.0,
                  max_factor: Optional[float] = None) -> float:
    """Fading factor lambda_k of paper 001, eqs. 11-12.

    ``lambda_k = (v'v - tr(H Gamma Q Gamma' H' + R)) / tr(H Phi P_{k-1} Phi' H')``  (eq. 12)

    (the paper prints the numerator as Z Z', meaning the scalar v'v).  It is the factor for
    which the faded prediction of eq. 10 makes the strictest criterion hold with equality:
    ``tr(H (Phi lambda P_{k-1} Phi' + Gamma Q Gamma') H' + R) = v'v``.

    Arguments, all matrices a filter has before its covariance prediction:

    * ``innovation`` v_k (m,) = z_k - H Phi x_{k-1} (x can be predicted before P);
    * ``HQH`` = H Gamma Q Gamma' H' (m, m);
    * ``R`` (m, m), the R the filter uses in this update;
    * ``HPpredH_no_Q`` = H Phi P_{k-1} Phi' H' (m, m), the predicted covariance without Q.

    Returns 1.0 exactly while :func:`divergence_test` (eq. 11, with ``gamma`` and
    H P_{k,k-1} H' = HPpredH_no_Q + HQH) passes: the paper only estimates lambda when the
    test fails.  When it fails with gamma >= 1, v'v > tr(HPpredH_no_Q + HQH + R), hence
    eq. 12 gives lambda > 1 by itself; the result is nevertheless clipped to >= 1 (relevant
    for gamma < 1), because lambda < 1 would shrink P_{k-1} -- the opposite of what the
    fading memory is for.  ``max_factor`` (optional, >= 1) caps lambda against a single wild
    innovation inflating P by orders of magnitude; the paper has no cap (default None).

    Raises InputError if the test fails while tr(HPpredH_no_Q) <= 0 (no state uncertainty
    projects on the measurement, so no fading factor can explain the innovation).
    """
    if max_factor is not None and (not (max_factor >= 1.0) or not math.isfinite(max_factor)):
        raise ParameterError(f"max_factor (fading factor cap) must be >= 1, got {max_factor}")
    v = _vector("innovation", innovation)
    m = v.shape[0]
    HQH = _square("HQH", HQH, m)
    R = _square("R", R, m)
    HPH0 = _square("HPpredH_no_Q", HPpredH_no_Q, m)
    if divergence_test(v, HPH0 + HQH, R, gamma):
        return 1.0
    denominator = np.trace(HPH0)
    if not denominator > 0.0:
        raise InputError(
            "HPpredH_no_Q: trace must be > 0 to compute a fading factor (eq. 12), got "
            f"{denominator}")
    lam = (v @ v - np.trace(HQH) - np.trace(R)) / denominator
    lam = max(1.0, float(lam))
    if max_factor is not None:
        lam = min(lam, float(max_factor))
    return lam


def fading_predict(Phi, P, GQG, lam: float) -> np.ndarray:
    """Fading-memory covariance prediction, paper 001 eq. 10.

    ``P_{k,k-1} = Phi (lam P_{k-1}) Phi' + Gamma Q Gamma'`` -- the factor multiplies P_{k-1}
    before propagation, not the process noise.  ``Phi`` (n, n), ``P`` = P_{k-1} (n, n),
    ``GQG`` = Gamma Q Gamma' (n, n), ``lam`` > 0 (from :func:`fading_factor`; 1 gives the
    standard prediction, eq. 6).  The result is symmetrized.
    """
    if not (lam > 0.0) or not math.isfinite(lam):
        raise InputError(f"lam (fading factor) must be finite and > 0, got {lam}")
    P = _square("P", P)
    n = P.shape[0]
    Phi = _matrix("Phi", Phi, (n, n))
    GQG = _square("GQG", GQG, n)
    return _symmetrize(lam * (Phi @ P @ Phi.T) + GQG)


# ----------------------------------------------------------------------------------------
# paper 001, section 2.1: outlier compression of the innovation
# ----------------------------------------------------------------------------------------
def compression_factor(innovation, G, K, alpha: float = 0.05,
                       D: Optional[float] = None) -> Tuple[float, float, float]:
    """Outlier compression factor Y_k of paper 001, eqs. 13-14.

    ``tau = v' G^-1 v`` with ``G = H P_{k,k-1} H' + R`` (m, m), the innovation covariance
    (eq. 13), and

    ``Y = 1`` if ``tau <= D^2 / lambda``, else ``Y = D / sqrt(tau lambda)``  (eq. 14)

    where lambda is the largest eigenvalue of K G K' (``K`` the gain, (n, m)) and D the
    threshold.  The compressed innovation is ``Y v`` (eq. 13); the IAKF uses it for the
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
    v = _vector("innovation", innovation)
    m = v.shape[0]
    G = _square("G", G, m)
    K = np.asarray(K, dtype=float)
    if K.ndim != 2 or K.shape[1] != m:
        raise InputError(f"K: expected shape (n, {m}), got {K.shape}")
    K = _matrix("K", K, K.shape)
    try:
        cho = np.linalg.cholesky(_symmetrize(G))
    except np.linalg.LinAlgError:
        raise InputError("G: innovation covariance is not positive definite") from None
    w = np.linalg.solve(cho, v)                      # G = L L', tau = |L^-1 v|^2
    tau = float(w @ w)
    if D is None:
        gate = chi2_threshold(alpha, m)
        Y = 1.0 if tau <= gate else math.sqrt(gate / tau)
        return Y, tau, gate
    if not (D > 0.0) or not math.isfinite(D):
        raise ParameterError(f"D (compression threshold) must be finite and > 0, got {D}")
    lam = float(np.linalg.eigvalsh(_symmetrize(K @ G @ K.T))[-1])
    if lam <= 0.0:
        return 1.0, tau, math.inf
    gate = D * D / lam
    Y = 1.0 if tau <= gate else D / math.sqrt(tau * lam)
    return Y, tau, gate


# ----------------------------------------------------------------------------------------
# paper 004, section 2.1: per-observation chi-square test
# ----------------------------------------------------------------------------------------
def chi2_threshold(alpha: float, dof: int = 1) -> float:
    """Upper alpha quantile of chi2(dof): the gate a chi-square test at significance alpha
    compares its statistic with (``chi2_threshold(0.01, 1)`` = 6.6349, paper 004's 6.635).
    """
    if not (0.0 < alpha < 1.0):
        raise ParameterError(f"alpha (significance level) must be in (0, 1), got {alpha}")
    if int(dof) != dof or dof < 1:
        raise ParameterError(f"dof (degrees of freedom) must be an integer >= 1, got {dof}")
    return _chi2_upper_quantile(float(alpha), int(dof))


@lru_cache(maxsize=64)
def _chi2_upper_quantile(alpha: float, dof: int) -> float:
    # cached: scipy's quantile costs ~0.3 ms, and a filter asks for the same gate every update
    return float(_chi2.isf(alpha, dof))


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
    s = np.diag(_square("S", S, m))
    if np.any(s <= 0.0):
        raise InputError(f"S: diagonal must be > 0, got {s}")
    return v * v / s


def chi_square_faults(innovation, S, threshold: float = CHI2_THRESHOLD_PAPER_004) -> np.ndarray:
    """Boolean mask of the faulty observations: r_i > threshold (paper 004, section 2.1).

    Default threshold 6.635 (chi2(1), alpha = 0.01): the paper's choice after trying
    alpha 0.25-0.01 (thresholds up to 6.635).  On clean Gaussian innovations each component
    is flagged with probability alpha.
    """
    if not (threshold > 0.0) or not math.isfinite(threshold):
        raise ParameterError(f"threshold (chi-square gate) must be finite and > 0, got {threshold}")
    return chi_square_per_observation(innovation, S) > threshold


# ----------------------------------------------------------------------------------------
# paper 004, section 2.2: Newton extrapolation of the previous observations
# ----------------------------------------------------------------------------------------
def newton_forward_extrapolate(samples, order: int = 4) -> Union[float, np.ndarray]:
    """One-step extrapolation by the equally spaced Newton polynomial (paper 004, sec. 2.2).

    ``samples``: equally spaced values, oldest first, shape (m,) (a scalar sequence) or
    (m, d) (a sequence of d-vectors, extrapolated per column).  Uses the last
    ``p + 1`` samples, p = min(order, m - 1), builds their difference table and evaluates the
    degree-p interpolation polynomial one spacing after the newest sample.  Returns a
    float (1-D input) or an array of shape (d,).  One sample is returned as it is (p = 0);
    zero samples raise InputError (a ValueError).

    Derivation.  Newton's backward-difference formula at the newest node f_N,
    ``f(N + s) = sum_j C(s + j - 1, j) nabla^j f_N``, at s = 1 has every coefficient
    C(j, j) = 1, so the extrapolation is simply the sum of the backward differences:

        f_{N+1} = f_N + nabla f_N + nabla^2 f_N + ... + nabla^p f_N

    (the same polynomial as the forward form sum_j C(p+1, j) Delta^j f_{N-p}).  Written
    with the samples (j = 0 the newest), because nabla^(p+1) of a degree-p polynomial is 0:

        f_{N+1} = sum_{j=0..p} (-1)^j C(p+1, j+1) f_{N-j}

    e.g. p = 4: 5 f_N - 10 f_{N-1} + 10 f_{N-2} - 5 f_{N-3} + f_{N-4}.  Exact for
    polynomials of degree <= p; for degree p+1 the error is nabla^(p+1) f (e.g. 120 a5 h^5
    for a5 t^5 and p = 4).

    Noise.  The weights amplify white noise in the samples: the standard deviation of the
    extrapolated value is sqrt(sum C(p+1, j+1)^2) = sqrt(C(2p+2, p+1) - 1) times that of one
    sample: 1, 2.24, 4.36, 8.31, 15.8 for p = 0..4.  A 4th-order extrapolation of an
    observation with white noise is therefore only useful when the noise is small against
    what the test rejects (the paper's m-times outliers); lower ``order`` trades model
    error for noise.
    """
    if int(order) != order or order < 0:
        raise ParameterError(f"order (Newton extrapolation order) must be an integer >= 0, got {order}")
    a = np.asarray(samples, dtype=float)
    if a.ndim not in (1, 2):
        raise InputError(f"samples: expected shape (m,) or (m, d), got {a.shape}")
    if a.shape[0] == 0:
        raise InputError("samples: need at least one previous sample to extrapolate")
    if not np.all(np.isfinite(a)):
        raise InputError("samples: contains NaN or inf")
    p = min(int(order), a.shape[0] - 1)
    table = a[a.shape[0] - p - 1:].copy()
    # table[-1] after j differencing passes is nabla^j f_N; sum them (s = 1 coefficients).
    result = table[-1].copy()
    for _ in range(p):
        table = np.diff(table, axis=0)
        result += table[-1]
    return float(result) if a.ndim == 1 else result


class ObservationHistory:
    """The previous observations paper 004 extrapolates (section 2.2), newest last.

    What to store: the measurement vector z of the loosely coupled filter, i.e. INS minus
    GNSS (position and/or velocity differences) -- the quantity the paper's filter tests and
    replaces.  For a moving vehicle raw GNSS positions are smooth too, but z is what the
    chi-square test looks at, so z is what we store; per component, a replaced value is
    ``np.where(faults, history.predict_next(), z)``.

    Append at every filter epoch the z the filter *used*: the measured one if accepted, the
    Newton replacement if rejected.  This keeps the samples equally spaced (the formula
    needs it) through isolated faults such as the paper's m-times outlier every 10 s; the
    price is that consecutive faults extrapolate from extrapolations.  An epoch that is not
    the next one (a GNSS outage) clears the history, since equal spacing is lost.

    Closed-loop filters: INS - GNSS is smooth only while the INS is not reset.  After the
    filter feeds its estimate back into the INS, call :meth:`apply_correction` with the
    change of z that the reset causes (H dx for the fed-back error state dx) so the stored
    samples read as if the INS had been corrected all along.

    Plain attributes only (a deque of arrays), so ``copy.deepcopy`` and pickling give an
    independent history, as FMU state save/restore needs.
    """

    state_fields = ("_values", "last_epoch")
    derived_fields = ("maxlen",)

    def __init__(self, maxlen: int = 5):
        if int(maxlen) != maxlen or maxlen < 1:
            raise ParameterError(f"maxlen (observation history length) must be an integer >= 1, got {maxlen}")
        self.maxlen = int(maxlen)
        self._values: deque = deque(maxlen=self.maxlen)
        self.last_epoch: Optional[int] = None

    def __len__(self) -> int:
        return len(self._values)

    def clear(self) -> None:
        self._values.clear()
        self.last_epoch = None

    def append(self, z, epoch: Optional[int] = None) -> None:
        """Store the observation used at ``epoch`` (default: the epoch after the last one)."""
        z = _vector("z", z)
        if self._values and z.shape != self._values[-1].shape:
            raise InputError(
                f"z: shape {z.shape} differs from the stored observations' {self._values[-1].shape}")
        if epoch is None:
            epoch = 0 if self.last_epoch is None else self.last_epoch + 1
        if int(epoch) != epoch:
            raise InputError(f"epoch: expected an integer, got {epoch}")
        epoch = int(epoch)
        if self.last_epoch is not None:
            if epoch <= self.last_epoch:
                raise InputError(f"epoch: {epoch} is not after the last stored epoch {self.last_epoch}")
            if epoch != self.last_epoch + 1:
                self._values.clear()
        self._values.append(z.copy())
        self.last_epoch = epoch

    def samples(self) -> np.ndarray:
        """Stored observations, oldest first, shape (len, m) (a copy)."""
        if not self._values:
            return np.zeros((0, 0))
        return np.array(self._values)

    def apply_correction(self, delta_z) -> None:
        """Subtract ``delta_z`` (m,) from every stored observation (closed-loop INS reset)."""
        delta = _vector("delta_z", delta_z)
        if self._values and delta.shape != self._values[-1].shape:
            raise InputError(
                f"delta_z: shape {delta.shape} differs from the stored observations' {self._values[-1].shape}")
        for value in self._values:
            value -= delta

    def predict_next(self, order: int = 4) -> Union[float, np.ndarray]:
        """Newton extrapolation of the stored observations to epoch ``last_epoch + 1``.

        Uses :func:`newton_forward_extrapolate` (lower order while fewer than order + 1
        samples are stored); raises InputError if the history is empty.
        """
        if not self._values:
            raise InputError("ObservationHistory: no previous observation to extrapolate from")
        return newton_forward_extrapolate(self.samples(), order)


# ----------------------------------------------------------------------------------------
# robust-filter extra: IGG-III equivalent weight
# ----------------------------------------------------------------------------------------
def igg3_weight(standardized_residual, k0: float = 1.5, k1: float = 3.0):
    """IGG-III equivalent-weight factor (Yang Yuanxi's robust estimation).

    With u = |standardized residual| (e.g. v_i / sqrt(S_ii), so u^2 is paper 004's r_i):

    * w = 1                                        for u <= k0 (keep the observation),
    * w = (k0 / u) ((k1 - u) / (k1 - k0))^2        for k0 < u <= k1 (down-weight),
    * w = 0                                        for u > k1 (reject).

    The equivalent weight is w p, i.e. the equivalent variance R_ii / w (infinite for w = 0:
    drop the component).  w is continuous (1 at k0, 0 at k1) and non-increasing in u.
    Typical k0 = 1.0-1.5, k1 = 2.5-4.5.  Accepts a scalar (returns float) or an array.
    """
    if not (0.0 < k0 < k1) or not math.isfinite(k1):
        raise ParameterError(f"k0, k1 (IGG-III constants) must satisfy 0 < k0 < k1, got {k0}, {k1}")
    u = np.abs(np.asarray(standardized_residual, dtype=float))
    if not np.all(np.isfinite(u)):
        raise InputError("standardized_residual: contains NaN or inf")
    with np.errstate(divide="ignore", invalid="ignore"):
        middle = (k0 / u) * ((k1 - u) / (k1 - k0)) ** 2
    w = np.where(u <= k0, 1.0, np.where(u <= k1, middle, 0.0))
    return float(w) if w.ndim == 0 else w
