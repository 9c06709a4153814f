"""The GNSS inputs of a walk for a filter stepped by hand: 1 Hz fixes from 1 s at 40 deg
latitude, 100 m, still until ``moving_from`` s, then walking at 1.8 m/s (north 1.08, east
1.44 m/s), the position following the velocity."""
from __future__ import annotations

import math

from navcore.ins import earth

LAT = math.radians(40.0)
WALK_VN, WALK_VE = 1.08, 1.44


def walk_fix(k, dt, moving_from=0.0):
    """The receiver's outputs at IMU step ``k`` of length ``dt`` (the latest fix)."""
    epoch = int(round((k + 1) * dt, 9))
    t = epoch * 1.0
    walked = max(t - moving_from, 0.0)
    moving = t > moving_from
    rn, re = earth.radii(LAT)
    return {"gnss_time": t, "gnss_lat": LAT + WALK_VN * walked / (rn + 100.0),
            "gnss_lon": WALK_VE * walked / ((re + 100.0) * math.cos(LAT)), "gnss_h": 100.0,
            "gnss_vn": WALK_VN * moving, "gnss_ve": WALK_VE * moving, "gnss_vd": 0.0,
            "gnss_valid": epoch > 0, "gnss_epoch": epoch}
