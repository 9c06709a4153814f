"""How far a vehicle's sampled truth is from obeying its own kinematics on the WGS-84
ellipsoid: velocity against the change of position, body rates against the change of
attitude, specific force against the change of velocity and gravity.

Each function takes the samples ``k = 0..n`` of a trajectory (time [s], geodetic position,
NED velocity, ZYX Euler angles, and where given the body rates / specific force of the
vehicle contract, docs/guide/vehicle_in_the_loop.md) and returns, per interval ``[k, k+1]``,
the mismatch between what the position/attitude/velocity did and the trapezoid of the
rate outputs, and an *allowance*: half the change of the rate output over the interval,
the most a vehicle integrating with a rectangle rule is off by (the contract accepts it).

* Velocity: the chord of the position, ``(dlat (R_N + h), dlon (R_E + h) cos lat, -dh) /
  dt`` (radii at the interval's middle, Groves 2.105-2.106), against ``(v_k + v_k+1) / 2``.
* Body rates (inertial, earth rate included): over the interval ``C_bn(k+1) = (I - [w_in
  dt x]) C_bn(k) exp([w_ib dt x])`` (Groves 5.34 with ``w_in = w_ie + w_en``, 5.41-5.44),
  so ``log(C_bn(k)^T (I + [w_in dt x]) C_bn(k+1)) / dt`` against the trapezoid of the
  body rates.
* Specific force: ``f^n = dv/dt + (2 w_ie + w_en) x v - g^n`` (Groves 5.54) with the chord
  of the velocity, against the trapezoid of ``C_bn f^b``.

:func:`integrated_attitude_error` integrates the body rates alone from the first attitude
and gives the angle to the reported attitude at every sample.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .constants import WGS84_OMEGA_IE as OMEGA_IE
from .earth import gravity, radii, transport_rate_ned
from .rotations import euler_to_dcm_array


def _interval(x):
    x = np.asarray(x, dtype=float)
    return 0.5 * (x[1:] + x[:-1]), np.diff(x, axis=0)


def _norm(x):
    return np.linalg.norm(x, axis=-1)


def _navigation_rates(lat, h, v_ned):
    """w_ie^n and w_en^n at each sample, shape (n, 3) each."""
    lat, h, v = np.asarray(lat, float), np.asarray(h, float), np.asarray(v_ned, float)
    w_ie = np.stack([OMEGA_IE * np.cos(lat), np.zeros_like(lat), -OMEGA_IE * np.sin(lat)],
                    axis=-1)                                    # Groves 5.41, per sample
    w_en = np.stack(transport_rate_ned(lat, h, v.T), axis=-1)
    return w_ie, w_en


def velocity_of_position(t, lat, lon, h):
    """NED velocity [m/s] of each interval from the change of geodetic position."""
    _, dt = _interval(t)
    lat_m, dlat = _interval(lat)
    h_m, dh = _interval(h)
    dlon = np.angle(np.exp(1j * np.diff(np.asarray(lon, dtype=float))))   # wrapped
    rn, re = radii(lat_m)
    return np.stack([dlat * (rn + h_m), dlon * (re + h_m) * np.cos(lat_m), -dh], axis=-1) \
        / dt[:, None]


def velocity_mismatch(t, lat, lon, h, v_ned):
    """(mismatch, allowance) per interval [m/s]: the chord of the position against the
    trapezoid of the velocity outputs (module docstring)."""
    v_mid, dv = _interval(v_ned)
    return _norm(velocity_of_position(t, lat, lon, h) - v_mid), 0.5 * _norm(dv)


def _skew(w):
    z = np.zeros(len(w))
    return np.stack([np.stack([z, -w[:, 2], w[:, 1]], -1), np.stack([w[:, 2], z, -w[:, 0]], -1),
                     np.stack([-w[:, 1], w[:, 0], z], -1)], axis=1)


def body_rate_mismatch(t, lat, h, v_ned, roll, pitch, yaw, rate_ib):
    """(mismatch, allowance) per interval [rad/s]: the body rate the attitude change makes
    (the navigation frame's own rotation taken off) against the trapezoid of ``rate_ib``."""
    _, dt = _interval(t)
    c = euler_to_dcm_array(roll, pitch, yaw)
    w_ie, w_en = _navigation_rates(lat, h, v_ned)
    w_in, _ = _interval(w_ie + w_en)
    frame = np.eye(3) + _skew(w_in * dt[:, None])
    change = np.einsum("kji,kjl,klm->kim", c[:-1], frame, c[1:])
    measured = Rotation.from_matrix(change).as_rotvec() / dt[:, None]
    rate_mid, d_rate = _interval(rate_ib)
    return _norm(measured - rate_mid), 0.5 * _norm(d_rate)


def specific_force_mismatch(t, lat, h, v_ned, roll, pitch, yaw, force_b):
    """(mismatch, allowance) per interval [m/s2]: the specific force the velocity change,
    Coriolis and gravity make against the trapezoid of ``C_bn f^b``."""
    _, dt = _interval(t)
    v = np.asarray(v_ned, dtype=float)
    w_ie, w_en = _navigation_rates(lat, h, v)
    g = np.zeros_like(v)
    g[:, 2] = gravity(np.asarray(lat, float), np.asarray(h, float))
    needed_at = np.cross(2 * w_ie + w_en, v) - g
    needed_mid, _ = _interval(needed_at)
    v_mid, dv = _interval(v)
    needed = dv / dt[:, None] + needed_mid
    f_n = np.einsum("kij,kj->ki", euler_to_dcm_array(roll, pitch, yaw),
                    np.asarray(force_b, dtype=float))
    f_mid, df = _interval(f_n)
    return _norm(needed - f_mid), 0.5 * _norm(df)


def integrated_attitude_error(t, lat, h, v_ned, roll, pitch, yaw, rate_ib):
    """Angle [rad] between the reported attitude and the one integrated from the first with
    the trapezoid of the body rates (the navigation frame's rotation taken off), per sample."""
    _, dt = _interval(t)
    c = euler_to_dcm_array(roll, pitch, yaw)
    w_ie, w_en = _navigation_rates(lat, h, v_ned)
    w_in, _ = _interval(w_ie + w_en)
    rate_mid, _ = _interval(rate_ib)
    steps = Rotation.from_rotvec(rate_mid * dt[:, None]).as_matrix()
    frames = Rotation.from_rotvec(-w_in * dt[:, None]).as_matrix()
    out = np.zeros(len(c))
    current = c[0]
    for k in range(len(dt)):
        current = frames[k] @ current @ steps[k]
        out[k + 1] = np.linalg.norm(Rotation.from_matrix(c[k + 1].T @ current).as_rotvec())
    return out


__all__ = ["velocity_of_position", "velocity_mismatch", "body_rate_mismatch",
           "specific_force_mismatch", "integrated_attitude_error"]
