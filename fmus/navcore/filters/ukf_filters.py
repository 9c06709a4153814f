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

Large-misalignment error model (rotation-vector form)
-----------------------------------------------------
This is the large-misalignment model of Yan Gongmin (*Strapdown inertial navigation algorithm
and integrated navigation principles*, 2016, sec. 7.5) with the Euler-platform angles replaced by
the rotation vector, so its kinematic matrix is the inverse right/left Jacobian of SO(3)
instead of the inverse Euler-rate matrix.  With ``C' = C_n^{n'} = exp(-[phi x])`` (true nav frame
to computed nav frame), a prime marking computed quantities, ``w_in = w_ie + w_en``, ``f^{n'}``
the computed specific force ``C_bn' f~^b`` and ``dbg``/``dba`` the errors of the compensated gyro
and accelerometer outputs:

*attitude* -- differentiating ``C' = C_bn' C_bn^T`` with the true and computed attitude
kinematics gives ``dC'/dt = [(C_bn' dbg - w_in' + C' w_in) x] C'``, so ``R = exp([phi x]) =
C'^T`` rotates with the spatial rate ``w_s = R (w_in' - C_bn' dbg) - w_in`` and the rotation
vector obeys the exact kinematics ``d(phi)/dt = J^-1(phi) w_s`` with::

    J^-1(phi) = I - 1/2 [phi x] + c(|phi|) [phi x]^2,   c(t) = (1 - (t/2) cot(t/2)) / t^2  (-> 1/12)

(to first order: ``-w_in x phi + d(w_in) - C_bn dbg``, the linear model's attitude row).
``w_in`` of the *true* state is evaluated exactly from the computed position and velocity minus
the position/velocity error of each sigma point.

*velocity* -- ``v' - v`` with ``v_dot = C_bn f^b - (2 w_ie + w_en) x v + g``::

    d(dv)/dt = (I - exp([phi x])) f^{n'} + exp([phi x]) C_bn' dba
               - [(2 w_ie' + w_en') x v' - (2 w_ie + w_en) x v] + (2 g / R) dr_d e_d

(``(I - exp([phi x])) f`` is ``f x phi = [f x] phi`` to first order, paper 000 eq. 1
``-[psi x] f`` and error_model's ``[f^n x] phi``).

*position and biases* as in error_model: ``d(dr)/dt = dv``, ``d(db)/dt = -db / tau`` (random
constant for ``tau = 0``).

Time update at a coarser rate
-----------------------------
Propagating 31 sigma points at 100 Hz would cost more than the rest of the filter, and the error
dynamics are slow (Schuler 84 min, earth rate, transport rate: all below 1e-3 rad/s), so the UKF
prediction (paper 000 eqs. 14-16) runs every ``ukf_predict_interval`` ``T`` seconds (default 0.1 s;
always also right before a measurement update) with the *interval means* of the nominal quantities:
``f^{n'}`` (sum of ``C_bn' dvel`` over the interval divided by ``T``, exact for the term linear in
``f``), ``C_bn'`` (time mean, exact for a constant bias), position and velocity.  Each point is
advanced by one step ``x+ = x + T x_dot`` with the position error taken to second order,
``dr+ = dr + T (dv + T/2 d(dv)/dt)``.

Process noise is additive, ``Q_d(T)`` with ``Q_d = diag(q) T`` plus the velocity noise integrated
into position (``q_v T^3/3`` and the ``q_v T^2/2`` cross terms); ``q`` is the spectral density of
error_model (ARW^2, VRW^2, bias drivers).  This equals the augmented-noise form of paper 000 (eqs.
9-10) to second order: the noise enters the model above as ``-J^-1 R C_bn' w_g`` and ``R C_bn'
w_a``, i.e. through rotations of an isotropic white noise (``R C Q C^T R^T = Q`` for
``Q = sigma^2 I``) multiplied by ``J^-1 = I + O(phi)``; the dropped noise-state cross terms are of
order ``|phi| q``, far below ``q`` for attitude errors of milliradians (see the unscented.py
docstring on additive versus augmented noise).

Measurement and feedback
------------------------
GPS position, paper 000 eqs. 3-4: ``z = r_INS - r_GPS = H x + xi`` with ``H = [I_3 0]`` (NED metres;
``measurement='position_velocity'`` appends velocity, ``H = [I_6 0]``).  The UKF measurement
update (paper 000 eqs. 17-23) gives the innovation, ``S = P_zz + R`` and the chi-square statistic /
NIS ``v^T S^-1 v`` (paper 000 eq. 24).  After every update the estimated errors are fed back (closed
loop: :meth:`Strapdown.correct`, biases accumulated) and the error mean is reset to zero.
"""
from __future__ import annotations

import math

import numpy as np

from ..ins import earth
from .ctfa import PAPER_T1, PAPER_T2, CtfaQSchedule, ctfa_thresholds
from ..ins.error_model import ATT, BA, BG, N_STATES, POS, VEL
from .imm import ImmBank, imm_combine
from .innovation_stats import nis
from .ins_gnss_kf import KfEngine, UpdateResult
from .recovery import GuardedEngine, flag_by_gate, inflate_navigation
from ..core.kernels import kernel
from ..ins.strapdown import _gravity, _radii
from .unscented import (UnscentedKalmanFilter, points_from_sqrt_rows, predicted_moments_rows,
                        predicted_state_error, sqrt_rows)

#: tolerance on accumulated time when deciding that a prediction interval is complete [s]
_TIME_EPS = 1e-9


# The process model works on component arrays of shape (3, N) (one row per axis, one column per
# sigma point), so a cross product is two gathers and three array operations whatever N.
_NEXT = np.array([1, 2, 0])
_PREV = np.array([2, 0, 1])


def _cross(a_next, a_prev, b):
    """Cross products a x b, b of shape (..., 3, N), for a given by its gathered components
    a_next = a[_NEXT] and a_prev = a[_PREV] (shape (3, N) or (3, 1))."""
    return a_next * b[..., _PREV, :] - a_prev * b[..., _NEXT, :]


def _rodrigues_coefficients(theta2):
    """sin(t)/t and (1 - cos t)/t^2 of |phi|^2 = theta2, with their series near 0."""
    theta = np.sqrt(theta2)
    small = theta2 < 1e-12
    if not small.any():                  # the usual case: the same values without the series
        return np.sin(theta) / theta, (1.0 - np.cos(theta)) / (theta * theta)
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta2 / 24.0, (1.0 - np.cos(safe)) / (safe * safe))
    return a, b


def _rotate_by_rotvec(phi_next, phi_prev, V, a, b):
    """exp([phi x]) V (Rodrigues) for V of shape (..., 3, N); a, b of _rodrigues_coefficients."""
    pxv = _cross(phi_next, phi_prev, V)
    return V + a * pxv + b * _cross(phi_next, phi_prev, pxv)


def _inverse_jacobian_apply(phi_next, phi_prev, w, theta2):
    """J^-1(phi) w = w - 1/2 phi x w + c(|phi|) phi x (phi x w) (rotation-vector kinematics)."""
    small = theta2 < 1e-8
    if small.any():
        theta = np.sqrt(np.where(small, 1.0, theta2))
        half = 0.5 * theta
        c = np.where(small, 1.0 / 12.0 + theta2 / 720.0,
                     (1.0 - half * np.cos(half) / np.sin(half)) / (theta * theta))
    else:                                # the same values without the series
        theta = np.sqrt(theta2)
        half = 0.5 * theta
        c = (1.0 - half * np.cos(half) / np.sin(half)) / (theta * theta)
    pxw = _cross(phi_next, phi_prev, w)
    return w - 0.5 * pxw + c * _cross(phi_next, phi_prev, pxw)


def _nav_rates(lat, h, vn, ve, rn, re):
    """(w_ie + w_en, 2 w_ie + w_en) in NED; arrays or floats; radii given."""
    sl, cl = np.sin(lat), np.cos(lat)
    w = earth.OMEGA_IE
    reh = re + h
    rnh = rn + h
    en_n, en_e, en_d = ve / reh, -vn / rnh, -ve * sl / (cl * reh)
    w_in = (w * cl + en_n, en_e, -w * sl + en_d)
    w_cor = (2.0 * w * cl + en_n, en_e, -2.0 * w * sl + en_d)
    return w_in, w_cor


class NominalInterval:
    """Means of the nominal (computed) navigation quantities over one UKF prediction interval:
    floats and arrays of one run (``v``, ``f`` (3,), ``C`` (3, 3)), or of B runs with a
    leading run axis (:func:`interval_means`)."""

    __slots__ = ("T", "lat", "h", "v", "C", "f")

    def __init__(self, T, lat, h, v, C, f):
        self.T, self.lat, self.h, self.v, self.C, self.f = T, lat, h, v, C, f


#: columns of a UKF engine's interval sums (one row per run): the interval length T, then
#: the trapezoid sums of lat, h, v (3) and C_bn (9 by rows) and the sum of C_bn dvel (3)
N_SUMS = 18


@kernel
def accumulate_rows(sums, before, after, dvel_c, dt):
    """Add one IMU interval of every run to its interval sums (B, :data:`N_SUMS`), in place:
    ``before``/``after`` the strapdown rows (B, 24) at its start and end, ``dvel_c`` (B, 3)
    the compensated velocity increments, ``dt`` (B,) the interval lengths."""
    for b in range(sums.shape[0]):
        s, r0, r1 = sums[b], before[b], after[b]
        half = 0.5 * dt[b]
        s[0] += dt[b]
        s[1] += half * (r0[0] + r1[0])
        s[2] += half * (r0[2] + r1[2])
        for i in range(12):                   # v (columns 3..5) and C_bn (6..14)
            s[3 + i] += half * (r0[3 + i] + r1[3 + i])
        # C_prev @ dvel_c as numpy's product rounds it (BLAS from both)
        s[15:18] += np.ascontiguousarray(r0[6:15]).reshape(3, 3) @ dvel_c[b]


def interval_means(sums):
    """The :class:`NominalInterval` of every run from its sums (B, :data:`N_SUMS`)."""
    T = sums[:, 0]
    runs = len(sums)
    return NominalInterval(T, sums[:, 1] / T, sums[:, 2] / T, sums[:, 3:6] / T[:, None],
                           sums[:, 6:15].reshape(runs, 3, 3) / T[:, None, None],
                           sums[:, 15:18] / T[:, None])


def prediction_due(T, predict_interval):
    """Whether an interval of ``T`` seconds completes the prediction interval (floats, or
    arrays: every run of a batch)."""
    return T >= predict_interval - _TIME_EPS


class _RunValues:
    """The nominal values of one interval of B runs for :func:`error_dynamics`: ``lat``,
    ``h`` (B,), ``v``, ``f`` (3, B), ``C`` (B, 3, 3), ``T`` (B,), and :meth:`spread`, which
    takes per-run arrays (..., B) to the runs' points (..., N), every run's points
    consecutive (one run: a broadcast, no copy)."""

    __slots__ = ("lat", "h", "v", "f", "C", "T", "runs", "per_run")

    def __init__(self, nom, points):
        self.lat = np.asarray(nom.lat, dtype=float).reshape(-1)
        self.runs = runs = self.lat.shape[0]
        self.h = np.asarray(nom.h, dtype=float).reshape(-1)
        self.T = np.asarray(nom.T, dtype=float).reshape(-1)
        self.v = np.asarray(nom.v, dtype=float).reshape(runs, 3).T
        self.f = np.asarray(nom.f, dtype=float).reshape(runs, 3).T
        self.C = np.asarray(nom.C, dtype=float).reshape(runs, 3, 3)
        self.per_run = points // runs

    def spread(self, a):
        return a if self.runs == 1 else np.repeat(a, self.per_run, axis=-1)


def error_dynamics(X, nom, tau_g=0.0, tau_a=0.0):
    """Time derivative of every sigma point (rows of X, shape (N, 15)); module docstring.

    ``nom`` is one run's interval (floats) or B runs' (arrays with a leading run axis, the N
    points then the B runs' points one run after the other, N / B each)."""
    return _error_dynamics(X, _RunValues(nom, X.shape[0]), tau_g, tau_a)


def _error_dynamics(X, run, tau_g, tau_a):
    Xt = X.T                                   # (15, N): one row per state
    dr, dv, phi = Xt[0:3], Xt[3:6], Xt[6:9]
    spread, runs = run.spread, run.runs
    lats, hs = run.lat.tolist(), run.h.tolist()
    radii = np.array([_radii(x) for x in lats]).T          # math: a float per run
    gravity = np.array([_gravity(x, y) for x, y in zip(lats, hs)])
    # the computed (primed) state of each run, then the true state of each point (computed
    # minus error), in one array (rows lat, h, v (3), R_N, R_E): the rates of both in one pass
    points = X.shape[0]
    state = np.empty((7, runs + points))
    state[0, :runs], state[1, :runs], state[2:5, :runs] = run.lat, run.h, run.v
    state[5:7, :runs] = radii
    state[5:7, runs:] = spread(radii)
    rn = state[5, runs:]
    np.subtract(spread(run.lat), dr[0] / (rn + spread(run.h)), out=state[0, runs:])
    np.add(spread(run.h), dr[2], out=state[1, runs:])
    np.subtract(spread(run.v), dv, out=state[2:5, runs:])
    v = state[2:5]
    w_in, w_cor = _nav_rates(state[0], state[1], v[0], v[1], state[5], state[6])
    w_in, w_cor = np.array(w_in), np.array(w_cor)
    coriolis = _cross(w_cor[_NEXT], w_cor[_PREV], v)      # w_cor' x v' and w_cor x v
    v_t = v[:, runs:]

    phi_rows = X[:, 6:9]
    theta2 = np.einsum("ij,ij->i", phi_rows, phi_rows)
    a, b = _rodrigues_coefficients(theta2)
    phi_next, phi_prev = phi[_NEXT], phi[_PREV]
    # exp([phi x]) of the three vectors it rotates, at once: w_in' - C' dbg, f^{n'}, C' dba
    # (every run's points by its own C': stacked products, each the floats of its 2-D one)
    C_t = run.C.transpose(0, 2, 1)
    by_run = X.reshape(runs, -1, N_STATES)
    V = np.empty((3, 3, points))
    np.subtract(spread(w_in[:, :runs]), (by_run[:, :, 9:12] @ C_t).reshape(-1, 3).T, out=V[0])
    V[1] = spread(run.f)
    V[2] = (by_run[:, :, 12:15] @ C_t).reshape(-1, 3).T
    RV = _rotate_by_rotvec(phi_next, phi_prev, V, a, b)

    # attitude: d(phi)/dt = J^-1(phi) [exp([phi x]) (w_in' - C' dbg) - w_in]
    w_s = RV[0] - w_in[:, runs:]
    dphi = _inverse_jacobian_apply(phi_next, phi_prev, w_s, theta2)

    # velocity
    ddv = spread(run.f) - RV[1] + RV[2]
    ddv -= spread(coriolis[:, :runs]) - coriolis[:, runs:]
    ddv[2] += spread(2.0 * gravity / np.sqrt(radii[0] * radii[1])) * dr[2]
    Xdot = np.empty_like(X)
    Xdot_t = Xdot.T
    Xdot_t[0:3] = dv
    Xdot_t[3:6] = ddv
    Xdot_t[6:9] = dphi
    Xdot_t[9:12] = 0.0 if tau_g <= 0 else -Xt[9:12] / tau_g
    Xdot_t[12:15] = 0.0 if tau_a <= 0 else -Xt[12:15] / tau_a
    return Xdot


def propagate_points(X, nom, tau_g=0.0, tau_a=0.0):
    """Process model f of paper 000 eq. 14 over one interval: one step with
    second-order position."""
    run = _RunValues(nom, X.shape[0])
    Xdot = _error_dynamics(X, run, tau_g, tau_a)
    T = run.spread(run.T)[:, None]
    Y = X + T * Xdot
    Y[:, 0:3] += 0.5 * T * T * Xdot[:, 3:6]
    return Y


def predict_rows(x, P, nom, Q, q_scale, Wm, Wc, spread, tau_g, tau_a):
    """The UKF time update (paper 000 eqs. 14-16) of B filters at once, each over its run's
    interval ``nom`` (:func:`interval_means`; one nominal shared by all filters when it has
    one run): means ``x`` (B, 15), checked symmetric covariances ``P`` (B, 15, 15), process
    noises ``Q`` (B, 15, 15) times ``q_scale`` (B,), the UT's weights and point ``spread``.
    One process-model call for every point of every filter (it works row by row).  Returns
    (x, P, square-root fallbacks (B,), finite (B,)) as :meth:`UnscentedKalmanFilter.predict`
    computes them for each filter."""
    L, fallback = sqrt_rows(P)
    X = points_from_sqrt_rows(x, L * spread)
    Y = propagate_points(X.reshape(-1, N_STATES), nom, tau_g, tau_a).reshape(X.shape)
    x, P, finite = predicted_moments_rows(Y, Wm, Wc, Q, q_scale)
    return x, P, fallback, finite


def discrete_process_noise(q_density, T):
    """Q_d(T) of the additive process noise (module docstring): diag(q) T plus the velocity
    noise integrated into position."""
    Q = np.diag(q_density * T)
    qv = q_density[VEL]
    Q[POS, POS] = np.diag(qv * T ** 3 / 3.0)
    cross = np.diag(qv * T * T / 2.0)
    Q[POS, VEL] = cross
    Q[VEL, POS] = cross
    return Q


class UkfEngine(KfEngine):
    """15-state INS/GNSS UKF with the nonlinear error model of the module docstring.

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
        """Mechanize one IMU interval with bias-compensated increments; accumulate the interval
        means (:func:`accumulate_rows` of this run) and run the UKF prediction when
        ``predict_interval`` is complete."""
        dtheta_c = dtheta - self.gyro_bias * dt
        dvel_c = dvel - self.accel_bias * dt
        self.rate_ib = dtheta_c / dt
        nav = self.nav
        before = nav.rows.copy()
        nav.update(dtheta_c, dvel_c, dt)
        accumulate_rows(self.sums, before, nav.rows, np.reshape(dvel_c, (1, 3)),
                        np.full(1, float(dt)))
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
        :func:`predict_rows` of this run."""
        ukf = self.ukf
        x, P, fallback, finite = predict_rows(
            ukf.x[None], ukf.checked_covariance()[None], nom, Q[None],
            np.full(1, float(self.q_scale)), ukf.Wm, ukf.Wc, ukf._spread, tau_g, tau_a)
        ukf.sqrt_fallbacks += int(fallback[0])
        if not finite[0]:
            raise predicted_state_error()
        ukf.x, ukf.P = x[0], P[0]

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
        """Measurement model of paper 000 eqs. 3-4 (linear: H = [I_m 0]) over the sigma points."""
        return X[:, :self.m]

    def update(self, z):
        """UKF measurement update (paper 000 eqs. 17-23) then closed-loop feedback."""
        self._predict()
        res = self.ukf.update(z, self._h, self.R0, vectorized=True)
        self._feedback(self.ukf.x)
        self.ukf.x = np.zeros(N_STATES)
        return UpdateResult(res["innovation"], res["S"], res["nis"], q_scale=self.q_scale)

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
                    flt.P = inflate_navigation(flt.P, lam)
        guard.close_epoch(True)
        return lam

    def _feedback(self, dx):
        self.nav.correct(dx[POS], dx[VEL], dx[ATT])
        self.gyro_bias = self.gyro_bias + dx[BG]
        self.accel_bias = self.accel_bias + dx[BA]
        self.n_updates += 1


class CtfaUkfEngine(GuardedEngine, UkfEngine):
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

    def update(self, z):
        self._predict()
        self.reacquire(z, self.ukf.x, self.ukf.P, (self.ukf,))
        result = super().update(z)
        self.chi2 = result.nis                       # paper 000 eq. 24
        self.q_scale = float(self.schedule.update(self.chi2)[0, 0])   # paper 000 eq. 25, next steps
        result.q_scale = self.q_scale
        return result


class ImmUkfEngine(GuardedEngine, UkfEngine):
    """IMM-UKF (paper 000's comparison, its ref. [14]): a bank of UKFs differing in Q.

    ``q_scales`` (one per model) multiply the configured Q; ``p_stay`` is the diagonal of the
    Markov transition matrix, the rest of each row spread evenly.  The bank
    (:class:`navcore.filters.imm.ImmBank`) mixes once per measurement interval (at the first
    prediction after an update), predicts every model, updates every model with the same
    measurement, updates the model probabilities from the Gaussian likelihoods and combines.  The
    combined error estimate is fed back to the single nominal INS and subtracted from every model
    (closed loop).  ``q_scale`` = probability-weighted scale; ``model_probabilities``;
    the NIS is that of the combined prediction.  Recovery guard (ours; off = the plain IMM):
    :meth:`UkfEngine.reacquire` on the mixed prediction, inflating every model.
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

    @property
    def model_probabilities(self):
        return self.bank.mu

    def predict_filters(self, nom, Q, tau_g, tau_a):
        """Every model's sigma points through one call of the process model (it works row by
        row, so each model's points propagate exactly as on their own), then each model's
        moments with its own Q."""
        scales = self.q_scales

        def predict_models(filters):
            X = np.concatenate([flt.sigma_points() for flt in filters])
            Y = propagate_points(X, nom, tau_g, tau_a)
            k = 2 * N_STATES + 1
            for j, flt in enumerate(filters):
                flt.predict_points(Y[j * k:(j + 1) * k], Q, q_scale=scales[j])

        self.bank.predict_all(predict_models)

    def prediction_covariance(self):
        return self.bank.P

    def covariance(self):
        return self.bank.P.copy()

    def update(self, z):
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
        statistic = nis(v, S)
        h, R = self._h, self.R0
        bank.update(lambda flt, j: flt.update(z, h, R, vectorized=True))
        dx = bank.x.copy()
        self._feedback(dx)
        bank.subtract_from_states(dx)
        self.q_scale = float(bank.mu @ self.q_scales)
        return UpdateResult(v, S, statistic, q_scale=self.q_scale)
