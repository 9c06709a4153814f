"""Adaptive INS/GNSS filters of paper 001 and the INS-only filter, built on :class:`KfEngine`.

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
* the robust engines of paper 004, :class:`~navcore.filters.robust_filters.
  NewtonRobustKfEngine` and :class:`~navcore.filters.robust_filters.Igg3RobustKfEngine`, in
  :mod:`navcore.filters.robust_filters`.
* :class:`InsOnlyEngine` -- no measurement feedback at all (paper 004's "INS only" curves).

The adaptive engines (and paper 004's Newton engine) update through :class:`RowUpdates`:
the arithmetic of their law over a leading run axis, so the runs of a batch
(:mod:`navcore.components.filter_batch`) update in one call and a single engine is a batch
of one.

In closed loop the predicted error state is zero, so the innovation is ``v = z`` (paper 001
eq. 5 with x_{k,k-1} = 0).  All engines return an :class:`UpdateResult` (NIS, r_scale,
fading factor, outlier flag) and keep their own extra diagnostics as attributes, read by the
components after each update.
"""
from __future__ import annotations

import math

import numpy as np

from . import adaptive_laws as laws
from ..ins.error_model import N_STATES
from ..errors import InputError
from .innovation_stats import chi2_gate, dot_rows, nis, nis_rows, trace_rows
from .ins_gnss_kf import KfEngine, UpdateResult, kalman_rows, predicted_rows
from .recovery import GuardedEngine, bounded_r_rows, faded_within_initial_rows

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
        the nominal R in use per axis (R0, or the receiver's R of the fix with
        ``r_from_receiver``; :func:`navcore.filters.recovery.bounded_r`), so a diverging
        state cannot drive the estimate away; paper 001's eq. 9 has no upper bound.
    r_floor_nominal : (ours; off = paper 001's law) R_hat's position variances stay at least
        the nominal ones in use (:attr:`r_min`).  The components set it with the recovery
        guard on and ``gnss_corr_time`` > 0: the user then declares the fixes' errors
        time-correlated and R0 already their honest variance
        (:mod:`navcore.filters.correlated_gnss`).  An innovation-based R estimate (eq. 9, a
        covariance matching; Mehra 1972, *Approaches to adaptive filtering*, IEEE Trans.
        Autom. Control 17) assumes white measurement errors; with correlated ones the
        filter follows the fixes' slow errors, its innovations shrink and R_hat falls below
        the errors' real variance -- on a real drive (docs/guide/your_real_log.md,
        ``imu_noise_factor`` 30) 32-52 % of the horizontal errors with fixes inside +/-3
        sigma against the Kf's 100 %, and 100 % with the floor.
    recovery : the recovery guard of :mod:`navcore.filters.recovery` (ours; off = paper 001's law):
        here the bound ``r_max_scale`` and the fading of paper 001 eq. 10 kept within the
        initial attitude and bias variances
        (:func:`navcore.filters.recovery.faded_within_initial_rows`).  This filter takes
        every fix, and after an outage its own fading factor (eq. 12) inflates P as much as
        the innovation asks, so it needs no re-acquisition (one on top of the fading factor
        made it worse after each outage of models/mems_outages).  ``recovery_epochs`` serves Iakf.
    """

    state_fields = ("R", "sage_husa_index")
    derived_fields = ("forgetting_factor", "reserve_gamma", "max_fading_factor",
                      "r_floor_fraction", "r_max_scale", "r_floor_nominal")

    def __init__(self, config, nav, *, forgetting_factor, reserve_gamma, r_floor_fraction,
                 max_fading_factor, r_max_scale, recovery, recovery_epochs, r_floor_nominal):
        super().__init__(config, nav)
        self.r_floor_nominal = bool(r_floor_nominal)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        self.r_max_scale = float(r_max_scale) if self.guard.enabled else None
        self.forgetting_factor = float(forgetting_factor)
        self.reserve_gamma = float(reserve_gamma)
        self.max_fading_factor = max_fading_factor
        self.r_floor_fraction = float(r_floor_fraction)
        laws.r_floor_from_initial(self.R0, self.r_floor_fraction)   # checks the fraction
        self.R = self.R0.copy()
        self.sage_husa_index = 0

    @property
    def r_min(self):
        """Floor of R_hat's variances: ``r_floor_fraction`` of the nominal R in use (R0, or
        the receiver's sigmas of this fix with ``r_from_receiver``); with
        ``r_floor_nominal`` the position variances of R0 themselves."""
        floor = laws.r_floor_from_initial(self.R0, self.r_floor_fraction)
        if self.r_floor_nominal:
            floor[:3] = np.maximum(floor[:3], np.diag(self.R0)[:3])
        return floor

    @property
    def r_max(self):
        """Recovery guard: ceiling of R_hat's variances, ``r_max_scale`` times the nominal R
        in use (None with the guard off).  Relative to the R of this fix, not to the
        configured ``r_pos_*``: with ``r_from_receiver`` a 1-cm RTK fix bounds R_hat at 2 cm,
        where a bound of 4 x (5 m)^2 let it grow 3.4e5-fold on a real drive."""
        if self.r_max_scale is None:
            return None
        return self.r_max_scale * np.diag(self.R0)

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
        lam = np.where([engine.fading_allowed() for engine in engines], lam, 1.0)
        P_pred = laws.fading_predict_rows(p_prop, q_acc, lam)
        guarded = [b for b, engine in enumerate(engines) if engine.guard.enabled]
        if guarded:                     # recovery guard: attitude and biases faded up to p0
            P_pred[guarded] = faded_within_initial_rows(
                p_prop[guarded], q_acc[guarded], lam[guarded],
                np.array([engines[b].p0_var for b in guarded]))
        dx, P, _, S, K = kalman_rows(P_pred, v, R, H)
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

    def fading_allowed(self):
        """Recovery guard: paper 001's fading factor (eq. 12) acts at a re-acquisition only,
        the first fix after ``recovery_epochs`` fix intervals without an accepted one (an
        outage; for Iakf also a run of compressed innovations, whose re-acquisition the
        factor makes); always with the guard off (paper 001 as printed).  Eq. 11 reads an
        innovation beyond its predicted covariance as a diverging state; on real data with
        the receiver's own sigmas (1 cm RTK) nearly every innovation is beyond it, because
        the receiver's errors are time-correlated and biased (R too small, not P), so the
        factor fired at most fixes and inflated P -- attitude and biases too -- at every one
        of them: the states then absorbed the fixes' errors (an accelerometer bias 0.3 m/s^2
        off before a 60 s outage of a real drive, 7 times Kf's drift in it).  After a gap
        the state is what is wrong, the law's case."""
        return not self.guard.enabled or bool(
            self.guard.due_at_opening(np.ones(self.m, dtype=bool)).any())

    def _take_update(self, outcome, b):
        """:meth:`_sage_husa_take` between the guard's epoch bookkeeping (every fix taken)."""
        self.guard.open_epoch()
        result = self._sage_husa_take(outcome, b)
        self.guard.close_epoch(np.ones(self.m, dtype=bool))
        return result

    def _sage_husa_take(self, outcome, b):
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
        adapted = self._sage_husa_take(outcome, b)
        Y = float(outcome["Y"][b])
        guard.close_epoch(Y == 1.0)
        self.compression = Y
        self.tau = float(outcome["tau"][b])
        return UpdateResult(outcome["innovation"][b], outcome["G"][b], self.tau,
                            r_scale=adapted.r_scale, fading_factor=adapted.fading_factor,
                            outlier=Y < 1.0)


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
