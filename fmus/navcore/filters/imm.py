"""Interacting multiple model (IMM) machinery, generic over a bank of filters.

Paper 000 compares its CTFA-UKF with the IMM-UKF of its ref. [14] (Zang et al. 2007): a bank of
UKFs that differ in their process noise Q, run in parallel and blended by model probabilities
driven by the measurement likelihoods.  The paper gives no IMM equations, so this module follows
the standard IMM cycle (Blom & Bar-Shalom 1988; Bar-Shalom, Li, Kirubarajan, *Estimation with
Applications to Tracking and Navigation*, sec. 11.6.6), for ``r`` models with transition matrix
``Pi[i, j] = P(model j at k | model i at k-1)`` (rows sum to 1):

1. interaction / mixing (:func:`imm_mix`)::

       c_bar_j  = sum_i Pi[i, j] mu_i                    predicted model probability
       mu_{i|j} = Pi[i, j] mu_i / c_bar_j                mixing probability
       x0_j     = sum_i mu_{i|j} x_i
       P0_j     = sum_i mu_{i|j} (P_i + (x_i - x0_j)(x_i - x0_j)^T)

2. model-matched prediction and update of each filter from ``(x0_j, P0_j)``;
3. model probability update (:func:`imm_update_probabilities`)::

       mu_j = c_bar_j Lambda_j / sum_l c_bar_l Lambda_l,   Lambda_j = N(v_j; 0, S_j)

4. combination (:func:`imm_combine`) for output only::

       x = sum_j mu_j x_j,   P = sum_j mu_j (P_j + (x_j - x)(x_j - x)^T)

Likelihoods of a 3-dimensional GNSS innovation easily reach 1e-300 after a manoeuvre, so the
probability update works on log-likelihoods (subtracting the largest before exponentiating)
and floors every probability at ``floor`` before renormalizing, so no model is locked out by
underflow to exactly zero.

In an INS filter the predictions run at the IMU rate and updates at the GNSS rate: one IMM cycle
(and ``Pi``) spans one measurement interval.  :class:`ImmBank` therefore mixes once, at the first
prediction after an update, and uses the mixed-and-predicted probabilities ``c_bar`` until the
next update.
"""
from __future__ import annotations

from typing import Any, Callable, List, Optional, Sequence, Tuple

import numpy as np

from navcore.errors import InputError, ParameterError
from navcore.filters.innovation_stats import (checked_cholesky, gaussian_log_likelihood,
                                      log_det_from_cholesky, nis_from_cholesky)

#: default lower bound of a model probability after the update (see module docstring)
DEFAULT_PROBABILITY_FLOOR = 1e-12


def log_likelihood(innovation: np.ndarray, S: np.ndarray) -> float:
    """``log N(v; 0, S) = -(v^T S^-1 v + log det S + m log 2 pi) / 2`` via Cholesky of ``S``
    (the same arithmetic as the UKF update's likelihood).

    Raises :class:`InputError` if ``S`` is not positive definite or the inputs are not finite.
    """
    v, L = checked_cholesky(innovation, S, "log_likelihood")
    return gaussian_log_likelihood(nis_from_cholesky(L, v), log_det_from_cholesky(L), v.shape[0])


def check_transition_matrix(Pi: np.ndarray, r: Optional[int] = None) -> np.ndarray:
    """Validate a Markov transition matrix (square, entries in [0, 1], rows summing to 1)."""
    Pi = np.array(Pi, dtype=float)
    if Pi.ndim != 2 or Pi.shape[0] != Pi.shape[1] or (r is not None and Pi.shape[0] != r):
        want = "square" if r is None else f"{r}x{r}"
        raise ParameterError(f"IMM transition matrix 'Pi' must be {want}, got shape {Pi.shape}")
    if not np.isfinite(Pi).all() or (Pi < 0.0).any() or (Pi > 1.0).any():
        raise ParameterError("IMM transition matrix 'Pi' entries must be finite and in [0, 1]")
    if not np.allclose(Pi.sum(axis=1), 1.0, rtol=0.0, atol=1e-9):
        raise ParameterError(f"IMM transition matrix 'Pi' rows must sum to 1, got {Pi.sum(axis=1)}")
    return Pi


def _check_probabilities(mu: np.ndarray, name: str) -> np.ndarray:
    mu = np.asarray(mu, dtype=float)
    # min() is NaN if any entry is NaN and sum() is inf/NaN for inf: two reductions cover all
    if mu.ndim != 1 or not (mu.min() >= 0.0 and abs(mu.sum() - 1.0) <= 1e-9):
        raise InputError(f"IMM: '{name}' must be a probability vector (>= 0, sum 1), got {mu}")
    return mu


def _mixing_inputs(mu: np.ndarray, xs: Sequence[np.ndarray],
                   Ps: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``mu`` checked and the states and covariances as arrays (r, n) and (r, n, n)."""
    mu = _check_probabilities(mu, "mu")
    r = mu.shape[0]
    if len(xs) != r or len(Ps) != r:
        raise InputError(
            f"imm_mix: {r} probabilities but {len(xs)} states and {len(Ps)} covariances"
        )
    return mu, np.asarray(xs, dtype=float), np.asarray(Ps, dtype=float)


def imm_mix(mu: np.ndarray, Pi: np.ndarray, xs: Sequence[np.ndarray],
            Ps: Sequence[np.ndarray]) -> Tuple[List[np.ndarray], List[np.ndarray], np.ndarray]:
    """Interaction step: ``(mixed_xs, mixed_Ps, c_bar)`` (module docstring, step 1).

    ``mu`` are the model probabilities at k-1, ``Pi[i, j]`` the transition probabilities,
    ``xs``/``Ps`` the model-conditioned estimates.  A model that no model can reach
    (``c_bar_j = 0``, a zero column of ``Pi``) is mixed with weights ``mu`` so it stays defined.
    """
    mu, X, Parr = _mixing_inputs(mu, xs, Ps)
    mixed_X, mixed_P, c_bar = imm_mix_rows(mu[None], np.asarray(Pi)[None], X[None], Parr[None])
    return list(mixed_X[0]), list(mixed_P[0]), c_bar[0]


def imm_mix_rows(mu: np.ndarray, Pi: np.ndarray, X: np.ndarray,
                 P: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`imm_mix` of B banks at once: checked probabilities ``mu`` (B, r), transition
    matrices ``Pi`` (B, r, r), states ``X`` (B, r, n) and covariances ``P`` (B, r, n, n),
    C-contiguous.  Returns the mixed states (B, r, n), covariances (B, r, n, n) and ``c_bar``
    (B, r).  numpy's stacked products give every bank the floats of its own 2-D products
    (0 differences on 2 000 random batches of 1 to 24 banks of 1 to 4 models)."""
    runs, r, n = X.shape
    joint = Pi * mu[:, :, None]                      # joint[b, i, j] = Pi_ij mu_i
    c_bar = joint.sum(axis=1)
    reachable = c_bar > 0.0
    W = np.where(reachable[:, None, :], joint / np.where(reachable, c_bar, 1.0)[:, None, :],
                 mu[:, :, None])                     # W[b, i, j] = mu_{i|j}
    Wt = W.transpose(0, 2, 1)
    mixed_X = Wt @ X                                 # row j = sum_i mu_{i|j} x_i
    # all r weighted covariance sums in one matmul (tensordot costs ~10 us per call)
    sums = (Wt @ P.reshape(runs, r, n * n)).reshape(runs, r, n, n)
    mixed_P = np.empty((runs, r, n, n))
    for j in range(r):
        d = X - mixed_X[:, j, None, :]               # (B, r, n)
        Pj = sums[:, j] + (d.transpose(0, 2, 1) * W[:, None, :, j]) @ d
        mixed_P[:, j] = 0.5 * (Pj + Pj.transpose(0, 2, 1))
    return mixed_X, mixed_P, c_bar


def mix_banks(banks: Sequence["ImmBank"]) -> List[Optional[Exception]]:
    """:meth:`ImmBank.mix` of every bank of ``banks`` (r models each, states of one shape),
    in one :func:`imm_mix_rows` call.  Returns, per bank, the error its own mixing raised
    (the bank is then not mixed), or None."""
    stacked = _stacked_inputs(banks)
    if stacked is not None:
        _mix_stacked(banks, *stacked)
        return [None] * len(banks)
    errors: List[Optional[Exception]] = [None] * len(banks)
    mixed, inputs = [], []
    for i, bank in enumerate(banks):
        try:
            inputs.append(_mixing_inputs(bank.mu, [f.x for f in bank.filters],
                                         [f.P for f in bank.filters]))
            mixed.append(bank)
        except Exception as exc:       # the bank's own error (InputError)
            errors[i] = exc
    if not mixed:
        return errors
    shapes = {(X.shape, P.shape) for _, X, P in inputs}
    if len(shapes) > 1:            # states of other sizes: each bank by itself
        return [mix_banks([bank])[0] for bank in banks]
    _mix_stacked(mixed, *(np.stack(arrays) for arrays in zip(*inputs)))
    return errors


def _stacked_inputs(banks: Sequence["ImmBank"]):
    """The probabilities (B, r), states (B, r, n) and covariances (B, r, n, n) of the banks
    ``banks``, stacked, when every bank's would pass :func:`_mixing_inputs` and all have
    one shape (the checks of each row, its min and its sum of r terms, are a bank's own);
    else None."""
    try:
        mu = np.array([bank.mu for bank in banks], dtype=float)
        X = np.array([[f.x for f in bank.filters] for bank in banks], dtype=float)
        P = np.array([[f.P for f in bank.filters] for bank in banks], dtype=float)
    except ValueError:             # states of other sizes or numbers of models
        return None
    if not (mu.ndim == 2 and X.ndim == 3 and X.shape[:2] == mu.shape
            and P.shape == X.shape + X.shape[2:]):
        return None
    if not ((mu.min(axis=1) >= 0.0) & (np.abs(mu.sum(axis=1) - 1.0) <= 1e-9)).all():
        return None
    return mu, X, P


def _mix_stacked(banks: Sequence["ImmBank"], mu: np.ndarray, X: np.ndarray,
                 P: np.ndarray) -> None:
    """:func:`imm_mix_rows` of the banks ``banks``, checked and stacked, each taking its mix."""
    mixed_X, mixed_P, c_bar = imm_mix_rows(mu, np.stack([bank.Pi for bank in banks]), X, P)
    for bank, xs, Ps, c in zip(banks, mixed_X, mixed_P, c_bar):
        bank.take_mixed(xs, Ps, c)


def imm_update_probabilities(c_bar: np.ndarray, likelihoods: np.ndarray, *, log: bool = False,
                             floor: float = DEFAULT_PROBABILITY_FLOOR) -> np.ndarray:
    """Posterior model probabilities ``mu_j ∝ c_bar_j Lambda_j`` (module docstring, step 3).

    ``likelihoods`` are ``Lambda_j`` or, with ``log=True``, ``log Lambda_j`` (preferred: no
    underflow).  Computed in log space: ``a_j = log c_bar_j + log Lambda_j``,
    ``mu = exp(a - max a) / sum``; then every probability is raised to at least ``floor`` and the
    vector renormalized, so it sums to 1 and stays in [0, 1].  If every model has zero
    likelihood (``-inf``), the measurement carries no information on the model and ``c_bar`` is
    returned.  NaN likelihoods raise :class:`InputError`.
    """
    c_bar = np.asarray(c_bar, dtype=float)
    lik = np.asarray(likelihoods, dtype=float)
    if lik.shape != c_bar.shape:
        raise InputError(
            f"imm_update_probabilities: {c_bar.shape[0]} models but {lik.shape} likelihoods"
        )
    if np.isnan(lik).any() or (not log and (lik < 0.0).any()):
        raise InputError(f"imm_update_probabilities: invalid model likelihoods {lik}")
    if not (0.0 <= floor < 1.0 / c_bar.shape[0]):
        raise ParameterError(f"imm_update_probabilities: 'floor' must be in [0, 1/r), got {floor}")
    r = c_bar.shape[0]
    # log(0) = -inf without a divide warning (np.errstate costs more than the whole update)
    log_lik = lik if log else np.log(lik, out=np.full(r, -np.inf), where=lik > 0.0)
    mu, infinite = imm_probabilities_rows(c_bar[None], log_lik[None], np.full(1, float(floor)))
    if infinite[0]:
        raise InputError(f"imm_update_probabilities: infinite model likelihood {lik}")
    return mu[0]


def imm_probabilities_rows(c_bar: np.ndarray, log_lik: np.ndarray,
                           floor: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """The arithmetic of :func:`imm_update_probabilities` for B banks at once: predicted
    probabilities ``c_bar`` (B, r), log-likelihoods ``log_lik`` (B, r, none NaN) and floors
    (B,) checked.  Returns the posterior probabilities (B, r) and, per bank, whether a
    likelihood is infinite (its row is then not meaningful).  Elementwise operations and the
    reductions of each row (its max; its sum of r terms in order, as numpy sums one row
    alone) give every bank the floats of its own call."""
    runs, r = c_bar.shape
    a = np.log(c_bar, out=np.full((runs, r), -np.inf), where=c_bar > 0.0) + log_lik
    infinite = (a == np.inf).any(axis=1)
    a_max = a.max(axis=1, keepdims=True)
    # no model with a likelihood: c_bar (the shift by -inf would give NaN)
    special = infinite | (a_max[:, 0] == -np.inf)
    mu = np.exp(a - np.where(special[:, None], 0.0, a_max))
    if special.any():
        mu[special] = c_bar[special]
    mu /= mu.sum(axis=1, keepdims=True)
    floored = floor > 0.0
    if floored.all():
        mu = np.maximum(mu, floor[:, None])
        mu /= mu.sum(axis=1, keepdims=True)
    elif floored.any():
        at_least = np.maximum(mu[floored], floor[floored, None])
        mu[floored] = at_least / at_least.sum(axis=1, keepdims=True)
    return mu, infinite


def imm_combine(mu: np.ndarray, xs: Sequence[np.ndarray],
                Ps: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
    """Combined estimate ``(x, P)`` of the bank (module docstring, step 4)."""
    x, P = imm_combine_rows(np.asarray(mu, dtype=float)[None],
                            np.asarray(xs, dtype=float)[None], np.asarray(Ps, dtype=float)[None])
    return x[0], P[0]


def imm_combine_rows(mu: np.ndarray, X: np.ndarray,
                     P: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """:func:`imm_combine` of B banks at once: probabilities ``mu`` (B, r), states ``X``
    (B, r, n) and covariances ``P`` (B, r, n, n), C-contiguous; returns ``x`` (B, n) and
    ``P`` (B, n, n).  numpy's stacked products give every bank the floats of its own 2-D
    products (the row vector ``mu`` by gemv, the spread by gemm), so one bank alone is a
    batch of one."""
    runs, r, n = X.shape
    weights = mu[:, None, :]
    x = (weights @ X)[:, 0]
    d = X - x[:, None, :]
    P = ((weights @ P.reshape(runs, r, n * n)).reshape(runs, n, n)
         + (d.transpose(0, 2, 1) * weights) @ d)
    return x, 0.5 * (P + P.transpose(0, 2, 1))


def update_banks(banks: Sequence["ImmBank"],
                 log_likelihoods: Sequence[Sequence[float]]) -> List[Optional[Exception]]:
    """The end of :meth:`ImmBank.update` for every bank of ``banks`` (r models of one state
    dimension each) after its models' updates, whose log-likelihoods are
    ``log_likelihoods[i]``: each bank's model probabilities
    (:func:`imm_update_probabilities`), then the combination of all banks in one
    :func:`imm_combine_rows` call.  Returns, per bank, the error its own update raised (the
    bank is then not combined), or None."""
    errors: List[Optional[Exception]] = [None] * len(banks)
    log_lik = np.array(log_likelihoods, dtype=float)
    c_bar = np.array([bank.mu for bank in banks])
    floor = np.array([bank.floor for bank in banks])
    mu, own = None, np.ones(len(banks), dtype=bool)
    if log_lik.shape == c_bar.shape and log_lik.ndim == 2:
        # a NaN likelihood or a floor out of range: the bank's own call raises
        mu, infinite = imm_probabilities_rows(c_bar, np.where(np.isnan(log_lik), 0.0, log_lik),
                                              floor)
        own = infinite | np.isnan(log_lik).any(axis=1) | ~((floor >= 0.0)
                                                           & (floor < 1.0 / c_bar.shape[1]))
    updated = []
    for i, bank in enumerate(banks):
        try:
            bank.mu = (imm_update_probabilities(bank.mu, np.asarray(log_likelihoods[i],
                                                                    dtype=float),
                                                log=True, floor=bank.floor)
                       if own[i] else mu[i])
        except Exception as exc:       # the bank's own error (InputError)
            errors[i] = exc
            continue
        updated.append(bank)
    if updated:
        x, P = imm_combine_rows(np.stack([bank.mu for bank in updated]),
                                np.array([[f.x for f in bank.filters] for bank in updated]),
                                np.array([[f.P for f in bank.filters] for bank in updated]))
        for bank, x_bank, P_bank in zip(updated, x, P):
            bank.x, bank.P = x_bank, P_bank
            bank.needs_mixing = True
    return errors


class ImmBank:
    """A bank of filters run as an IMM (module docstring).

    ``filters`` are objects with settable attributes ``x`` and ``P`` (e.g.
    :class:`navcore.filters.unscented.UnscentedKalmanFilter`).  Model-specific behaviour is passed
    as callables, so the bank does not care what a model is:

    * ``predict(predict_fn)``: mixes if this is the first prediction since the last update,
      then calls ``predict_fn(filter, j)`` for every model ``j`` (e.g.
      ``lambda flt, j: flt.predict(f, Qs[j], dt)``); ``predict_all(predict_fn)`` the same
      with one call ``predict_fn(filters)`` for all models (models that share the process
      model can propagate all their points at once);
    * ``update(update_fn)``: calls ``update_fn(filter, j)`` for every model; it returns the
      model's log-likelihood of the measurement, either as a float or as a dict with key
      ``'log_likelihood'`` (what ``UnscentedKalmanFilter.update`` returns); then updates the
      model probabilities and the combined estimate.

    Attributes: ``mu`` (model probabilities; after a prediction, the predicted ``c_bar``),
    ``x``/``P`` (combined estimate), ``Pi``, ``floor``, ``filters``.  Plain attributes,
    deep-copyable (provided the filters are).
    """

    state_fields = ("filters", "mu", "needs_mixing", "x", "P")
    derived_fields = ("Pi", "floor")

    def __init__(self, filters: Sequence[Any], Pi: np.ndarray, mu0: Optional[np.ndarray] = None,
                 floor: float = DEFAULT_PROBABILITY_FLOOR):
        self.filters = list(filters)
        r = len(self.filters)
        if r < 1:
            raise ParameterError("ImmBank: needs at least one filter")
        self.Pi = check_transition_matrix(Pi, r)
        if mu0 is None:
            mu0 = np.full(r, 1.0 / r)
        try:
            self.mu = _check_probabilities(np.array(mu0, dtype=float), "mu0").copy()
        except InputError as exc:
            raise ParameterError(str(exc)) from None
        if self.mu.shape[0] != r:
            raise ParameterError(f"ImmBank: 'mu0' has {self.mu.shape[0]} entries for {r} filters")
        if not (0.0 <= floor < 1.0 / r):
            raise ParameterError(f"ImmBank: 'floor' must be in [0, 1/{r}), got {floor}")
        self.floor = float(floor)
        self.needs_mixing = True
        self.x, self.P = imm_combine(
            self.mu, [f.x for f in self.filters], [f.P for f in self.filters]
        )

    def mix(self) -> None:
        """Interaction step: replace each filter's ``(x, P)`` by its mixed initial condition and
        ``mu`` by the predicted probabilities ``c_bar``."""
        self.take_mixed(*imm_mix(self.mu, self.Pi, [f.x for f in self.filters],
                                 [f.P for f in self.filters]))

    def take_mixed(self, xs: Sequence[np.ndarray], Ps: Sequence[np.ndarray],
                   c_bar: np.ndarray) -> None:
        """The end of :meth:`mix` from :func:`imm_mix`'s results (or one bank's of
        :func:`mix_banks`)."""
        for flt, x, P in zip(self.filters, xs, Ps):
            flt.x, flt.P = x, P
        self.mu = c_bar / c_bar.sum()
        self.needs_mixing = False

    def predict(self, predict_fn: Callable[[Any, int], Any]) -> None:
        """Mix (once per measurement interval), then ``predict_fn(filter, j)`` for every model."""
        self.predict_all(lambda filters: [predict_fn(flt, j) for j, flt in enumerate(filters)])

    def predict_all(self, predict_fn: Callable[[List[Any]], Any]) -> None:
        """Mix (once per measurement interval), then ``predict_fn(filters)`` predicts every
        model in one call (e.g. one process-model evaluation over all models' sigma points)."""
        if self.needs_mixing:
            self.mix()
        predict_fn(self.filters)
        self.x, self.P = imm_combine(
            self.mu, [f.x for f in self.filters], [f.P for f in self.filters]
        )

    def update(self, update_fn: Callable[[Any, int], Any]) -> np.ndarray:
        """``update_fn(filter, j)`` for every model, then model probabilities and combination.

        Returns the log-likelihoods of the models.  If no prediction ran since the previous
        update, the bank mixes first, so every update belongs to one IMM cycle.
        """
        if self.needs_mixing:
            self.mix()
        log_liks = np.empty(len(self.filters))
        for j, flt in enumerate(self.filters):
            result = update_fn(flt, j)
            log_liks[j] = result["log_likelihood"] if isinstance(result, dict) else float(result)
        error = update_banks([self], [log_liks])[0]
        if error is not None:
            raise error
        return log_liks

    def subtract_from_states(self, delta: np.ndarray) -> None:
        """Shift every model's state by ``-delta`` (and the combined one): error-state feedback.

        After an INS error-state filter feeds its combined estimate back into the navigation
        solution it calls this with that estimate, so every model stays consistent with the
        corrected INS (covariances are unchanged by a known shift).
        """
        delta = np.asarray(delta, dtype=float)
        for flt in self.filters:
            flt.x = flt.x - delta
        self.x = self.x - delta
