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
    d(dbg)/dt = -dbg / tau_g + w_bg,    d(dba)/dt = -dba / tau_a + w_ba  (random constant if tau = 0)

with ``d(w_in)`` the change of the navigation-frame rate caused by the velocity and latitude
errors.  White gyro and accelerometer noise (ARW, VRW) enter phi and dv.
"""
from __future__ import annotations

import numpy as np

from . import earth

N_STATES = 15
POS, VEL, ATT, BG, BA = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15))


def _skew_into(F, r, c, v):
    """Write [v x] into F[r:r+3, c:c+3]."""
    F[r, c + 1] = -v[2]
    F[r, c + 2] = v[1]
    F[r + 1, c] = v[2]
    F[r + 1, c + 2] = -v[0]
    F[r + 2, c] = -v[1]
    F[r + 2, c + 1] = v[0]


def system_matrix(lat, h, v_ned, C_bn, f_ned, tau_g=0.0, tau_a=0.0):
    """Continuous-time error dynamics matrix F (15x15) of the model in the module docstring.

    ``f_ned`` is the specific force resolved in NED [m/s^2]; ``tau_g``/``tau_a`` are the
    Gauss-Markov correlation times of the bias errors [s] (0 = random constant).
    """
    rn, re = earth.radii(lat)
    rn_h, re_h = rn + h, re + h
    sl, cl = np.sin(lat), np.cos(lat)
    tl = sl / cl
    vn, ve, vd = v_ned
    w = earth.OMEGA_IE
    w_ie = (w * cl, 0.0, -w * sl)
    w_en = (ve / re_h, -vn / rn_h, -ve * tl / re_h)
    w_in = (w_ie[0] + w_en[0], w_ie[1] + w_en[1], w_ie[2] + w_en[2])
    w_cor = (2 * w_ie[0] + w_en[0], 2 * w_ie[1] + w_en[1], 2 * w_ie[2] + w_en[2])
    g = earth.gravity(lat, h)

    F = np.zeros((N_STATES, N_STATES))
    F[0, 3] = F[1, 4] = F[2, 5] = 1.0
    # velocity error
    _skew_into(F, 3, 6, f_ned)
    F[3:6, 12:15] = C_bn
    _skew_into(F, 3, 3, (-w_cor[0], -w_cor[1], -w_cor[2]))
    F[5, 2] = 2.0 * g / np.sqrt(rn * re)
    # attitude error
    _skew_into(F, 6, 6, (-w_in[0], -w_in[1], -w_in[2]))
    # d(w_en)/d(dv)
    F[6, 4] = 1.0 / re_h
    F[7, 3] = -1.0 / rn_h
    F[8, 4] = -tl / re_h
    # d(w_ie)/d(lat) with dlat = dr_n / (R_N + h)
    F[6, 0] = -w * sl / rn_h
    F[8, 0] = -w * cl / rn_h
    F[6:9, 9:12] = -C_bn
    if tau_g > 0:
        F[9, 9] = F[10, 10] = F[11, 11] = -1.0 / tau_g
    if tau_a > 0:
        F[12, 12] = F[13, 13] = F[14, 14] = -1.0 / tau_a
    return F


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
