"""The UKF family against the Kf at rest after a static alignment (init_mode 'align'): a
consumer IMU standing level at 40 deg N with a vertical accelerometer bias, 4 Hz fixes of
1 cm for 1 s after the 3 s alignment, then a 2 s outage.  The filters share the error model and the
parameters, and what they learn at rest is linear (the vertical accelerometer bias from the
fixes), so their vertical drifts over the outage agree.  They did not while the alignment
kept the configured level sigma (10 deg) instead of its own (the accelerometer bias over g,
1.15 deg): the UKF's sigma points at +/-sqrt(15) x 10 deg tilt saw a mean vertical error
-g E[1 - cos phi] = -0.3 m/s^2 that is not there, learned the vertical bias late and
drifted as it did not (here 3.1 cm against the Kf's 12.5 cm; the real drive's standing car:
7.7 cm RMS against 2.3 cm)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.components import registry as components
from navcore.ins import earth

LAT, LON, H = math.radians(40.0), math.radians(-105.0), 1600.0
#: the IMU's accelerometer bias (body FRD, level body: z is down) [m/s^2]
ACCEL_BIAS = np.array([0.0, 0.0, 0.12])
DT, ALIGN, OUTAGE = 0.01, 3.0, (4.0, 6.0)
PARAMETERS = dict(init_mode="align", align_time=ALIGN, init_lat=LAT, init_lon=LON, init_h=H,
                  measurement="position", r_pos_n=0.01, r_pos_e=0.01, r_pos_d=0.01,
                  p0_att_level=0.1745, p0_att_yaw=1.745, p0_accel_bias_ug=20000.0,
                  p0_gyro_bias_dph=720.0)


def _inputs(t, dt):
    """The IMU at rest, level, heading north, and the 4 Hz fixes (none in the outage)."""
    end = t + dt
    f = -earth.gravity_ned(LAT, H) + ACCEL_BIAS
    w = earth.earth_rate_ned(LAT)
    epoch = int(end * 4.0 + 1e-9)
    x = {"imu_time": end, "imu_dt": dt, "gnss_epoch": epoch, "gnss_time": epoch / 4.0,
         "gnss_valid": not OUTAGE[0] < epoch / 4.0 <= OUTAGE[1], "gnss_lat": LAT,
         "gnss_lon": LON, "gnss_h": H, "gnss_vn": 0.0, "gnss_ve": 0.0, "gnss_vd": 0.0}
    for i, a in enumerate("xyz"):
        x[f"imu_dtheta_{a}"], x[f"imu_dvel_{a}"] = w[i] * dt, f[i] * dt
        x[f"imu_gyro_{a}"], x[f"imu_accel_{a}"] = w[i], f[i]
    return x


def _run(name):
    """(the component's outputs just after the alignment, the down errors [m] over the
    outage at the fixes' epochs)."""
    component = getattr(components, name)(**PARAMETERS)
    component.initialize(0.0)
    n = int(round(OUTAGE[1] / DT))
    aligned, down = None, []
    for k in range(n):
        out = component.step(k * DT, DT, _inputs(k * DT, DT))
        if aligned is None and out["aligned"]:
            aligned = dict(out)
        end = (k + 1) * DT
        if OUTAGE[0] < end + 1e-9 and abs(end * 4.0 - round(end * 4.0)) < 1e-6:
            down.append(H - out["nav_h"])
    return aligned, np.array(down)


@pytest.fixture(scope="module")
def runs():
    return {name: _run(name) for name in ("Kf", "Ukf", "CtfaUkf", "ImmUkf")}


def test_the_alignment_knows_its_level_to_the_accelerometer_bias_over_g(runs):
    # a horizontal accelerometer bias of sigma b tilts the level by b / g: 20000 ug -> 1.15 deg
    expected = 20000e-6 * 9.80665 / earth.gravity(LAT, H)
    for name, (aligned, _) in runs.items():
        assert aligned["std_att_n"] == pytest.approx(expected, rel=1e-3), name
        assert aligned["std_att_e"] == pytest.approx(expected, rel=1e-3), name
        assert aligned["std_att_d"] == pytest.approx(1.745, rel=1e-3), name


def test_the_ukfs_drift_down_as_the_kf_in_an_outage_at_rest(runs):
    _, kf = runs["Kf"]
    # the Kf's drift: the part of the 0.12 m/s^2 bias 1 s of fixes did not find, over 2 s
    # (12.5 cm at the end; the fix at the outage's start first)
    assert len(kf) == 9 and abs(kf[0]) < 0.005 and 0.05 < kf[-1] < 0.3
    # what the unscented transform legitimately adds: the second-order mean of the level's
    # sigma s (1.15 deg on each axis) in the vertical specific force, g E[1 - cos phi] =
    # g s^2, over the outage's T: g s^2 T^2 / 2 = 7.9 mm
    s = 20000e-6 * 9.80665 / earth.gravity(LAT, H)
    T = OUTAGE[1] - OUTAGE[0]
    bound = earth.gravity(LAT, H) * s * s * T * T / 2.0
    assert bound == pytest.approx(0.0079, abs=1e-4)
    for name in ("Ukf", "CtfaUkf", "ImmUkf"):
        _, down = runs[name]
        assert np.abs(down - kf).max() < bound, (name, down, kf)
