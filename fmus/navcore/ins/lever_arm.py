"""The GNSS antenna lever arm: where the antenna is, seen from the IMU, in the body frame.

A receiver measures the position and velocity of its antenna; the strapdown mechanization
those of the IMU.  With the lever arm ``l`` (body frame FRD, from the IMU to the antenna's
phase centre) and the attitude ``C_bn`` (Groves 2013, *Principles of GNSS, Inertial, and
Multisensor Integrated Navigation Systems*, 2nd ed., eqs. 2.150-2.151 and 14.99-14.100)::

    r_antenna = r_imu + C_bn l                                   (NED metres)
    v_antenna = v_imu + C_bn (omega_ib^b x l) - omega_ie^n x (C_bn l)

``omega_ib^b`` is the inertial angular rate of the body (the gyros' rate, bias-compensated).
The filters compare the INS carried to the antenna with the fix; the attitude-error term of
the lever arm (``[C_bn l x] phi``: |l| times the attitude error, 4 mm for 0.38 m and 0.01 rad)
is left out of the measurement matrix, so every engine keeps its H = [I 0].  A zero lever arm
changes nothing: the terms are not computed.
"""
from __future__ import annotations

import numpy as np

from ..core.component import Limits, real
from . import earth

#: accepted lever-arm components [m] (an antenna on a ship's mast, a wing tip)
LEVER_ARM_LIMITS = Limits(-100.0, 100.0)

LEVER_ARM_PARAMETERS = tuple(
    real(f"lever_arm_{a}", "m", f"GNSS antenna lever arm, body {a} (forward/right/down) from "
         "the IMU to the antenna", 0.0, LEVER_ARM_LIMITS) for a in "xyz")


def lever_arm_of(params, prefix="lever_arm"):
    """The lever arm of the parameters ``<prefix>_x/y/z`` as an array, None when zero."""
    lever = np.array([params[f"{prefix}_{a}"] for a in "xyz"], dtype=float)
    return lever if lever.any() else None


def antenna_position_offset(C_bn, lever):
    """``C_bn l``: the antenna's position relative to the IMU, NED [m]."""
    return np.asarray(C_bn) @ lever


def antenna_velocity_offset(C_bn, lever, rate_ib, lat):
    """``C_bn (omega_ib^b x l) - omega_ie^n x (C_bn l)``: the antenna's velocity relative to
    the IMU's, NED [m/s], for the body rate ``rate_ib`` [rad/s] at latitude ``lat``."""
    C_bn = np.asarray(C_bn)
    return C_bn @ np.cross(rate_ib, lever) - np.cross(earth.earth_rate_ned(lat), C_bn @ lever)


def antenna_fix(lat, lon, h, v_ned, C_bn, lever, rate_nb_ned):
    """(lat, lon, h, v_ned) of the antenna of a body at the IMU position ``lat, lon, h`` and
    velocity ``v_ned`` with attitude ``C_bn``, turning at ``rate_nb_ned`` (the rate of the
    body against the navigation frame, NED [rad/s]; the Earth and transport rates' part is
    below 1e-4 rad/s and left out)."""
    offset = antenna_position_offset(C_bn, lever)
    rn, re = earth.radii(lat)
    lat_a = lat + offset[0] / (rn + h)
    lon_a = lon + offset[1] / ((re + h) * np.cos(lat))
    return lat_a, lon_a, h - offset[2], np.asarray(v_ned) + np.cross(rate_nb_ned, offset)
