"""Attitude (AHRS) unscented filters of paper 003 (Xiao & Lu): MRP state, gravity and
magnetic-field vector measurements, optional fuzzy adaptation of R.

State (paper 003 eq. 23, whose body is lost in our copy; the MRP attitude of Crassidis &
Markley 2003, "Unscented filtering for spacecraft attitude estimation", J. Guidance 26(4),
plus the gyro bias they estimate with it)::

    x = [sigma (3), b_g (3)]      sigma: MRP of C_bn (navcore.ins.mrp), b_g: gyro bias [rad/s]

The gyro bias is estimated because a MEMS gyro's turn-on bias (tens of deg/h) integrates to
degrees of heading within the paper's 240 s, and because gravity plus the magnetic field make
the full attitude, hence all three bias components, observable at rest.  The earth rate the
gyros sense (7.3e-5 rad/s at most) is not modelled: on a table at rest it is a constant body
rate and ends in the bias estimate.

Time update, over the interval since the previous update with the gyro increments
``dtheta_k`` accumulated as ``dq = prod_k q(dtheta_k)`` (body frame)::

    q(sigma+) = q(sigma) (x) dq (x) q(-b_g T),    b_g+ = b_g

(first order in ``b_g T``; exact for a constant body rate), evaluated on every sigma point,
points continued in the MRP set nearest the prior mean (:func:`navcore.ins.mrp.nearer_set`).
Process noise: the gyro angle random walk ``N_g`` maps through the MRP kinematics
``d sigma / dt = B omega / 4`` with ``B B^T = (1 + s)^2 I`` (Schaub & Junkins eq. 3.163),
so ``Q_sigma = N_g^2 T (1 + s)^2 / 16 I``; the bias walks with ``Q_b = N_b^2 T I``.

Measurement (paper 003 eq. 24)::

    z = [f_b, m_b / H] = [C_bn^T (0, 0, -g), C_bn^T (H cos I, 0, H sin I) / H] + v

with ``f_b`` the accelerometer's specific force (at rest: minus gravity) and the magnetometer
reading scaled by the field intensity ``H`` (so both blocks are of order 1).
``R = diag(r_a^2 I_3, (r_m / H)^2 I_3)``.  After each step the MRP switches to its shadow
when ``|sigma| > 1`` and the covariance follows (:func:`navcore.ins.mrp.shadow_jacobian`).

Fuzzy adaptive R (paper 003 eqs. 15-19, 25): see :class:`FuzzyAdaptiveR`.
"""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np

from ..core.kernels import jitable, kernel
from ..core.python_math import hypot
from ..errors import InputError
from .fuzzy import FuzzyRScale
from ..ins.mrp import (dcm_to_mrp, mrp_of_quat, mrp_to_dcm_batch, nearer_set,
                       quat_of_mrp, shadow, shadow_jacobian)
from ..ins.rotations import wrap_angle
from .unscented import UnscentedKalmanFilter

#: measurement dimension: accelerometer 3 + magnetometer 3
MEASUREMENT_DIM = 6


def triad_attitude(f_b, m_b, inclination):
    """C_bn from one specific-force and one magnetometer sample at rest (TRIAD with gravity as
    the first vector: Shuster & Oh 1981, J. Guidance 4(1)); the field model has no
    declination, so north is magnetic north."""
    f_b = np.asarray(f_b, dtype=float)
    m_b = np.asarray(m_b, dtype=float)
    down = -f_b / np.linalg.norm(f_b)
    east = np.cross(down, m_b)
    n_east = np.linalg.norm(east)
    if not (np.linalg.norm(f_b) > 0 and n_east > 0):
        raise InputError("AHRS initialization: accelerometer and magnetometer vectors are "
                         "zero or parallel")
    east /= n_east
    north = np.cross(east, down)
    return np.vstack((north, east, down))     # rows: the NED axes in body coordinates


@jitable
def _qmul(p, q):
    """Hamilton product of two quaternions given as float tuples (one IMU sample's work:
    plain floats cost less than numpy for 4 numbers)."""
    w1, x1, y1, z1 = p
    w2, x2, y2, z2 = q
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


@jitable
def _rotvec_quat(x, y, z):
    """Quaternion of the rotation vector (x, y, z) as a float tuple."""
    t = math.sqrt(x * x + y * y + z * z)
    s = math.sin(0.5 * t) / t if t > 1e-6 else 0.5 - t * t / 48.0
    return (math.cos(0.5 * t), s * x, s * y, s * z)


@kernel
def accumulate_rows(rows, imu_time, dt, dtheta, mag_time, nav_time, dq, interval, last_update,
                    update_interval, max_mag_age, due):
    """What :meth:`AhrsFilter.step` does on a new IMU interval, for the batch rows ``rows``
    (their inputs ``imu_time``, ``dt``, ``dtheta`` (k, 3), ``mag_time``: row i of each is
    run ``rows[i]``'s): the interval's end into ``nav_time``, the gyro increment into the
    pending quaternion ``dq`` (B, 4) and ``interval`` (:meth:`UkfAhrsEngine.accumulate`), and
    into ``due[i]`` whether the run's measurement update is due with a fresh magnetometer
    sample (its ``update_interval`` and ``max_mag_age``, since its ``last_update``)."""
    for i in range(rows.shape[0]):
        b = rows[i]
        t = imu_time[i]
        nav_time[b] = t
        q = _qmul((dq[b, 0], dq[b, 1], dq[b, 2], dq[b, 3]),
                  _rotvec_quat(dtheta[i, 0], dtheta[i, 1], dtheta[i, 2]))
        dq[b, 0], dq[b, 1], dq[b, 2], dq[b, 3] = q
        interval[b] += dt[i]
        due[i] = (abs(mag_time[i] - t) <= max_mag_age[b] + 1e-9
                  and t - last_update[b] >= update_interval[b] - 1e-9)


@jitable
def _state_quat(x0, x1, x2, x3, x4, x5, T, dq):
    """:meth:`UkfAhrsEngine.current_quat` of the state ``x0 .. x5`` (MRP, gyro bias), the
    pending interval ``T`` and its gyro quaternion ``dq`` (a float tuple)."""
    q = quat_of_mrp(x0, x1, x2)
    if T <= 0.0:
        return q
    return _qmul(_qmul(q, dq), _rotvec_quat(-x3 * T, -x4 * T, -x5 * T))


@jitable
def _euler(w, x, y, z):
    """ZYX Euler angles (roll, pitch, yaw) of the C_bn of quaternion (w, x, y, z) (Groves
    eq. 2.38 via eq. 2.34), normalised first, yaw folded into (-pi, pi] (Python's ``hypot``
    in kernels too: a C one rounds otherwise)."""
    n = w * w + x * x + y * y + z * z
    a = 2.0 * (w * x + y * z)
    b = n - 2.0 * (x * x + y * y)
    yaw = math.atan2(2.0 * (w * z + x * y), n - 2.0 * (y * y + z * z))
    return (math.atan2(a, b), math.atan2(2.0 * (w * y - z * x), hypot(a, b)),
            math.pi if yaw <= -math.pi else yaw)


def quat_euler(q):
    """ZYX Euler angles (roll, pitch, yaw) of the C_bn of quaternion ``q`` (a 4-sequence of
    floats), yaw in (-pi, pi]."""
    return _euler(*q)


@kernel
def solution_rows(out, rows, x, interval, dq, nav_time, r_scale, columns):
    """:meth:`AhrsFilter._write_solution` without the sigmas for the batch rows ``rows``
    (the state ``x`` (B, 6), pending ``interval`` (B,) and ``dq`` (B, 4), ``nav_time``
    (B,), ``r_scale`` (B, 2)) into the rows of ``out``: ``columns`` of nav_time, aligned,
    nav_roll, nav_pitch, nav_yaw, nav_bg_x/y/z, r_scale_accel, r_scale_mag."""
    for i in range(rows.shape[0]):
        b = rows[i]
        r = x[b]
        q = _state_quat(r[0], r[1], r[2], r[3], r[4], r[5], interval[b],
                        (dq[b, 0], dq[b, 1], dq[b, 2], dq[b, 3]))
        o = out[b]
        o[columns[0]] = nav_time[b]
        o[columns[1]] = 1.0
        o[columns[2]], o[columns[3]], o[columns[4]] = _euler(q[0], q[1], q[2], q[3])
        o[columns[5]], o[columns[6]], o[columns[7]] = r[3], r[4], r[5]
        o[columns[8]], o[columns[9]] = r_scale[b, 0], r_scale[b, 1]


@kernel
def _propagate_rows(X, dq, T, out):
    """:func:`propagate_points` of B filters: points ``X`` (B, P, 6), gyro quaternions
    ``dq`` (B, 4), intervals ``T`` (B,), into ``out`` (B, P, 6); each filter's points
    continued in the MRP set nearest its point 0."""
    for b in range(X.shape[0]):
        d = (dq[b, 0], dq[b, 1], dq[b, 2], dq[b, 3])
        t = T[b]
        rx, ry, rz = X[b, 0, 0], X[b, 0, 1], X[b, 0, 2]
        for i in range(X.shape[1]):
            x = X[b, i]
            q = _qmul(_qmul(quat_of_mrp(x[0], x[1], x[2]), d),
                      _rotvec_quat(-x[3] * t, -x[4] * t, -x[5] * t))
            m = mrp_of_quat(q[0], q[1], q[2], q[3])
            o = out[b, i]
            o[0], o[1], o[2] = nearer_set(m[0], m[1], m[2], rx, ry, rz)
            o[3], o[4], o[5] = x[3], x[4], x[5]


def propagate_points(X, dq, T):
    """The time update of the module docstring on the sigma points ``X`` (B, P, 6) of B
    filters, with their gyro quaternions ``dq`` (B, 4) and intervals ``T`` (B,): (B, P, 6),
    each filter's points continued in the MRP set nearest its point 0 (its prior mean)."""
    out = np.empty(X.shape)
    _propagate_rows(np.ascontiguousarray(X, dtype=float), np.ascontiguousarray(dq, dtype=float),
                    np.ascontiguousarray(T, dtype=float), out)
    return out


def measure_points(X, gravity, field_unit):
    """Paper 003 eq. 24 on sigma points ``X`` (N, 6): (N, 6) rows ``[f_b, m_b / H]``."""
    C = mrp_to_dcm_batch(X[:, :3])                   # C_bn per point
    f = -gravity * C[:, 2, :]                         # C_bn^T (0, 0, -g)
    m = C.transpose(0, 2, 1) @ field_unit              # C_bn^T m_n / H
    return np.concatenate((f, m), axis=1)


def process_noise_diagonal(s, T, gyro_arw, gyro_bias_rw):
    """The diagonal of Q of one time update over ``T`` as ``(q_att, q_bias)`` (module
    docstring), ``s`` the squared norm of the MRP."""
    return gyro_arw ** 2 * T * (1.0 + s) ** 2 / 16.0, gyro_bias_rw ** 2 * T


def attitude_process_noise(x, T, gyro_arw, gyro_bias_rw):
    """Q of one time update over ``T`` from the state ``x`` (module docstring)."""
    q_att, q_bias = process_noise_diagonal(float(x[:3] @ x[:3]), T, gyro_arw, gyro_bias_rw)
    return np.diag([q_att] * 3 + [q_bias] * 3)


def shadow_switched(x, P):
    """``(x, P)`` with the MRP switched to its shadow and P through the Jacobian when
    ``|sigma| > 1``; None when the MRP stays."""
    sigma = x[:3]
    if float(sigma @ sigma) <= 1.0:
        return None
    J = np.eye(6)
    J[:3, :3] = shadow_jacobian(sigma)
    P = J @ P @ J.T
    return np.concatenate((shadow(sigma), x[3:])), 0.5 * (P + P.T)


@kernel
def _mrp_euler_rows(X, out):
    """:func:`quat_euler` of the quaternion of the MRP of every point of ``X`` (B, P, >= 3)
    into ``out`` (B, P, 3)."""
    for b in range(X.shape[0]):
        for i in range(X.shape[1]):
            w, x, y, z = quat_of_mrp(X[b, i, 0], X[b, i, 1], X[b, i, 2])
            out[b, i, 0], out[b, i, 1], out[b, i, 2] = _euler(w, x, y, z)


def euler_sigma_rows(X, Wm, Wc):
    """1-sigma of roll, pitch, yaw (B, 3) from the sigma points ``X`` (B, 13, 6) of B
    filters (weights ``Wm``, ``Wc``): the angles of every point (:func:`quat_euler`),
    wrapped about the central point's."""
    # C order: the stacked products below round by the layout of their operands
    angles = np.empty(X.shape[:2] + (3,))
    _mrp_euler_rows(np.ascontiguousarray(X, dtype=float), angles)
    dev = wrap_angle(angles - angles[:, :1])
    mean = Wm @ dev
    dev = dev - mean[:, None, :]
    return np.sqrt(np.maximum(Wc @ (dev * dev), 0.0))


class UkfAhrsEngine:
    """The UKF of the module docstring.

    Parameters: ``gravity`` [m/s^2], ``field_intensity`` H [T], ``inclination`` I [rad],
    ``gyro_arw`` [rad/sqrt(s)], ``gyro_bias_rw`` [rad/s/sqrt(s)], ``r_accel`` [m/s^2],
    ``r_mag`` [T] (1-sigma per axis), ``p0_att`` [rad], ``p0_gyro_bias`` [rad/s],
    ``alpha``, ``beta``, ``kappa`` (scaled UT), ``adaptive``: a :class:`FuzzyAdaptiveR` or
    None.  The filter starts when :meth:`start` gets the initial attitude.
    """

    state_fields = ("ukf", "r_scale", "adaptive", "started", "dq", "interval", "last_nis",
                    "shadow_switches")
    derived_fields = ("gravity", "field_intensity", "field_unit", "inclination", "gyro_arw",
                      "gyro_bias_rw", "R0", "p0")

    def __init__(self, gravity, field_intensity, inclination, gyro_arw, gyro_bias_rw, r_accel,
                 r_mag, p0_att, p0_gyro_bias, alpha, beta, kappa,
                 adaptive: Optional["FuzzyAdaptiveR"] = None):
        self.gravity = float(gravity)
        self.field_intensity = float(field_intensity)
        self.field_unit = np.array([math.cos(inclination), 0.0, math.sin(inclination)])
        self.inclination = float(inclination)
        self.gyro_arw = float(gyro_arw)
        self.gyro_bias_rw = float(gyro_bias_rw)
        self.R0 = np.diag([r_accel ** 2] * 3 + [(r_mag / field_intensity) ** 2] * 3)
        self.r_scale = np.ones(2)          # accelerometer, magnetometer block factors
        self.p0 = np.array([p0_att / 4.0] * 3 + [p0_gyro_bias] * 3) ** 2
        self.ukf = UnscentedKalmanFilter(6, alpha, beta, kappa)
        self.adaptive = adaptive
        self.started = False
        self.dq = (1.0, 0.0, 0.0, 0.0)
        self.interval = 0.0
        self.last_nis = 0.0
        self.shadow_switches = 0

    # -- life cycle ------------------------------------------------------------------------
    def start(self, C_bn):
        self.ukf.x = np.concatenate((dcm_to_mrp(C_bn), np.zeros(3)))
        self.ukf.P = np.diag(self.p0)
        self.started = True

    def accumulate(self, dtheta, dt):
        """Add one gyro increment [rad] over ``dt`` [s] to the pending time update."""
        x, y, z = dtheta
        self.dq = _qmul(self.dq, _rotvec_quat(float(x), float(y), float(z)))
        self.interval += dt

    def _switch_to_shadow(self):
        switched = shadow_switched(self.ukf.x, self.ukf.P)
        if switched is not None:
            self.ukf.x, self.ukf.P = switched
            self.shadow_switches += 1

    def _process(self, X, dq, T):
        return propagate_points(X[None], np.asarray(dq)[None], np.array([T]))[0]

    def predict(self):
        """UKF time update over the accumulated interval (nothing if it is empty)."""
        T = self.interval
        if T <= 0.0:
            return
        Q = attitude_process_noise(self.ukf.x, T, self.gyro_arw, self.gyro_bias_rw)
        self.ukf.predict(self._process, Q, np.array(self.dq), T, vectorized=True)
        self.dq = (1.0, 0.0, 0.0, 0.0)
        self.interval = 0.0
        self._switch_to_shadow()

    def _measure(self, X):
        return measure_points(X, self.gravity, self.field_unit)

    def update(self, f_b, m_b):
        """Time update to now, then the measurement update with specific force ``f_b``
        [m/s^2] and magnetometer ``m_b`` [T]; returns the innovation."""
        self.predict()
        z = np.concatenate((np.asarray(f_b, float), np.asarray(m_b, float) / self.field_intensity))
        prediction = self.ukf.predict_measurement(self._measure, vectorized=True)
        if self.adaptive is not None:
            self.r_scale = self.adaptive.step(z - prediction.z_pred, prediction.Pzz,
                                              self.R0, self.r_scale)
        R = self.R0 * np.repeat(self.r_scale, 3)[:, None]
        result = self.ukf.correct(z, prediction, R)
        self.last_nis = result["nis"]
        self._switch_to_shadow()
        return result["innovation"]

    # -- outputs ---------------------------------------------------------------------------
    def current_quat(self):
        """Quaternion of the attitude now: the state composed with the pending gyro
        increments and the bias over them (as the next time update will do)."""
        return _state_quat(*self.ukf.x.tolist(), self.interval, self.dq)

    def euler(self):
        """(roll, pitch, yaw) now (paper 003 eq. 26, via the quaternion)."""
        return quat_euler(self.current_quat())

    def euler_sigma(self):
        """1-sigma of roll, pitch, yaw from the sigma points of the MRP block."""
        return euler_sigma_rows(self.ukf.sigma_points()[None], self.ukf.Wm, self.ukf.Wc)[0]

    @property
    def gyro_bias(self):
        return self.ukf.x[3:]


class FuzzyAdaptiveR:
    """Fuzzy adaptation of R, paper 003 eqs. 15-19 and 25.

    At every update ``k`` with innovation ``r_k = z_k - h(x_k|k-1)`` (paper 003 eq. 18):

    * ``C_z = 1/N sum_{i=k-N+1..k} r_i r_i^T`` (paper 003 eq. 17, window ``N``),
      ``P_z = Pzz + R_(k-1)`` (paper 003 eq. 16, the UKF's innovation covariance),
      ``E_k = C_z - P_z`` (paper 003 eq. 19);
    * per block b (accelerometer, magnetometer; paper 003 eq. 25): ``e = tr E_k,b / tr P_z,b``
      and ``de = e_k - e_(k-1)`` go through :class:`~navcore.filters.fuzzy.FuzzyRScale` to ``F_b``;
    * ``R_k,b = F_b R_(k-1),b`` (paper 003 eq. 15), the scale kept within
      ``[r_scale_min, r_scale_max]`` times the nominal R, and used in this update.

    Until ``N`` innovations exist, ``F = 1``.  ``window`` >= 2 (the component's parameter
    ``fuzzy_window`` declares the range).
    """

    state_fields = ("residuals", "count", "e", "de")
    derived_fields = ("inference", "blocks", "window", "r_scale_min", "r_scale_max")

    def __init__(self, inference: FuzzyRScale, window: int, r_scale_min: float,
                 r_scale_max: float):
        self.inference = inference
        self.blocks = inference.stacked(2)        # the inference of both blocks at once
        self.window = int(window)
        self.r_scale_min = float(r_scale_min)
        self.r_scale_max = float(r_scale_max)
        self.residuals = np.zeros((self.window, MEASUREMENT_DIM))
        self.count = 0
        self.e = np.zeros(2)
        self.de = np.zeros(2)

    def windows(self) -> "FuzzyWindows":
        """This adaptation as the one row of a :class:`FuzzyWindows`, whose arrays but the
        count are views of its own."""
        return FuzzyWindows(self.residuals[None], np.array([self.count]), self.e[None],
                            self.de[None], np.array([self.window]),
                            np.array([self.r_scale_min]), np.array([self.r_scale_max]))

    def step(self, innovation, Pzz, R0, r_scale):
        """New block scales after the innovation ``innovation`` (see the class docstring);
        ``r_scale`` itself until the window is full."""
        windows = self.windows()
        new, adapted = adapt_r_scales(windows, np.zeros(1, dtype=np.intp), self.blocks,
                                      np.asarray(innovation)[None], np.asarray(Pzz)[None],
                                      np.asarray(R0)[None],
                                      np.asarray(r_scale, dtype=float)[None])
        self.count = int(windows.count[0])
        return new[0] if adapted[0] else r_scale


class FuzzyWindows(NamedTuple):
    """The state and limits of n :class:`FuzzyAdaptiveR` as rows: innovation windows
    ``residuals`` (n, W, 6; filter i's first ``window[i]`` rows), ``count`` (n,), ``e`` and
    ``de`` (n, 2), the scale limits ``low`` and ``high`` (n,)."""

    residuals: np.ndarray
    count: np.ndarray
    e: np.ndarray
    de: np.ndarray
    window: np.ndarray
    low: np.ndarray
    high: np.ndarray


def adapt_r_scales(windows: FuzzyWindows, runs, blocks, innovations, Pzz, R0, r_scales):
    """:meth:`FuzzyAdaptiveR.step` of the adaptations of rows ``runs`` (n) of ``windows``
    at once (their rows changed in place), with their innovations (n, 6), ``Pzz`` and ``R0``
    (n, 6, 6) and scales (n, 2); ``blocks`` the :class:`~navcore.filters.fuzzy.
    StackedInference` of their 2n blocks (filter i's accelerometer then magnetometer).
    Returns the new scales (n, 2) and which filters adapted them (n bools: their window is
    full); the others' rows are their scales.  Each filter's floats are those of its step
    alone (numpy's reductions over the window and over a block's 3 values add in the same
    order stacked)."""
    window = windows.window[runs]
    windows.residuals[runs, windows.count[runs] % window] = innovations
    windows.count[runs] += 1
    count = windows.count[runs]
    adapted = count >= window
    new = np.array(r_scales, dtype=float)
    if not adapted.any():
        return new, adapted
    if adapted.all():
        rows, scales = slice(None), new
    else:
        rows = adapted.nonzero()[0]
        scales = new[rows]
        Pzz, R0 = Pzz[rows], R0[rows]
        blocks = blocks.rows(np.repeat(2 * rows, 2) + np.tile([0, 1], len(rows)))
    ready, window, count = runs[rows], window[rows], count[rows]
    Pz = (np.diagonal(Pzz, axis1=1, axis2=2)
          + np.diagonal(R0, axis1=1, axis2=2) * np.repeat(scales, 3, axis=1))
    residuals = windows.residuals[ready]
    if (window == window[0]).all():
        residuals = residuals[:, :window[0]]
        Cz = np.mean(residuals * residuals, axis=1)
    else:
        Cz = np.array([np.mean(r[:w] * r[:w], axis=0)
                       for r, w in zip(residuals, window.tolist())])
    Pz_sum = Pz.reshape(-1, 2, 3).sum(axis=2)
    e_new = (Cz.reshape(-1, 2, 3).sum(axis=2) - Pz_sum) / Pz_sum
    de = np.where((count > window)[:, None], e_new - windows.e[ready], 0.0)
    windows.e[ready], windows.de[ready] = e_new, de
    factors = blocks(e_new.reshape(-1), de.reshape(-1)).reshape(-1, 2)
    new[rows] = np.minimum(np.maximum(scales * factors, windows.low[ready][:, None]),
                           windows.high[ready][:, None])
    return new, adapted
