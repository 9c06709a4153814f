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
by step with :func:`navcore.strapdown.integrate_position` (trapezoid of the velocities), which
is also what the mechanization does, so the ideal increments returned by
:meth:`navcore.strapdown.Strapdown.inverse_update` reproduce the truth exactly when a fresh
:class:`~navcore.strapdown.Strapdown` integrates them.

Profile format
--------------
``{"start": {"lat_deg", "lon_deg", "h", "speed" (0), "yaw_deg" (0), "pitch_deg" (0),
"roll_deg" (0)}, "segments": [{"type": ..., "duration": s, ...}, ...]}``; the start pitch and
roll are attitude offsets (the start flight-path angle is zero).  Segment types and their
parameters (angles in degrees; ``transition`` [s], default 2, is the ramp length, capped at
half the duration; 0 gives abrupt changes):

``static``
    at rest (the speed at its start must be 0), attitude held.
``level`` / ``cruise``
    constant velocity.
``accelerate``
    along-track speed change: ``accel`` [m/s^2, peak, signed] or ``final_speed`` [m/s].
``climb``
    ``climb_angle_deg`` (target flight-path angle, negative = descend) or ``vertical_rate``
    [m/s, up positive; angle from the speed at segment start]; the flight path pitches to the
    target over ``transition``, holds, and returns to level over ``transition`` at the end.
    Optional ``accel`` or ``final_speed``.
``turn``
    coordinated turn: ``turn_rate_deg`` [deg/s, peak, positive = right] or
    ``heading_change_deg``; bank = atan(V psi_dot / g0).  Optional ``accel``/``final_speed``.
``roll`` / ``pitch``
    attitude manoeuvre about the flight path: ``amplitude_deg`` (signed) and, for
    ``shape`` "sine" (default), ``period`` [s]: offset = A sin(2 pi t / period) * window;
    ``shape`` "step": offset = A * window (ramp in, hold, ramp out).
``hold_attitude``
    turntable-style attitude at rest: ``roll_deg``, ``pitch_deg``, ``yaw_deg``, reached over
    ``transition`` (default 2 s) by raised-cosine ramps, then held.
``rotate``
    turntable rotation at rest about an axis fixed in the room: ``axis_n``, ``axis_e``,
    ``axis_d`` (NED components, normalised; default down = a yaw table) and ``rate_deg``
    [deg/s, peak] or ``angle_deg`` (total); the rate follows the trapezoidal window,
    ``C_bn(t) = exp([a x] angle(t)) C_bn(start)``.  The pitch must stay within +-85 deg.

After the last segment the final state is held (straight level flight or rest).
"""
from __future__ import annotations

import copy
import json
import math
from typing import Any, Dict

from .component import ParameterError
from .rotations import _euler_from_rows, _euler_rows, _matmul_rows, _rodrigues_rows
from .strapdown import Strapdown, integrate_position

#: standard gravity used for the coordinated-turn bank angle [m/s^2]
G0 = 9.80665
DEFAULT_TRANSITION = 2.0
_PI = math.pi
_D2R = math.pi / 180.0

_COMMON = ("type", "duration", "transition")
_ALLOWED = {
    "static": (),
    "level": (),
    "cruise": (),
    "accelerate": ("accel", "final_speed"),
    "climb": ("climb_angle_deg", "vertical_rate", "accel", "final_speed"),
    "turn": ("turn_rate_deg", "heading_change_deg", "accel", "final_speed"),
    "roll": ("amplitude_deg", "period", "shape"),
    "pitch": ("amplitude_deg", "period", "shape"),
    "hold_attitude": ("roll_deg", "pitch_deg", "yaw_deg"),
    "rotate": ("axis_n", "axis_e", "axis_d", "rate_deg", "angle_deg"),
}
_START_KEYS = ("lat_deg", "lon_deg", "h", "speed", "yaw_deg", "pitch_deg", "roll_deg")
_MAX_PITCH_DEG = 85.0


# ---------------------------------------------------------------------------------------
# window functions (C1 raised-cosine ramps) and their integrals
# ---------------------------------------------------------------------------------------
def _ramp(tau, T):
    if tau <= 0.0:
        return 0.0
    if tau >= T:
        return 1.0
    return 0.5 * (1.0 - math.cos(_PI * tau / T))


def _ramp_integral(tau, T):
    if tau <= 0.0:
        return 0.0
    if tau >= T:
        return tau - 0.5 * T
    return 0.5 * (tau - T / _PI * math.sin(_PI * tau / T))


def _window(tau, D, T):
    """0 -> 1 over [0, T], 1, 1 -> 0 over [D-T, D]."""
    return _ramp(tau, T) - _ramp(tau - (D - T), T)


def _window_integral(tau, D, T):
    """Integral of _window from 0 to tau; equals D - T at tau = D."""
    return _ramp_integral(tau, T) - _ramp_integral(tau - (D - T), T)


def _wrap(a):
    w = math.fmod(a + _PI, 2.0 * _PI)
    if w <= 0.0:
        w += 2.0 * _PI
    return w - _PI


# ---------------------------------------------------------------------------------------
# profile validation / compilation
# ---------------------------------------------------------------------------------------
def _is_number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


class _SegmentReader:
    """Reads and checks the parameters of one segment; errors name index, type, parameter."""

    def __init__(self, index, seg):
        self.index = index
        self.seg = seg
        self.type = seg.get("type") if isinstance(seg, dict) else None

    def fail(self, name, reason):
        raise ParameterError(
            f"profile segment {self.index} ('{self.type}'): parameter '{name}' {reason}")

    def get(self, name, default=None, required=False, minimum=None, strict=False):
        if name not in self.seg:
            if required:
                self.fail(name, "is missing")
            return default
        x = self.seg[name]
        if not _is_number(x) or not math.isfinite(x):
            self.fail(name, f"must be a finite number, got {x!r}")
        x = float(x)
        if minimum is not None and (x <= minimum if strict else x < minimum):
            self.fail(name, f"must be {'>' if strict else '>='} {minimum}, got {x}")
        return x

    def one_of(self, a, b, required=True):
        has_a, has_b = a in self.seg, b in self.seg
        if has_a and has_b:
            self.fail(a, f"and '{b}' are exclusive: give one of them")
        if required and not (has_a or has_b):
            self.fail(a, f"is missing (give '{a}' or '{b}')")
        return a if has_a else (b if has_b else None)


def _compile(profile):
    """Check a profile and turn it into a list of plain-number segment records."""
    if not isinstance(profile, dict):
        raise ParameterError(f"profile must be a dict with 'start' and 'segments', got {type(profile).__name__}")
    start = profile.get("start")
    if not isinstance(start, dict):
        raise ParameterError("profile: 'start' is missing or not an object")
    for key in start:
        if key not in _START_KEYS:
            raise ParameterError(f"profile start: unknown parameter '{key}' (known: {', '.join(_START_KEYS)})")

    def start_value(name, default=None):
        if name not in start:
            if default is None:
                raise ParameterError(f"profile start: parameter '{name}' is missing")
            return default
        x = start[name]
        if not _is_number(x) or not math.isfinite(x):
            raise ParameterError(f"profile start: parameter '{name}' must be a finite number, got {x!r}")
        return float(x)

    lat_deg = start_value("lat_deg")
    if abs(lat_deg) >= 89.0:
        raise ParameterError(f"profile start: parameter 'lat_deg' must be within +-89 deg, got {lat_deg}")
    st = {
        "lat": lat_deg * _D2R,
        "lon": start_value("lon_deg") * _D2R,
        "h": start_value("h"),
        "V": start_value("speed", 0.0),
        "psi": start_value("yaw_deg", 0.0) * _D2R,
        "pitch_off": start_value("pitch_deg", 0.0) * _D2R,
        "roll_off": start_value("roll_deg", 0.0) * _D2R,
    }
    if st["V"] < 0.0:
        raise ParameterError(f"profile start: parameter 'speed' must be >= 0, got {st['V']}")
    if abs(st["pitch_off"]) > _MAX_PITCH_DEG * _D2R:
        raise ParameterError(f"profile start: parameter 'pitch_deg' must be within +-{_MAX_PITCH_DEG} deg")

    segments = profile.get("segments")
    if not isinstance(segments, list) or not segments:
        raise ParameterError("profile: 'segments' is missing or empty")

    V, psi, roll_off, pitch_off = st["V"], st["psi"], st["roll_off"], st["pitch_off"]
    t0 = 0.0
    out = []
    for i, seg in enumerate(segments):
        rd = _SegmentReader(i, seg)
        if not isinstance(seg, dict):
            raise ParameterError(f"profile segment {i}: must be an object, got {seg!r}")
        kind = seg.get("type")
        if kind not in _ALLOWED:
            raise ParameterError(
                f"profile segment {i} ('{kind}'): parameter 'type' is unknown "
                f"(known: {', '.join(sorted(_ALLOWED))})")
        for key in seg:
            if key not in _COMMON and key not in _ALLOWED[kind]:
                rd.fail(key, f"is not known for this type (known: "
                             f"{', '.join(_COMMON[1:] + _ALLOWED[kind])})")
        D = rd.get("duration", required=True, minimum=0.0, strict=True)
        T = rd.get("transition", DEFAULT_TRANSITION, minimum=0.0)
        rec: Dict[str, Any] = {
            "index": i, "type": kind, "t0": t0, "D": D,
            "T": min(T, 0.5 * D), "Th": min(T, D),
            "V0": V, "psi0": psi, "roll0": roll_off, "pitch0": pitch_off,
            "accel": 0.0, "turn": 0.0, "gamma": 0.0,
            "roll_amp": 0.0, "roll_period": 0.0, "roll_shape": "none",
            "pitch_amp": 0.0, "pitch_period": 0.0, "pitch_shape": "none",
            "droll": 0.0, "dpitch": 0.0, "dpsi": 0.0,
            "axis": (0.0, 0.0, 1.0), "rate": 0.0,
        }
        Tw = rec["T"]
        if kind in ("static", "hold_attitude", "rotate"):
            if V > 1e-9:
                rd.fail("type", f"needs the vehicle at rest, but the speed at segment start is "
                                f"{V:.6g} m/s (decelerate first: 'accelerate' with 'final_speed': 0)")
            V = rec["V0"] = 0.0
        if kind in ("accelerate", "climb", "turn"):
            which = rd.one_of("accel", "final_speed", required=(kind == "accelerate"))
            if which == "accel":
                rec["accel"] = rd.get("accel")
            elif which == "final_speed":
                vf = rd.get("final_speed", minimum=0.0)
                rec["accel"] = (vf - V) / (D - Tw)
            V_end = V + rec["accel"] * (D - Tw)
            if which == "final_speed":
                V_end = vf
            if V_end < -1e-9:
                rd.fail(which, f"makes the speed negative ({V_end:.6g} m/s at segment end)")
            V_end = max(V_end, 0.0)
        else:
            V_end = V
        if kind == "climb":
            which = rd.one_of("climb_angle_deg", "vertical_rate")
            if which == "climb_angle_deg":
                gam = rd.get("climb_angle_deg") * _D2R
            else:
                vr = rd.get("vertical_rate")
                if not abs(vr) < V:
                    rd.fail("vertical_rate", f"({vr} m/s) must be smaller in magnitude than the "
                                             f"speed at segment start ({V:.6g} m/s)")
                gam = math.asin(vr / V)
            if abs(gam) + abs(pitch_off) > _MAX_PITCH_DEG * _D2R:
                rd.fail(which, f"gives a pitch beyond +-{_MAX_PITCH_DEG} deg")
            rec["gamma"] = gam
        elif kind == "turn":
            which = rd.one_of("turn_rate_deg", "heading_change_deg")
            if which == "turn_rate_deg":
                rec["turn"] = rd.get("turn_rate_deg") * _D2R
            else:
                rec["turn"] = rd.get("heading_change_deg") * _D2R / (D - Tw)
        elif kind in ("roll", "pitch"):
            amp = rd.get("amplitude_deg", required=True) * _D2R
            shape = seg.get("shape", "sine")
            if shape not in ("sine", "step"):
                rd.fail("shape", f"must be 'sine' or 'step', got {shape!r}")
            period = rd.get("period", required=(shape == "sine"), minimum=0.0, strict=True) or 0.0
            if kind == "pitch" and abs(amp) + abs(pitch_off) > _MAX_PITCH_DEG * _D2R:
                rd.fail("amplitude_deg", f"gives a pitch beyond +-{_MAX_PITCH_DEG} deg")
            rec[kind + "_amp"], rec[kind + "_period"], rec[kind + "_shape"] = amp, period, shape
        elif kind == "hold_attitude":
            r_t = rd.get("roll_deg", required=True) * _D2R
            p_t = rd.get("pitch_deg", required=True) * _D2R
            y_t = rd.get("yaw_deg", required=True) * _D2R
            if abs(p_t) > _MAX_PITCH_DEG * _D2R:
                rd.fail("pitch_deg", f"must be within +-{_MAX_PITCH_DEG} deg")
            rec["droll"] = _wrap(r_t - roll_off)
            rec["dpitch"] = p_t - pitch_off
            rec["dpsi"] = _wrap(y_t - psi)
        elif kind == "rotate":
            _compile_rotation(rd, rec, roll_off, pitch_off, psi)

        # end state, exact
        psi_end = psi + rec["turn"] * (D - Tw) + rec["dpsi"]
        roll_end = roll_off + rec["droll"]
        pitch_end = pitch_off + rec["dpitch"]
        if kind == "rotate":
            _, psi_end, _, _, roll_end, pitch_end = _evaluate(rec, D)
        rec.update(t1=t0 + D, V1=V_end, psi1=psi_end, roll1=roll_end, pitch1=pitch_end)
        out.append(rec)
        V, psi, roll_off, pitch_off = V_end, psi_end, roll_end, pitch_end
        t0 += D
    return st, out


def _rotation_angle(rec, tau):
    D, T = rec["D"], rec["T"]
    if T > 0.0:
        return rec["rate"] * _window_integral(tau, D, T)
    return rec["rate"] * min(max(tau, 0.0), D)


def _rotated_euler(rec, angle):
    a = rec["axis"]
    C0 = _euler_rows(rec["roll0"], rec["pitch0"], rec["psi0"])
    return _euler_from_rows(_matmul_rows(_rodrigues_rows(a[0] * angle, a[1] * angle,
                                                         a[2] * angle), C0))


def _compile_rotation(rd, rec, roll_off, pitch_off, psi):
    """Axis and rate of a 'rotate' segment; checks that the pitch stays within limits."""
    axis = [rd.get(f"axis_{c}", default) for c, default in (("n", 0.0), ("e", 0.0),
                                                              ("d", 1.0))]
    norm = math.sqrt(sum(c * c for c in axis))
    if not norm > 0.0:
        rd.fail("axis_n", "axis_n, axis_e, axis_d must not all be zero")
    rec["axis"] = tuple(c / norm for c in axis)
    which = rd.one_of("rate_deg", "angle_deg")
    if which == "rate_deg":
        rec["rate"] = rd.get("rate_deg") * _D2R
    else:
        rec["rate"] = rd.get("angle_deg") * _D2R / (rec["D"] - rec["T"])
    for i in range(101):
        _, pitch, _ = _rotated_euler(rec, _rotation_angle(rec, rec["D"] * i / 100.0))
        if abs(pitch) > _MAX_PITCH_DEG * _D2R:
            rd.fail(which, f"turns the pitch beyond +-{_MAX_PITCH_DEG} deg")


def _evaluate(rec, tau):
    """(V, psi, psi_dot, gamma, roll_off, pitch_off) at time tau into segment ``rec``."""
    D, T = rec["D"], rec["T"]
    kind = rec["type"]
    if kind == "rotate":
        roll, pitch, yaw = _rotated_euler(rec, _rotation_angle(rec, tau))
        return 0.0, yaw, 0.0, 0.0, roll, pitch
    if kind == "hold_attitude":
        r = _ramp(tau, rec["Th"]) if rec["Th"] > 0.0 else 1.0
        return (0.0, rec["psi0"] + rec["dpsi"] * r, 0.0, 0.0,
                rec["roll0"] + rec["droll"] * r, rec["pitch0"] + rec["dpitch"] * r)
    if T > 0.0:
        w = _window(tau, D, T)
        W = _window_integral(tau, D, T)
    else:  # abrupt: rates on for the whole segment
        w = 1.0 if 0.0 < tau < D else 0.0
        W = min(max(tau, 0.0), D)
    V = rec["V0"] + rec["accel"] * W
    if V < 0.0:
        V = 0.0
    psi = rec["psi0"] + rec["turn"] * W
    psi_dot = rec["turn"] * w
    gamma = rec["gamma"] * w
    roll_off = rec["roll0"]
    pitch_off = rec["pitch0"]
    if kind == "roll":
        roll_off += rec["roll_amp"] * w * (
            math.sin(2.0 * _PI * tau / rec["roll_period"]) if rec["roll_shape"] == "sine" else 1.0)
    elif kind == "pitch":
        pitch_off += rec["pitch_amp"] * w * (
            math.sin(2.0 * _PI * tau / rec["pitch_period"]) if rec["pitch_shape"] == "sine" else 1.0)
    return V, psi, psi_dot, gamma, roll_off, pitch_off


class TrajectoryGenerator:
    """Steps a motion profile: truth state at ``t_k = k dt`` and the ideal IMU increments
    over ``[t_{k-1}, t_k]``.

    ``profile`` is a profile dict, a built-in name or a JSON file path (see
    :func:`load_profile`).  All state lives in plain attributes (deep-copyable and picklable),
    and stepping is deterministic.  After each :meth:`step`, ``last_rate_norm`` [rad/s] is
    ``|dtheta|/dt`` (inertial body rate, earth rate included) and ``last_accel_norm``
    [m/s^2] is ``|v_k - v_{k-1}|/dt`` (acceleration over the earth, without gravity: zero at
    rest), the manoeuvre-intensity measures used by the IMU error model.
    """

    state_fields = ("_seg", "_k", "time", "lat", "lon", "h", "_v", "_euler", "_ins",
                    "last_rate_norm", "last_accel_norm")
    derived_fields = ("profile", "dt", "_segments", "_duration")

    def __init__(self, profile, dt):
        if not isinstance(profile, dict):
            profile = load_profile(profile)
        if not (_is_number(dt) and math.isfinite(dt) and dt > 0.0):
            raise ParameterError(f"trajectory: step 'dt' must be a finite number > 0, got {dt!r}")
        self.profile = copy.deepcopy(profile)
        self.dt = float(dt)
        start, self._segments = _compile(self.profile)
        self._duration = self._segments[-1]["t1"]
        self._seg = 0
        self._k = 0
        self.time = 0.0
        self.lat, self.lon, self.h = start["lat"], start["lon"], start["h"]
        V, psi, psi_dot, gamma, roll_off, pitch_off = _evaluate(self._segments[0], 0.0)
        self._v = self._velocity(V, psi, gamma)
        self._euler = self._attitude(V, psi, psi_dot, gamma, roll_off, pitch_off)
        self._ins = Strapdown(self.lat, self.lon, self.h, self._v, _euler_rows(*self._euler))
        self.last_rate_norm = 0.0
        self.last_accel_norm = 0.0

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
        return _evaluate(rec, t - rec["t0"])

    def state(self):
        """Truth valid now: dict(time, lat, lon, h, vn, ve, vd, roll, pitch, yaw) in SI
        units; roll and yaw wrapped to (-pi, pi]."""
        roll, pitch, yaw = self._euler
        return {
            "time": self.time, "lat": self.lat, "lon": self.lon, "h": self.h,
            "vn": self._v[0], "ve": self._v[1], "vd": self._v[2],
            "roll": _wrap(roll), "pitch": pitch, "yaw": _wrap(yaw),
        }

    def step(self):
        """Advance by dt; return (truth dict at the new time, dtheta [rad, body, ndarray 3],
        dvel [m/s, body, ndarray 3]) with the increments over the step."""
        k = self._k + 1
        t = k * self.dt
        V, psi, psi_dot, gamma, roll_off, pitch_off = self._kinematics(t)
        v_next = self._velocity(V, psi, gamma)
        lat, lon, h = integrate_position(self.lat, self.lon, self.h, self._v, v_next, self.dt)
        euler = self._attitude(V, psi, psi_dot, gamma, roll_off, pitch_off)
        dtheta, dvel = self._ins.inverse_update(lat, lon, h, v_next, _euler_rows(*euler), self.dt)
        v0 = self._v
        ax, ay, az = v_next[0] - v0[0], v_next[1] - v0[1], v_next[2] - v0[2]
        self.last_accel_norm = math.sqrt(ax * ax + ay * ay + az * az) / self.dt
        gx, gy, gz = dtheta.tolist()
        self.last_rate_norm = math.sqrt(gx * gx + gy * gy + gz * gz) / self.dt
        self._k = k
        self.time = t
        self.lat, self.lon, self.h = lat, lon, h
        self._v = v_next
        self._euler = euler
        return self.state(), dtheta, dvel


# ---------------------------------------------------------------------------------------
# built-in profiles
# ---------------------------------------------------------------------------------------
def _static_profile():
    """One hour at rest at 40.1 N, 118.6 E, 100 m, level, heading north."""
    return {
        "start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 100.0, "speed": 0.0, "yaw_deg": 0.0},
        "segments": [{"type": "static", "duration": 3600.0}],
    }


def _aircraft_500s_profile():
    """Paper 001 (Yuan et al.): 500 s flight from 118.6 E, 40.1 N, 100 m.

    The paper lists only the phases (takeoff run, climb, accelerated level flight, climb,
    accelerated level flight, uniform level flight, turn) and the total of 500 s; the numbers
    are our choice, typical of a jet trainer, heading north at the start:

    ========  ======  ============================================================
    t [s]     phase   values
    ========  ======  ============================================================
    0-40      takeoff run on the runway, 0 -> 80 m/s (peak 2.1 m/s^2)
    40-80     climb at 10 deg flight-path angle (5 s pitch-up / level-off), ~ +490 m
    80-130    level acceleration 80 -> 150 m/s
    130-190   climb at 10 deg (5 s transitions), ~ +1430 m -> about 2020 m
    190-240   level acceleration 150 -> 200 m/s
    240-440   uniform level flight (cruise) at 200 m/s
    440-500   coordinated 180 deg right turn, peak 3.2 deg/s (bank ~49 deg)
    ========  ======  ============================================================
    """
    return {
        "start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 100.0, "speed": 0.0, "yaw_deg": 0.0},
        "segments": [
            {"type": "accelerate", "duration": 40.0, "final_speed": 80.0, "transition": 2.0},
            {"type": "climb", "duration": 40.0, "climb_angle_deg": 10.0, "transition": 5.0},
            {"type": "accelerate", "duration": 50.0, "final_speed": 150.0, "transition": 3.0},
            {"type": "climb", "duration": 60.0, "climb_angle_deg": 10.0, "transition": 5.0},
            {"type": "accelerate", "duration": 50.0, "final_speed": 200.0, "transition": 3.0},
            {"type": "cruise", "duration": 200.0},
            {"type": "turn", "duration": 60.0, "heading_change_deg": 180.0, "transition": 4.0},
        ],
    }


def _manoeuvre_1h_profile():
    """One hour of mixed manoeuvres at 100-150 m/s from 40.1 N, 118.6 E, 1000 m: six copies
    of a 600 s block of turns (+90, -120, +180, -150 deg at 2.4-3.2 deg/s), paired climbs
    and descents (+-8 deg, +-5 deg; net height change zero), speed changes 100 <-> 150 m/s,
    a roll oscillation (15 deg, 10 s period) and a pitch oscillation (5 deg, 8 s)."""
    block = [
        {"type": "level", "duration": 20.0},
        {"type": "turn", "duration": 40.0, "heading_change_deg": 90.0, "transition": 3.0},
        {"type": "climb", "duration": 60.0, "climb_angle_deg": 8.0, "transition": 4.0},
        {"type": "climb", "duration": 60.0, "climb_angle_deg": -8.0, "transition": 4.0},
        {"type": "accelerate", "duration": 40.0, "final_speed": 150.0},
        {"type": "turn", "duration": 50.0, "heading_change_deg": -120.0, "transition": 3.0},
        {"type": "roll", "duration": 40.0, "amplitude_deg": 15.0, "period": 10.0},
        {"type": "climb", "duration": 40.0, "climb_angle_deg": 5.0, "transition": 4.0},
        {"type": "climb", "duration": 40.0, "climb_angle_deg": -5.0, "transition": 4.0},
        {"type": "accelerate", "duration": 40.0, "final_speed": 100.0},
        {"type": "turn", "duration": 60.0, "heading_change_deg": 180.0, "transition": 4.0},
        {"type": "pitch", "duration": 40.0, "amplitude_deg": 5.0, "period": 8.0},
        {"type": "turn", "duration": 50.0, "heading_change_deg": -150.0, "transition": 3.0},
        {"type": "level", "duration": 20.0},
    ]
    return {
        "start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 1000.0, "speed": 100.0, "yaw_deg": 30.0},
        "segments": [dict(s) for _ in range(6) for s in block],
    }


def _uav_maneuver_profile():
    """Paper 000 (Yang et al.): about 60 min of UAV flight, strong manoeuvres 0-10 min and
    20-50 min, low dynamics 10-20 min and after 50 min (the paper's Fig. 3 description).

    Our choices (the paper shows plots only): start in flight at 34.2 N, 108.9 E, 500 m,
    40 m/s, heading 45 deg.  A 300 s strong block: turns of 90-180 deg at 8-10 deg/s (bank
    up to ~45 deg), paired climbs/descents of 8-15 deg, speed changes between 30 and 60 m/s
    (up to 2.7 m/s^2), a roll oscillation (20 deg, 4 s period) and a pitch oscillation
    (8 deg, 5 s period).  A 600 s low-dynamics block: straight level flight with two gentle
    30 deg turns (0.55 deg/s) and a slow 40 -> 45 m/s speed change.  Sequence: strong x2
    (0-600 s), low (600-1200 s), strong x6 (1200-3000 s), low (3000-3600 s).
    """
    strong = [
        {"type": "turn", "duration": 12.0, "heading_change_deg": 90.0, "transition": 1.5},
        {"type": "climb", "duration": 20.0, "climb_angle_deg": 10.0},
        {"type": "climb", "duration": 20.0, "climb_angle_deg": -10.0},
        {"type": "accelerate", "duration": 12.0, "final_speed": 55.0, "transition": 1.5},
        {"type": "turn", "duration": 15.0, "heading_change_deg": -135.0, "transition": 1.5},
        {"type": "climb", "duration": 20.0, "climb_angle_deg": 8.0},
        {"type": "climb", "duration": 20.0, "climb_angle_deg": -8.0},
        {"type": "roll", "duration": 16.0, "amplitude_deg": 20.0, "period": 4.0, "transition": 1.5},
        {"type": "accelerate", "duration": 15.0, "final_speed": 30.0, "transition": 1.5},
        {"type": "turn", "duration": 20.0, "heading_change_deg": 180.0},
        {"type": "pitch", "duration": 15.0, "amplitude_deg": 8.0, "period": 5.0, "transition": 1.5},
        {"type": "climb", "duration": 20.0, "climb_angle_deg": 15.0},
        {"type": "climb", "duration": 20.0, "climb_angle_deg": -15.0},
        {"type": "accelerate", "duration": 15.0, "final_speed": 60.0, "transition": 1.5},
        {"type": "turn", "duration": 15.0, "heading_change_deg": 90.0, "transition": 1.5},
        {"type": "accelerate", "duration": 15.0, "final_speed": 40.0, "transition": 1.5},
        {"type": "turn", "duration": 15.0, "heading_change_deg": -135.0, "transition": 1.5},
        {"type": "level", "duration": 15.0},
    ]
    low = [
        {"type": "level", "duration": 200.0},
        {"type": "turn", "duration": 60.0, "heading_change_deg": 30.0, "transition": 5.0},
        {"type": "level", "duration": 100.0},
        {"type": "accelerate", "duration": 60.0, "final_speed": 45.0, "transition": 5.0},
        {"type": "turn", "duration": 60.0, "heading_change_deg": -30.0, "transition": 5.0},
        {"type": "level", "duration": 120.0},
    ]
    blocks = [strong, strong, low] + [strong] * 6 + [low]
    return {
        "start": {"lat_deg": 34.2, "lon_deg": 108.9, "h": 500.0, "speed": 40.0, "yaw_deg": 45.0},
        "segments": [dict(s) for b in blocks for s in b],
    }


def _turntable_240s_profile():
    """Paper 003 (Xiao & Lu): 240 s on a turntable at rest at one attitude ("placed at a
    random angle"; ours: roll 8, pitch 12, yaw 35 deg) at the authors' institute in
    Shijiazhuang, 38.04 N, 114.51 E, 80 m.  The vibration from 121 s is a sensor disturbance
    (TrajectoryImu's vibration parameters), not a motion."""
    return {
        "start": {"lat_deg": 38.04, "lon_deg": 114.51, "h": 80.0, "speed": 0.0,
                  "roll_deg": 8.0, "pitch_deg": 12.0, "yaw_deg": 35.0},
        "segments": [{"type": "static", "duration": 240.0}],
    }


_BUILTIN = {
    "static": _static_profile,
    "turntable_240s": _turntable_240s_profile,
    "aircraft_500s": _aircraft_500s_profile,
    "manoeuvre_1h": _manoeuvre_1h_profile,
    "uav_maneuver": _uav_maneuver_profile,
}

#: names accepted by builtin_profile
BUILTIN_PROFILES = tuple(_BUILTIN)
#: largest motion-profile file read (a profile of 10 000 segments is about 1 MB)
MAX_PROFILE_BYTES = 4 * 1024 * 1024


def builtin_profile(name):
    """A fresh copy of a built-in profile: one of ``BUILTIN_PROFILES``."""
    try:
        return _BUILTIN[name]()
    except (KeyError, TypeError):
        raise ParameterError(
            f"profile '{name}' is not a built-in profile (known: {', '.join(BUILTIN_PROFILES)}) "
            "and not a file") from None


def load_profile(path_or_name):
    """A built-in profile by name, or a profile read from a JSON file (as data, at most
    :data:`MAX_PROFILE_BYTES`); the profile is checked (as :class:`TrajectoryGenerator`
    would) before it is returned."""
    if isinstance(path_or_name, str) and path_or_name in _BUILTIN:
        return builtin_profile(path_or_name)
    path = str(path_or_name)
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_PROFILE_BYTES + 1)
        if len(data) > MAX_PROFILE_BYTES:
            raise ParameterError(f"profile file '{path}' is larger than the {MAX_PROFILE_BYTES} "
                                 "bytes a motion profile may have")
        profile = json.loads(data.decode("utf-8"))
    except FileNotFoundError:
        raise ParameterError(
            f"profile '{path}' is neither a built-in profile ({', '.join(BUILTIN_PROFILES)}) "
            "nor an existing file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ParameterError(f"profile file '{path}' cannot be read: {e}") from None
    except (json.JSONDecodeError, RecursionError) as e:
        raise ParameterError(f"profile file '{path}' is not valid JSON: {e}") from None
    try:
        _compile(profile)
    except ParameterError as e:
        raise ParameterError(f"profile file '{path}': {e}") from None
    return profile
