"""Motion-profile segments: checking a profile and the closed-form kinematics of a segment.

:func:`compile_profile` checks a profile dict (errors name the segment, its type and the
parameter) and turns it into plain-number segment records; :func:`evaluate` gives the
kinematic quantities of :mod:`navcore.ins.trajectory` (speed, heading, its rate, flight-path angle,
attitude offsets) at any time into a segment, in closed form.

Profile format (user documentation and an example: docs/guide/motion_profiles.md)
--------------------------------------------------------------------------------
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

import math
from typing import Any, Dict

from .constants import DEG as _D2R
from ..errors import ParameterError
from .rotations import _euler_from_rows, _euler_rows, _matmul_rows, _rodrigues_rows

DEFAULT_TRANSITION = 2.0
_PI = math.pi

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


def wrap_pi(a):
    """Wrap an angle [rad] to (-pi, pi] (Python floats)."""
    w = math.fmod(a + _PI, 2.0 * _PI)
    if w <= 0.0:
        w += 2.0 * _PI
    return w - _PI


# ---------------------------------------------------------------------------------------
# profile validation / compilation
# ---------------------------------------------------------------------------------------
def is_number(x):
    """True for an int or float that is not a bool."""
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
        if not is_number(x) or not math.isfinite(x):
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


def compile_profile(profile):
    """Check a profile and turn it into ``(start, segments)``: the start state and a list of
    plain-number segment records, each with its exact end state."""
    if not isinstance(profile, dict):
        raise ParameterError(
            f"profile must be a dict with 'start' and 'segments', got {type(profile).__name__}"
        )
    st = _compile_start(profile.get("start"))
    segments = profile.get("segments")
    if not isinstance(segments, list) or not segments:
        raise ParameterError("profile: 'segments' is missing or empty")
    state = (st["V"], st["psi"], st["roll_off"], st["pitch_off"])
    t0 = 0.0
    out = []
    for i, seg in enumerate(segments):
        rec = _compile_segment(i, seg, t0, *state)
        out.append(rec)
        state = (rec["V1"], rec["psi1"], rec["roll1"], rec["pitch1"])
        t0 += rec["D"]
    return st, out


def _compile_start(start):
    """The checked start state of a profile (angles in rad)."""
    if not isinstance(start, dict):
        raise ParameterError("profile: 'start' is missing or not an object")
    for key in start:
        if key not in _START_KEYS:
            raise ParameterError(
                f"profile start: unknown parameter '{key}' (known: {', '.join(_START_KEYS)})"
            )

    def start_value(name, default=None):
        if name not in start:
            if default is None:
                raise ParameterError(f"profile start: parameter '{name}' is missing")
            return default
        x = start[name]
        if not is_number(x) or not math.isfinite(x):
            raise ParameterError(
                f"profile start: parameter '{name}' must be a finite number, got {x!r}"
            )
        return float(x)

    lat_deg = start_value("lat_deg")
    if abs(lat_deg) >= 89.0:
        raise ParameterError(
            f"profile start: parameter 'lat_deg' must be within +-89 deg, got {lat_deg}"
        )
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
        raise ParameterError(
            f"profile start: parameter 'pitch_deg' must be within +-{_MAX_PITCH_DEG} deg"
        )
    return st


def _segment_reader(i, seg):
    """A reader for segment ``i`` after checking its type and parameter names."""
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
    return rd


def _compile_segment(i, seg, t0, V, psi, roll_off, pitch_off):
    """The record of segment ``i`` starting at ``t0`` from speed ``V``, heading ``psi`` and
    the attitude offsets, with its exact end state (``t1``, ``V1``, ``psi1``, ``roll1``,
    ``pitch1``)."""
    rd = _segment_reader(i, seg)
    kind = rd.type
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
    if kind in ("static", "hold_attitude", "rotate"):
        if V > 1e-9:
            rd.fail("type", f"needs the vehicle at rest, but the speed at segment start is "
                            f"{V:.6g} m/s (decelerate first: 'accelerate' with 'final_speed': 0)")
        V = rec["V0"] = 0.0
    V_end = _compile_speed_change(rd, rec, V) if kind in ("accelerate", "climb", "turn") else V
    _compile_shape(rd, rec, V, psi, roll_off, pitch_off)

    # end state, exact
    psi_end = psi + rec["turn"] * (D - rec["T"]) + rec["dpsi"]
    roll_end = roll_off + rec["droll"]
    pitch_end = pitch_off + rec["dpitch"]
    if kind == "rotate":
        _, psi_end, _, _, roll_end, pitch_end = evaluate(rec, D)
    rec.update(t1=t0 + D, V1=V_end, psi1=psi_end, roll1=roll_end, pitch1=pitch_end)
    return rec


def _compile_speed_change(rd, rec, V):
    """``accel``/``final_speed`` of an accelerate, climb or turn segment; returns the speed
    at the segment end."""
    D, Tw = rec["D"], rec["T"]
    which = rd.one_of("accel", "final_speed", required=(rd.type == "accelerate"))
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
    return max(V_end, 0.0)


def _compile_shape(rd, rec, V, psi, roll_off, pitch_off):
    """The type-specific part of a segment record: climb angle, turn rate, attitude
    manoeuvre, held attitude or turntable rotation."""
    kind, seg, Tw = rd.type, rd.seg, rec["T"]
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
            rec["turn"] = rd.get("heading_change_deg") * _D2R / (rec["D"] - Tw)
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
        rec["droll"] = wrap_pi(r_t - roll_off)
        rec["dpitch"] = p_t - pitch_off
        rec["dpsi"] = wrap_pi(y_t - psi)
    elif kind == "rotate":
        _compile_rotation(rd, rec, roll_off, pitch_off, psi)


def _rotation_angle(rec, tau):
    D, T = rec["D"], rec["T"]
    if T > 0.0:
        return rec["rate"] * _window_integral(tau, D, T)
    return rec["rate"] * min(max(tau, 0.0), D)


def _rotated_euler(rec, angle):
    a = rec["axis"]
    return _euler_from_rows(_matmul_rows(_rodrigues_rows(a[0] * angle, a[1] * angle,
                                                         a[2] * angle), rec["C0"]))


def _compile_rotation(rd, rec, roll_off, pitch_off, psi):
    """Axis and rate of a 'rotate' segment; checks that the pitch stays within limits."""
    axis = [rd.get(f"axis_{c}", default) for c, default in (("n", 0.0), ("e", 0.0),
                                                              ("d", 1.0))]
    norm = math.sqrt(sum(c * c for c in axis))
    if not norm > 0.0:
        rd.fail("axis_n", "axis_n, axis_e, axis_d must not all be zero")
    rec["axis"] = tuple(c / norm for c in axis)
    # the attitude at the segment start, rotated about the axis by _rotated_euler
    rec["C0"] = tuple(map(tuple, _euler_rows(rec["roll0"], rec["pitch0"], rec["psi0"])))
    which = rd.one_of("rate_deg", "angle_deg")
    if which == "rate_deg":
        rec["rate"] = rd.get("rate_deg") * _D2R
    else:
        rec["rate"] = rd.get("angle_deg") * _D2R / (rec["D"] - rec["T"])
    for i in range(101):
        _, pitch, _ = _rotated_euler(rec, _rotation_angle(rec, rec["D"] * i / 100.0))
        if abs(pitch) > _MAX_PITCH_DEG * _D2R:
            rd.fail(which, f"turns the pitch beyond +-{_MAX_PITCH_DEG} deg")


def evaluate(rec, tau):
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
        pitch_off += (
            rec["pitch_amp"]
            * w
            * (
                math.sin(2.0 * _PI * tau / rec["pitch_period"])
                if rec["pitch_shape"] == "sine"
                else 1.0
            )
        )
    return V, psi, psi_dot, gamma, roll_off, pitch_off
