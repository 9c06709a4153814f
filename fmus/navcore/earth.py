"""WGS-84 earth model in the local NED navigation frame.

Functions take latitude in rad and height in m above the ellipsoid and work on scalars or
numpy arrays.  References: Groves, *Principles of GNSS, Inertial, and Multisensor Integrated
Navigation Systems*, 2nd ed., eqs. (2.105)-(2.106) (radii), (2.134) (normal gravity with
height, Somigliana + free-air series), (5.41)-(5.44) (earth and transport rates in NED).
"""
from __future__ import annotations

import numpy as np

#: semi-major axis [m]
A = 6378137.0
#: flattening [-]
F = 1.0 / 298.257223563
#: first eccentricity squared [-]
E2 = F * (2.0 - F)
#: semi-minor axis [m]
B = A * (1.0 - F)
#: earth rotation rate [rad/s]
OMEGA_IE = 7.292115e-5
#: earth gravitational constant GM [m^3/s^2]
GM = 3.986004418e14
#: normal gravity at the equator and at the poles [m/s^2] (Somigliana)
GAMMA_E = 9.7803253359
GAMMA_P = 9.8321849378
_K_SOMIGLIANA = (B * GAMMA_P - A * GAMMA_E) / (A * GAMMA_E)
_M = OMEGA_IE**2 * A**2 * B / GM


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
    g0 = GAMMA_E * (1.0 + _K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F + _M - 2.0 * F * s2) * h + 3.0 * h**2 / A**2)


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


def lla_rates(lat, h, v_ned):
    """Time derivatives (dlat/dt, dlon/dt, dh/dt) [rad/s, rad/s, m/s] for NED velocity."""
    rn, re = radii(lat)
    return np.array([
        v_ned[0] / (rn + h),
        v_ned[1] / ((re + h) * np.cos(lat)),
        -v_ned[2],
    ])


def ned_to_lla_delta(lat, h, d_ned):
    """Small NED displacement [m] -> (dlat, dlon, dh) [rad, rad, m] at (lat, h)."""
    rn, re = radii(lat)
    d = np.asarray(d_ned, dtype=float)
    return np.array([d[..., 0] / (rn + h), d[..., 1] / ((re + h) * np.cos(lat)), -d[..., 2]])


def lla_delta_to_ned(lat, h, dlat, dlon, dh):
    """(dlat, dlon, dh) [rad, rad, m] -> NED displacement [m] at (lat, h), first order."""
    rn, re = radii(lat)
    return np.stack([dlat * (rn + h), dlon * (re + h) * np.cos(lat), -dh], axis=-1)
