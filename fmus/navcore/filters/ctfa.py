"""Chi-square-test fuzzy adaptive (CTFA) process-noise schedule, paper 000 eqs. 24-25.

Yang et al. evaluate the process model after every measurement update with the chi-square
statistic of the innovation (paper 000 eq. 24)::

    q_k = (z_k - z_pred)^T P_zz^-1 (z_k - z_pred)

(the paper prints it as a quotient ``v v^T / P_zz``; for a vector measurement that means
``v^T P_zz^-1 v``, and the paper's ``P_zz`` contains the measurement noise through its augmented
sigma points, i.e. it is the innovation covariance ``S``).  It then sets the process noise for
the next step with the piecewise-linear "fuzzy membership" function of paper 000 eq. 25::

    Q_est = Q_{k-1}                                             q_k < q_min
          = (q_k - q_min) / (q_max - q_min) (Q_max - Q_min) + Q_min   q_min <= q_k <= q_max
          = Q_max                                               q_k > q_max

with ``Q_0 = Q_min``.  The paper writes the slope as ``1/5.1``, which is ``1/(q_max - q_min)``
for its thresholds ``q_min = 6.25`` and ``q_max = 11.35`` (chi-square quantiles at 90 % and 99 %
for 3 degrees of freedom, the dimension of its GPS position measurement, paper 000 eqs. 3-4).

Note the memory in the first branch: below ``q_min`` the paper *keeps* the previous Q ("the
model is not adjusted"), it does not fall back to ``Q_min``.  Because every Q the schedule
produces has the form ``Q_min + w (Q_max - Q_min)``, the schedule is carried exactly by the
scalar weight ``w in [0, 1]``: :func:`ctfa_q_scale` maps ``(q_k, w_{k-1})`` to ``w_k`` and
:class:`CtfaQSchedule` turns it into Q.  Passing ``previous_weight=0`` gives the memoryless
variant "Q_min below q_min", which equals paper 000 eq. 25 as long as nothing above ``q_min`` has
been seen since ``Q_0 = Q_min``.  The statistic itself is :mod:`navcore.filters.innovation_stats`'s.

Ours, not the paper's: :class:`CtfaQSchedule` takes a ``pass_decay`` factor ``d in [0, 1]`` applied
while the test passes, ``w_k = d w_{k-1}`` for ``q_k < q_min``.  ``d = 1`` is paper 000 eq. 25 as
printed (the default), ``d = 0`` the memoryless variant; in between Q returns exponentially towards
``Q_min`` (time constant ``-T_fix / ln d`` for fixes every ``T_fix``) once the manoeuvre that
raised it is over, instead of staying wherever the last exceedance put it (with 3 degrees of
freedom ``q_k >= 6.25`` on 10 % of the epochs of a correct model).
"""
from __future__ import annotations

import math
from typing import Tuple

import numpy as np

from navcore.errors import InputError, ParameterError
from navcore.filters.innovation_stats import CTFA_THRESHOLDS_PAPER_000, chi2_lower_quantile

#: thresholds printed in paper 000 (eq. 25) for a 3-dimensional measurement
PAPER_T1, PAPER_T2 = CTFA_THRESHOLDS_PAPER_000


def ctfa_thresholds(dof: int, p_low: float = 0.90, p_high: float = 0.99) -> Tuple[float, float]:
    """Thresholds ``(q_min, q_max)`` of paper 000 eq. 25: chi-square quantiles at ``p_low``
    and ``p_high``.

    For ``dof = 3`` this gives ``(6.2514, 11.3449)``; the paper prints 6.25 and 11.35 (11.345
    rounded up).  ``dof`` is the measurement dimension.
    """
    if int(dof) != dof or dof < 1:
        raise ParameterError(f"ctfa_thresholds: 'dof' must be a positive integer, got {dof}")
    if not (0.0 < p_low < p_high < 1.0):
        raise ParameterError(
            f"ctfa_thresholds: need 0 < p_low < p_high < 1, got p_low={p_low}, p_high={p_high}")
    return float(chi2_lower_quantile(p_low, dof)), float(chi2_lower_quantile(p_high, dof))


def _check_thresholds(T1: float, T2: float, where: str) -> None:
    if not (math.isfinite(T1) and math.isfinite(T2)) or T1 < 0.0 or T2 <= T1:
        raise ParameterError(f"{where}: thresholds must satisfy 0 <= T1 < T2, got T1={T1}, T2={T2}")


def _check_stat(stat: float, where: str) -> float:
    stat = float(stat)
    if not math.isfinite(stat) or stat < 0.0:
        raise InputError(
            f"{where}: chi-square statistic 'stat' must be finite and >= 0, got {stat}"
        )
    return stat


def ctfa_q_scale(stat: float, T1: float = PAPER_T1, T2: float = PAPER_T2,
                 previous_weight: float = 0.0) -> float:
    """Weight ``w`` of paper 000 eq. 25 with ``Q = Q_min + w (Q_max - Q_min)``.

    ``w = previous_weight`` if ``stat < T1`` (the paper keeps ``Q_{k-1}``; with the default 0
    this is the memoryless "Q_min below T1"), ``(stat - T1) / (T2 - T1)`` for
    ``T1 <= stat <= T2`` and ``1`` above ``T2``.
    """
    where = "ctfa_q_scale"
    _check_thresholds(T1, T2, where)
    stat = _check_stat(stat, where)
    if not (0.0 <= previous_weight <= 1.0):
        raise InputError(f"{where}: 'previous_weight' must be in [0, 1], got {previous_weight}")
    if stat < T1:
        return float(previous_weight)
    if stat > T2:
        return 1.0
    return (stat - T1) / (T2 - T1)


class CtfaQSchedule:
    """Stateful paper 000 eq. 25 schedule: holds the weight ``w`` so that
    ``Q = Qmin + w (Qmax - Qmin)``.

    ``update(stat)`` applies paper 000 eq. 25 after a measurement update and returns the Q for the
    next prediction; ``pass_decay`` < 1 is our return towards Qmin while the test passes (module
    docstring).  Starts at ``Q_0 = Qmin`` (``w = 0``).  Plain attributes, deep-copyable.
    ``Qmin`` and ``Qmax`` are validated: same square shape, finite, symmetric, and
    ``Qmax - Qmin`` positive semi-definite (so every scheduled Q lies between them).
    """

    state_fields = ("weight", "Q")
    derived_fields = ("Qmin", "Qmax", "T1", "T2", "_span", "pass_decay")

    def __init__(self, Qmin: np.ndarray, Qmax: np.ndarray, T1: float = PAPER_T1,
                 T2: float = PAPER_T2, pass_decay: float = 1.0):
        _check_thresholds(T1, T2, "CtfaQSchedule")
        pass_decay = float(pass_decay)
        if not 0.0 <= pass_decay <= 1.0:
            raise ParameterError(f"CtfaQSchedule: 'pass_decay' must be in [0, 1], got {pass_decay}")
        self.pass_decay = pass_decay
        Qmin = np.array(Qmin, dtype=float)
        Qmax = np.array(Qmax, dtype=float)
        for name, Q in (("Qmin", Qmin), ("Qmax", Qmax)):
            if Q.ndim != 2 or Q.shape[0] != Q.shape[1]:
                raise ParameterError(
                    f"CtfaQSchedule: '{name}' must be a square matrix, got shape {Q.shape}"
                )
            if not np.isfinite(Q).all():
                raise ParameterError(f"CtfaQSchedule: '{name}' must be finite")
            if not np.allclose(Q, Q.T, rtol=1e-12, atol=0.0):
                raise ParameterError(f"CtfaQSchedule: '{name}' must be symmetric")
        if Qmin.shape != Qmax.shape:
            raise ParameterError(
                f"CtfaQSchedule: 'Qmin' {Qmin.shape} and 'Qmax' {Qmax.shape} differ in shape")
        span = Qmax - Qmin
        min_eig = float(np.linalg.eigvalsh(span).min())
        if min_eig < -1e-12 * max(float(np.abs(Qmax).max()), 1e-300):
            raise ParameterError("CtfaQSchedule: 'Qmax - Qmin' must be positive semi-definite "
                                 f"(smallest eigenvalue {min_eig:.3g})")
        self.Qmin, self.Qmax, self.T1, self.T2 = Qmin, Qmax, float(T1), float(T2)
        self._span = span
        self.weight = 0.0
        self.Q = Qmin.copy()

    def update(self, stat: float) -> np.ndarray:
        """Eq. 25 with the chi-square statistic of the last update (below ``T1`` the weight is
        multiplied by ``pass_decay``, 1 = the paper's hold); returns the new Q."""
        self.weight = ctfa_q_scale(stat, self.T1, self.T2, self.pass_decay * self.weight)
        self.Q = self.Qmin + self.weight * self._span
        return self.Q

    def reset(self) -> None:
        """Back to ``Q_0 = Qmin``."""
        self.weight = 0.0
        self.Q = self.Qmin.copy()
