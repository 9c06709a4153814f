"""Process noise a user can trust: the factor from an IMU's datasheet noise figures to the Q of
the filter.

A datasheet gives the white noise of a gyro and an accelerometer (angle and velocity random
walk) and a bias instability, measured on a bench: at rest, at constant temperature, over an
Allan variance plot.  In a car the same consumer MEMS IMU also sees what those figures leave
out -- scale-factor and cross-axis errors multiplied by the turn rates and accelerations,
g-sensitivity, vibration rectification, temperature drift of the biases, the resampling and
filtering of the log -- and the 15-state filter has no state for any of them.  Left out of Q
they make the filter sure of an INS that drifts: on a real drive (``docs/guide/
your_real_log.md``) the Kf with the datasheet figures was about 100 m off after a 60 s outage
with a 4.5 m sigma, and 13-65 % of its errors were inside +/-3 sigma.

The field's remedy is to inflate the process noise for the unmodelled errors (Groves 2013,
*Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed.,
ch. 3 on tuning a Kalman filter and ch. 14 on the INS/GNSS system noise: the system noise is
set larger than the sensors' own noise to cover the errors the state leaves unmodelled;
rtklibexplorer's GNSS_IMU, the peer
filter of the drive above, scales its IMU specifications by "noise factors for unmodelled
errors" per state group).  Every INS/GNSS filter has ``imu_noise_factor``: the angle and
velocity random walks and the two bias instabilities it assumes (``q_gyro_arw_dpsh``,
``q_accel_vrw_ugpsHz``, ``q_*_bias_instability_*``) are multiplied by it, so each part of Q
by its square.  The default 1 keeps the configured figures bit for bit (the papers'
scenarios simulate an IMU whose errors are exactly those figures);
:data:`CONSUMER_IMU_NOISE_FACTOR` is the value ``navfmu convert kf-gins --config`` and the
guide recommend for a consumer MEMS IMU with datasheet figures, and
:func:`suggested_factor` the one the NIS warning (:mod:`navcore.filters.nis_monitor`) proposes
when a run says Q is too small.
"""
from __future__ import annotations

import math

from ..core.component import Limits, real

IMU_NOISE_PARAMETERS = (
    real("imu_noise_factor", "", "factor on the IMU noise figures assumed (q_gyro_arw_dpsh, "
         "q_accel_vrw_ugpsHz, q_*_bias_instability_*): Q of each is scaled by its square, for "
         "the errors of a real IMU a datasheet leaves out (1 = the figures as given; about 30 "
         "for a consumer MEMS IMU with datasheet figures, docs/guide/your_real_log.md)", 1.0,
         Limits(1e-3, 1e4)),
)

#: the factor recommended for a consumer MEMS IMU described by its datasheet figures: on the
#: real drive of docs/guide/your_real_log.md it puts 90 % or more of every filter's errors
#: inside +/-3 sigma per axis (with gnss_corr_time for the receiver's correlated errors)
CONSUMER_IMU_NOISE_FACTOR = 30.0
#: [deg/sqrt(h)] a gyro angle random walk at least this large is a MEMS gyro's (consumer and
#: industrial MEMS parts: 0.1-1 deg/sqrt(h); fibre-optic and ring-laser gyros are well below;
#: Groves 2013, ch. 4, on the grades of inertial sensors): the figures given for it are a
#: datasheet's, which :data:`CONSUMER_IMU_NOISE_FACTOR` is for
MEMS_GYRO_ARW_DPSH = 0.1


def recommended_factor(gyro_arw_dpsh: float) -> float:
    """The ``imu_noise_factor`` to start from for an IMU whose gyro angle random walk is
    ``gyro_arw_dpsh``: :data:`CONSUMER_IMU_NOISE_FACTOR` for a MEMS gyro, 1 otherwise (a
    tactical or navigation-grade IMU's figures cover its errors far better)."""
    return CONSUMER_IMU_NOISE_FACTOR if gyro_arw_dpsh >= MEMS_GYRO_ARW_DPSH else 1.0


def suggested_factor(factor: float, nis_ratio: float) -> float:
    """The factor to try when a run's NIS is ``nis_ratio`` times its dof (median over a
    window) at ``factor``: ``factor`` times ``nis_ratio``, rounded up to one significant
    digit.  The innovation's variance grows more slowly than Q: were it Q's sigma, the
    factor would go by ``sqrt(nis_ratio)``; for a position-aided INS whose R is negligible
    (the steady state of a double integrator with position fixes, position variance
    proportional to ``q**0.25``, the continuous steady state ``sqrt(2) q**0.25 r**0.75``
    of the filter for white acceleration noise q and position noise r) by
    ``nis_ratio**2``.  The middle course is a value to try and check on the data: on the
    real drive of docs/guide/your_real_log.md the filters' windows give 20-30 at the factor 1,
    where 30 makes its sigma honest."""
    raw = factor * max(nis_ratio, 1.0)
    scale = 10.0 ** math.floor(math.log10(raw))
    return math.ceil(raw / scale - 1e-9) * scale


__all__ = ["CONSUMER_IMU_NOISE_FACTOR", "IMU_NOISE_PARAMETERS", "MEMS_GYRO_ARW_DPSH",
           "recommended_factor", "suggested_factor"]
