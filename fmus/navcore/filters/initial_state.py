"""Where an INS/GNSS filter starts: the given state, the first GNSS fix, or a static alignment
(parameter ``init_mode`` of every filter).

``given`` (default)
    The parameters ``init_*``, from the start (the papers' scenarios, unchanged).  At the first
    valid fix the filter compares its position with the fix (:func:`disagreement`, the
    innovation at the fix's time, before the update): off by
    more than :data:`INIT_CHECK_SIGMAS` sigmas on an axis (sigma = sqrt(P + R) of that axis)
    it warns once, naming the axis, the distance and ``init_mode = 'gnss'``.
``gnss``
    Position and velocity from the first valid fix once the vehicle moves (horizontal speed at
    least ``init_speed_min``): the fix's own velocity with ``measurement`` =
    ``position_velocity``, else the mean velocity between two consecutive fixes at most
    :data:`MAX_DIFFERENCED_FIX_GAP` apart; the position carried to the IMU epoch with that
    velocity; yaw from the course over ground ``atan2(v_e, v_n)`` (a vehicle moving forward,
    no sideslip or crab); roll and pitch by leveling (below) over the latest stretch of IMU
    intervals at rest (:func:`at_rest`), else roll 0 and pitch from the flight-path angle
    ``atan2(-v_d, v_h)``.  Groves (2013), *Principles of GNSS, Inertial, and Multisensor
    Integrated Navigation Systems*, 2nd ed., sec. 5.6.1 (position and velocity from GNSS) and
    sec. 5.6.2 (attitude from the trajectory and leveling).
``static``
    As ``gnss``, and before it the rest period the IMU shows is detected, levels the IMU and
    gives the gyro biases (:mod:`navcore.filters.static_alignment`).
``align``
    Static coarse alignment over the first ``align_time`` seconds of IMU intervals (the
    vehicle at rest): leveling from the mean specific force and gyrocompassing from the mean
    angular rate (:func:`coarse_alignment`; Groves 2013 sec. 5.6.2; Titterton & Weston (2004),
    *Strapdown Inertial Navigation Technology*, 2nd ed., sec. 10.4.2 -- the analytic coarse
    alignment); velocity 0, position from the first valid fix (or the given one when no fix
    came by then).  Gyrocompassing needs gyros that sense the Earth rate (15 deg/h times the
    cosine of the latitude): the heading error is about the gyro bias / (Earth rate cos(lat))
    rad, so 0.01 deg/h gives 0.05 deg at 40 deg latitude while a MEMS gyro of 10 deg/h gives
    no heading at all (use ``gnss`` there).
    Roll and pitch start with the level's own sigma (:func:`level_sigma` of the accelerometer
    bias sigma), as with ``static``, not the configured ``p0_att_level``.

Until the state is known the filter integrates nothing: it follows the IMU's time tags
(``nav_time``), outputs the given state with ``aligned`` = false (the metrics skip those
samples) and applies no fix.  The covariance it starts with has the configured ``p0_*``, each
raised to what the method knows at least (:meth:`Initializer.start_sigmas`).
"""
from __future__ import annotations

import math

import numpy as np

from ..ins import earth
from ..core.component import Limits, real, string
from ..ins.rotations import euler_to_dcm, wrap_angle

INIT_MODES = ("given", "gnss", "align", "static")
#: the modes that start at a fix once moving (``static``: with the static alignment of
#: :mod:`navcore.filters.static_alignment` before it)
FROM_FIX = ("gnss", "static")
#: a given state farther from the first fix than this many sigmas (sqrt(P + R)) is warned of
INIT_CHECK_SIGMAS = 5.0
#: default horizontal speed from which the course over ground is the heading [m/s]: a slow
#: walk (people walk at 1.2-1.4 m/s; a walk at 1.8 m/s never reached the former 2 m/s).  A
#: low speed costs no false confidence: the heading's sigma is the course's own, atan(sigma_v
#: / v) (:meth:`Initializer.start_sigmas`), 3 deg at 1 m/s for a 0.05 m/s velocity sigma
DEFAULT_INIT_SPEED = 1.0
#: a filter waiting for a fix at init_speed_min this long after its first valid fix warns [s]
INIT_WAIT_WARNING_S = 60.0
#: default length of a static alignment [s]
DEFAULT_ALIGN_TIME = 60.0
#: largest time between two fixes whose positions give the initial velocity [s]
MAX_DIFFERENCED_FIX_GAP = 2.0
#: an IMU interval is at rest when |f| is within this of gravity [m/s^2] ...
REST_ACCEL_TOLERANCE = 0.3
#: ... and |omega| below this [rad/s] (about 1 deg/s)
REST_RATE_TOLERANCE = 0.02
#: heading 1-sigma after a course initialization: atan(velocity sigma / speed), at least this
#: [rad] (what the course cannot see: a car's sideslip, a walker's sway)
MIN_COURSE_SIGMA = math.radians(2.0)
#: level 1-sigma without a rest stretch (roll 0, pitch from the flight path) [rad]
NO_REST_LEVEL_SIGMA = math.radians(5.0)

INIT_PARAMETERS = (
    string("init_mode", "initial state: 'given' (the init_* parameters), 'gnss' (first fix "
           "once moving: position, velocity, yaw from the course, level from the "
           "accelerometers at rest), 'align' (static coarse alignment: leveling and "
           "gyrocompassing over align_time) or 'static' (as 'gnss', levelled and the gyro "
           "biases estimated over the rest period the IMU shows before the start)", "given"),
    real("init_speed_min", "m/s", "init_mode 'gnss': horizontal speed from which the course "
         "over ground gives the heading (a slow walk)", DEFAULT_INIT_SPEED,
         Limits(0.0, 1e3, low_open=True)),
    real("align_time", "s", "init_mode 'align': length of the static alignment from the start",
         DEFAULT_ALIGN_TIME, Limits(0.0, 3600.0, low_open=True)),
)


def level(f_body):
    """(roll, pitch) [rad] from the specific force at rest ``f_body`` (FRD, = -gravity)."""
    fx, fy, fz = (float(x) for x in f_body)
    return math.atan2(-fy, -fz), math.atan2(fx, math.hypot(fy, fz))


def level_sigma(accel_bias_sigma, g, f_std=(0.0, 0.0), n=1):
    """1-sigma [rad] of roll and pitch levelled on the mean specific force of ``n`` intervals
    at rest (:func:`level`): ``hypot(accelerometer bias sigma, f_std / sqrt(n)) / g``, the
    larger of the two horizontal axes (a horizontal accelerometer bias b tilts the level by
    b / g and the rest cannot tell them apart; ``f_std`` the spread of the specific force,
    m/s^2).  ``accel_bias_sigma`` (the first two used) [m/s^2], ``g`` [m/s^2]."""
    return float(np.max(np.hypot(np.asarray(accel_bias_sigma, dtype=float)[:2],
                                 np.asarray(f_std, dtype=float)[:2] / math.sqrt(n)))) / g


def coarse_alignment(f_body, w_body):
    """(roll, pitch, yaw) [rad] from the mean specific force and angular rate at rest: roll
    and pitch by leveling, yaw from the horizontal part of the Earth rate (north) seen in the
    leveled frame: with ``w_l = C(roll, pitch, 0) w_body``, ``yaw = atan2(-w_l,y, w_l,x)``."""
    roll, pitch = level(f_body)
    w_level = euler_to_dcm(roll, pitch, 0.0) @ np.asarray(w_body, dtype=float)
    return roll, pitch, math.atan2(-w_level[1], w_level[0])


def at_rest(dtheta, dvel, dt, g) -> bool:
    """An interval at rest: specific force of magnitude ``g`` and angular rate near zero,
    within :data:`REST_ACCEL_TOLERANCE` and :data:`REST_RATE_TOLERANCE`."""
    f = math.sqrt(sum(x * x for x in dvel)) / dt
    w = math.sqrt(sum(x * x for x in dtheta)) / dt
    return abs(f - g) < REST_ACCEL_TOLERANCE and w < REST_RATE_TOLERANCE


def disagreement(z_pos, pos_var, r_pos):
    """Largest normalized distance of the INS position from a fix over the NED axes, from the
    innovation ``z_pos`` (INS - fix, NED metres) with sigma sqrt(``pos_var`` + ``r_pos``^2):
    (distance in sigmas, axis index, metres)."""
    d = np.asarray(z_pos, dtype=float)[:3]
    sigma = np.sqrt(np.asarray(pos_var, dtype=float) + np.asarray(r_pos, dtype=float) ** 2)
    k = int(np.argmax(np.abs(d) / sigma))
    return float(abs(d[k]) / sigma[k]), k, float(d[k])


class Initializer:
    """Collects IMU intervals and fixes until the initial state is known (module
    docstring); ``done`` from the start for ``given``."""

    state_fields = ("done", "elapsed", "rest_dvel", "rest_dtheta", "rest_time", "all_dvel",
                    "all_dtheta", "previous_fix", "first_position", "checked", "warned",
                    "first_fix_time", "fastest", "wait_warned", "velocity_gap", "start_std")
    derived_fields = ("mode", "speed_min", "align_time", "use_fix_velocity")

    def __init__(self, mode, speed_min=DEFAULT_INIT_SPEED, align_time=DEFAULT_ALIGN_TIME,
                 use_fix_velocity=True):
        self.mode, self.speed_min, self.align_time = mode, speed_min, align_time
        self.use_fix_velocity = use_fix_velocity
        self.done = mode == "given"
        self.checked = False          # given: the first fix was compared with the state
        self.warned = False           # ... and found too far from it (warned once)
        self.elapsed = 0.0
        self.rest_dvel, self.rest_dtheta, self.rest_time = np.zeros(3), np.zeros(3), 0.0
        self.all_dvel, self.all_dtheta = np.zeros(3), np.zeros(3)
        self.previous_fix = None      # (time, lat, lon, h)
        self.first_position = None    # (lat, lon, h)
        self.first_fix_time = None    # gnss: time of the first valid fix [s]
        self.fastest = 0.0            # ... and the largest horizontal speed since [m/s]
        self.wait_warned = False      # ... and the wait was warned of
        self.velocity_gap = MAX_DIFFERENCED_FIX_GAP   # [s] between the fixes differenced
        self.start_std = None         # the receiver's sigmas N/E/D of the fix started from

    # -- intervals -------------------------------------------------------------------------
    def add_interval(self, dtheta, dvel, dt, lat, h):
        """One IMU interval before the state is known (``lat``, ``h``: for gravity)."""
        self.elapsed += dt
        self.all_dtheta += dtheta
        self.all_dvel += dvel
        if at_rest(dtheta, dvel, dt, earth.gravity(lat, h)):
            self.rest_dtheta += dtheta
            self.rest_dvel += dvel
            self.rest_time += dt
        elif self.mode in FROM_FIX:    # the latest stretch at rest is the one levelled on
            self.rest_dtheta, self.rest_dvel, self.rest_time = np.zeros(3), np.zeros(3), 0.0

    def alignment_ready(self) -> bool:
        return self.mode == "align" and self.elapsed >= self.align_time - 1e-9

    # -- fixes -----------------------------------------------------------------------------
    def _velocity(self, fix):
        """The velocity at the fix [m/s, NED], or None when it is not known yet."""
        t, lat, lon, h, v = fix[:5]
        if self.use_fix_velocity:
            return np.array(v, dtype=float)
        previous, self.previous_fix = self.previous_fix, (t, lat, lon, h)
        if previous is None or not 0.0 < t - previous[0] <= MAX_DIFFERENCED_FIX_GAP:
            return None
        t0, lat0, lon0, h0 = previous
        self.velocity_gap = t - t0
        rn, re = earth.radii(lat)
        return np.array([(lat - lat0) * (rn + h), wrap_angle(lon - lon0) * (re + h)
                         * math.cos(lat), -(h - h0)]) / (t - t0)

    def state_from_fix(self, fix, nav_time):
        """(lat, lon, h, v_ned, roll, pitch, yaw) at ``nav_time`` from a valid ``fix``
        (time, lat, lon, h, v, ...) in mode ``gnss``, or None while the vehicle is not moving."""
        t, lat, lon, h = fix[:4]
        if self.first_position is None:
            self.first_position = (lat, lon, h)
            self.first_fix_time = t
        v = self._velocity(fix)
        if v is not None:
            self.fastest = max(self.fastest, math.hypot(v[0], v[1]))
        if v is None or math.hypot(v[0], v[1]) < self.speed_min:
            return None
        age = nav_time - t
        rn, re = earth.radii(lat)
        lat_now = lat + v[0] * age / (rn + h)
        lon_now = lon + v[1] * age / ((re + h) * math.cos(lat))
        if self.rest_time > 0.0:
            roll, pitch = level(self.rest_dvel / self.rest_time)
        else:
            roll, pitch = 0.0, math.atan2(-v[2], math.hypot(v[0], v[1]))
        yaw = math.atan2(v[1], v[0])
        if len(fix) > 5:
            self.start_std = np.array(fix[5], dtype=float)
        return lat_now, lon_now, h - v[2] * age, v, roll, pitch, yaw

    def waiting_warning(self, t):
        """Mode ``gnss``: the warning (once) that no fix at ``init_speed_min`` came in the
        :data:`INIT_WAIT_WARNING_S` seconds since the first valid fix, at gnss_time ``t``; else
        None.  Without it a walk below the speed ran to its end on the given state."""
        if (self.done or self.wait_warned or self.first_fix_time is None
                or t - self.first_fix_time < INIT_WAIT_WARNING_S):
            return None
        self.wait_warned = True
        return (f"init_mode 'gnss': no fix with a horizontal speed of at least init_speed_min "
                f"= {self.speed_min:g} m/s in the {t - self.first_fix_time:.4g} s since the "
                f"first valid fix (the fastest: {self.fastest:.3g} m/s); the filter has not "
                "started and outputs its given state (aligned = false) until one comes: lower "
                "init_speed_min, or set init_mode = 'given' or 'align'")

    def note_fix(self, fix):
        """A valid fix in mode ``align``: its position is the alignment's."""
        if self.first_position is None:
            self.first_position = tuple(fix[1:4])

    def state_from_alignment(self, given_position):
        """(lat, lon, h, v_ned, roll, pitch, yaw) of the static alignment (mode ``align``),
        at the first fix's position or ``given_position`` (lat, lon, h)."""
        lat, lon, h = self.first_position or given_position
        roll, pitch, yaw = coarse_alignment(self.all_dvel / self.elapsed,
                                            self.all_dtheta / self.elapsed)
        return lat, lon, h, np.zeros(3), roll, pitch, yaw

    def start_sigmas(self, p0, r_sigma, speed):
        """The initial 1-sigma vector ``p0`` (15,) with position, velocity and attitude
        raised to what the method knows at least: the fix's sigma for position and
        velocity (``gnss``) and :data:`NO_REST_LEVEL_SIGMA` for a level taken from the
        flight path.  The yaw's sigma (``gnss``) is the course's own, whatever the configured
        one (which belongs to the given state): the course ``atan2(v_e, v_n)`` of a velocity
        whose horizontal sigma is ``sigma_v`` is off by ``atan(sigma_v / speed)`` (the
        cross-track velocity error over the speed, first order; Groves 2013 sec. 5.6.2,
        heading from the trajectory), at least :data:`MIN_COURSE_SIGMA`.  Keeping a
        configured 100 deg after taking the yaw from a 10 m/s course left the UKF's first
        updates to turn the heading on a 100 deg uncertainty (outages ended 79 m off on a
        real car against Kf's 9 m)."""
        p0 = np.array(p0, dtype=float)
        if self.mode in FROM_FIX:
            p0[0:3] = np.maximum(p0[0:3], r_sigma[0:3])
            v_sigma = (r_sigma[3:6] if len(r_sigma) == 6 else
                       math.sqrt(2.0) * r_sigma[0:3] / self.velocity_gap)
            p0[3:6] = np.maximum(p0[3:6], v_sigma)
            p0[8] = max(MIN_COURSE_SIGMA, math.atan2(float(max(v_sigma[:2])), speed))
            if self.rest_time == 0.0:
                p0[6:8] = np.maximum(p0[6:8], NO_REST_LEVEL_SIGMA)
        return p0
