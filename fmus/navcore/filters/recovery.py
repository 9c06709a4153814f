"""Recovery guards of the adaptive and robust filters: re-acquisition after outages and runs of
rejections, and bounded adaptive scales.

A gate (a chi-square test, an equivalent-weight function, an outlier compression) trusts the
filter's predicted covariance.  When the real errors outgrow it -- an IMU worse than the
filter's Q, a GNSS outage that let the INS drift further than P says, biased and
time-correlated GNSS errors -- every later fix looks like an outlier and is rejected, so the
state never comes back; an adaptive R estimate fed by those innovations runs away instead.
The literature's remedy is to read a *run* of rejections as a fault of the state, not of the
measurements, and to inflate the state covariance until the measurement is consistent with it
again (Groves 2013, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation
Systems*, 2nd ed., ch. 17, innovation filtering: consecutive rejected measurements indicate
that the state estimates are at fault; the error covariance is then increased or the filter
reinitialized), with adaptive factors kept within bounds (Yang, He & Xu 2001, *Adaptively
robust filtering for kinematic geodetic positioning*, J. Geodesy 75: the adaptive factor
bounded; the fading factor of the strong tracking filter, Zhou & Frank 1996, Int. J. Control
65, chosen, as here, so that the innovation matches its predicted covariance).

:class:`RecoveryGuard` (one per filter engine) implements, when parameter ``recovery`` is on:

* **rejection-run limit** -- per measurement component, the time since it was last accepted
  counts the epochs of a run of rejections *and* of an outage (no fix at all) alike.  A
  component the filter's law flags again after ``recovery_epochs`` fix intervals without an
  accepted value is re-acquired: the navigation part of the predicted covariance (position,
  velocity, attitude up to its initial variance, and their cross terms with the biases;
  :func:`inflate_navigation`) is
  inflated by the factor ``lambda >= 1`` for which the flagged components' innovation has its
  expected NIS (:func:`inflation_factor`: ``v' (lambda H P H' + R)^-1 v = k`` for k components),
  and the law runs again on the inflated prediction with those components accepted.  So the
  first fix after an outage of ``recovery_epochs`` intervals or more that the law would
  reject is taken, with the covariance inflated by what the outage really did to the state;
  a shorter outage or a single outlier between accepted fixes is left to the law.
* **bounded adaptive scales** -- :func:`bounded_r` keeps an estimated R at most ``r_max_scale``
  times the nominal R in use per axis (SageHusaFading, Iakf): the configured R, or with
  ``r_from_receiver`` the receiver's own R of the fix (a bound relative to the configured
  5 m let R grow 3.4e5-fold over 1-cm RTK fixes).

With ``recovery`` off every filter is its paper's law as printed; the papers' scenarios set it
off (their filter.ssv), so their numbers are those of the law.  What each filter flags:
``navcore.filters.adaptive_filters`` and ``navcore.filters.ukf_filters`` say it in their classes.
"""
from __future__ import annotations

import numpy as np

from .array_checks import symmetrize
from ..core.component import Limits, boolean, integer, real
from ..ins.error_model import ATT, POS, VEL
from .innovation_stats import chi2_gate

#: significance of the chi-square gate of filters whose law has no gate of its own
#: (SageHusaFading, the UKF family): a fix whose NIS exceeds the 99 % quantile is flagged
FLAG_ALPHA = 0.01
#: largest covariance inflation of one re-acquisition (a 1e6-fold variance: 1000 sigma)
MAX_INFLATION = 1e6
#: fix intervals shorter than this fraction of the smallest one seen are not intervals
_INTERVAL_TOLERANCE = 1e-6

#: parameters every filter component declares (the Kf, Ukf and InsOnly have no guard: the
#: parameters are accepted so that one filter.ssv serves every filter of a scenario)
RECOVERY_PARAMETERS = (
    boolean("recovery", "recovery guards of the adaptive and robust filters (re-acquisition "
            "after outages and runs of rejections, bounded adaptive scales); false = each "
            "paper's law as printed", True),
    integer("recovery_epochs", "fix intervals without an accepted value after which a "
            "component the filter's law rejects is re-acquired with an inflated covariance",
            5, Limits(1, 100000)),
)
#: bound of the estimated R (SageHusaFading, Iakf)
R_MAX_SCALE = real("r_max_scale", "", "recovery guard: the estimated R stays at most this "
                   "multiple of the nominal R in use per axis (r_pos_*/r_vel_*, or the receiver's "
                   "sigmas with r_from_receiver; variances; with recovery on)",
                   4.0, Limits(1.0, 1e12))


def recovery_options(params):
    """Engine keyword arguments of the guard from a component's parameters."""
    return dict(recovery=bool(params["recovery"]), recovery_epochs=int(params["recovery_epochs"]))


def inflation_factor(v, HPH, R, target):
    """The factor ``lambda >= 1`` with ``v' (lambda HPH + R)^-1 v = target`` (1 when the NIS is
    already at most ``target``; at most :data:`MAX_INFLATION`).

    Whitened by R (``R = L L'``), ``v' (lambda A + R)^-1 v = sum_i c_i^2 / (lambda mu_i + 1)``
    with ``mu_i`` the eigenvalues of ``L^-1 A L^-T`` and ``c`` the whitened innovation in
    their basis: decreasing in lambda, so bisection on log lambda finds the root.
    """
    L = np.linalg.cholesky(R)
    A = np.linalg.solve(L, np.linalg.solve(L, HPH).T)
    mu, U = np.linalg.eigh(symmetrize(A))
    c2 = (U.T @ np.linalg.solve(L, v)) ** 2
    mu = np.maximum(mu, 0.0)

    def nis_at(lam):
        return float(np.sum(c2 / (lam * mu + 1.0)))

    if nis_at(1.0) <= target:
        return 1.0
    if nis_at(MAX_INFLATION) > target:
        return MAX_INFLATION
    lo, hi = 0.0, np.log(MAX_INFLATION)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if nis_at(np.exp(mid)) > target:
            lo = mid
        else:
            hi = mid
    return float(np.exp(hi))


_POS_VEL = np.zeros(15, dtype=bool)
_POS_VEL[POS] = _POS_VEL[VEL] = True
_ATTITUDE = np.zeros(15, dtype=bool)
_ATTITUDE[ATT] = True


def _scales_within_initial(var, lam, p0_var, capped):
    """Per-state variance factors (B, 15): ``lam`` (B,) on position and velocity, on the
    states ``capped`` only until their variance ``var`` reaches the initial one ``p0_var``
    (never below 1), 1 elsewhere.  No update can make a filter less sure of its attitude or
    biases than it was before any measurement: an inflation of them stops there (covariance
    bounding at the initial uncertainty)."""
    room = np.maximum(1.0, p0_var / np.maximum(var, np.finfo(float).tiny))
    return np.where(_POS_VEL[None, :], lam[:, None],
                    np.where(capped[None, :], np.minimum(lam[:, None], room), 1.0))


def inflate_navigation(P, lam, p0_var):
    """``D P D`` with ``D = diag(sqrt(lam_i))``: lambda on position and velocity, on attitude
    only until its variance reaches the initial one ``p0_var`` (15,), 1 on the biases
    (positive definite whenever P is).

    Attitude is not measured by a fix: each re-acquisition multiplied its variance by lambda
    and no update brought it back, so repeated re-acquisitions (101 in 300 s of a real log,
    with a fix interval taken from the filter's start) grew the heading sigma geometrically
    (1e30 rad after 36 of them) until the UKF's sigma points overflowed to NaN."""
    if lam == 1.0:
        return P
    d = np.sqrt(_scales_within_initial(np.diag(P)[None], np.array([lam]), p0_var[None],
                                       _ATTITUDE)[0])
    return P * np.outer(d, d)


def faded_within_initial_rows(p_prop, q_acc, lam, p0_var):
    """Paper 001 eq. 10, ``P_pred = lambda Phi P Phi' + Q``, with the fading factor applied in
    full to position and velocity and to attitude and the sensor biases only until their
    variance reaches its initial one ``p0_var`` (:func:`_scales_within_initial`):
    ``D Phi P Phi' D + Q`` with ``D = diag(sqrt(lambda_i))`` (positive definite whenever P is).

    Eq. 12 sizes lambda from the position/velocity innovation and multiplies the whole P by
    it.  On real data with centimetre fixes (RTK) and decimetre model errors its test fires
    at nearly every fix, and the weakly observable heading and bias variances, which no update
    brings back down, grow geometrically: on a real drive the attitude variance reached
    2800 rad^2 and the position variance 1e12 m^2 after a 60 s outage, and Iakf stopped on a
    non-positive-definite G.  A consistent run, whose faded variances stay below p0, gets
    the law as printed.  ``lam`` (B,), ``p0_var`` (B, 15)."""
    var = np.diagonal(p_prop, axis1=-2, axis2=-1)
    d = np.sqrt(_scales_within_initial(var, lam, p0_var, ~_POS_VEL))
    return p_prop * (d[:, :, None] * d[:, None, :]) + q_acc


def bounded_r(R, r_max):
    """``R`` with its variances at most ``r_max`` (m,): D^-1 R D^-1 (D = diag(sqrt(r_max)))
    with its eigenvalues capped at 1, scaled back -- the ceiling counterpart of
    :func:`navcore.filters.adaptive_laws.guard_positive_definite` (correlations kept)."""
    rows = R[None]
    bounded = bounded_r_rows(rows, r_max[None])
    return R if bounded is rows else bounded[0]


def bounded_r_rows(R, r_max):
    """:func:`bounded_r` of every run: ``R`` (B, m, m), ``r_max`` (B, m); ``R`` itself
    when no run's variances exceed their bound."""
    scale = np.sqrt(r_max)
    outer = scale[:, :, None] * scale[:, None, :]
    S = R / outer
    w, V = np.linalg.eigh(0.5 * (S + S.swapaxes(-1, -2)))
    over = ~(w[:, -1] <= 1.0)
    if not over.any():
        return R
    capped = (V * np.minimum(w, 1.0)[:, None, :]) @ V.swapaxes(-1, -2) * outer
    return np.where(over[:, None, None], 0.5 * (capped + capped.swapaxes(-1, -2)), R)


class RecoveryGuard:
    """The rejection-run and outage bookkeeping of one filter (module docstring).

    The engine calls :meth:`advance` for every IMU interval, :meth:`open_epoch` at the start
    of an update, :meth:`due` with the components its law flags, and :meth:`close_epoch` with
    the components it accepted.  ``n_reacquired`` counts re-acquisitions.
    """

    state_fields = ("elapsed", "interval", "since_accepted", "n_reacquired", "opened")
    derived_fields = ("enabled", "epochs")

    def __init__(self, m, *, recovery, recovery_epochs):
        self.enabled = bool(recovery)
        self.epochs = int(recovery_epochs)
        self.elapsed = 0.0                 # s since the last update
        self.interval = 0.0                # smallest fix interval seen [s] (0: none yet)
        self.since_accepted = np.zeros(m)  # s since each component was last accepted
        self.n_reacquired = 0
        self.opened = False                # an update has been opened (fix intervals begin)

    def advance(self, dt):
        self.advance_over((dt,))

    def advance_over(self, dts):
        """The IMU intervals ``dts`` since the last call, one after the other."""
        elapsed = self.elapsed
        for dt in dts:
            elapsed += dt
        self.elapsed = elapsed

    def open_epoch(self):
        self.interval, self.since_accepted = self._opened()
        self.elapsed = 0.0
        self.opened = True

    def _opened(self):
        """(interval, since_accepted) as :meth:`open_epoch` leaves them.  A fix interval is
        the time between two updates: the time from the filter's start (or its start from
        the data) to its first update is not one -- a first fix 5 ms after the start would
        otherwise make every later run of two rejected fixes a re-acquisition."""
        gap = self.elapsed
        interval = self.interval
        if self.opened and gap > 0.0 and (interval == 0.0 or gap < interval):
            interval = gap
        return interval, self.since_accepted + gap

    def may_reacquire(self):
        """True when some component has gone ``recovery_epochs`` intervals without an accepted
        value (so a flagged one would be re-acquired; lets a filter skip computing flags)."""
        return (self.enabled and self.interval > 0.0 and bool(np.any(
            self.since_accepted >= self.epochs * self.interval * (1.0 - _INTERVAL_TOLERANCE))))

    def due(self, flagged):
        """The flagged components to re-acquire now (bool mask)."""
        return self._due(flagged, self.interval, self.since_accepted)

    def due_at_opening(self, flagged):
        """What :meth:`due` returns after :meth:`open_epoch` (which this leaves undone)."""
        return self._due(flagged, *self._opened())

    def _due(self, flagged, interval, since_accepted):
        flagged = np.asarray(flagged, dtype=bool)
        if not self.enabled or interval == 0.0 or not flagged.any():
            return np.zeros_like(flagged)
        limit = self.epochs * interval * (1.0 - _INTERVAL_TOLERANCE)
        return flagged & (since_accepted >= limit)

    def close_epoch(self, accepted):
        self.since_accepted = np.where(accepted, 0.0, self.since_accepted)

    def reacquisition(self, v, HPH, R, due):
        """The inflation factor for the components ``due`` (counted as a re-acquisition)."""
        self.n_reacquired += 1
        return self.reacquisition_factor(v, HPH, R, due)

    @staticmethod
    def reacquisition_factor(v, HPH, R, due):
        """:meth:`reacquisition`'s factor, not counted."""
        idx = np.flatnonzero(due)
        return inflation_factor(v[idx], HPH[np.ix_(idx, idx)], R[np.ix_(idx, idx)], idx.size)


def flag_by_gate(nis_value, m):
    """Every component flagged when the NIS exceeds the chi2(m) gate at :data:`FLAG_ALPHA`
    (filters whose law has no gate of its own)."""
    return np.full(m, nis_value > chi2_gate(FLAG_ALPHA, m))




class GuardedEngine:
    """Mixin of a guarded filter engine: holds its :class:`RecoveryGuard` (``guard``) and
    counts the IMU time between updates for it.  List it before the engine's base class."""

    state_fields = ("guard",)

    def init_guard(self, *, recovery, recovery_epochs):
        self.guard = RecoveryGuard(self.m, recovery=recovery, recovery_epochs=recovery_epochs)

    def advance_clocks_over(self, dts):
        super().advance_clocks_over(dts)
        self.guard.advance_over(dts)


__all__ = ["RECOVERY_PARAMETERS", "R_MAX_SCALE", "GuardedEngine", "RecoveryGuard", "bounded_r",
           "bounded_r_rows", "faded_within_initial_rows",
           "flag_by_gate", "inflate_navigation", "inflation_factor", "recovery_options"]
