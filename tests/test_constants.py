"""The physical constants of navcore.ins.constants against the standards' printed numbers.

WGS-84: NIMA TR8350.2, 3rd ed. (2000), table 3.1 (defining parameters a, 1/f, omega, GM),
table 3.3 (semi-minor axis b, first eccentricity squared e^2) and table 3.4 (normal gravity
at the equator and the poles).  Standard gravity: 3rd CGPM (1901), ISO 80000-3.  The derived
values (b, e^2) are computed in navcore from a and f, so comparing them with the printed
ones checks the derivation, not a copy.
"""
import math

import pytest

from navcore.ins import constants, earth


def test_wgs84_defining_parameters_as_printed():
    assert constants.WGS84_A == 6378137.0
    assert 1.0 / constants.WGS84_F == pytest.approx(298.257223563, rel=1e-15)
    assert constants.WGS84_OMEGA_IE == 7.292115e-5
    assert constants.WGS84_GM == 3.986004418e14


def test_wgs84_derived_geometry_matches_table_3_3():
    assert constants.WGS84_B == pytest.approx(6356752.3142, abs=5e-5)     # printed to 0.1 mm
    assert constants.WGS84_E2 == pytest.approx(6.69437999014e-3, abs=5e-15)


def test_wgs84_normal_gravity_as_printed_and_reproduced_by_the_earth_model():
    assert constants.WGS84_GAMMA_E == 9.7803253359
    assert constants.WGS84_GAMMA_P == 9.8321849378
    # Somigliana's formula of navcore.ins.earth gives the printed values at the equator and
    # the poles on the ellipsoid (h = 0)
    assert earth.gravity(0.0, 0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert earth.gravity(math.pi / 2, 0.0) == pytest.approx(9.8321849378, abs=1e-10)
    # TR8350.2's Somigliana constant k = 0.00193185265241 (eq. 4-1), here derived from the
    # printed b, gamma_e, gamma_p, whose last digits (1e-10 m/s^2) bound the agreement
    assert earth.SOMIGLIANA_K == pytest.approx(0.00193185265241, abs=1e-11)


def test_standard_gravity_and_unit_factors():
    assert constants.G0 == 9.80665
    assert constants.DEG * 180.0 == pytest.approx(math.pi, rel=1e-16)
    assert constants.DPH * 3600.0 * 180.0 / math.pi == pytest.approx(1.0, rel=1e-15)
    assert constants.DPSH * 60.0 * 180.0 / math.pi == pytest.approx(1.0, rel=1e-15)
    assert constants.UG == pytest.approx(9.80665e-6, rel=1e-15)


def test_earth_model_uses_the_one_definition():
    assert (earth.A, earth.B, earth.E2, earth.F, earth.OMEGA_IE, earth.GM, earth.GAMMA_E,
            earth.GAMMA_P) == (constants.WGS84_A, constants.WGS84_B, constants.WGS84_E2,
                               constants.WGS84_F, constants.WGS84_OMEGA_IE, constants.WGS84_GM,
                               constants.WGS84_GAMMA_E, constants.WGS84_GAMMA_P)
