"""Earth field and gravity of the ahrs_turntable scenario, from a geomagnetic model.

Paper 003 gives neither the place nor the date of its turntable test.  We take the authors'
institute (Ordnance Engineering College, Shijiazhuang: 38.04 N, 114.51 E, 80 m) and the date
the paper was received (2013-04-08), and evaluate the International Geomagnetic Reference
Field (IGRF-14 through the ``ppigrf`` package) there: total intensity H and inclination I
of the paper's field model ``[H cos I, 0, H sin I]`` (its yaw is from magnetic north; the
declination, -5.6 deg here, is not modelled).  Gravity is WGS-84 normal gravity
(navcore.ins.earth.gravity).  Run ``python models/ahrs_turntable/make_field.py`` to print the
values written in ``trajectory.ssv`` and ``filter.ssv`` (mag_field_T, mag_inclination,
gravity_mps2); tests/test_ahrs_scenario.py checks that the files hold them.
"""
from __future__ import annotations

import datetime
import math

LAT_DEG, LON_DEG, HEIGHT_M = 38.04, 114.51, 80.0
DATE = datetime.datetime(2013, 4, 8)


def field():
    """``(H [T], I [rad], declination [rad])`` from IGRF at the scenario's place and date."""
    import numpy as np
    import ppigrf

    be, bn, bu = (float(np.squeeze(c)) for c in
                  ppigrf.igrf(LON_DEG, LAT_DEG, HEIGHT_M / 1000.0, DATE))
    horizontal = math.hypot(be, bn)
    return (1e-9 * math.sqrt(be * be + bn * bn + bu * bu), math.atan2(-bu, horizontal),
            math.atan2(be, bn))


def gravity():
    from navcore.ins.earth import gravity as normal_gravity

    return float(normal_gravity(math.radians(LAT_DEG), HEIGHT_M))


if __name__ == "__main__":
    H, incl, decl = field()
    print(f"mag_field_T     {H!r}")
    print(f"mag_inclination {incl!r}   ({math.degrees(incl):.3f} deg; declination "
          f"{math.degrees(decl):.2f} deg not modelled)")
    print(f"gravity_mps2    {gravity()!r}")
