"""The robust INS/GNSS filters, built on :class:`KfEngine` as those of
:mod:`navcore.filters.adaptive_filters`:

* :class:`NewtonRobustKfEngine` -- paper 004: per-observation chi-square test (threshold 6.635)
  and replacement of a failed observation by the Newton forward extrapolation of the
  previous observations; it updates through :class:`~navcore.filters.adaptive_filters.
  RowUpdates`, so the runs of a batch update in one call.
* :class:`Igg3RobustKfEngine` -- IGG-III equivalent weights on the standardized innovations (the
  "equivalent weight" method paper 004 lists in its section 1.2; not a paper's own filter).
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from . import robust_laws
from ..ins.error_model import N_STATES
from ..errors import InputError
from .adaptive_filters import RowUpdates, _require_finite, masked_update
from .aid_blind import AidBlindTest
from .innovation_stats import chi_square_per_observation, nis, nis_rows
from .ins_gnss_kf import KfEngine, UpdateResult, kalman_rows
from .recovery import GuardedEngine, inflate_navigation


#: NewtonRobustKfEngine: a replacement whose error variance reaches this multiple of R_ii (1000
#: sigma) carries no information and is left out of the update (first epoch, or a run of
#: faults so long that the history holds only extrapolations of extrapolations)
UNUSABLE_VARIANCE_FACTOR = 1e6
#: how the R of a replaced observation is set (NewtonRobustKf's ``replacement_variance``)
REPLACEMENT_VARIANCES = ("propagated", "nominal")


class NewtonRobustKfEngine(RowUpdates, AidBlindTest, GuardedEngine, KfEngine):
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

    With land aids the test of step 2 uses the covariance without the aids' updates since the
    last fix (:mod:`navcore.filters.aid_blind`): an aid never makes a fix fail it.

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
        self.init_blind()
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
        s = np.array([np.diag(engine.tested_prediction(P_pred[b])[:m, :m]) for b, engine in
                      enumerate(engines)]) + np.diagonal(R, axis1=1, axis2=2)
        if np.any(s <= 0.0):
            raise InputError(f"S: diagonal must be > 0, got {s[(s <= 0.0).any(axis=1)][0]}")
        chi2 = z * z / s            # chi_square_per_observation of every run (aid_blind's S)
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
                z, outcome["P_pred"][b], self.R0, due), self.p0_var)
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

    def aid_applied(self, dx):
        """A land aid's feedback shifts the stored observations as a fix's does (step 4)."""
        self.history.apply_correction(self.H @ dx)

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
        self.fix_taken()
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
class Igg3RobustKfEngine(AidBlindTest, GuardedEngine, KfEngine):
    """IGG-III equivalent-weight robust filter (the "等价权函数法" of paper 004 sec. 1.2).

    Per component, the standardized innovation ``u_i = v_i / sqrt(S_ii)`` with
    ``S = H P_{k,k-1} H' + R0`` gives the weight ``w_i`` of
    :func:`robust_laws.igg3_weight` (1 up to k0, down-weighted up to k1, 0 beyond); the
    update uses the equivalent variance ``R_ii / w_i`` (a component with w_i = 0 is left out).
    The component's defaults k0 = 1.5, k1 = 3.0 (Yang Yuanxi's usual constants): 13 % of clean
    components are down-weighted a little, 0.3 % rejected.

    Recovery guard (ours, :mod:`navcore.filters.recovery`; off = the plain IGG-III law): a
    component rejected (w = 0) after ``recovery_epochs`` fix intervals without an accepted value
    (w > 0), or down-weighted (0 < w < 1) at the last of ``recovery_epochs`` fixes in a row
    without full weight (``short_weight_fixes``), is re-acquired: the prediction is inflated
    until its innovation is consistent, the weights are computed again on it and the component
    keeps at least full weight. The down-weighting run is for an INS error that outgrows the
    predicted covariance without reaching k1 sigma (a low-cost IMU in strong manoeuvres, errors
    the model lacks): IGG-III then shrinks good fixes at most epochs, the filter coasts and the
    innovations grow -- on ``uav_maneuver``'s first 120 s (white GNSS errors only) the law ends
    2.4 times the Kf's position error, with only rejection runs counted 2.0 times, with both 1.2
    times. A rejected fix is re-acquired only at the end of a run of rejections, never at the
    end of a down-weighting run: an outlier beyond k1 after a run of down-weighted fixes stays
    rejected (``aircraft_outliers``' 20-sigma outliers every 10 s: with one count for both, such
    runs re-acquired outliers and the position error reached 99 m; with the two, every outlier
    is rejected, the numbers of the law). The down-weighting run counts fixes, not time: an
    outage is no evidence against the prediction, and a clock that ran through verify's 30 s
    outage re-acquired the first fix after it, down-weighted for a 2.5-sigma error of its own,
    and took that error (11 m).

    With land aids the weights come from the covariance without the aids' updates since the
    last fix (:mod:`navcore.filters.aid_blind`): an aid never down-weights a fix.

    After an update: ``weights`` (m,), ``n_rejected`` (components with w = 0).
    """

    state_fields = ("weights", "n_rejected", "short_weight_fixes")
    derived_fields = ("igg_k0", "igg_k1")

    def __init__(self, config, nav, *, igg_k0, igg_k1, recovery, recovery_epochs):
        super().__init__(config, nav)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        #: per component, the fixes in a row it had less than full weight (w < 1)
        self.short_weight_fixes = np.zeros(self.m, dtype=np.int64)
        self.init_blind()
        self.igg_k0 = float(igg_k0)
        self.igg_k1 = float(igg_k1)
        self.weights = np.ones(self.m)
        self.n_rejected = 0

    def update(self, z):
        """IGG-III weighted update; see the class docstring."""
        z = np.asarray(z, dtype=float)
        P_pred, S = self.predicted_innovation()
        tested = self.tested_prediction(P_pred)
        u = z / np.sqrt(np.diag(tested)[:self.m] + np.diag(self.R0))
        w = robust_laws.igg3_weight(u, self.igg_k0, self.igg_k1)
        self.guard.open_epoch()
        run = self.short_weight_fixes + 1          # fixes in a row without full weight, this one
        due = self.guard.due(w == 0.0) | (self.guard.enabled & (w > 0.0) & (w < 1.0)
                                          & (run >= self.guard.epochs))
        if due.any():                 # recovery guard: re-acquire with an inflated prediction
            P_pred = inflate_navigation(P_pred, self.guard.reacquisition(z, P_pred, self.R0, due),
                                        self.p0_var)
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
        self.fix_taken()
        self.guard.close_epoch(keep)
        self.short_weight_fixes = np.where(w == 1.0, 0, run)
        self.weights = w
        self.n_rejected = int((~keep).sum())
        r0 = np.diag(self.R0)
        # trace(R_equivalent)/trace(R0) over the components kept (a dropped one has none)
        r_scale = float(np.sum(r0[idx] / w[idx]) / np.sum(r0[idx])) if idx.size else 1.0
        return UpdateResult(z, S, nis(z, S), r_scale=r_scale,
                            outlier=bool((w < 1.0).any()))


# ------------------------------------------------------------------------------------------
