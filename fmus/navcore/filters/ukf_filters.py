"""Unscented INS/GNSS error-state filters of paper 000 (Yang et al. 2018): UKF, CTFA-UKF, IMM-UKF.

All three share the interface of :class:`navcore.filters.ins_gnss_kf.KfEngine` (``propagate``,
``measurement``, ``update``, ``covariance_diagonal``, ``nav``, ``gyro_bias``, ``accel_bias``,
``m``, ``H``, ``R0``, ``config``) so the component shell of
:mod:`navcore.components.filter_component` drives them unchanged.

Nominal navigation and error state
----------------------------------
The strapdown mechanization (:class:`navcore.ins.strapdown.Strapdown`) runs at the IMU rate on the
bias-compensated increments.  The UKF (:class:`navcore.filters.unscented.UnscentedKalmanFilter`,
paper 000 eqs. 11-23) estimates the 15-state error of :mod:`navcore.ins.error_model` with the same
order, units and signs::

    x = [dr (NED m), dv (m/s), phi (rad), dbg (rad/s), dba (m/s^2)]

but with a genuinely nonlinear attitude-error model: ``phi`` is the *rotation vector* of the
attitude error, ``C_bn_computed = exp(-[phi x]) C_bn_true`` (to first order the
``(I - [phi x])`` of error_model; :meth:`Strapdown.correct` applies exactly ``exp([phi x])``).

The large-misalignment error model, the prediction at a coarser rate and its process noise:
:mod:`navcore.filters.ukf_time_update`.

Measurement and feedback
------------------------
GPS position, paper 000 eqs. 3-4: ``z = r_INS - r_GPS = H x + xi`` with ``H = [I_3 0]`` (NED metres;
``measurement='position_velocity'`` appends velocity, ``H = [I_6 0]``).  The UKF measurement
update (paper 000 eqs. 17-23) gives the innovation, ``S = P_zz + R`` and the chi-square statistic /
NIS ``v^T S^-1 v`` (paper 000 eq. 24).  After every update the estimated errors are fed back (closed
loop: :meth:`Strapdown.correct`, biases accumulated) and the error mean is reset to zero.
"""
from __future__ import annotations

import copy

import numpy as np

from .aid_blind import AidBlindCovariance
from .ctfa import PAPER_T1, PAPER_T2, CtfaQSchedule, ctfa_thresholds
from ..ins.error_model import ATT, BA, BG, N_STATES, POS, VEL
from ..ins.strapdown import Strapdown
from .imm import ImmBank, imm_combine, imm_mix, update_banks
from .innovation_stats import (checked_cholesky, gaussian_log_likelihood,
                               log_det_from_cholesky, nis, nis_from_cholesky)
from .land_aids import linear_update
from .ins_gnss_kf import KfEngine, UpdateResult
from .recovery import GuardedEngine, flag_by_gate, inflate_navigation
from .ukf_time_update import (N_SUMS, advance_interval_rows, discrete_process_noise,
                              interval_means, predict_unscented_filters, prediction_due)
from .unscented import UnscentedKalmanFilter
from .unscented_rows import update_filters


class UkfEngine(KfEngine):
    """15-state INS/GNSS UKF with the nonlinear error model of
    :mod:`navcore.filters.ukf_time_update`.

    Paper 000's plain "UKF" (fixed Q): paper 000 eqs. 11-23 on the error model above, position
    measurement paper 000 eqs. 3-4, closed-loop feedback.  ``predict_interval`` [s] is the UKF
    prediction interval; ``alpha``, ``beta``, ``kappa`` the scaled-UT parameters (paper 000
    eqs. 11-13; the components' defaults 1, 2, 0, see navcore.filters.unscented).  ``q_scale``
    multiplies the configured process noise density (the adaptive subclasses change it between
    predictions).
    """

    state_fields = ("ukf", "q_scale", "_q_cache", "sums")
    derived_fields = ("predict_interval", "alpha", "beta", "kappa")

    def __init__(self, config, nav, *, predict_interval, alpha, beta, kappa):
        super().__init__(config, nav)
        self.predict_interval = float(predict_interval)
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)
        self.ukf = self._new_ukf()
        self.q_scale = 1.0
        self._q_cache = (None, None)
        self._reset_interval()

    def _new_ukf(self):
        return UnscentedKalmanFilter(N_STATES, self.alpha, self.beta, self.kappa,
                                     x0=np.zeros(N_STATES), P0=self.P.copy())

    # -- time update -------------------------------------------------------------------
    def _reset_interval(self):
        #: the interval sums (1, N_SUMS) of :func:`accumulate_rows`
        self.sums = np.zeros((1, N_SUMS))

    @property
    def _T(self):
        """Length [s] of the interval accumulated since the last prediction."""
        return self.sums[0, 0].item()

    def propagate(self, dtheta, dvel, dt):
        """Mechanize one IMU interval with bias-compensated increments and accumulate the
        interval means (:func:`advance_interval_rows` of this run); run the UKF prediction
        when ``predict_interval`` is complete."""
        nav = self.nav
        mechanize = None if type(nav).update is Strapdown.update else (
            lambda dtheta_c, dvel_c: nav.update(dtheta_c[0], dvel_c[0], dt))
        self.rate_ib = advance_interval_rows(
            nav.rows, self.sums, np.reshape(dtheta, (1, 3)), np.reshape(dvel, (1, 3)),
            self.gyro_bias.reshape(1, 3), self.accel_bias.reshape(1, 3), dt, mechanize)[0]
        if prediction_due(self._T, self.predict_interval):
            self._predict()
        self.advance_clocks(dt)

    def _interval(self):
        return interval_means(self.sums)

    def process_noise(self, T):
        """Discrete Q_d(T) at scale 1 (cached for the usual constant interval)."""
        T_cached, Q = self._q_cache
        if T_cached != T:
            Q = discrete_process_noise(self.q_density, T)
            self._q_cache = (T, Q)
        return Q

    def _predict(self):
        """UKF time update (paper 000 eqs. 14-16) over the accumulated interval."""
        if self._T <= 0.0:
            return
        cfg = self.config
        self.predict_filters(self._interval(), self.process_noise(self._T), cfg.gyro_bias_tau,
                             cfg.accel_bias_tau)
        self._reset_interval()

    def predict_filters(self, nom, Q, tau_g, tau_a):
        """Predict the filter(s) over one interval (subclasses with several filters override):
        :func:`~navcore.filters.ukf_time_update.predict_unscented_filters` of this run's filter."""
        self.predict_with_blind([self.ukf], nom, Q, [self.q_scale], tau_g, tau_a)

    def predict_with_blind(self, filters, nom, Q, q_scales, tau_g, tau_a):
        """:func:`~navcore.filters.ukf_time_update.predict_unscented_filters` of ``filters``
        (an engine that keeps the covariances without the land aids predicts them with them:
        :class:`UnscentedAidBlind`)."""
        predict_unscented_filters(filters, nom, Q, q_scales, tau_g, tau_a)

    def prediction_covariance(self):
        """P of the latest prediction (or update): the part of :meth:`covariance_diagonal`
        that changes only there."""
        return self.ukf.P

    def covariance_diagonal(self):
        """Diagonal of P at the last prediction plus the noise of the pending interval."""
        return (np.diagonal(self.prediction_covariance())
                + self.q_scale * self.q_density * self._T)

    def covariance(self):
        return self.ukf.P.copy()

    # -- measurement update ------------------------------------------------------------
    def _h(self, X):
        """Measurement model of paper 000 eqs. 3-4 (linear: H = [I_m 0]) over the sigma points
        (the last axis of ``X``: one filter's or many filters' points)."""
        return X[..., :self.m]

    def update(self, z):
        """UKF measurement update (paper 000 eqs. 17-23) then closed-loop feedback: the
        engine's code before its filters' update (:meth:`measured_filters`), their update by
        :func:`~navcore.filters.unscented_rows.update_filters` (which a batch calls with the
        filters of all its runs), :meth:`filters_corrected` and :meth:`update_finished`."""
        filters, before = self.measured_filters(z)
        corrections, errors = update_filters(filters, np.tile(z, (len(filters), 1)),
                                             np.tile(self.R0, (len(filters), 1, 1)), self._h)
        error = next((e for e in errors if e is not None), None)
        if error is not None:
            raise error
        error = self.filters_corrected([self], [corrections])[0]
        if error is not None:
            raise error
        return self.update_finished(before, corrections)

    def measured_filters(self, z):
        """:meth:`update` before the filters' update with ``z``: the prediction due; returns
        the filters to update and what :meth:`update_finished` takes of this part."""
        self._predict()
        return [self.ukf], None

    @staticmethod
    def filters_corrected(engines, corrections):
        """:meth:`update` after the filters' update, for the engines ``engines`` at once
        (their filters' :class:`~navcore.filters.unscented_rows.Correction` lists): nothing
        for one filter.  Returns per engine the error its own update raises, or None."""
        return [None] * len(engines)

    def update_finished(self, before, corrections):
        """The end of :meth:`update`: the closed-loop feedback and the update's result."""
        correction = corrections[0]
        self._feedback(self.ukf.x)
        self.ukf.x = np.zeros(N_STATES)
        return UpdateResult(correction.v, correction.S, correction.nis, q_scale=self.q_scale)

    def reacquire(self, z, x, P, filters):
        """Recovery guard (:mod:`navcore.filters.recovery`) of the adaptive UKFs, which accept
        every fix: the first fix after ``recovery_epochs`` intervals without one whose NIS against
        the prediction (mean ``x``, covariance ``P``) exceeds the 99 % chi-square gate
        inflates the navigation part of every filter's covariance in ``filters`` until that
        NIS is m.  Returns the factor (1: nothing done)."""
        guard = self.guard
        guard.open_epoch()
        lam = 1.0
        if guard.may_reacquire():
            m = self.m
            v = z - x[:m]
            due = guard.due(flag_by_gate(nis(v, P[:m, :m] + self.R0), m))
            if due.any():
                lam = guard.reacquisition(v, P, self.R0, due)
                for flt in filters:
                    flt.P = inflate_navigation(flt.P, lam, self.p0_var)
        guard.close_epoch(True)
        return lam

    def aid_update(self, H, z, R):
        """A land aid's pseudo-measurement ``z = H x`` (:mod:`navcore.filters.land_aids`),
        linear in the error state, so the unscented update is the Kalman update: the
        prediction due, then every filter's plain update (no adaptive law, no model
        probabilities moved) and the closed-loop feedback of the estimate."""
        self._predict()
        for flt in self.aided_filters():
            flt.x, flt.P = linear_update(flt.x, flt.P, z, H, R)
        self._feedback_aided()

    def aided_filters(self):
        """The filters a land aid updates."""
        return [self.ukf]

    def _feedback_aided(self):
        """:meth:`aid_update`'s feedback of the filters' estimate."""
        self._feedback(self.ukf.x)
        self.ukf.x = np.zeros(N_STATES)

    def _feedback(self, dx):
        self.nav.correct(dx[POS], dx[VEL], dx[ATT])
        self.gyro_bias = self.gyro_bias + dx[BG]
        self.accel_bias = self.accel_bias + dx[BA]
        self.n_updates += 1


class UnscentedAidBlind(AidBlindCovariance):
    """:class:`~navcore.filters.aid_blind.AidBlindCovariance` of an adaptive UKF (CtfaUkf,
    ImmUkf), whose adaptation reads the fixes' innovations: ``blind_P`` (F, n, n) holds one
    covariance per filter of :meth:`aided_filters`, predicted with them by the same unscented
    time update (:meth:`predict_with_blind`), so the adaptation sees
    :meth:`blind_innovation_covariances` while the update uses the aided filters."""

    def blind_now(self):
        self._predict()
        if self.blind_P is not None:
            return self.blind_P
        return np.stack([flt.P for flt in self.aided_filters()])

    def predict_with_blind(self, filters, nom, Q, q_scales, tau_g, tau_a):
        """:func:`~navcore.filters.ukf_time_update.predict_unscented_filters` of ``filters``
        and, while ``blind_P`` is held, of copies of them with the blind covariances (the
        same means, process noise and scales), in one call."""
        if self.blind_P is None:
            super().predict_with_blind(filters, nom, Q, q_scales, tau_g, tau_a)
            return
        shadows = [copy.copy(flt) for flt in filters]
        for shadow, P in zip(shadows, self.blind_P):
            shadow.P = P
        super().predict_with_blind(list(filters) + shadows, nom, Q, list(q_scales) * 2, tau_g,
                                   tau_a)
        self.blind_P = np.stack([shadow.P for shadow in shadows])

    def blind_innovation_covariances(self):
        """``S = H P_blind H' + R0`` of each filter (F, m, m), or None while no aid updated
        since the last fix (the adaptation then reads the update's own S)."""
        if self.blind_P is None:
            return None
        m = self.m
        return self.blind_P[:, :m, :m] + self.R0


class CtfaUkfEngine(UnscentedAidBlind, GuardedEngine, UkfEngine):
    """Paper 000's CTFA-UKF: the UKF plus the chi-square fuzzy adaptive Q schedule (paper 000
    eqs. 24-25).

    After every update the chi-square statistic ``q_k = v^T S^-1 v`` (paper 000 eq. 24, the NIS of
    the UKF update, ``S = P_zz + R``) sets the process noise of the following predictions::

        Q = Q_{k-1}                                      q_k < T1   (the previous Q is kept)
          = Qmin + (q_k - T1)/(T2 - T1) (Qmax - Qmin)     T1 <= q_k <= T2
          = Qmax                                         q_k > T2

    with ``Q_0 = Qmin`` = the configured Q and ``Qmax = q_max_scale Qmin``
    (:class:`navcore.filters.ctfa.CtfaQSchedule`).  ``T1``/``T2``: the paper's 6.25/11.35 for the
    3-dimensional position measurement; for another dimension (or when ``t1``/``t2`` are 0) the
    90 %/99 % chi-square quantiles of the measurement dimension (``ctfa_thresholds``).
    ``q_scale`` is the current Q relative to Qmin, ``chi2`` the latest statistic.
    ``pass_decay`` (ours, not the paper's; 1 = paper 000 eq. 25 as printed): factor on ``Q - Qmin``
    at every update that passes the test, so Q returns towards Qmin after a manoeuvre.
    Recovery guard (ours; off = paper 000's law): :meth:`UkfEngine.reacquire` before the update.
    With land aids, ``q_k`` is taken against the covariance without the aids' updates since
    the last fix (:class:`UnscentedAidBlind`): an aid never makes a good fix raise Q.
    """

    state_fields = ("schedule", "chi2")
    derived_fields = ("q_max_scale",)

    def __init__(self, config, nav, *, q_max_scale, t1, t2, pass_decay, recovery,
                 recovery_epochs, **kwargs):
        super().__init__(config, nav, **kwargs)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        if self.m == 3:
            d1, d2 = PAPER_T1, PAPER_T2
        else:
            d1, d2 = ctfa_thresholds(self.m)
        T1 = float(t1) if t1 > 0 else d1
        T2 = float(t2) if t2 > 0 else d2
        self.q_max_scale = float(q_max_scale)
        # the schedule on the scalar scale of Q: Qmin = [1], Qmax = [q_max_scale]
        self.schedule = CtfaQSchedule(np.eye(1), self.q_max_scale * np.eye(1), T1, T2,
                                      pass_decay)
        self.chi2 = 0.0
        self.init_blind()

    def measured_filters(self, z):
        filters, before = super().measured_filters(z)
        self.reacquire(z, self.ukf.x, self.ukf.P, (self.ukf,))
        return filters, before

    def update_finished(self, before, corrections):
        S_blind = self.blind_innovation_covariances()
        result = super().update_finished(before, corrections)
        # paper 000 eq. 24, against the covariance without the land aids (aid_blind)
        self.chi2 = result.nis if S_blind is None else nis(corrections[0].v, S_blind[0])
        self.fix_taken()
        self.q_scale = float(self.schedule.update(self.chi2)[0, 0])   # paper 000 eq. 25, next steps
        result.q_scale = self.q_scale
        return result


class ImmUkfEngine(UnscentedAidBlind, GuardedEngine, UkfEngine):
    """IMM-UKF (paper 000's comparison, its ref. [14]): a bank of UKFs differing in Q.

    ``q_scales`` (one per model) multiply the configured Q; ``p_stay`` is the diagonal of the
    Markov transition matrix, the rest of each row spread evenly.  The bank
    (:class:`navcore.filters.imm.ImmBank`) mixes once per measurement interval (at the first
    prediction after an update), predicts every model, updates every model with the same
    measurement, updates the model probabilities from the Gaussian likelihoods and combines.  The
    combined error estimate is fed back to the single nominal INS and subtracted from every model
    (closed loop).  ``q_scale`` = probability-weighted scale; ``model_probabilities``;
    the NIS is that of the combined prediction.  Recovery guard (ours; off = the plain IMM):
    :meth:`UkfEngine.reacquire` on the mixed prediction, inflating every model.  With land
    aids, each model's likelihood is taken against its covariance without the aids' updates
    since the last fix (:class:`UnscentedAidBlind`); its update uses the aided one.
    """

    state_fields = ("bank",)
    derived_fields = ("q_scales",)

    def __init__(self, config, nav, *, q_scales, p_stay, recovery, recovery_epochs, **kwargs):
        super().__init__(config, nav, **kwargs)
        q_scales = [float(s) for s in q_scales]
        r = len(q_scales)
        if r == 1:
            Pi = np.ones((1, 1))
        else:
            Pi = np.full((r, r), (1.0 - p_stay) / (r - 1))
            np.fill_diagonal(Pi, p_stay)
        self.q_scales = np.array(q_scales)
        self.bank = ImmBank([self._new_ukf() for _ in range(r)], Pi)
        self.ukf = None
        self.q_scale = float(self.bank.mu @ self.q_scales)
        self.init_guard(recovery=recovery, recovery_epochs=recovery_epochs)
        self.init_blind()

    @property
    def model_probabilities(self):
        return self.bank.mu

    def predict_filters(self, nom, Q, tau_g, tau_a):
        """Every model's sigma points through one call of the process model, each model's
        moments with its own Q (:func:`~navcore.filters.ukf_time_update.predict_unscented_filters`),
        after the bank's mixing."""
        scales = self.q_scales
        self.bank.predict_all(
            lambda filters: self.predict_with_blind(filters, nom, Q, scales, tau_g, tau_a))

    def blind_now(self):
        """The blind covariances start as the models' own, mixed when the bank's mixing is
        due at the next prediction (the step the blind path takes before that prediction,
        the aided filters taking it after the aid)."""
        blind = super().blind_now()
        bank = self.bank
        if self.blind_P is None and bank.needs_mixing:
            blind = np.stack(imm_mix(bank.mu, bank.Pi, [f.x for f in bank.filters],
                                     list(blind))[1])
        return blind

    def adapted_log_likelihoods(self, corrections):
        """The models' log-likelihoods of the fix that move the model probabilities: the
        update's own, or against the blind covariances while an aid updated since the last
        fix."""
        S_blind = self.blind_innovation_covariances()
        if S_blind is None:
            return [c.log_likelihood for c in corrections]
        out = []
        for c, S in zip(corrections, S_blind):
            v, L = checked_cholesky(c.v, S, f"{type(self).__name__}: blind S")
            out.append(gaussian_log_likelihood(nis_from_cholesky(L, v), log_det_from_cholesky(L),
                                               self.m))
        return out

    def prediction_covariance(self):
        return self.bank.P

    def aided_filters(self):
        return self.bank.filters

    def _feedback_aided(self):
        bank = self.bank
        bank.x, bank.P = imm_combine(bank.mu, [f.x for f in bank.filters],
                                     [f.P for f in bank.filters])
        dx = bank.x.copy()
        self._feedback(dx)
        bank.subtract_from_states(dx)

    def covariance(self):
        return self.bank.P.copy()

    def measured_filters(self, z):
        self._predict()
        bank = self.bank
        if bank.needs_mixing:        # no prediction since the last update: start the cycle
            bank.mix()
        if self.reacquire(z, bank.x, bank.P, bank.filters) != 1.0:
            bank.x, bank.P = imm_combine(bank.mu, [f.x for f in bank.filters],
                                         [f.P for f in bank.filters])
        m = self.m
        # chi-square statistic of the combined (mixture) prediction
        v = z - bank.x[:m]
        S = bank.P[:m, :m] + self.R0
        return bank.filters, (v, S, nis(v, S))

    @staticmethod
    def filters_corrected(engines, corrections):
        """The banks' model probabilities and combinations after their models' updates
        (:func:`~navcore.filters.imm.update_banks`: all banks' combinations in one call)."""
        return update_banks([engine.bank for engine in engines],
                            [engine.adapted_log_likelihoods(models)
                             for engine, models in zip(engines, corrections)])

    def update_finished(self, before, corrections):
        v, S, statistic = before
        bank = self.bank
        dx = bank.x.copy()
        self._feedback(dx)
        bank.subtract_from_states(dx)
        self.q_scale = float(bank.mu @ self.q_scales)
        self.fix_taken()
        return UpdateResult(v, S, statistic, q_scale=self.q_scale)
