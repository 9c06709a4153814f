"""Static alignment at the start (``init_mode = 'static'``): the rest period before the vehicle
moves, detected from the IMU, levels the IMU and gives the gyro biases; the heading comes
from the GNSS course once moving (as ``init_mode = 'gnss'``).

Motion detector: the IMU intervals are cut into windows of ``static_window`` seconds; a
window is at rest when the per-axis standard deviation of the specific force is at most
``static_accel_std`` and of the angular rate at most ``static_rate_std`` (the variance test
of a zero-velocity detector: Skog, Handel, Nilsson and Rantakokko 2010, "Zero-velocity
detection -- an algorithm evaluation", IEEE Trans. Biomed. Eng. 57(11); Groves 2013,
*Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., sec.
15.4.1).  The rest period is the latest run of consecutive windows at rest before the start
(a moving window ends the run, the next window at rest begins a new one), so a car that
idles, rolls a metre and stops again levels on its last stop, and the windows of the first
metres driven before the fix that starts the filter do not erase it.

Over the rest period, with the mean specific force ``f`` and angular rate ``w`` of its n
intervals (Groves 2013 sec. 5.6.2, leveling; sec. 5.6.3, gyro calibration at rest):

* roll = atan2(-f_y, -f_z), pitch = atan2(f_x, sqrt(f_y^2 + f_z^2));  their 1-sigma:
  hypot(accelerometer bias sigma, spread_f / sqrt(n)) / g (a horizontal accelerometer bias
  b tilts the level by b / g, and the rest cannot tell them apart);
* gyro bias = w - C_nb [0, 0, -omega_ie sin(lat)] (the vertical Earth rate in the levelled
  body), 1-sigma hypot(spread_w / sqrt(n), omega_ie cos(lat)) per axis
  (:func:`navcore.filters.initial_biases.gyro_bias_at_rest`: the horizontal Earth rate needs
  the heading a MEMS gyro cannot find).

Without a window at rest before the start the data is not static: one warning, and the
start is that of ``init_mode = 'gnss'`` (level from the accelerometers' latest quiet
intervals or the flight path, the gyro bias as given).
"""
from __future__ import annotations

import math

import numpy as np

from ..core.component import Limits, real
from .initial_biases import STATIC_ACCEL_SPREAD, STATIC_RATE_SPREAD, gyro_bias_at_rest
from .initial_state import level, level_sigma

#: default window of the motion detector [s]
DEFAULT_STATIC_WINDOW = 1.0

STATIC_PARAMETERS = (
    real("static_window", "s", "init_mode 'static': window of the motion detector (a window "
         "is at rest when the standard deviations below hold on every axis)",
         DEFAULT_STATIC_WINDOW, Limits(0.0, 600.0, low_open=True)),
    real("static_accel_std", "m/s2", "init_mode 'static': largest standard deviation of the "
         "specific force over a window at rest, per axis", STATIC_ACCEL_SPREAD,
         Limits(0.0, 100.0, low_open=True)),
    real("static_rate_std", "rad/s", "init_mode 'static': largest standard deviation of the "
         "angular rate over a window at rest, per axis", STATIC_RATE_SPREAD,
         Limits(0.0, 10.0, low_open=True)),
)


class _Sums:
    """n, duration and the sums of the rates, specific forces and their squares (3 each)."""

    state_fields = ("n", "time", "w", "w2", "f", "f2")

    def __init__(self):
        self.n, self.time = 0, 0.0
        self.w, self.w2, self.f, self.f2 = (np.zeros(3) for _ in range(4))

    def add(self, w, f, dt):
        self.n += 1
        self.time += dt
        self.w += w
        self.w2 += w * w
        self.f += f
        self.f2 += f * f

    def merge(self, other):
        self.n += other.n
        self.time += other.time
        for name in ("w", "w2", "f", "f2"):
            setattr(self, name, getattr(self, name) + getattr(other, name))

    def spreads(self):
        """(mean rate, its per-axis std, mean specific force, its per-axis std)."""
        w, f = self.w / self.n, self.f / self.n
        return (w, np.sqrt(np.maximum(self.w2 / self.n - w * w, 0.0)),
                f, np.sqrt(np.maximum(self.f2 / self.n - f * f, 0.0)))


class RestDetector:
    """The motion detector and the sums of the latest rest period (module docstring); fed
    with every IMU interval before the start."""

    state_fields = ("window", "rest", "resting", "quietest")
    derived_fields = ("length", "accel_std", "rate_std")

    def __init__(self, length=DEFAULT_STATIC_WINDOW, accel_std=STATIC_ACCEL_SPREAD,
                 rate_std=STATIC_RATE_SPREAD):
        self.length, self.accel_std, self.rate_std = float(length), accel_std, rate_std
        self.window, self.rest = _Sums(), _Sums()
        self.resting = False                      # the latest full window was at rest
        self.quietest = (math.inf, math.inf)      # of the windows seen: (accel std, rate std)

    def add_interval(self, dtheta, dvel, dt):
        """One IMU interval (increments over ``dt``)."""
        window = self.window
        window.add(np.asarray(dtheta, dtype=float) / dt, np.asarray(dvel, dtype=float) / dt, dt)
        if window.time < self.length - 1e-9:
            return
        _, w_std, _, f_std = window.spreads()
        at_rest = f_std.max() <= self.accel_std and w_std.max() <= self.rate_std
        if at_rest and not self.resting:          # a new rest period begins
            self.rest = _Sums()
        if at_rest:
            self.rest.merge(window)
        self.resting = at_rest
        if f_std.max() < self.quietest[0]:
            self.quietest = (float(f_std.max()), float(w_std.max()))
        self.window = _Sums()

    @property
    def rest_time(self):
        """[s] the length of the latest rest period."""
        return self.rest.time

    def estimate(self, lat, accel_bias_sigma, g):
        """(roll, pitch, level sigma, gyro bias (3,), its sigma (3,), None) from the rest
        period at latitude ``lat``, the accelerometer bias 1-sigma ``accel_bias_sigma`` (3,)
        [m/s^2] and gravity ``g``; or (None, ..., warning) without a window at rest."""
        if self.rest.n == 0:
            quiet = ("no full window yet" if not math.isfinite(self.quietest[0]) else
                     f"the quietest: standard deviation of the specific force "
                     f"{self.quietest[0]:.3g} m/s^2 (limit {self.accel_std:g}), of the "
                     f"angular rate {self.quietest[1]:.3g} rad/s (limit {self.rate_std:g})")
            return None, None, None, None, None, (
                f"init_mode 'static': the IMU is not static: no window of static_window = "
                f"{self.length:g} s at rest before the start ({quiet}); the IMU is levelled as "
                "with init_mode 'gnss' and the gyro bias is not estimated: start the log at "
                "rest, or raise static_accel_std / static_rate_std")
        w, w_std, f, f_std = self.rest.spreads()
        roll, pitch = level(f)
        bias, bias_sigma = gyro_bias_at_rest(w, w_std, f, self.rest.n, lat)
        return (roll, pitch, level_sigma(accel_bias_sigma, g, f_std, self.rest.n), bias,
                bias_sigma, None)


__all__ = ["DEFAULT_STATIC_WINDOW", "RestDetector", "STATIC_PARAMETERS"]
