"""The UKF engines' time update (paper 000 eqs. 14-16 on the error model of
:mod:`navcore.filters.ukf_filters`), for one run or many: the process model over sigma points,
the interval means of the nominal navigation it runs on, and the prediction of many filters in
one call.

Every function takes a leading run axis, and an engine alone calls it with one run, so a run
alone and a run inside a batch (:mod:`navcore.components.ukf_batch`) compute the same floats:
:func:`accumulate_rows` adds an IMU interval to every run's interval sums (a kernel),
:func:`interval_means` turns them into each run's :class:`NominalInterval`,
:func:`error_dynamics` and :func:`propagate_points` (kernels over the points) map the points
of B runs, each with its run's nominal (one nominal may serve the points of several filters:
an IMM bank), and :func:`predict_rows` predicts B filters (one square root per covariance,
one process-model call for all their points, their moments in stacked products).

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
"""
from __future__ import annotations

import math

import numpy as np

from ..core.kernels import jitable, kernel
from ..ins import earth
from ..ins.error_model import N_STATES, POS, VEL
from ..ins.strapdown import _gravity, _radii, update_rows
from .ins_gnss_kf import compensated_rows
from .unscented_rows import predicted_moments_rows, predicted_state_error, sigma_points_rows

#: tolerance on accumulated time when deciding that a prediction interval is complete [s]
_TIME_EPS = 1e-9


# The process model is a kernel over the sigma points; its formulas are these scalar helpers
# (compiled into it), written as the numpy expressions they replaced: the same operations in
# the same order, so every point gets the floats of the array code.
@jitable
def _cross(a0, a1, a2, b0, b1, b2):
    """The cross product a x b of two vectors given by their components."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@jitable
def _rodrigues_coefficients(theta2):
    """sin(t)/t and (1 - cos t)/t^2 of |phi|^2 = theta2, with their series near 0."""
    if theta2 < 1e-12:
        return 1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0
    theta = math.sqrt(theta2)
    return math.sin(theta) / theta, (1.0 - math.cos(theta)) / (theta * theta)


@jitable
def _rotate_by_rotvec(p0, p1, p2, v0, v1, v2, a, b):
    """exp([phi x]) v (Rodrigues); a, b of _rodrigues_coefficients."""
    c0, c1, c2 = _cross(p0, p1, p2, v0, v1, v2)
    d0, d1, d2 = _cross(p0, p1, p2, c0, c1, c2)
    return v0 + a * c0 + b * d0, v1 + a * c1 + b * d1, v2 + a * c2 + b * d2


@jitable
def _inverse_jacobian_apply(p0, p1, p2, w0, w1, w2, theta2):
    """J^-1(phi) w = w - 1/2 phi x w + c(|phi|) phi x (phi x w) (rotation-vector kinematics)."""
    if theta2 < 1e-8:
        c = 1.0 / 12.0 + theta2 / 720.0
    else:
        theta = math.sqrt(theta2)
        half = 0.5 * theta
        c = (1.0 - half * math.cos(half) / math.sin(half)) / (theta * theta)
    c0, c1, c2 = _cross(p0, p1, p2, w0, w1, w2)
    d0, d1, d2 = _cross(p0, p1, p2, c0, c1, c2)
    return w0 - 0.5 * c0 + c * d0, w1 - 0.5 * c1 + c * d1, w2 - 0.5 * c2 + c * d2


@jitable
def _nav_rates(lat, h, vn, ve, rn, re):
    """(w_ie + w_en, 2 w_ie + w_en) in NED; radii given."""
    sl, cl = math.sin(lat), math.cos(lat)
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


def advance_interval_rows(nav_rows, sums, dtheta, dvel, gyro_bias, accel_bias, dt,
                          mechanize=None):
    """:meth:`UkfEngine.propagate`'s IMU interval of every run (B rows each): the bias
    compensation (:func:`~navcore.filters.ins_gnss_kf.compensated_rows`), the mechanization
    of the strapdown rows (:func:`update_rows`, or ``mechanize(dtheta_c, dvel_c)`` for a
    strapdown subclass's own update) and the interval sums (:func:`accumulate_rows`), in
    place.  Returns the body rates (B, 3)."""
    dtheta_c, dvel_c, rate_ib, _ = compensated_rows(dtheta, dvel, gyro_bias, accel_bias, dt)
    before = nav_rows.copy()
    dts = np.full(len(nav_rows), float(dt))
    if mechanize is None:
        update_rows(nav_rows, dtheta_c, dvel_c, dts)
    else:
        mechanize(dtheta_c, dvel_c)
    accumulate_rows(sums, before, nav_rows, dvel_c, dts)
    return rate_ib


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
    """The nominal values of one interval of B runs for the process model, contiguous with
    a leading run axis: ``lat``, ``h``, ``T`` (B,), ``v``, ``f`` (B, 3), ``C`` (B, 3, 3);
    ``per_run`` points of each run, one run after the other."""

    __slots__ = ("lat", "h", "v", "f", "C", "T", "per_run")

    def __init__(self, nom, points):
        self.lat = np.asarray(nom.lat, dtype=float).reshape(-1)
        runs = self.lat.shape[0]
        self.h = np.asarray(nom.h, dtype=float).reshape(-1)
        self.T = np.asarray(nom.T, dtype=float).reshape(-1)
        self.v = np.ascontiguousarray(np.asarray(nom.v, dtype=float).reshape(runs, 3))
        self.f = np.ascontiguousarray(np.asarray(nom.f, dtype=float).reshape(runs, 3))
        self.C = np.asarray(nom.C, dtype=float).reshape(runs, 3, 3)
        self.per_run = points // runs


def error_dynamics(X, nom, tau_g=0.0, tau_a=0.0):
    """Time derivative of every sigma point (rows of X, shape (N, 15)); module docstring.

    ``nom`` is one run's interval (floats) or B runs' (arrays with a leading run axis, the N
    points then the B runs' points one run after the other, N / B each)."""
    return _error_dynamics(X, _RunValues(nom, X.shape[0]), tau_g, tau_a)


def _error_dynamics(X, run, tau_g, tau_a):
    """The derivative kernel's call; the reductions stay numpy's (|phi|^2 by einsum, the bias
    errors in the nav frame by stacked products: a compiled loop would sum otherwise)."""
    phi = X[:, 6:9]
    theta2 = np.einsum("ij,ij->i", phi, phi)
    # every run's points by its own C': stacked products, each the floats of its 2-D one
    runs = len(run.lat)
    C_t = run.C.transpose(0, 2, 1)
    by_run = X.reshape(runs, -1, N_STATES)
    gyro_n = (by_run[:, :, 9:12] @ C_t).reshape(-1, 3)
    accel_n = (by_run[:, :, 12:15] @ C_t).reshape(-1, 3)
    Xdot = np.empty((X.shape[0], N_STATES))
    _derivative_rows(X, theta2, gyro_n, accel_n, run.per_run, run.lat, run.h, run.v, run.f,
                     float(tau_g), float(tau_a), Xdot)
    return Xdot


@kernel
def _derivative_rows(X, theta2, gyro_n, accel_n, per_run, lat, h, v, f, tau_g, tau_a, Xdot):
    """The error dynamics (module docstring) of the ``per_run`` points of every run, into
    ``Xdot``: ``gyro_n``/``accel_n`` are each point's bias errors times C' (N, 3)."""
    for k in range(lat.shape[0]):
        rn, re = _radii(lat[k])
        (wi0, wi1, wi2), (wc0, wc1, wc2) = _nav_rates(lat[k], h[k], v[k, 0], v[k, 1], rn, re)
        k0, k1, k2 = _cross(wc0, wc1, wc2, v[k, 0], v[k, 1], v[k, 2])   # w_cor' x v'
        vertical = 2.0 * _gravity(lat[k], h[k]) / math.sqrt(rn * re)
        f0, f1, f2 = f[k, 0], f[k, 1], f[k, 2]
        for p in range(k * per_run, (k + 1) * per_run):
            x = X[p]
            # the true state of the point: the computed one minus its error
            vt0, vt1, vt2 = v[k, 0] - x[3], v[k, 1] - x[4], v[k, 2] - x[5]
            (ti0, ti1, ti2), (tc0, tc1, tc2) = _nav_rates(
                lat[k] - x[0] / (rn + h[k]), h[k] + x[2], vt0, vt1, rn, re)
            c0, c1, c2 = _cross(tc0, tc1, tc2, vt0, vt1, vt2)              # w_cor x v
            a, b = _rodrigues_coefficients(theta2[p])
            p0, p1, p2 = x[6], x[7], x[8]
            # attitude: d(phi)/dt = J^-1(phi) [exp([phi x]) (w_in' - C' dbg) - w_in]
            s0, s1, s2 = _rotate_by_rotvec(p0, p1, p2, wi0 - gyro_n[p, 0], wi1 - gyro_n[p, 1],
                                           wi2 - gyro_n[p, 2], a, b)
            Xdot[p, 6], Xdot[p, 7], Xdot[p, 8] = _inverse_jacobian_apply(
                p0, p1, p2, s0 - ti0, s1 - ti1, s2 - ti2, theta2[p])
            # velocity: (I - exp([phi x])) f' + exp([phi x]) C' dba - coriolis difference
            r0, r1, r2 = _rotate_by_rotvec(p0, p1, p2, f0, f1, f2, a, b)
            e0, e1, e2 = _rotate_by_rotvec(p0, p1, p2, accel_n[p, 0], accel_n[p, 1],
                                           accel_n[p, 2], a, b)
            Xdot[p, 3] = f0 - r0 + e0 - (k0 - c0)
            Xdot[p, 4] = f1 - r1 + e1 - (k1 - c1)
            Xdot[p, 5] = f2 - r2 + e2 - (k2 - c2) + vertical * x[2]
            Xdot[p, 0], Xdot[p, 1], Xdot[p, 2] = x[3], x[4], x[5]
            for i in range(9, 12):
                Xdot[p, i] = 0.0 if tau_g <= 0 else -x[i] / tau_g
            for i in range(12, 15):
                Xdot[p, i] = 0.0 if tau_a <= 0 else -x[i] / tau_a


@kernel
def _step_rows(X, Xdot, T, per_run, Y):
    """One step of every point, ``Y = X + T Xdot`` with second-order position, T its run's."""
    for p in range(X.shape[0]):
        t = T[p // per_run]
        for i in range(N_STATES):
            Y[p, i] = X[p, i] + t * Xdot[p, i]
        for i in range(3):
            Y[p, i] += 0.5 * t * t * Xdot[p, 3 + i]


def propagate_points(X, nom, tau_g=0.0, tau_a=0.0):
    """Process model f of paper 000 eq. 14 over one interval: one step with
    second-order position."""
    run = _RunValues(nom, X.shape[0])
    Xdot = _error_dynamics(X, run, tau_g, tau_a)
    Y = np.empty((X.shape[0], N_STATES))
    _step_rows(X, Xdot, run.T, run.per_run, Y)
    return Y


def predict_rows(x, P, nom, Q, q_scale, Wm, Wc, spread, tau_g, tau_a):
    """The UKF time update (paper 000 eqs. 14-16) of B filters at once, each over its run's
    interval ``nom`` (:func:`interval_means`; one nominal shared by all filters when it has
    one run): means ``x`` (B, 15), checked symmetric covariances ``P`` (B, 15, 15), process
    noises ``Q`` (B, 15, 15) times ``q_scale`` (B,), the UT's weights and point ``spread``.
    One process-model call for every point of every filter (it works row by row).  Returns
    (x, P, square-root fallbacks (B,), finite (B,)) as :meth:`UnscentedKalmanFilter.predict`
    computes them for each filter."""
    X, fallback = sigma_points_rows(x, P, spread)
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


def predict_filter_groups(filters, x, P, nom, Q, q_scales, tau_g, tau_a, models):
    """:func:`predict_rows` of the unscented filters ``filters``
    (:class:`~navcore.filters.unscented.UnscentedKalmanFilter`, one transform) whose states
    are ``x`` (F, n) and checked covariances ``P`` (F, n, n), with process noises ``Q``
    (F, n, n) times ``q_scales`` (F,): ``models`` consecutive filters per run of ``nom``.
    Every filter counts its square-root fallbacks; the filters of a run take their
    prediction when all of them are finite.  Returns, per run, whether they were, and the
    predicted means (F, n) and covariances (F, n, n) of all filters (the filters' own are
    views of them)."""
    first = filters[0]
    x, P, fallback, finite = predict_rows(x, P, nom, Q, q_scales, first.Wm, first.Wc,
                                          first._spread, tau_g, tau_a)
    finite_runs = finite.reshape(-1, models).all(axis=1)
    if fallback.any():
        for flt, fell_back in zip(filters, fallback.tolist()):
            flt.sqrt_fallbacks += fell_back
    taken = finite_runs.tolist()
    for j, (flt, state, covariance) in enumerate(zip(filters, list(x), list(P))):
        if taken[j // models]:
            flt.x, flt.P = state, covariance
    return finite_runs, x, P


def predict_unscented_filters(filters, nom, Q, q_scales, tau_g, tau_a):
    """:func:`predict_filter_groups` of one run's filters over its interval ``nom`` with the
    process noise ``Q`` times each filter's scale of ``q_scales``: their states checked as
    :meth:`~navcore.filters.unscented.UnscentedKalmanFilter.predict` checks them, updated in
    place; raises its error when a prediction is not finite."""
    P = np.stack([flt.checked_covariance() for flt in filters])
    x = np.stack([flt.x for flt in filters])
    Q = np.broadcast_to(Q, (len(filters),) + np.shape(Q))
    if not predict_filter_groups(filters, x, P, nom, Q, np.asarray(q_scales, dtype=float),
                                 tau_g, tau_a, len(filters))[0][0]:
        raise predicted_state_error()
