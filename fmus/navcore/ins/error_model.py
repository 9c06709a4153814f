"""15-state INS error model in NED for loosely coupled INS/GNSS filters.

State vector (all filters of the INS/GNSS family use this order and these units)::

    x = [dr_n, dr_e, dr_d,      position error, computed - true, NED          [m]
         dv_n, dv_e, dv_d,      velocity error, computed - true               [m/s]
         phi_n, phi_e, phi_d,   attitude error, C_bn_comp = (I - [phi x]) C_bn_true  [rad]
         dbg_x, dbg_y, dbg_z,   gyro bias still to add to the estimate        [rad/s]
         dba_x, dba_y, dba_z]   accel bias still to add to the estimate       [m/s^2]

so the compensated gyro rate is off by ``-dbg`` ... precisely: with ``b_true = b_est + dbg`` the
computed angular rate exceeds the true one by ``dbg`` and the computed specific force by
``dba``.  This is the phi-angle error model of Titterton & Weston (ch. 12) / Qin Yongyuan
(ch. 7, the model behind paper 001's eq. 1), with position in metres::

    d(dr)/dt  = dv                                         (transport-rate coupling neglected)
    d(dv)/dt  = [f^n x] phi + C_bn dba - (2 w_ie + w_en) x dv + (2 g / R) dr_d e_d
    d(phi)/dt = -w_in x phi + d(w_in) - C_bn dbg
    d(dbg)/dt = -dbg / tau_g + w_bg,    d(dba)/dt = -dba / tau_a + w_ba  (random constant if tau =
    0)

with ``d(w_in)`` the change of the navigation-frame rate caused by the velocity and latitude
errors.  White gyro and accelerometer noise (ARW, VRW) enter phi and dv.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..core.kernels import jitable, kernel
from . import earth, strapdown

N_STATES = 15
POS, VEL, ATT, BG, BA = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15))


#: flat indices (row * N_STATES + column) of the entries of F that change with the state, in
#: the order :func:`_state_entries` returns them
_STATE_ENTRIES = np.array([
    # [f^n x] phi                     C_bn dba
    3 * 15 + 7, 3 * 15 + 8, 4 * 15 + 6, 4 * 15 + 8, 5 * 15 + 6, 5 * 15 + 7,
    3 * 15 + 12, 3 * 15 + 13, 3 * 15 + 14, 4 * 15 + 12, 4 * 15 + 13, 4 * 15 + 14,
    5 * 15 + 12, 5 * 15 + 13, 5 * 15 + 14,
    # -(2 w_ie + w_en) x dv, then (2 g / R) dr_d
    3 * 15 + 4, 3 * 15 + 5, 4 * 15 + 3, 4 * 15 + 5, 5 * 15 + 3, 5 * 15 + 4, 5 * 15 + 2,
    # -w_in x phi, d(w_en)/d(dv), d(w_ie)/d(lat)
    6 * 15 + 7, 6 * 15 + 8, 7 * 15 + 6, 7 * 15 + 8, 8 * 15 + 6, 8 * 15 + 7,
    6 * 15 + 4, 7 * 15 + 3, 8 * 15 + 4, 6 * 15 + 0, 8 * 15 + 0,
    # -C_bn dbg
    6 * 15 + 9, 6 * 15 + 10, 6 * 15 + 11, 7 * 15 + 9, 7 * 15 + 10, 7 * 15 + 11,
    8 * 15 + 9, 8 * 15 + 10, 8 * 15 + 11,
], dtype=np.intp)
#: d(dr)/dt = dv
_UNIT_ENTRIES = np.array([0 * 15 + 3, 1 * 15 + 4, 2 * 15 + 5], dtype=np.intp)
_DIAGONAL = np.arange(N_STATES) * (N_STATES + 1)


@jitable
def _state_entries(lat, h, v_ned, C_bn, f_ned):
    """The entries of F at :data:`_STATE_ENTRIES` as Python floats (the model of the module
    docstring; radii and gravity as :func:`navcore.ins.earth.radii` /
    :func:`~navcore.ins.earth.gravity`
    compute them, with the same expressions)."""
    sl, cl = math.sin(lat), math.cos(lat)
    s2 = sl * sl      # not ** 2: CPython's pow and a compiled x ** 2 (x * x) round apart
    w = 1.0 - earth.E2 * s2
    rn = earth.A * (1.0 - earth.E2) / w ** 1.5
    re = earth.A / math.sqrt(w)
    g0 = earth.GAMMA_E * (1.0 + earth.SOMIGLIANA_K * s2) / math.sqrt(1.0 - earth.E2 * s2)
    g = g0 * (1.0 - 2.0 / earth.A * (1.0 + earth.F + earth.GRAVITY_M - 2.0 * earth.F * s2) * h
              + 3.0 * (h * h) / (earth.A * earth.A))
    rn_h, re_h = rn + h, re + h
    tl = sl / cl
    vn, ve = v_ned[0], v_ned[1]
    om = earth.OMEGA_IE
    wie_n, wie_d = om * cl, -om * sl
    wen_n, wen_e, wen_d = ve / re_h, -vn / rn_h, -ve * tl / re_h
    win_n, win_e, win_d = wie_n + wen_n, 0.0 + wen_e, wie_d + wen_d
    wc_n, wc_e, wc_d = 2 * wie_n + wen_n, 2 * 0.0 + wen_e, 2 * wie_d + wen_d
    f0, f1, f2 = f_ned[0], f_ned[1], f_ned[2]
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = (C_bn[0], C_bn[1], C_bn[2], C_bn[3], C_bn[4],
                                                   C_bn[5], C_bn[6], C_bn[7], C_bn[8])
    return (
        -f2, f1, f2, -f0, -f1, f0,
        c00, c01, c02, c10, c11, c12, c20, c21, c22,
        wc_d, -wc_e, -wc_d, wc_n, wc_e, -wc_n, 2.0 * g / math.sqrt(rn * re),
        win_d, -win_e, -win_d, win_n, win_e, -win_n,
        1.0 / re_h, -1.0 / rn_h, -tl / re_h, -om * sl / rn_h, -om * cl / rn_h,
        -c00, -c01, -c02, -c10, -c11, -c12, -c20, -c21, -c22,
    )


def _bias_entries(tau_g, tau_a):
    """(flat indices, values) of the Gauss-Markov diagonal of F (none for random constants)."""
    index, values = [], []
    for first, tau in ((9, tau_g), (12, tau_a)):
        if tau > 0:
            index += [int(_DIAGONAL[i]) for i in range(first, first + 3)]
            values += [-1.0 / tau] * 3
    return index, values


def system_matrix(lat, h, v_ned, C_bn, f_ned, tau_g=0.0, tau_a=0.0):
    """Continuous-time error dynamics matrix F (15x15) of the model in the module docstring.

    ``f_ned`` is the specific force resolved in NED [m/s^2]; ``tau_g``/``tau_a`` are the
    Gauss-Markov correlation times of the bias errors [s] (0 = random constant).
    """
    F = np.zeros(N_STATES * N_STATES)
    F[_UNIT_ENTRIES] = 1.0
    F[_STATE_ENTRIES] = _state_entries(float(lat), float(h), np.asarray(v_ned).tolist(),
                                       np.asarray(C_bn).ravel().tolist(),
                                       np.asarray(f_ned).tolist())
    index, values = _bias_entries(tau_g, tau_a)
    F[index] = values
    return F.reshape(N_STATES, N_STATES)


def transition_matrix(lat, h, v_ned, C_bn, f_ned, dt, tau_g=0.0, tau_a=0.0):
    """First-order transition matrix ``I + F dt`` over one IMU interval of ``dt`` [s]
    (arguments as :func:`system_matrix`), equal to ``np.eye(15) + system_matrix(...) * dt``
    to the last bit but built without the intermediate matrices (:func:`transition_rows` of
    one run)."""
    row = np.zeros((1, strapdown.N_COLUMNS))
    row[0, 0], row[0, 2] = lat, h
    row[0, 3:6] = np.reshape(v_ned, 3)
    row[0, 6:15] = np.reshape(C_bn, 9)
    out = np.empty((1, N_STATES, N_STATES))
    transition_rows(out, row, np.asarray(f_ned, dtype=float).reshape(1, 3), np.full(1, float(dt)),
                    transition_template(dt, tau_g, tau_a))
    return out[0]


@kernel
def transition_rows(out, nav_rows, f_ned, dt, template):
    """:func:`transition_matrix` of every run of a batch: ``out`` (B, 15, 15) from the
    strapdown state rows ``nav_rows`` (B, 24; :data:`navcore.ins.strapdown.COLUMNS`, read
    before or after the update as the caller decides), ``f_ned`` (B, 3), ``dt`` (B,) and the
    state-independent ``template`` (225,) of :func:`transition_template` for that ``dt``."""
    for b in range(out.shape[0]):
        s = nav_rows[b]           # lat s[0], h s[2], v_ned s[3:6], C_bn by rows s[6:15]
        entries = _state_entries(s[0], s[2], s[3:6], s[6:15], f_ned[b])
        flat = out[b].reshape(N_STATES * N_STATES)
        flat[:] = template
        step = dt[b]
        for i in range(len(entries)):
            # 0.0 + x turns the -0.0 of a zero entry into the +0.0 of np.eye(15) + F * dt
            flat[_STATE_ENTRIES[i]] = 0.0 + entries[i] * step


def transition_template(dt, tau_g=0.0, tau_a=0.0):
    """The entries of ``I + F dt`` that do not depend on the state (flat (225,), read-only;
    cached per ``dt``, ``tau_g``, ``tau_a``)."""
    return _transition_template(float(dt), float(tau_g), float(tau_a))


@functools.lru_cache(maxsize=64)
def _transition_template(dt, tau_g, tau_a):
    """The entries of ``I + F dt`` that do not depend on the state (flat, read-only)."""
    phi = np.zeros(N_STATES * N_STATES)
    phi[_DIAGONAL] = 1.0
    phi[_UNIT_ENTRIES] = 0.0 + 1.0 * dt
    index, values = _bias_entries(tau_g, tau_a)
    if index:
        phi[index] = [1.0 + x * dt for x in values]
    phi.flags.writeable = False
    return phi


def process_noise_density(gyro_arw, accel_vrw, gyro_bias_sigma, gyro_bias_tau,
                          accel_bias_sigma, accel_bias_tau):
    """Diagonal of the continuous process-noise spectral density (15,).

    ``gyro_arw`` [rad/sqrt(s)], ``accel_vrw`` [m/s/sqrt(s)]; the bias drivers are those of a
    first-order Gauss-Markov process with steady-state sigma and correlation time tau:
    q = 2 sigma^2 / tau (no driving noise when tau = 0, a random constant).
    """
    q = np.zeros(N_STATES)
    q[VEL] = accel_vrw**2
    q[ATT] = gyro_arw**2
    if gyro_bias_tau > 0:
        q[BG] = 2.0 * gyro_bias_sigma**2 / gyro_bias_tau
    if accel_bias_tau > 0:
        q[BA] = 2.0 * accel_bias_sigma**2 / accel_bias_tau
    return q
