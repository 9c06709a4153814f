"""Adaptive and robust INS/GNSS filters of papers 001 and 004, built on :class:`KfEngine`.

Every engine here is the baseline 15-state closed-loop error-state filter of
:mod:`navcore.filters.ins_gnss_kf` with a different measurement update; propagation, feedback and
the measurement ``z = INS - GNSS`` are shared.  The adaptation laws are the pure functions of
:mod:`navcore.filters.adaptive_laws` (paper 001) and :mod:`navcore.filters.robust_laws` (paper 004),
the statistics those of :mod:`navcore.filters.innovation_stats`:

* :class:`SageHusaFadingEngine` -- simplified Sage-Husa R estimator (paper 001 eq. 9) combined
  with the fading-memory filter (paper 001 eqs. 10-12): the combination of paper 001's
  reference [9] and its Fig. 4 ("Sage-Husa + fading").
* :class:`IakfEngine` -- paper 001's improved adaptive filter: the above plus the outlier
  compression of the innovation (paper 001 eqs. 13-14).
* :class:`NewtonRobustKfEngine` -- paper 004: per-observation chi-square test (threshold 6.635)
  and replacement of a failed observation by the Newton forward extrapolation of the
  previous observations.
* :class:`Igg3RobustKfEngine` -- IGG-III equivalent weights on the standardized innovations (the
  "equivalent weight" method paper 004 lists in its section 1.2; not a paper's own filter).
* :class:`InsOnlyEngine` -- no measurement feedback at all (paper 004's "INS only" curves).

The adaptive and robust engines update through :class:`RowUpdates`: the arithmetic of their
law over a leading run axis, so the runs of a batch (:mod:`navcore.components.filter_batch`)
update in one call and a single engine is a batch of one.

In closed loop the predicted error state is zero, so the innovation is ``v = z`` (paper 001
eq. 5 with x_{k,k-1} = 0).  All engines return an :class:`UpdateResult` (NIS, r_scale,
fading factor, outlier flag) and keep their own extra diagnostics as attributes, read by the
components after each update.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from . import adaptive_laws as laws
from . import robust_laws
from ..ins.error_model import N_STATES
from ..errors import InputError
from .innovation_stats import (chi2_gate, chi_square_per_observation, dot_rows, nis, nis_rows,
    trace_rows)
from .ins_gnss_kf import KfEngine, UpdateResult, kalman_rows, predicted_rows
from .recovery import GuardedEngine, bounded_r_rows, inflate_navigation

def masked_update(P_pred, z, R, keep):
    """Kalman update with only the measurement components where ``keep`` is True.

    The measurement matrix is ``[I_m 0]`` (z = INS - GNSS of the first m states), so the
    rows of the kept components select states directly.  Joseph form, like
    :meth:`KfEngine.kalman_update`.  Returns ``(dx, P)``; with nothing kept, ``dx = 0``
    and ``P = P_pred`` (a pure prediction).
    """
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        return np.zeros(N_STATES), 0.5 * (P_pred + P_pred.T)
    PHt = P_pred[:, idx]
    S = PHt[idx, :] + R[np.ix_(idx, idx)]
    K = np.linalg.solve(S, PHt.T).T
    KH = np.zeros((N_STATES, N_STATES))
    KH[:, idx] = K
    IKH = np.eye(N_STATES) - KH
    P = IKH @ P_pred @ IKH.T + K @ R[np.ix_(idx, idx)] @ K.T
    return K @ z[idx], 0.5 * (P + P.T)


def _require_finite(*named, show_values=True):
    """Raise the checked laws' InputError for the first (name, stacked array) with a NaN or
    inf (an innovation's message shows the values, as :func:`array_checks.vector`'s, unless
    not ``show_values``)."""
    for name, rows in named:
        if not np.isfinite(rows).all():
            if name == "innovation" and show_values:
                bad = rows[~np.isfinite(rows).all(axis=1)][0]
                raise InputError(f"{name}: contains NaN or inf: {bad}")
            raise InputError(f"{name}: contains NaN or inf")


class RowUpdates:
    """Mixin of an engine whose update is arithmetic over a leading run axis: the engines
    of one class in a batch update in one call of :meth:`updates`, a single engine as a
    batch of one (:meth:`update`), so both run the same code on the same floats.  A class
    writes ``_update_rows(engines, z, p_prop, q_acc)`` (the arithmetic of every run from the
    measurements and the two parts of the prediction; it changes no engine and raises the
    error of a run that has one) and ``_take_update(outcome, b)`` (run b's own bookkeeping
    with its row of the outcome: feedback, counters, diagnostics; its UpdateResult).  List
    it before the engine's base class."""

    def update(self, z):
        """One update with the measurement ``z`` (:meth:`updates` of this engine alone)."""
        result, = self.updates([self], np.asarray(z, dtype=float)[None], self.P[None],
                               self.phi_acc[None], self.q_acc[None])
        if isinstance(result, Exception):
            raise result
        return result

    @classmethod
    def updates(cls, engines, z, P, phi_acc, q_acc):
        """The updates of ``engines`` (of this class, one measurement dimension) with the
        measurements ``z`` (B, m) and their P, Phi_acc and Q_acc stacked (B, 15, 15).
        Returns per engine its UpdateResult, or the exception its own update raised (an
        engine whose arithmetic fails is left unchanged).  When any run's arithmetic
        fails, every run updates alone, so each meets its own error."""
        try:
            outcome = cls._update_rows(engines, z, predicted_rows(P, phi_acc), q_acc)
        except Exception as exc:
            if len(engines) == 1:
                return [exc]
            return [type(engine).updates([engine], z[b:b + 1], P[b:b + 1], phi_acc[b:b + 1],
                                         q_acc[b:b + 1])[0]
                    for b, engine in enumerate(engines)]
        results = []
        for b, engine in enumerate(engines):
            try:
                results.append(engine._take_update(outcome, b))
            except Exception as exc:          # the run's own error
                results.append(exc)
        return results


# ------------------------------------------------------------------------------------------
class SageHusaFadingEngine(RowUpdates, GuardedEngine, KfEngine):
    """Simplified Sage-Husa R estimation + fading memory (paper 001, secs. 1.1-1.2).

    One update (``v = z``, closed loop; equations of paper 001)::

        p_prop, q_acc = Phi P_{k-1} Phi', Gamma Q Gamma'          (the two parts of eq. 6)
        lambda = 1 if eq. 11 holds else eq. 12                    (with the current R_hat)
        P_pred = lambda p_prop + q_acc                            (eq. 10)
        K, x, P from P_pred and R_hat                             (eqs. 4, 7, 8; Joseph form)
        R_hat <- eq. 9 with d_k = (1-b)/(1-b^(k+1)), then the PD guard

    The fading factor multiplies only the propagated P_{k-1} part (paper 001 eq. 10), never the
    process noise.  The Sage-Husa index k counts updates from 1, so R0 (the datasheet R of
    the scenario) counts as the first sample of the exponentially weighted mean (see
    :func:`adaptive_laws.sage_husa_weight`).

    Parameters
    ----------
    forgetting_factor : b of paper 001 eq. 9, in (0, 1]; paper 001: 0.95-0.99.  Default 0.95,
        the short end: a memory of about 1/(1-b) = 20 updates (20 s at 1 Hz), so R_hat
        follows a step of the measurement noise quickly (the measurements behind the choice:
        docs/aircraft_500s.md).
    reserve_gamma : gamma of paper 001 eq. 11 (> 0).  Default 10: the test must fire on a
        real divergence only, because every firing is costly: paper 001 eq. 12 multiplies the whole
        P_{k-1} by lambda, including the weakly observable heading and bias variances, which
        the next updates do not bring back down.  For a consistent filter v'v has mean exactly
        tr(E[v v']); with R in NED metres the three position innovations dominate the trace
        (the paper mixes radians and metres in its traces), so v'v / tr ~ chi2(3)/3 and the
        nominal false-alarm probability per epoch is P(chi2(3) > 3 gamma): 39 % for
        gamma = 1, 2.9 % for 3, 0.18 % for 5, 1.4e-6 for 10.  The real rate is higher early
        in a run, when R_hat rests on a few samples (d_k ~ 1/(k+1)); what smaller gammas did
        on aircraft_500s: docs/aircraft_500s.md.
    r_floor_fraction : variance floor of the positive-definiteness guard as a fraction of
        diag(R0) (:func:`adaptive_laws.r_floor_from_initial`); default 1 % of the variance
        (10 % of the sigma): never binds while the estimator behaves, and keeps R invertible
        when a long quiet stretch or compressed innovations drive it towards H P H'.
    max_fading_factor : optional cap on lambda (None = paper 001's uncapped eq. 12).
    r_max_scale : recovery guard (with ``recovery`` on): R_hat stays at most this multiple of
        R0 per axis (:func:`navcore.filters.recovery.bounded_r`), so a diverging state cannot drive
        the estimate away; paper 001's eq. 9 has no upper bound.
    recovery : the recovery guard of :mod:`navcore.filters.recovery` (ours; off = paper 001's law):
        here only the bound ``r_max_scale``.  This filter takes every fix, and after an outage
        its own fading factor (eq. 12) inflates P as much as the innovation asks, so it needs
        no re-acquisition (one on top of the fading factor made it worse after each outage
        of models/mems_outages).  ``recovery_epochs`` serves Iakf.
    """

    state_fields = ("R", "sage_husa_index")
    derived_fields = ("forgetting_factor", "reserve_gamma", "max_fading_factor", "r_min",
                      "r_max")

    def __init__(self, config, nav, *, forgetting_factor, reserve_gamma, r_floor_fraction,
                 max_fading_factor, r_max_scale, recovery, recovery_epochs):
        super().__init__(config, nav)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        self.r_max = float(r_max_scale) * np.diag(self.R0) if self.guard.enabled else None
        self.forgetting_factor = float(forgetting_factor)
        self.reserve_gamma = float(reserve_gamma)
        self.max_fading_factor = max_fading_factor
        self.r_min = laws.r_floor_from_initial(self.R0, r_floor_fraction)
        self.R = self.R0.copy()
        self.sage_husa_index = 0

    # -- the arithmetic of the runs' updates (RowUpdates), pieces shared with IakfEngine -------
    @classmethod
    def _update_rows(cls, engines, z, p_prop, q_acc):
        """Paper 001 eqs. 9-12 of every run (the innovation is ``z``: closed loop)."""
        return cls._adapted_rows(engines, z, p_prop, q_acc)

    @staticmethod
    def _adapted_rows(engines, v, p_prop, q_acc):
        """The divergence test, fading factor and faded prediction (paper 001 eqs. 11, 12,
        10), the Kalman update with R_hat (eqs. 4, 7, 8) and the next R_hat (eq. 9, its
        guard and bound) of every run with the innovations ``v`` (B, m) -- compressed in
        the IAKF, so the same v drives the state and the R estimate (paper 001, text under
        eq. 14).  Changes no engine; raises the error of the first run that has one, as
        the checked laws do."""
        m = v.shape[1]
        H = engines[0].H
        R = np.array([engine.R for engine in engines])
        _require_finite(("innovation", v), ("HQH", q_acc[:, :m, :m]), ("R", R),
                        ("HPpredH_no_Q", p_prop[:, :m, :m]))
        lam, refused = laws.fading_factor_rows(
            dot_rows(v, v), q_acc[:, :m, :m], R, p_prop[:, :m, :m],
            np.array([engine.reserve_gamma for engine in engines]),
            np.array([math.inf if engine.max_fading_factor is None else engine.max_fading_factor
                      for engine in engines]))
        if refused.any():
            laws.raise_no_fading_factor(trace_rows(p_prop[:, :m, :m])[refused][0])
        if not np.isfinite(lam).all():
            raise InputError(f"lam (fading factor) must be finite and > 0, got "
                             f"{lam[~np.isfinite(lam)][0]}")
        _require_finite(("P_propagated", p_prop), ("GQG", q_acc))
        dx, P, _, S, K = kalman_rows(laws.fading_predict_rows(p_prop, q_acc, lam), v, R, H)
        _require_finite(("K", K), ("P_post", P))
        weights = np.array([laws.sage_husa_weight(engine.sage_husa_index + 1,
                                                  engine.forgetting_factor)
                            for engine in engines])
        R_new = laws.sage_husa_r_rows(R, v, H, K, P, weights)
        _require_finite(("R", R_new))
        R_new = laws.guard_positive_definite_rows(
            R_new, np.array([engine.r_min for engine in engines]))
        bounded = [b for b, engine in enumerate(engines) if engine.r_max is not None]
        if bounded:                     # recovery guard: bounded adaptive scale
            R_new[bounded] = bounded_r_rows(
                R_new[bounded], np.array([engines[b].r_max for b in bounded]))
        return dict(v=v, lam=lam, dx=dx, P=P, S=S, R_used=R, R=R_new, nis=nis_rows(v, S))

    def _take_update(self, outcome, b):
        """Run b's Sage-Husa index, R_hat and feedback from ``outcome``, and its result."""
        self.sage_husa_index += 1
        self.R = outcome["R"][b]
        self.apply(outcome["dx"][b], outcome["P"][b])
        return UpdateResult(outcome["v"][b], outcome["S"][b], float(outcome["nis"][b]),
                            r_scale=float(np.trace(outcome["R_used"][b]) / np.trace(self.R0)),
                            fading_factor=float(outcome["lam"][b]))

    def r_sigma_estimate(self):
        """Current R_hat as 1-sigma per measurement axis (pos n/e/d [m], vel n/e/d [m/s])."""
        return np.sqrt(np.diag(self.R))


# ------------------------------------------------------------------------------------------
class IakfEngine(SageHusaFadingEngine):
    """Paper 001's improved adaptive Kalman filter: Sage-Husa + fading + outlier compression.

    Order of operations (paper 001 sec. 2; its flow chart, Fig. 1, is missing from our copy,
    so the order follows the text):

    1. Outlier test and compression on the *unfaded* prediction (paper 001 eqs. 13-14):
       ``G = H P_{k,k-1} H' + R_hat`` with P_{k,k-1} from paper 001 eq. 6 -- paper 001 eq. 13
       defines G from P_{k,k-1}, and sec. 2 explains that the fading memory "cannot judge and
       handle" outliers.  Testing first matters: paper 001 eq. 12 chooses lambda so that tr(G)
       equals v'v, so after fading an outlier would always look normal and pass with a large gain --
       exactly the failure of Sage-Husa + fading at 350-360 s that the paper reports.
       ``tau = v' G^-1 v``; with the paper's threshold D = sqrt(lambda_max C_n^alpha) the
       gate is the chi2(n) quantile C (n = m, the measurement dimension) and
       ``Y = sqrt(C / tau)`` above it (see :func:`adaptive_laws.compression_factor`).
    2. ``v <- Y v`` (paper 001 eq. 13).
    3. Divergence test and fading factor (paper 001 eqs. 11-12) on the compressed innovation,
       faded prediction paper 001 eq. 10.  Without an outlier (Y = 1) the filter is exactly
       :class:`SageHusaFadingEngine`, as the paper says ("退化为普通简化的 Sage-Husa").
    4. Kalman update with the compressed innovation and R_hat, then R_hat by paper 001 eq. 9
       from the same compressed innovation ("用修正的新息去估计量测方差阵 R_k 和当前时刻的状态").

    ``outlier_alpha``: alpha of the chi2 quantile, 0.05 or 0.02 in paper 001; default 0.02.
    Each false compression of a clean epoch discards good position information, and a
    filter whose tuning is optimistic early in a flight sees clean epochs cross the gate
    more often than alpha; the smaller alpha compresses fewer of them (measured on
    aircraft_500s: docs/aircraft_500s.md).
    Recovery guard (ours, :mod:`navcore.filters.recovery`; off = paper 001's law): an epoch whose
    innovation would be compressed after ``recovery_epochs`` fix intervals without an
    uncompressed one (a run of compressions or an outage) is re-acquired: its innovation is
    taken uncompressed (Y = 1), so steps 3-4 -- the divergence test and paper 001's own
    fading factor -- inflate the prediction as much as the innovation asks.  R_hat is bounded
    as in :class:`SageHusaFadingEngine`.

    After an update, ``compression`` holds Y and ``tau`` the statistic.
    """

    state_fields = ("compression", "tau")
    derived_fields = ("outlier_alpha",)

    def __init__(self, config, nav, *, outlier_alpha, **kwargs):
        super().__init__(config, nav, **kwargs)
        chi2_gate(outlier_alpha, self.m)   # checks the level (compression_factor gates)
        self.outlier_alpha = float(outlier_alpha)
        self.compression = 1.0
        self.tau = 0.0

    @classmethod
    def _update_rows(cls, engines, z, p_prop, q_acc):
        """IAKF update (paper 001 eqs. 9-14) of every run; see the class docstring for the
        order."""
        v = z
        m = v.shape[1]
        P_std = p_prop + q_acc                                   # paper 001 eq. 6
        G = P_std[:, :m, :m] + np.array([engine.R for engine in engines])
        # paper 001 eq. 7, the gain eq. 14's threshold D would need: only checked here, as
        # compression_factor checks it
        K_std = np.linalg.solve(G, P_std[:, :, :m].swapaxes(-1, -2))
        _require_finite(("innovation", v), ("G", G), ("K", K_std))
        try:
            tau = laws.compression_statistic_rows(v, G)
        except np.linalg.LinAlgError:
            raise InputError("G: innovation covariance 'S' is not positive definite") from None
        Y = laws.compression_rows(tau, np.array([chi2_gate(engine.outlier_alpha, m)
                                                 for engine in engines]))
        # recovery guard: taken uncompressed, the fading factor inflates P (a run whose
        # innovation is not compressed flags nothing)
        reacquired = np.array([y < 1.0 and engine.guard.due_at_opening(np.full(m, True)).any()
                               for engine, y in zip(engines, Y.tolist())], dtype=bool)
        Y = np.where(reacquired, 1.0, Y)
        outcome = cls._adapted_rows(engines, Y[:, None] * v, p_prop, q_acc)  # eq. 13
        outcome.update(innovation=v, G=G, tau=tau, Y=Y, reacquired=reacquired)
        return outcome

    def _take_update(self, outcome, b):
        """Run b's guard, Sage-Husa update and feedback from ``outcome``, and its result:
        the NIS of the raw innovation against the unfaded prediction, the statistic the
        outlier test used (what a user compares with the chi2(m) gate)."""
        guard = self.guard
        guard.open_epoch()
        if outcome["reacquired"][b]:
            guard.n_reacquired += 1
        adapted = super()._take_update(outcome, b)
        Y = float(outcome["Y"][b])
        guard.close_epoch(Y == 1.0)
        self.compression = Y
        self.tau = float(outcome["tau"][b])
        return UpdateResult(outcome["innovation"][b], outcome["G"][b], self.tau,
                            r_scale=adapted.r_scale, fading_factor=adapted.fading_factor,
                            outlier=Y < 1.0)


# ------------------------------------------------------------------------------------------
#: NewtonRobustKfEngine: a replacement whose error variance reaches this multiple of R_ii (1000
#: sigma) carries no information and is left out of the update (first epoch, or a run of
#: faults so long that the history holds only extrapolations of extrapolations)
UNUSABLE_VARIANCE_FACTOR = 1e6
#: how the R of a replaced observation is set (NewtonRobustKf's ``replacement_variance``)
REPLACEMENT_VARIANCES = ("propagated", "nominal")


class NewtonRobustKfEngine(RowUpdates, GuardedEngine, KfEngine):
    """Paper 004: per-observation chi-square test + Newton extrapolation of failed observations.

    Each update:

    1. ``S = H P_{k,k-1} H' + R`` (standard prediction, fixed R) and the per-observation
       statistics ``r_i = v_i^2 / S_ii`` (paper 004 sec. 2.1, "single observation chi-square
       test", one degree of freedom; :func:`innovation_stats.chi_square_per_observation`).
    2. ``r_i > chi2_threshold`` (paper: 6.635, chi2(1) at alpha = 0.01) marks observation i
       as failed.
    3. A failed observation is replaced by the one-step Newton forward extrapolation of the
       previous observations of that component (sec. 2.2; ``newton_order``, 4 in the paper;
       lower while fewer previous epochs exist).  The replacement is what enters the update.
       With no previous observation (the first epoch) there is nothing to extrapolate and the
       component is left out of that update; so is a replacement whose propagated error
       variance reaches ``UNUSABLE_VARIANCE_FACTOR`` R_ii (a long run of faults).
    4. Standard Kalman update; the observation used (measured or replaced) is appended to the
       history, and after the closed-loop feedback the stored observations are shifted by
       the correction H dx (:meth:`robust_laws.ObservationHistory.apply_correction`) so
       they read as if the INS had been corrected all along -- otherwise every feedback
       would put a step into the INS-minus-GNSS sequence that the polynomial extrapolates.

    The observation is the paper's INS minus GNSS (position NED [m], velocity NED [m/s]),
    updated at the GNSS rate (1 s in the paper and in ``aircraft_outliers``).

    ``replacement_variance`` (our addition; the paper is silent):

    * ``"nominal"`` -- the replaced component keeps its nominal R_ii (the literal reading);
    * ``"propagated"`` (default) -- the error variance of the extrapolation
      (:meth:`_extrapolated_variance`): R_ii times ``sum_j w_j^2 = C(2p+2, p+1) - 1`` for
      order p (1, 5, 19, 69, 251 for p = 0..4) when the p+1 samples were measured: the
      extrapolated value is a weighted sum of earlier observations whose white GNSS noise
      it amplifies by that factor (see :func:`robust_laws.newton_forward_extrapolate`).
      With 5 m position noise a 4th-order replacement has about 79 m of noise; feeding it
      with a 5 m sigma would do more harm than most outliers it replaces.

    Equal spacing: the engine counts the time since its last update (in :meth:`propagate`)
    and gives the history the epoch index ``round(gap / interval)`` after the last one,
    ``interval`` being the first gap seen; a missed fix (outage, stale fix) therefore
    clears the history instead of extrapolating over an unequal spacing.

    Recovery guard (ours, :mod:`navcore.filters.recovery`; off = the paper's law): a component that
    fails the test after ``recovery_epochs`` fix intervals without an accepted value (a run of
    faults or an outage) is re-acquired: the prediction is inflated until its innovation is
    consistent, the test runs again on it and the component is taken as measured.

    After an update: ``chi2_values`` (m,), ``chi2_max``, ``rejected`` (bool mask),
    ``n_rejected``.
    """

    state_fields = ("history", "sample_variances", "time", "last_update_time",
                    "update_interval", "history_epoch", "chi2_values", "chi2_max", "rejected",
                    "n_rejected")
    derived_fields = ("chi2_threshold", "newton_order", "replacement_variance")

    def __init__(self, config, nav, *, chi2_threshold, newton_order, replacement_variance,
                 recovery, recovery_epochs):
        super().__init__(config, nav)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        self.chi2_threshold = float(chi2_threshold)
        self.newton_order = int(newton_order)
        self.replacement_variance = replacement_variance
        self.history = robust_laws.ObservationHistory(maxlen=self.newton_order + 1)
        #: error variance of each stored observation, per component (R_ii for a measured
        #: one, the propagated variance for a replaced one), parallel to ``history``
        self.sample_variances = deque(maxlen=self.newton_order + 1)
        self.time = 0.0               # s of IMU data integrated
        self.last_update_time = None
        self.update_interval = None
        self.history_epoch = 0
        self.chi2_values = np.zeros(self.m)
        self.chi2_max = 0.0
        self.rejected = np.zeros(self.m, dtype=bool)
        self.n_rejected = 0

    def advance_clocks_over(self, dts):
        """Count time for the history's epoch index."""
        super().advance_clocks_over(dts)
        time = self.time
        for dt in dts:
            time += dt
        self.time = time

    def _next_epoch(self):
        epoch, self.update_interval = self._epoch_now()
        self.last_update_time = self.time
        self.history_epoch = epoch
        return epoch

    def _epoch_now(self):
        """(epoch, update interval) of an update now, as :meth:`_next_epoch` sets them."""
        if self.last_update_time is None:
            return 0, self.update_interval
        gap = self.time - self.last_update_time
        interval = gap if self.update_interval is None else self.update_interval
        steps = round(gap / interval) if interval > 0 else 1
        return self.history_epoch + max(1, steps), interval

    def _history_now(self):
        """Whether the history holds samples an update now extrapolates (the epoch now
        follows its last one: a missed fix leaves the samples unequally spaced)."""
        last = self.history.last_epoch
        return len(self.history) > 0 and (last is None or self._epoch_now()[0] == last + 1)

    def _extrapolated_variance(self):
        """Error variance of the Newton extrapolation, per component (m,).

        The extrapolation is ``sum_j w_j f_{N-j}`` with ``w_j = (-1)^j C(p+1, j+1)``
        (:func:`robust_laws.newton_forward_extrapolate`), so for independent sample errors
        its variance is ``sum_j w_j^2 var_{N-j}`` -- ``(C(2p+2, p+1) - 1) R_ii`` when every
        sample was measured, more when some were themselves replacements (a run of faults
        extrapolates from extrapolations: the variance grows and the replacement's weight
        in the update fades instead of the filter trusting a diverging polynomial).
        """
        variances = np.array(self.sample_variances)
        p = min(self.newton_order, len(variances) - 1)
        weights = np.array([math.comb(p + 1, j + 1) for j in range(p + 1)], dtype=float)
        newest_first = variances[::-1][:p + 1]
        return (weights ** 2) @ newest_first

    @classmethod
    def _update_rows(cls, engines, z, p_prop, q_acc):
        """Chi-square test + Newton replacement (paper 004 secs. 2.1-2.2) of every run: the
        test of all runs at once, the replacement of each run with a failed observation by
        its own history (:meth:`_replaced`), the Kalman updates of all runs but those that
        leave a component out (:func:`masked_update`, each alone) in one call."""
        m = z.shape[1]
        P_pred = p_prop + q_acc
        R = np.array([engine.R0 for engine in engines])
        S = P_pred[:, :m, :m] + R
        _require_finite(("innovation", z), ("S", S), show_values=False)
        s = np.diagonal(S, axis1=1, axis2=2)
        if np.any(s <= 0.0):
            raise InputError(f"S: diagonal must be > 0, got {s[(s <= 0.0).any(axis=1)][0]}")
        chi2 = z * z / s                        # chi_square_per_observation of every run
        faults = chi2 > np.array([engine.chi2_threshold for engine in engines])[:, None]
        outcome = dict(z=z, P_pred=P_pred, S=S, chi2=chi2, faults=faults, R=R, z_used=z,
                       variance_used=np.diagonal(R, axis1=1, axis2=2).copy(),
                       drop=np.zeros_like(faults), reacquired=np.zeros(len(engines), bool))
        faulty = np.flatnonzero(faults.any(axis=1)).tolist()
        if faulty:
            outcome["z_used"] = z.copy()
            for b in faulty:
                engines[b]._replaced(outcome, b)
        P_pred, z_used, R, drop = (outcome[name] for name in ("P_pred", "z_used", "R", "drop"))
        dx = np.empty((len(engines), N_STATES))
        P = np.empty_like(P_pred)
        whole = ~drop.any(axis=1)
        if whole.all():
            dx, P, _, _, _ = kalman_rows(P_pred, z_used, R, engines[0].H)
        else:
            if whole.any():
                dx[whole], P[whole], _, _, _ = kalman_rows(P_pred[whole], z_used[whole],
                                                           R[whole], engines[0].H)
            for b in np.flatnonzero(~whole).tolist():
                dx[b], P[b] = masked_update(P_pred[b], z_used[b], R[b], ~drop[b])
        outcome.update(dx=dx, P=P, nis=nis_rows(z, outcome["S"]),
                       shift=(engines[0].H @ dx[:, :, None])[:, :, 0])
        return outcome

    def _replaced(self, outcome, b):
        """Run b's law where an observation failed the test, in its rows of ``outcome``:
        the recovery guard's re-acquisition (an inflated prediction, the test again), then
        the replacement of each failed observation by the Newton extrapolation of the
        history, or its omission."""
        m = self.m
        z, faults = outcome["z"][b], outcome["faults"][b]
        due = self.guard.due_at_opening(faults)
        if due.any():                 # recovery guard: re-acquire with an inflated prediction
            P_pred = inflate_navigation(outcome["P_pred"][b], self.guard.reacquisition_factor(
                z, outcome["P_pred"][b], self.R0, due))
            S = P_pred[:m, :m] + self.R0
            chi2 = chi_square_per_observation(z, S)
            faults = (chi2 > self.chi2_threshold) & ~due
            outcome["P_pred"][b], outcome["S"][b], outcome["chi2"][b] = P_pred, S, chi2
            outcome["faults"][b], outcome["reacquired"][b] = faults, True
        if not faults.any():
            return
        r0 = np.diag(self.R0)
        cap = UNUSABLE_VARIANCE_FACTOR * r0
        if self._history_now():
            outcome["z_used"][b] = np.where(faults, self.history.predict_next(self.newton_order),
                                            z)
            variance_used = np.where(faults, np.minimum(self._extrapolated_variance(), cap), r0)
        else:
            variance_used = np.where(faults, cap, r0)  # nothing to extrapolate from
        outcome["variance_used"][b] = variance_used
        outcome["drop"][b] = faults & (variance_used >= cap)
        if self.replacement_variance == "propagated":
            outcome["R"][b] = np.diag(variance_used)

    def _take_update(self, outcome, b):
        """Run b's guard, history, feedback and diagnostics from ``outcome``, and its
        result."""
        guard = self.guard
        guard.open_epoch()
        if outcome["reacquired"][b]:
            guard.n_reacquired += 1
        epoch = self._next_epoch()
        if self.history.last_epoch is not None and epoch != self.history.last_epoch + 1:
            self.history.clear()  # a missed fix: the samples are no longer equally spaced
            self.sample_variances.clear()
        faults = outcome["faults"][b]
        self.history.append(outcome["z_used"][b], epoch)
        self.sample_variances.append(outcome["variance_used"][b])
        while len(self.sample_variances) > len(self.history):
            self.sample_variances.popleft()
        self.apply(outcome["dx"][b], outcome["P"][b])
        guard.close_epoch(~faults)
        self.history.apply_correction(outcome["shift"][b])
        chi2 = outcome["chi2"][b]
        self.chi2_values = chi2
        self.chi2_max = float(chi2.max())
        self.rejected = faults
        self.n_rejected = int(faults.sum())
        return UpdateResult(outcome["z"][b], outcome["S"][b], float(outcome["nis"][b]),
                            outlier=bool(faults.any()))


# ------------------------------------------------------------------------------------------
class Igg3RobustKfEngine(GuardedEngine, KfEngine):
    """IGG-III equivalent-weight robust filter (the "等价权函数法" of paper 004 sec. 1.2).

    Per component, the standardized innovation ``u_i = v_i / sqrt(S_ii)`` with
    ``S = H P_{k,k-1} H' + R0`` gives the weight ``w_i`` of
    :func:`robust_laws.igg3_weight` (1 up to k0, down-weighted up to k1, 0 beyond); the
    update uses the equivalent variance ``R_ii / w_i`` (a component with w_i = 0 is left out).
    The component's defaults k0 = 1.5, k1 = 3.0 (Yang Yuanxi's usual constants): 13 % of clean
    components are down-weighted a little, 0.3 % rejected.

    Recovery guard (ours, :mod:`navcore.filters.recovery`; off = the plain IGG-III law): a component
    rejected (w = 0) after ``recovery_epochs`` fix intervals without an accepted value is
    re-acquired: the prediction is inflated until its innovation is consistent, the weights
    are computed again on it and the component keeps at least full weight.

    After an update: ``weights`` (m,), ``n_rejected`` (components with w = 0).
    """

    state_fields = ("weights", "n_rejected")
    derived_fields = ("igg_k0", "igg_k1")

    def __init__(self, config, nav, *, igg_k0, igg_k1, recovery, recovery_epochs):
        super().__init__(config, nav)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        self.igg_k0 = float(igg_k0)
        self.igg_k1 = float(igg_k1)
        self.weights = np.ones(self.m)
        self.n_rejected = 0

    def update(self, z):
        """IGG-III weighted update; see the class docstring."""
        z = np.asarray(z, dtype=float)
        P_pred, S = self.predicted_innovation()
        u = z / np.sqrt(np.diag(S))
        w = robust_laws.igg3_weight(u, self.igg_k0, self.igg_k1)
        self.guard.open_epoch()
        due = self.guard.due(w == 0.0)
        if due.any():                 # recovery guard: re-acquire with an inflated prediction
            P_pred = inflate_navigation(P_pred, self.guard.reacquisition(z, P_pred, self.R0, due))
            S = P_pred[:self.m, :self.m] + self.R0
            u = z / np.sqrt(np.diag(S))
            w = np.where(due, 1.0, robust_laws.igg3_weight(u, self.igg_k0, self.igg_k1))
        keep = w > 0.0
        R = self.R0.copy()
        idx = np.flatnonzero(keep)
        R[idx, idx] /= w[idx]
        if keep.all():
            dx, P, _, _, _ = self.kalman_update(P_pred, z, R)
        else:
            dx, P = masked_update(P_pred, z, R, keep)
        self.apply(dx, P)
        self.guard.close_epoch(keep)
        self.weights = w
        self.n_rejected = int((~keep).sum())
        r0 = np.diag(self.R0)
        # trace(R_equivalent)/trace(R0) over the components kept (a dropped one has none)
        r_scale = float(np.sum(r0[idx] / w[idx]) / np.sum(r0[idx])) if idx.size else 1.0
        return UpdateResult(z, S, nis(z, S), r_scale=r_scale,
                            outlier=bool((w < 1.0).any()))


# ------------------------------------------------------------------------------------------
class InsOnlyEngine(KfEngine):
    """Free inertial navigation: the mechanization with no measurement feedback.

    :meth:`update` only evaluates the innovation against the propagated covariance (for
    diagnostics) and changes nothing: no correction, no covariance update, so P just
    propagates from P0 with the process noise (``Phi_acc P0 Phi_acc' + Q_acc``).
    """

    def update(self, z):
        """Innovation diagnostics only; the state and covariance are left untouched."""
        z = np.asarray(z, dtype=float)
        _, S = self.predicted_innovation()
        return UpdateResult(z, S, nis(z, S))
