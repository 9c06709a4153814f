"""Motion profiles: the built-in profiles of the papers' scenarios and profile files.

A profile is the dict :mod:`navcore.ins.profile_segments` describes; :func:`builtin_profile` gives
a fresh copy of a built-in one, :func:`load_profile` a built-in one by name or a checked
profile read from a JSON file.
"""
from __future__ import annotations

import json

from ..errors import ParameterError
from .profile_segments import compile_profile


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
    :data:`MAX_PROFILE_BYTES`); the profile is checked (as
    :class:`navcore.ins.trajectory.TrajectoryGenerator` would) before it is returned."""
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
        compile_profile(profile)
    except ParameterError as e:
        raise ParameterError(f"profile file '{path}': {e}") from None
    return profile
