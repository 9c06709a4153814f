"""Physical constants and unit factors: one definition of each for all of navcore.

* Standard gravity ``G0`` = 9.80665 m/s^2, the conventional "g" of datasheet units (ug,
  deg/h/g) and of the coordinated-turn bank angle (3rd CGPM 1901; ISO 80000-3).
* The WGS-84 ellipsoid and its normal gravity field (NIMA TR8350.2, 3rd ed., tables 3.1, 3.3
  and 3.4): semi-major axis, flattening, earth rotation rate, GM, normal gravity at the
  equator and at the poles; the semi-minor axis and the first eccentricity squared follow
  from a and f.
* The datasheet unit factors to SI (deg, deg/h, deg/sqrt(h), ug), converted once in navcore.

``tests/test_constants.py`` pins every value against the standards' numbers.
"""
from __future__ import annotations

import math

#: standard gravity [m/s^2] (3rd CGPM 1901), the "g" of datasheet units
G0 = 9.80665

#: WGS-84 semi-major axis a [m]
WGS84_A = 6378137.0
#: WGS-84 flattening f = 1/298.257223563 [-]
WGS84_F = 1.0 / 298.257223563
#: WGS-84 first eccentricity squared e^2 = f (2 - f) [-]
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
#: WGS-84 semi-minor axis b = a (1 - f) [m]
WGS84_B = WGS84_A * (1.0 - WGS84_F)
#: WGS-84 earth rotation rate omega_ie [rad/s]
WGS84_OMEGA_IE = 7.292115e-5
#: WGS-84 earth gravitational constant GM [m^3/s^2]
WGS84_GM = 3.986004418e14
#: WGS-84 normal gravity at the equator [m/s^2] (Somigliana)
WGS84_GAMMA_E = 9.7803253359
#: WGS-84 normal gravity at the poles [m/s^2] (Somigliana)
WGS84_GAMMA_P = 9.8321849378

#: deg -> rad
DEG = math.pi / 180.0
#: deg/h -> rad/s
DPH = DEG / 3600.0
#: deg/sqrt(h) -> rad/sqrt(s)
DPSH = DEG / 60.0
#: ug -> m/s^2 (also ug/sqrt(Hz) -> m/s^2/sqrt(Hz) = m/s/sqrt(s))
UG = 1e-6 * G0
