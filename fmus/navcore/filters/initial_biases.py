"""Initial sensor biases of every INS/GNSS filter: given per axis, or the gyro bias estimated
from a static interval at the start.

Given (parameters ``init_gyro_bias_x/y/z`` [rad/s], ``init_accel_bias_x/y/z`` [m/s^2], 0 by
default): the filter starts with these biases removed from the IMU, with the 1-sigma per axis
``p0_gyro_bias_x/y/z`` [rad/s] and ``p0_accel_bias_x/y/z`` [m/s^2] (0, the default: the
axis takes ``p0_gyro_bias_dph`` / ``p0_accel_bias_ug``, one sigma for every axis).  A consumer
gyro's turn-on bias (600-980 deg/h on a walk's IMU) known from a calibration goes here.

Static (``init_static_time`` > 0 s, with ``init_mode`` = ``gnss``): the IMU intervals of the
first ``init_static_time`` seconds, the vehicle at rest, give the gyro bias: the mean angular
rate less the Earth rate's vertical component seen in the body (levelled on the same
interval: roll and pitch from the mean specific force), ``b = mean(w) - C_nb' [0, 0,
-omega_ie sin(lat)]``.  The Earth rate's horizontal part, ``omega_ie cos(lat)`` (11.5 deg/h at
40 deg latitude), needs the heading, unknown at rest for a MEMS gyro (it cannot gyrocompass),
so it stays in the estimate: the bias's 1-sigma is ``hypot(spread / sqrt(n), omega_ie
cos(lat))`` with the per-axis standard deviation ``spread`` of the n rates (Groves 2013,
*Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., sec.
5.6.3 (fine alignment / zero-velocity calibration of the gyro biases at rest); Titterton &
Weston 2004, sec. 10.4).  The accelerometer biases are not observable at rest apart from the
level (a bias along a level axis is a tilt), so they stay as given.  Data that is not static
-- a per-axis standard deviation of the specific force above :data:`STATIC_ACCEL_SPREAD` or of
the angular rate above :data:`STATIC_RATE_SPREAD` -- gives a warning and no estimate.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from ..core.component import Limits, real
from ..ins.constants import WGS84_OMEGA_IE
from ..ins.rotations import euler_to_dcm
from .initial_state import level

#: largest per-axis standard deviation of the specific force of a static interval [m/s^2]
#: (a MEMS accelerometer at rest: a few mm/s^2 of noise; an idling car's vibration stays below)
STATIC_ACCEL_SPREAD = 0.2
#: ... and of the angular rate [rad/s] (0.57 deg/s)
STATIC_RATE_SPREAD = 0.01
#: a static interval shorter than this is too short to estimate anything [s]
MIN_STATIC_TIME = 1.0

AXES = ("x", "y", "z")
_GYRO_BIAS_LIMITS = Limits(-1.0, 1.0)        # rad/s (57 deg/s)
_ACCEL_BIAS_LIMITS = Limits(-5.0, 5.0)       # m/s^2
_GYRO_SIGMA_LIMITS = Limits(0.0, 1.0)
_ACCEL_SIGMA_LIMITS = Limits(0.0, 5.0)

INITIAL_BIAS_PARAMETERS = (
    *(real(f"init_gyro_bias_{a}", "rad/s", f"initial gyro bias, body {a}", 0.0,
           _GYRO_BIAS_LIMITS) for a in AXES),
    *(real(f"init_accel_bias_{a}", "m/s2", f"initial accelerometer bias, body {a}", 0.0,
           _ACCEL_BIAS_LIMITS) for a in AXES),
    *(real(f"p0_gyro_bias_{a}", "rad/s", f"initial 1-sigma gyro bias, body {a} (0: "
           "p0_gyro_bias_dph)", 0.0, _GYRO_SIGMA_LIMITS) for a in AXES),
    *(real(f"p0_accel_bias_{a}", "m/s2", f"initial 1-sigma accelerometer bias, body {a} (0: "
           "p0_accel_bias_ug)", 0.0, _ACCEL_SIGMA_LIMITS) for a in AXES),
    real("init_static_time", "s", "init_mode 'gnss': length of the static interval at the start "
         "whose mean angular rate gives the initial gyro bias (0 = none)", 0.0,
         Limits(0.0, 3600.0)),
)


def given_biases(params):
    """(gyro bias [rad/s], accel bias [m/s^2]) (3,) each, from the parameters."""
    return (np.array([params[f"init_gyro_bias_{a}"] for a in AXES], dtype=float),
            np.array([params[f"init_accel_bias_{a}"] for a in AXES], dtype=float))


def bias_sigmas(params, gyro_sigma, accel_sigma):
    """The initial 1-sigmas of the gyro and accel biases (6,): per axis the parameter
    ``p0_*_bias_<axis>`` where it is positive, else the one-for-all ``gyro_sigma`` /
    ``accel_sigma`` [SI]."""
    gyro = [params[f"p0_gyro_bias_{a}"] or gyro_sigma for a in AXES]
    accel = [params[f"p0_accel_bias_{a}"] or accel_sigma for a in AXES]
    return np.array(gyro + accel, dtype=float)


class StaticBiasEstimator:
    """The sums of the IMU intervals of the static interval at the start (module docstring);
    one per filter, fed by the filter until its state is known."""

    state_fields = ("elapsed", "n", "sum_w", "sum_w2", "sum_f", "sum_f2")
    derived_fields = ("length",)

    def __init__(self, length):
        self.length = float(length)
        self.elapsed = 0.0
        self.n = 0
        self.sum_w, self.sum_w2 = np.zeros(3), np.zeros(3)
        self.sum_f, self.sum_f2 = np.zeros(3), np.zeros(3)

    def add_interval(self, dtheta, dvel, dt):
        """One IMU interval from the start (ignored past ``length``)."""
        if self.length <= 0.0 or self.elapsed >= self.length - 1e-9:
            return
        self.elapsed += dt
        w = np.asarray(dtheta, dtype=float) / dt
        f = np.asarray(dvel, dtype=float) / dt
        self.n += 1
        self.sum_w += w
        self.sum_w2 += w * w
        self.sum_f += f
        self.sum_f2 += f * f

    def _spread(self, total, squares):
        mean = total / self.n
        return mean, np.sqrt(np.maximum(squares / self.n - mean * mean, 0.0))

    def estimate(self, lat):
        """(gyro bias (3,) [rad/s], its 1-sigma (3,), None) at latitude ``lat``, or (None,
        None, warning) when the interval is too short or not static (module docstring)."""
        if self.elapsed < MIN_STATIC_TIME:
            return None, None, (f"init_static_time = {self.length:g} s: only "
                                f"{self.elapsed:.3g} s of IMU data before the start (at least "
                                f"{MIN_STATIC_TIME:g} s): the gyro bias is not estimated")
        w, w_spread = self._spread(self.sum_w, self.sum_w2)
        f, f_spread = self._spread(self.sum_f, self.sum_f2)
        if f_spread.max() > STATIC_ACCEL_SPREAD or w_spread.max() > STATIC_RATE_SPREAD:
            return None, None, (
                f"init_static_time = {self.length:g} s: the IMU is not static over the first "
                f"{self.elapsed:.4g} s (standard deviation of the specific force up to "
                f"{f_spread.max():.3g} m/s^2, limit {STATIC_ACCEL_SPREAD:g}; of the angular "
                f"rate up to {w_spread.max():.3g} rad/s, limit {STATIC_RATE_SPREAD:g}): the "
                "gyro bias is not estimated; shorten init_static_time to the part at rest")
        bias, sigma = gyro_bias_at_rest(w, w_spread, f, self.n, lat)
        return bias, sigma, None


def gyro_bias_at_rest(w, w_spread, f, n, lat):
    """(gyro bias (3,), its 1-sigma (3,)) [rad/s] from the mean angular rate ``w``, its
    per-axis standard deviation ``w_spread`` and the mean specific force ``f`` of ``n`` IMU
    intervals at rest at latitude ``lat`` (module docstring): the rate less the vertical
    Earth rate seen in the body levelled on ``f``."""
    roll, pitch = level(f)
    c_nb = euler_to_dcm(roll, pitch, 0.0).T     # n -> b of the levelled frame
    earth_down = np.array([0.0, 0.0, -WGS84_OMEGA_IE * math.sin(lat)])
    return (np.asarray(w, dtype=float) - c_nb @ earth_down,
            np.hypot(np.asarray(w_spread) / math.sqrt(n), WGS84_OMEGA_IE * math.cos(lat)))


def check_static_mode(init_mode: str, static_time: float) -> Optional[str]:
    """Why ``init_static_time`` cannot be used with ``init_mode`` (None when it can)."""
    if static_time > 0.0 and init_mode != "gnss":
        return (f"> 0 needs init_mode = 'gnss' (the static interval comes before the start "
                f"from the data), got init_mode = {init_mode!r}")
    return None


__all__ = ["INITIAL_BIAS_PARAMETERS", "MIN_STATIC_TIME", "STATIC_ACCEL_SPREAD",
           "STATIC_RATE_SPREAD", "StaticBiasEstimator", "bias_sigmas", "check_static_mode",
           "given_biases", "gyro_bias_at_rest"]
