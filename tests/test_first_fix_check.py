"""A filter whose first fix is far from its initial position says so (once), through its
notices, which the FMU logs as a warning: the GNSS source then flies another trajectory than
the filter was set up for, as when a host leaves the trajectory's String ``profile`` at its
default (OMSimulator applies no String from an .ssv file)."""
from __future__ import annotations

import math

import pytest

from navcore.components import registry
from navcore.components.filter_component import FIRST_FIX_DISTANCE_M
from navcore.ins import earth

LAT = math.radians(40.0)
H = 0.01
FIX_FILTERS = ["Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf",
               "CtfaUkf", "ImmUkf"]


def _imu(k):
    return {"imu_time": (k + 1) * H, "imu_dt": H, "imu_dtheta_x": 0.0, "imu_dtheta_y": 0.0,
            "imu_dtheta_z": 0.0, "imu_dvel_x": 0.0, "imu_dvel_y": 0.0, "imu_dvel_z": -9.80 * H}


def _notices_with_fixes(name, north_m):
    """Notices of filter ``name`` at (LAT, 0, 100 m) after fixes ``north_m`` metres north."""
    f = registry.REGISTRY[name](init_lat=LAT, init_h=100.0)
    f.start(0.0)
    rn, _ = earth.radii(LAT)
    notices = []
    for k in range(300):
        epoch = (k + 1) // 100
        fix = {"gnss_time": epoch * 1.0, "gnss_lat": LAT + north_m / (rn + 100.0),
               "gnss_lon": 0.0, "gnss_h": 100.0, "gnss_vn": 0.0, "gnss_ve": 0.0, "gnss_vd": 0.0,
               "gnss_valid": epoch > 0, "gnss_epoch": epoch}
        f.advance(k * H, H, {**_imu(k), **fix})
        notices += f.take_notices()
    return notices


@pytest.mark.parametrize("name", FIX_FILTERS)
def test_a_first_fix_far_from_the_initial_position_is_reported_once(name):
    far = 3.0 * FIRST_FIX_DISTANCE_M
    notices = [n for n in _notices_with_fixes(name, far) if "first fix" in n]
    assert len(notices) == 1
    assert f"is {far / 1000.0:.4g} km from the filter's position" in notices[0]
    assert "'profile'" in notices[0]


@pytest.mark.parametrize("name", ["Kf", "Ukf"])
def test_a_first_fix_near_the_initial_position_says_nothing(name):
    assert [n for n in _notices_with_fixes(name, 30.0) if "first fix" in n] == []
