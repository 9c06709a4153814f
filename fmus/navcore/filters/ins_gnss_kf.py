"""Loosely coupled INS/GNSS error-state Kalman filter with closed-loop feedback.

The strapdown mechanization (:mod:`navcore.ins.strapdown`) carries the navigation solution; the
filter estimates its errors with the 15-state model of :mod:`navcore.ins.error_model` and feeds
them back after every update (closed loop), so the error state is zero between updates.

Covariance propagation between two measurement updates keeps two parts (one matrix product
chain per IMU step, the same cost as propagating P)::

    Phi_acc = Phi_k ... Phi_1                 transition since the last update
    Q_acc   = sum_j Phi_{k..j+1} Qd_j Phi'    process noise accumulated since then
    P_{k,k-1} = Phi_acc P_{k-1} Phi_acc' + Q_acc         (paper 001, eq. 6)

because the adaptive filters need the two parts separately (the fading factor of paper 001,
eqs. 10 and 12, scales only the propagated ``P_{k-1}`` part).

The update is the standard one (paper 001, eqs. 4, 5, 7, 8) in Joseph form; subclasses change
:meth:`KfEngine.update` (adaptive R, fading memory, outlier handling) and keep the rest.
The measurement is ``z = INS - GNSS`` of position in NED metres and, optionally, velocity.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..core.kernels import kernel
from ..ins import earth
from ..ins.error_model import (ATT, BA, BG, N_STATES, POS, VEL, process_noise_density,
    transition_rows, transition_template)
from .innovation_stats import nis
from .land_aids import linear_update
from ..ins.lever_arm import antenna_position_offset, antenna_velocity_offset
from ..ins.strapdown import Strapdown, update_rows

#: the identity of the error state (read only)
_IDENTITY = np.eye(N_STATES)
_IDENTITY.flags.writeable = False

#: measurement modes and their dimension
MEASUREMENTS = {"position": 3, "position_velocity": 6}


@dataclass
class KfConfig:
    """Filter tuning in SI units (the FMU parameters are converted into this once)."""

    p0: np.ndarray                 # (15,) initial 1-sigma of the error state
    gyro_arw: float                # rad/sqrt(s)
    accel_vrw: float               # m/s/sqrt(s)
    gyro_bias_sigma: float         # rad/s, Gauss-Markov steady state (process noise)
    gyro_bias_tau: float           # s, 0 = random constant
    accel_bias_sigma: float        # m/s^2
    accel_bias_tau: float          # s
    r_sigma: np.ndarray            # (3,) or (6,) measurement 1-sigma, pos NED [m] (+ vel [m/s])
    measurement: str = "position_velocity"
    lever_arm: Optional[np.ndarray] = None   # (3,) body [m], IMU to antenna; None = zero
    gyro_bias0: Optional[np.ndarray] = None  # (3,) initial gyro bias [rad/s]; None = zero
    accel_bias0: Optional[np.ndarray] = None  # (3,) initial accel bias [m/s^2]; None = zero


@dataclass
class UpdateResult:
    """What an update did: innovation, its covariance, NIS and the diagnostics."""

    innovation: np.ndarray
    S: np.ndarray
    nis: float
    q_scale: float = 1.0
    r_scale: float = 1.0
    fading_factor: float = 1.0
    outlier: bool = False


def propagate_rows(nav_rows, gyro_bias, accel_bias, phi_acc, q_acc, q_density, dtheta, dvel,
                   dt, template, mechanize=None):
    """:meth:`KfEngine.propagate` of every run of a batch (arrays with a leading run axis of
    B: the strapdown rows (B, 24), advanced in place; the biases, increments (B, 3); the
    accumulated transition and process noise (B, 15, 15); the noise densities (B, 15)) over
    one interval ``dt`` shared by the runs, with the transition ``template`` of that dt.
    Returns the new (Phi_acc, Q_acc, body rate).  numpy's stacked products give each run the
    floats of its own 2-D product (``tests/test_kf_batch.py``).  ``mechanize(dtheta_c,
    dvel_c)``, when given, advances the rows instead of :func:`update_rows` (a strapdown
    subclass's own ``update``)."""
    runs = len(nav_rows)
    dtheta_c, dvel_c, rate_ib, f_body = compensated_rows(dtheta, dvel, gyro_bias, accel_bias, dt)
    C_bn = nav_rows[:, 6:15].reshape(runs, 3, 3)
    f_ned = (C_bn @ f_body[:, :, None])[:, :, 0]   # with the attitude at the start
    dts = np.full(runs, dt)
    if mechanize is None:
        update_rows(nav_rows, dtheta_c, dvel_c, dts)
    else:
        mechanize(dtheta_c, dvel_c)
    phi = np.empty((runs, N_STATES, N_STATES))
    transition_rows(phi, nav_rows, f_ned, dts, template)
    phi_acc = phi @ phi_acc
    q_acc = phi @ q_acc @ np.ascontiguousarray(phi.transpose(0, 2, 1))
    add_noise_rows(q_acc, q_density, float(dt))
    return phi_acc, q_acc, rate_ib


def predicted_rows(P, phi_acc):
    """``Phi_acc P Phi_acc'``, the propagated part of :meth:`KfEngine.predicted_parts`, of
    every run: (B, 15, 15) arrays, or one run's (15, 15).  numpy's stacked products give
    each run the floats of its own 2-D product (``tests/test_kf_batch.py``)."""
    return phi_acc @ P @ phi_acc.swapaxes(-1, -2)


def kalman_rows(P_pred, z, R, H):
    """The standard update (paper 001 eqs. 4, 5, 7, 8; Joseph form) of every run: the
    prediction ``P_pred`` (B, 15, 15), the measurement ``z`` (B, m) and ``R`` ((B, m, m),
    or one (m, m) for all), or one run's arrays without the run axis; ``H`` (m, 15)
    selects the first m states.  Returns (dx, P, v, S, K), with the run axis where the
    arguments have it.  numpy solves and multiplies every run's slices as one run's 2-D
    call does (one LAPACK solve and one BLAS product per slice)."""
    m = H.shape[0]
    v = z  # the predicted error state is zero in closed loop: v = z - H x_pred = z
    PHt = P_pred[..., :m]
    S = PHt[..., :m, :] + R
    K = np.linalg.solve(S, PHt.swapaxes(-1, -2)).swapaxes(-1, -2)
    IKH = _IDENTITY - K @ H
    P = IKH @ P_pred @ IKH.swapaxes(-1, -2) + K @ R @ K.swapaxes(-1, -2)
    return (K @ v[..., None])[..., 0], 0.5 * (P + P.swapaxes(-1, -2)), v, S, K


def compensated_rows(dtheta, dvel, gyro_bias, accel_bias, dt):
    """(dtheta_c, dvel_c, body rate, specific force) of every run (B, 3 each):
    :func:`compensate_rows` into new arrays."""
    out = np.empty((4, len(dtheta), 3))      # one allocation: four C-contiguous blocks
    compensate_rows(dtheta, dvel, gyro_bias, accel_bias, float(dt), out[0], out[1], out[2],
                    out[3])
    return out[0], out[1], out[2], out[3]


@kernel
def compensate_rows(dtheta, dvel, gyro_bias, accel_bias, dt, dtheta_c, dvel_c, rate_ib,
                    f_body):
    """The bias-compensated increments of every run (B, 3 each) over one interval ``dt``:
    ``dtheta_c = dtheta - gyro_bias dt``, ``dvel_c = dvel - accel_bias dt``, the body rate
    ``dtheta_c / dt`` and the specific force ``dvel_c / dt``."""
    for b in range(dtheta.shape[0]):
        for i in range(3):
            theta = dtheta[b, i] - gyro_bias[b, i] * dt
            vel = dvel[b, i] - accel_bias[b, i] * dt
            dtheta_c[b, i], dvel_c[b, i] = theta, vel
            rate_ib[b, i], f_body[b, i] = theta / dt, vel / dt


@kernel
def add_noise_rows(q_acc, q_density, dt):
    """``Q_acc += diag(q_density dt)`` for every run (B, 15, 15), in place."""
    for b in range(q_acc.shape[0]):
        for i in range(q_acc.shape[1]):
            q_acc[b, i, i] += q_density[b, i] * dt


def _initial_bias(value):
    """A configured initial bias as a fresh (3,) float array (zeros for None)."""
    return np.zeros(3) if value is None else np.array(value, dtype=float).reshape(3)


class KfEngine:
    """The baseline 15-state Kalman filter (``Kf``); see the module docstring."""

    state_fields = ("nav", "P", "gyro_bias", "accel_bias", "phi_acc", "q_acc", "n_updates",
                    "last", "rate_ib", "aids")
    derived_fields = ("config", "q_density", "R0", "m", "H")

    def __init__(self, config: KfConfig, nav: Strapdown):
        self.config = config
        self.nav = nav
        self.P = np.diag(np.asarray(config.p0, dtype=float) ** 2)
        self.q_density = process_noise_density(
            config.gyro_arw, config.accel_vrw, config.gyro_bias_sigma, config.gyro_bias_tau,
            config.accel_bias_sigma, config.accel_bias_tau)
        self.R0 = np.diag(np.asarray(config.r_sigma, dtype=float) ** 2)
        self.m = MEASUREMENTS[config.measurement]
        self.H = np.zeros((self.m, N_STATES))
        self.H[:, :self.m] = np.eye(self.m)
        self.gyro_bias = _initial_bias(config.gyro_bias0)
        self.accel_bias = _initial_bias(config.accel_bias0)
        self.phi_acc = np.eye(N_STATES)
        self.q_acc = np.zeros((N_STATES, N_STATES))
        self.n_updates = 0
        self.last = None  # UpdateResult of the latest update
        self.rate_ib = np.zeros(3)  # body rate of the latest interval (lever-arm velocity)
        self.aids = None  # the land aids (navcore.filters.land_aids), set by the component

    @property
    def p0_var(self):
        """The initial variances of the error state (15,): the ceiling of the recovery
        guards' inflation of attitude and biases (navcore.filters.recovery)."""
        return np.asarray(self.config.p0, dtype=float) ** 2

    # -- time update -------------------------------------------------------------------
    def propagate(self, dtheta, dvel, dt):
        """Mechanize one IMU interval with bias-compensated increments and propagate P
        (:func:`propagate_rows` of this run), then :meth:`advance_clocks`."""
        cfg = self.config
        nav = self.nav
        mechanize = None if type(nav).update is Strapdown.update else (
            lambda dtheta_c, dvel_c: nav.update(dtheta_c[0], dvel_c[0], dt))
        phi_acc, q_acc, rate_ib = propagate_rows(
            nav.rows, self.gyro_bias.reshape(1, 3), self.accel_bias.reshape(1, 3),
            self.phi_acc[None], self.q_acc[None], self.q_density[None],
            np.reshape(dtheta, (1, 3)), np.reshape(dvel, (1, 3)), dt,
            transition_template(dt, cfg.gyro_bias_tau, cfg.accel_bias_tau), mechanize)
        self.phi_acc, self.q_acc, self.rate_ib = phi_acc[0], q_acc[0], rate_ib[0]
        self.advance_clocks(dt)

    def advance_clocks(self, dt):
        """What else an IMU interval of ``dt`` advances (:meth:`advance_clocks_over`)."""
        self.advance_clocks_over((dt,))

    def advance_clocks_over(self, dts):
        """What else the IMU intervals ``dts`` advance, one after the other (a subclass's
        time counters): pure sums of the intervals, so a batch may add them later, in the
        same order and in one call."""

    def predicted_parts(self):
        """(Phi_acc P_{k-1} Phi_acc', Q_acc): the two parts of P_{k,k-1}
        (:func:`predicted_rows` of this run)."""
        return predicted_rows(self.P, self.phi_acc), self.q_acc

    def close_prediction(self, P_pred):
        """Adopt ``P_pred`` as the covariance and restart the accumulators."""
        self.P = 0.5 * (P_pred + P_pred.T)
        self.phi_acc = _IDENTITY.copy()
        self.q_acc = np.zeros((N_STATES, N_STATES))

    def covariance_diagonal(self):
        """Diagonal of the current covariance, cheaply (one product per call)."""
        a = self.phi_acc
        return np.einsum("ij,ij->i", a @ self.P, a) + np.diagonal(self.q_acc)

    def covariance(self):
        """Current covariance of the error state (P_{k,k-1} between updates)."""
        p_prop, q_acc = self.predicted_parts()
        return p_prop + q_acc

    def predicted_innovation(self, R=None):
        """(P_{k,k-1}, S): the unfaded prediction (paper 001 eq. 6) and the innovation covariance
        ``S = H P_{k,k-1} H' + R`` (``R`` defaults to the fixed R0).  H selects the first m
        states, so H P H' is the leading m x m block."""
        P_pred = self.covariance()
        return P_pred, P_pred[:self.m, :self.m] + (self.R0 if R is None else R)

    # -- measurement -------------------------------------------------------------------
    def measurement(self, fix_lat, fix_lon, fix_h, fix_v_ned, age):
        """z = INS - GNSS in NED metres (and m/s); the INS position is taken back to the fix
        time ``age`` seconds ago with its velocity (first order), and carried to the antenna
        with the configured lever arm (:mod:`navcore.filters.lever_arm`)."""
        nav = self.nav
        rn, re = earth.radii(nav.lat)
        v = nav.v_ned
        z = np.empty(self.m)
        z[0] = (nav.lat - fix_lat) * (rn + nav.h) - v[0] * age
        z[1] = (nav.lon - fix_lon) * (re + nav.h) * np.cos(nav.lat) - v[1] * age
        z[2] = -(nav.h - fix_h) - v[2] * age
        if self.m == 6:
            z[3:6] = v - fix_v_ned
        lever = self.config.lever_arm
        if lever is not None:
            z[:3] += antenna_position_offset(nav.C_bn, lever)
            if self.m == 6:
                z[3:6] += antenna_velocity_offset(nav.C_bn, lever, self.rate_ib, nav.lat)
        return z

    def kalman_update(self, P_pred, z, R):
        """Standard update (paper 001 eqs. 4, 5, 7, 8; Joseph form): :func:`kalman_rows` of
        this run.  Returns (dx, P, v, S, K)."""
        return kalman_rows(P_pred, np.asarray(z), R, self.H)

    def update(self, z):
        """Baseline update with the fixed R; returns an :class:`UpdateResult`."""
        p_prop, q_acc = self.predicted_parts()
        P_pred = p_prop + q_acc
        dx, P, v, S, _ = self.kalman_update(P_pred, z, self.R0)
        return self.updated(dx, P, v, S)

    def updated(self, dx, P, v, S):
        """:meth:`update` after its arithmetic (the correction ``dx`` and covariance ``P``
        of the innovation ``v`` with covariance ``S``): the feedback, and the result."""
        self.apply(dx, P)
        return UpdateResult(v, S, nis(v, S))

    def aid_update(self, H, z, R):
        """A land aid's pseudo-measurement ``z = H x`` (:mod:`navcore.filters.land_aids`): the
        plain Kalman update and feedback, whatever the engine's own law for the fixes."""
        dx, P = linear_update(np.zeros(N_STATES), self.covariance(), z, H, R)
        self.apply(dx, P)
        self.aid_applied(dx)

    def aid_applied(self, dx):
        """After :meth:`aid_update` fed back ``dx``: what a law keeps of past innovations
        follows the corrected INS (a subclass's bookkeeping; nothing here)."""

    def apply(self, dx, P):
        """Closed-loop feedback of the estimated errors and reset of the accumulators."""
        self.nav.correct(dx[POS], dx[VEL], dx[ATT])
        self.gyro_bias = self.gyro_bias + dx[BG]
        self.accel_bias = self.accel_bias + dx[BA]
        self.close_prediction(P)
        self.n_updates += 1

