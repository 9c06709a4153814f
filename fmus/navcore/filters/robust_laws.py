"""Robust-filter laws of paper 004 (chi-square fault test, Newton extrapolation) and IGG-III.

Pure functions over numpy arrays plus the small observation history the extrapolation needs
(:class:`ObservationHistory`), called by the robust INS/GNSS filters in their update step.

Paper 004 (Cai et al., *Robust Kalman filtering algorithm using Newton interpolation*, 2020)
-------------------------------------------------------------------------------------------
The copy of paper 004 we have lost its numbered equations; what is implemented follows its
text (sections 2.1 and 2.2):

* :func:`chi_square_faults` -- the "single observation chi-square test": the statistic
  v_i^2 / S_ii (:func:`navcore.filters.innovation_stats.chi_square_per_observation`, one degree of
  freedom per observation) against the paper's threshold 6.635
  (:data:`navcore.filters.innovation_stats.CHI2_THRESHOLD_PAPER_004`, chi2(1) at alpha = 0.01;
  :func:`navcore.filters.innovation_stats.chi2_gate` gives it for any alpha and dof).
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
from typing import Optional, Union

import numpy as np

from .array_checks import vector
from ..errors import InputError, ParameterError
from .innovation_stats import CHI2_THRESHOLD_PAPER_004, chi_square_per_observation


# ----------------------------------------------------------------------------------------
# paper 004, section 2.1: per-observation chi-square test
# ----------------------------------------------------------------------------------------
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
        raise ParameterError(
            f"order (Newton extrapolation order) must be an integer >= 0, got {order}"
        )
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
            raise ParameterError(
                f"maxlen (observation history length) must be an integer >= 1, got {maxlen}"
            )
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
        z = vector("z", z)
        if self._values and z.shape != self._values[-1].shape:
            raise InputError(
                f"z: shape {z.shape} differs from the stored observations' {self._values[-1].shape}"
            )
        if epoch is None:
            epoch = 0 if self.last_epoch is None else self.last_epoch + 1
        if int(epoch) != epoch:
            raise InputError(f"epoch: expected an integer, got {epoch}")
        epoch = int(epoch)
        if self.last_epoch is not None:
            if epoch <= self.last_epoch:
                raise InputError(
                    f"epoch: {epoch} is not after the last stored epoch {self.last_epoch}"
                )
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
        delta = vector("delta_z", delta_z)
        if self._values and delta.shape != self._values[-1].shape:
            raise InputError(
                f"delta_z: shape {delta.shape} differs from the stored observations' "
                f"{self._values[-1].shape}"
            )
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
