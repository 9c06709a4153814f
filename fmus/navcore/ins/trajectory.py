"""Truth trajectories from motion profiles, with the ideal IMU increments that produce them.

Kinematic model
---------------
The vehicle is described by its speed ``V`` [m/s], heading ``psi``, flight-path angle
``gamma`` and two attitude offsets (``roll_off``, ``pitch_off``) used by the attitude
manoeuvres and by turntable attitudes.  Velocity and attitude follow from them::

    v_ned = V [cos(gamma) cos(psi), cos(gamma) sin(psi), -sin(gamma)]
    yaw   = psi
    pitch = gamma + pitch_off
    roll  = atan(V psi_dot / g0) + roll_off      (coordinated-turn bank, g0 = 9.80665 m/s^2)

Every segment prescribes these quantities as closed-form functions of the time since the
segment start, so the state at any instant is exact and independent of the step size, and
each segment ends exactly on its documented final values.  Rates (``dV/dt``, ``psi_dot``)
follow a trapezoidal window whose edges are raised-cosine ramps of length ``transition``;
shapes (``gamma`` of a climb, attitude offsets) follow the same window (or a sine times it).
The ramps are C1, so angular rates and accelerations are continuous (no jumps) across
segment boundaries.  Position is not an independent kinematic variable: it is advanced step
by step with :func:`navcore.ins.strapdown.integrate_position` (trapezoid of the velocities), which
is also what the mechanization does, so the ideal increments returned by
:meth:`navcore.ins.strapdown.Strapdown.inverse_update` reproduce the truth exactly when a fresh
:class:`~navcore.ins.strapdown.Strapdown` integrates them.

The profiles themselves (format, checks, segment kinematics) are
:mod:`navcore.ins.profile_segments`; the built-in ones and the profile files
:mod:`navcore.ins.motion_profiles`.
"""
from __future__ import annotations

import copy
import math

import numpy as np

from . import ideal_track
from ..errors import ParameterError
from .constants import G0
from .motion_profiles import load_profile
from .profile_segments import compile_profile, evaluate, is_number, wrap_pi
from .rotations import _euler_rows
from .strapdown import Strapdown, integrate_position


class TrajectoryGenerator:
    """Steps a motion profile: truth state at ``t_k = k dt`` and the ideal IMU increments
    over ``[t_{k-1}, t_k]``.

    ``profile`` is a profile dict, a built-in name or a JSON file path (see
    :func:`load_profile`).  All state lives in plain attributes (deep-copyable and picklable),
    and stepping is deterministic.  After each :meth:`step`, ``last_rate_norm`` [rad/s] is
    ``|dtheta|/dt`` (inertial body rate, earth rate included) and ``last_accel_norm``
    [m/s^2] is ``|v_k - v_{k-1}|/dt`` (acceleration over the earth, without gravity: zero at
    rest), the manoeuvre-intensity measures used by the IMU error model.

    The samples are shared, through :mod:`navcore.ins.ideal_track`, with every other generator
    of the same profile and step in this process: a sample another generator has computed
    from the same state is read, not recomputed (the same floats).
    """

    state_fields = ("_seg", "_k", "time", "lat", "lon", "h", "_v", "_euler", "_ins",
                    "last_rate_norm", "last_accel_norm")
    derived_fields = ("profile", "dt", "_segments", "_duration", "_track_key")

    def __init__(self, profile, dt):
        if not isinstance(profile, dict):
            profile = load_profile(profile)
        if not (is_number(dt) and math.isfinite(dt) and dt > 0.0):
            raise ParameterError(f"trajectory: step 'dt' must be a finite number > 0, got {dt!r}")
        self.profile = copy.deepcopy(profile)
        self.dt = float(dt)
        start, self._segments = compile_profile(self.profile)
        self._duration = self._segments[-1]["t1"]
        self._seg = 0
        self._k = 0
        self.time = 0.0
        self.lat, self.lon, self.h = start["lat"], start["lon"], start["h"]
        V, psi, psi_dot, gamma, roll_off, pitch_off = evaluate(self._segments[0], 0.0)
        self._v = self._velocity(V, psi, gamma)
        self._euler = self._attitude(V, psi, psi_dot, gamma, roll_off, pitch_off)
        self._ins = Strapdown(self.lat, self.lon, self.h, self._v, _euler_rows(*self._euler))
        self.last_rate_norm = 0.0
        self.last_accel_norm = 0.0
        self._track_key = ideal_track.track_key(self.profile, self.dt)

    def _track_row(self):
        """This state, as a track row (the increments of the latest sample are the inverse
        strapdown's memory of them)."""
        ins = self._ins
        return (self.lat, self.lon, self.h, *self._v, *self._euler, *ins._dtheta_prev,
                *ins._dvel_prev, self.last_rate_norm, self.last_accel_norm, float(self._seg))

    @property
    def duration(self):
        """Length of the profile [s] (the generator keeps going afterwards, holding the end)."""
        return self._duration

    @staticmethod
    def _velocity(V, psi, gamma):
        cg = math.cos(gamma)
        return (V * cg * math.cos(psi), V * cg * math.sin(psi), -V * math.sin(gamma))

    @staticmethod
    def _attitude(V, psi, psi_dot, gamma, roll_off, pitch_off):
        return (math.atan(V * psi_dot / G0) + roll_off, gamma + pitch_off, psi)

    def _kinematics(self, t):
        segs = self._segments
        i = self._seg
        n = len(segs)
        while i < n and t > segs[i]["t1"]:
            i += 1
        self._seg = i
        if i == n:
            last = segs[-1]
            return last["V1"], last["psi1"], 0.0, 0.0, last["roll1"], last["pitch1"]
        rec = segs[i]
        return evaluate(rec, t - rec["t0"])

    def state(self):
        """Truth valid now: dict(time, lat, lon, h, vn, ve, vd, roll, pitch, yaw) in SI
        units; roll and yaw wrapped to (-pi, pi]."""
        roll, pitch, yaw = self._euler
        return {
            "time": self.time, "lat": self.lat, "lon": self.lon, "h": self.h,
            "vn": self._v[0], "ve": self._v[1], "vd": self._v[2],
            "roll": wrap_pi(roll), "pitch": pitch, "yaw": wrap_pi(yaw),
        }

    def step(self):
        """Advance by dt; return (truth dict at the new time, dtheta [rad, body, ndarray 3],
        dvel [m/s, body, ndarray 3]) with the increments over the step."""
        k = self._k + 1
        if k == 1:   # counted when it flies, not when built (a state restore builds one too)
            ideal_track.register(self._track_key, self._track_row())
        track = ideal_track.find(self._track_key)
        if track is None:
            return self._compute(k)
        state = (self.lat, self.lon, self.h, *self._v)
        row = track.row(k, state)
        if row is not None:
            return self._read(k, row)
        out = self._compute(k)
        if k == track.n:
            track.record(k, state, self._track_row())
        return out

    def _compute(self, k):
        t = k * self.dt
        V, psi, psi_dot, gamma, roll_off, pitch_off = self._kinematics(t)
        v_next = self._velocity(V, psi, gamma)
        lat, lon, h = integrate_position(self.lat, self.lon, self.h, self._v, v_next, self.dt)
        euler = self._attitude(V, psi, psi_dot, gamma, roll_off, pitch_off)
        # the position is integrate_position's of the velocities: no need to check it again
        dtheta, dvel = self._ins._inverse_to(lat, lon, h, v_next, _euler_rows(*euler), self.dt)
        v0 = self._v
        ax, ay, az = v_next[0] - v0[0], v_next[1] - v0[1], v_next[2] - v0[2]
        self.last_accel_norm = math.sqrt(ax * ax + ay * ay + az * az) / self.dt
        gx, gy, gz = dtheta.tolist()
        self.last_rate_norm = math.sqrt(gx * gx + gy * gy + gz * gz) / self.dt
        self._moved(k, lat, lon, h, v_next, euler)
        return self.state(), dtheta, dvel

    def _read(self, k, row):
        """Sample ``k`` from its track row: the state :meth:`_compute` would leave."""
        lat, lon, h = row[0], row[1], row[2]
        v_next, euler = row[3:6], row[6:9]
        dtheta, dvel = row[9:12], row[12:15]
        ins = self._ins
        ins._move_to(lat, lon, h, tuple(ins.v_ned.tolist()), v_next, _euler_rows(*euler),
                     dtheta, dvel)
        self.last_rate_norm, self.last_accel_norm = row[15], row[16]
        self._seg = int(row[17])
        self._moved(k, lat, lon, h, v_next, euler)
        return self.state(), np.array(dtheta), np.array(dvel)

    def _moved(self, k, lat, lon, h, v_next, euler):
        self._k = k
        self.time = k * self.dt
        self.lat, self.lon, self.h = lat, lon, h
        self._v = v_next
        self._euler = euler
