"""The signal contracts shared by components: names, types and SI units.

Every INS/GNSS filter declares ``FILTER_INPUTS`` and at least ``FILTER_OUTPUTS`` so that any
filter can replace any other in a system model.  Time of validity travels with the data:
``imu_time`` is the end of the interval the increments cover (the interval is
``[imu_time - imu_dt, imu_time]``), ``gnss_time`` is when the fix was taken, ``nav_time`` is
the time the navigation solution is valid for, ``truth_time`` the time of the truth sample.
"""
from __future__ import annotations

import math

from .component import FINITE, Limits, boolean, integer, real

AXES_NED = ("n", "e", "d")
AXES_BODY = ("x", "y", "z")

# Accepted ranges of the signals a component checks on its inputs: times within about 30
# years of the start, positions on or near the earth (latitude within the poles, heights
# from a deep valley to low orbit), speeds of anything that flies; per IMU interval of at most
# 1 s, a rotation of at most pi and a velocity change of at most 1 km/s (100 g for 1 s).
TIME = Limits(-1e9, 1e9)
LATITUDE = Limits(-math.pi / 2, math.pi / 2, low_open=True, high_open=True)
LONGITUDE = Limits(-2 * math.pi, 2 * math.pi)
EULER_ANGLE = Limits(-2 * math.pi, 2 * math.pi)
HEIGHT = Limits(-1e5, 1e6)
VELOCITY = Limits(-1e4, 1e4)
INTERVAL = Limits(0.0, 1.0)
DTHETA = Limits(-math.pi, math.pi)
DVEL = Limits(-1e3, 1e3)

#: the position and velocity every interface carries (truth, fix, initial state, solution):
#: (name suffix, unit, quantity, accepted range), declared once
POSITION_FIELDS = (
    ("lat", "rad", "geodetic latitude", LATITUDE),
    ("lon", "rad", "longitude", LONGITUDE),
    ("h", "m", "height above the WGS-84 ellipsoid", HEIGHT),
)
VELOCITY_FIELDS = tuple((f"v{a}", "m/s", f"velocity {axis}", VELOCITY)
                        for a, axis in zip(AXES_NED, ("north", "east", "down")))


def state_ports(prefix, adjective, start=0.0, ranged=True):
    """The Reals ``<prefix>_lat .. <prefix>_vd`` ("true latitude", "measured velocity north");
    ``ranged=False``: finite only (a filter's estimate, which may leave the ranges)."""
    return tuple(real(f"{prefix}_{suffix}", unit, f"{adjective} {quantity}", start,
                      limits if ranged else FINITE)
                 for suffix, unit, quantity, limits in POSITION_FIELDS + VELOCITY_FIELDS)


TRUTH = (
    real("truth_time", "s", "time the truth sample is valid for", limits=TIME),
    *state_ports("truth", "true"),
    real("truth_roll", "rad", "true roll (ZYX Euler)"),
    real("truth_pitch", "rad", "true pitch (ZYX Euler)"),
    real("truth_yaw", "rad", "true yaw / heading (ZYX Euler), (-pi, pi]"),
)

IMU = (
    real("imu_time", "s", "end of the interval the increments cover", limits=TIME),
    real("imu_dt", "s", "length of the interval the increments cover", limits=INTERVAL),
    *(real(f"imu_dtheta_{a}", "rad", f"angle increment about body {a} over the interval",
           limits=DTHETA) for a in AXES_BODY),
    *(real(f"imu_dvel_{a}", "m/s", f"specific-force velocity increment along body {a}",
           limits=DVEL) for a in AXES_BODY),
    *(real(f"imu_gyro_{a}", "rad/s", f"mean angular rate about body {a} (dtheta/dt)")
      for a in AXES_BODY),
    *(real(f"imu_accel_{a}", "m/s2", f"mean specific force along body {a} (dvel/dt)")
      for a in AXES_BODY),
)

MAG = (
    real("mag_time", "s", "time the magnetometer sample is valid for"),
    *(real(f"mag_{a}", "T", f"magnetic flux density along body {a}") for a in AXES_BODY),
)

# names of the per-axis signals (body x, y, z), built once for the components that write or
# read them every sample
IMU_DTHETA_NAMES, IMU_DVEL_NAMES, IMU_GYRO_NAMES, IMU_ACCEL_NAMES = (
    tuple(p.name for p in IMU[i:i + 3]) for i in (2, 5, 8, 11))
MAG_NAMES = tuple(p.name for p in MAG[1:])

GNSS = (
    real("gnss_time", "s", "time the latest fix was taken", limits=TIME),
    *state_ports("gnss", "measured"),
    boolean("gnss_valid", "the latest fix is usable (false during outages)"),
    integer("gnss_epoch", "counter of fixes; a filter updates when it changes"),
)

#: the receiver's own 1-sigma of the latest fix's position (a replayed log's std_n/e/d; 0:
#: none): a filter with ``r_from_receiver`` takes them as its R
GNSS_STD = tuple(real(f"gnss_std_{a}", "m", f"receiver's 1-sigma of the latest fix, {axis} "
                      "(0: not given)", 0.0, Limits(0.0, 1e4))
                 for a, axis in zip(AXES_NED, ("north", "east", "down")))

#: diagnostic output of the receiver model, for evaluation only (a filter never reads it)
GNSS_INJECTED = (
    boolean("gnss_outlier", "an outlier was injected into the latest fix (evaluation only)"),
)

#: inputs of every INS/GNSS filter (a filter never reads truth)
FILTER_INPUTS = IMU[:8] + GNSS + GNSS_STD

_NAV = (
    real("nav_time", "s", "time the navigation solution is valid for"),
    *state_ports("nav", "estimated", ranged=False),
    real("nav_roll", "rad", "estimated roll"),
    real("nav_pitch", "rad", "estimated pitch"),
    real("nav_yaw", "rad", "estimated yaw"),
    *(real(f"nav_bg_{a}", "rad/s", f"estimated gyro bias, body {a}") for a in AXES_BODY),
    *(real(f"nav_ba_{a}", "m/s2", f"estimated accelerometer bias, body {a}") for a in AXES_BODY),
)
#: the position, velocity and attitude outputs, in the order of ``Strapdown.solution()``
NAV_SOLUTION_NAMES = tuple(p.name for p in _NAV[1:10])
NAV_BG_NAMES = tuple(p.name for p in _NAV[10:13])
NAV_BA_NAMES = tuple(p.name for p in _NAV[13:16])

_STD = (
    *(real(f"std_p{a}", "m", f"1-sigma of the position error, {a.upper()}") for a in AXES_NED),
    *(real(f"std_v{a}", "m/s", f"1-sigma of the velocity error, {a.upper()}") for a in AXES_NED),
    *(real(f"std_att_{a}", "rad", f"1-sigma of the attitude error angle about {a.upper()}")
      for a in AXES_NED),
    *(real(f"std_bg_{a}", "rad/s", f"1-sigma of the gyro bias error, body {a}") for a in AXES_BODY),
    *(real(f"std_ba_{a}", "m/s2", f"1-sigma of the accel bias error, body {a}") for a in AXES_BODY),
)

_DIAGNOSTICS = (
    real("nis", "", "normalized innovation squared of the latest update (0 without update)"),
    integer("nis_dof", "degrees of freedom of nis (measurement dimension, 0 without update)"),
    boolean("updated", "a measurement update happened in the last step"),
    real("q_scale", "", "adaptive process-noise scale (1 for a fixed-Q filter)", 1.0),
    real("r_scale", "", "adaptive measurement-noise scale, trace(R_used)/trace(R0)", 1.0),
    real("fading_factor", "", "fading-memory factor lambda of the latest update (1 = none)", 1.0),
    boolean("outlier", "the latest measurement was judged an outlier"),
    real("fix_age", "s", "age of the latest fix when it reached the filter: nav_time - "
         "gnss_time (negative for a fix from the future, applied when the INS reaches it)"),
    integer("n_stale_fixes", "fixes not applied because their gnss_time was more than "
            "max_fix_age from nav_time, or before the epoch of a fix already applied"),
)

#: the filter has its initial state (an AHRS its attitude; an INS/GNSS filter with init_mode
#: 'gnss' or 'align' its start from the data): the metrics skip the samples before
ALIGNED = boolean("aligned", "the filter has a solution (false until its initialization)")

#: outputs every INS/GNSS filter has (filters may add their own diagnostics)
FILTER_OUTPUTS = _NAV + _STD + _DIAGNOSTICS + (ALIGNED,)


#: inputs of every attitude (AHRS) filter: IMU increments and the magnetometer
AHRS_INPUTS = IMU[:8] + MAG

_BY_NAME = {p.name: p for p in _NAV + _DIAGNOSTICS}

#: outputs every AHRS filter has: attitude, its 1-sigma, gyro bias, innovation statistics
AHRS_OUTPUTS = (
    _BY_NAME["nav_time"],
    ALIGNED,
    *(_BY_NAME[f"nav_{a}"] for a in ("roll", "pitch", "yaw")),
    *(real(f"std_{a}", "rad", f"1-sigma of the {a} error") for a in ("roll", "pitch", "yaw")),
    *(_BY_NAME[f"nav_bg_{a}"] for a in AXES_BODY),
    *(_BY_NAME[n] for n in ("nis", "nis_dof", "updated")),
    real("r_scale_accel", "", "R of the accelerometer block / its nominal value", 1.0),
    real("r_scale_mag", "", "R of the magnetometer block / its nominal value", 1.0),
)
