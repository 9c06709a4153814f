"""WGS-84 earth model in the local NED navigation frame.

Functions take latitude in rad and height in m above the ellipsoid and work on scalars or
numpy arrays; the WGS-84 constants are those of :mod:`navcore.ins.constants`.  References:
Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*,
2nd ed., eqs. (2.105)-(2.106) (radii), (2.134) (normal gravity with
height, Somigliana + free-air series), (5.41)-(5.44) (earth and transport rates in NED).
"""
from __future__ import annotations

import numpy as np

from .constants import WGS84_A as A
from .constants import WGS84_B as B
from .constants import WGS84_E2 as E2
from .constants import WGS84_F as F
from .constants import WGS84_GAMMA_E as GAMMA_E
from .constants import WGS84_GAMMA_P as GAMMA_P
from .constants import WGS84_GM as GM
from .constants import WGS84_OMEGA_IE as OMEGA_IE

#: Somigliana's constant k = (b gamma_p - a gamma_e) / (a gamma_e) of normal gravity [-]
SOMIGLIANA_K = (B * GAMMA_P - A * GAMMA_E) / (A * GAMMA_E)
#: m = omega_ie^2 a^2 b / GM of the free-air height correction [-]
GRAVITY_M = OMEGA_IE**2 * A**2 * B / GM


def radii(lat):
    """Meridian radius R_N (north-south) and transverse radius R_E (east-west) [m].

    R_N = a(1-e^2)/(1-e^2 sin^2 L)^(3/2),  R_E = a/sqrt(1-e^2 sin^2 L)   (Groves 2.105-2.106)
    """
    s2 = np.sin(lat) ** 2
    w = 1.0 - E2 * s2
    rn = A * (1.0 - E2) / w**1.5
    re = A / np.sqrt(w)
    return rn, re


def gravity(lat, h):
    """Magnitude of normal gravity [m/s^2] at latitude ``lat`` and height ``h``.

    Somigliana on the ellipsoid with the second-order free-air height correction
    (Groves 2.134, WGS-84 constants).  In NED the gravity vector is (0, 0, gravity).
    """
    s2 = np.sin(lat) ** 2
    g0 = GAMMA_E * (1.0 + SOMIGLIANA_K * s2) / np.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F + GRAVITY_M - 2.0 * F * s2) * h + 3.0 * h**2 / A**2)


def gravity_ned(lat, h):
    """Normal gravity vector in NED [m/s^2]."""
    return np.array([0.0, 0.0, float(gravity(lat, h))])


def earth_rate_ned(lat):
    """Earth rotation rate resolved in NED, omega_ie^n [rad/s] (Groves 5.41)."""
    return np.array([OMEGA_IE * np.cos(lat), 0.0, -OMEGA_IE * np.sin(lat)])


def transport_rate_ned(lat, h, v_ned):
    """Transport rate omega_en^n [rad/s] for NED velocity ``v_ned`` (Groves 5.44)."""
    rn, re = radii(lat)
    vn, ve = v_ned[0], v_ned[1]
    return np.array([ve / (re + h), -vn / (rn + h), -ve * np.tan(lat) / (re + h)])


def ned_to_lla_delta(lat, h, d_ned):
    """Small NED displacement [m] -> (dlat, dlon, dh) [rad, rad, m] at (lat, h)."""
    rn, re = radii(lat)
    d = np.asarray(d_ned, dtype=float)
    return np.array([d[..., 0] / (rn + h), d[..., 1] / ((re + h) * np.cos(lat)), -d[..., 2]])


def lla_delta_to_ned(lat, h, dlat, dlon, dh):
    """(dlat, dlon, dh) [rad, rad, m] -> NED displacement [m] at (lat, h), first order."""
    rn, re = radii(lat)
    return np.stack([dlat * (rn + h), dlon * (re + h) * np.cos(lat), -dh], axis=-1)
