"""Simulated land vehicles for the land aids' tests: a car with two stops and a walk with
stops, their known rest intervals, and their sensors run once (:mod:`direct_replay`).

The trajectory generator has no road: a car at constant speed is, to an ideal IMU, at rest.
A vehicle's vibration while it moves stands in for the road, an engine or the steps: the
IMU's white noise is ``VIBRATION`` times larger inside the moving intervals
(``noise_level_windows``), and the filters assume the moving level.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from direct_replay import MODELS, simulate_sensors

START = {"lat_deg": 40.1, "lon_deg": 118.6, "h": 100.0, "speed": 0.0, "yaw_deg": 30.0}
VIBRATION = 5.0


def _go(duration, speed, transition=2.0):
    return {"type": "accelerate", "duration": duration, "final_speed": speed,
            "transition": transition}


def _segments(spec):
    """(segments, rest intervals [(t0, t1)]) of ``spec``: (kind, duration[, value])."""
    segments, rests, t = [], [], 0.0
    for kind, duration, *value in spec:
        if kind == "stop":
            segments.append({"type": "static", "duration": duration})
            rests.append((t, t + duration))
        elif kind == "speed":
            segments.append(_go(duration, value[0], min(2.0, duration / 2)))
        elif kind == "turn":
            segments.append({"type": "turn", "duration": duration,
                             "heading_change_deg": value[0], "transition": 2.0})
        else:
            segments.append({"type": "cruise", "duration": duration})
        t += duration
    return segments, rests, t


#: the car: 12 m/s streets, a 30 s stop from 88 s and a 20 s stop from 214 s
CAR = (("stop", 20.0), ("speed", 10.0, 12.0), ("cruise", 20.0), ("turn", 10.0, 90.0),
       ("cruise", 20.0), ("speed", 8.0, 0.0), ("stop", 30.0), ("speed", 8.0, 10.0),
       ("cruise", 10.0), ("turn", 10.0, -90.0), ("cruise", 30.0), ("turn", 10.0, 60.0),
       ("cruise", 20.0), ("speed", 8.0, 0.0), ("stop", 20.0), ("speed", 10.0, 8.0),
       ("cruise", 20.0))
#: the car's outages: one over its first stop, one while it drives (turn and straight)
CAR_OUTAGES = ((84.0, 114.0), (140.0, 170.0))
#: the walk: 1.4 m/s, a 5 s stop every 12-16 s
WALK = (("stop", 20.0), *(
    part for turn in (0.0, 90.0, 0.0, -90.0, 45.0, 0.0)
    for part in (("speed", 2.0, 1.4), ("turn", 8.0, turn) if turn else ("cruise", 8.0, 0.0),
                 ("speed", 2.0, 0.0), ("stop", 5.0))), ("speed", 2.0, 1.4), ("cruise", 10.0))
WALK_OUTAGES = ((40.0, 100.0),)


def profile(spec):
    """(profile dict, rest intervals, duration) of a vehicle ``spec``."""
    segments, rests, duration = _segments(spec)
    return {"start": dict(START), "segments": segments}, rests, duration


def moving_windows(rests, duration, factor=VIBRATION):
    """``noise_level_windows`` text: ``factor`` outside the rest intervals."""
    edges = [0.0] + [x for r in rests for x in r] + [duration + 1.0]
    return "; ".join(f"{a},{b},{factor}" for a, b in zip(edges[::2], edges[1::2]) if b > a)


#: the receiver's white noise only (the scenario's correlated errors and biases off), so
#: the error in an outage is the inertial drift the aids act on
CLEAN_GNSS = {f"{q}_{a}": 0.0 for q in ("pos_gm_sigma", "pos_bias_sigma", "vel_gm_sigma")
              for a in "ned"}


def vehicle_sensors(spec, outages, folder: Path, seed=1):
    """(sensors, rests, duration) of a vehicle run with GNSS ``outages`` (the mems_outages
    scenario's MEMS IMU and receiver)."""
    prof, rests, duration = profile(spec)
    path = folder / "profile.json"
    path.write_text(json.dumps(prof))
    sensors = simulate_sensors(MODELS / "mems_outages", stop_time=duration, overrides={
        "trajectory": {"profile": str(path), "seed": seed,
                       "noise_level_windows": moving_windows(rests, duration)},
        "gnss": {"outages": "; ".join(f"{a},{b}" for a, b in outages), **CLEAN_GNSS}})
    return sensors, rests, duration


#: the filters' start and the moving noise level (the scenario's IMU figures times VIBRATION)
FILTER_START = {
    "init_lat": math.radians(START["lat_deg"]), "init_lon": math.radians(START["lon_deg"]),
    "init_h": START["h"], "init_vn": 0.0, "init_ve": 0.0, "init_vd": 0.0,
    "init_roll": 0.0, "init_pitch": 0.0, "init_yaw": math.radians(START["yaw_deg"]),
    "r_pos_n": 0.5, "r_pos_e": 0.5, "r_pos_d": 0.5, "r_vel_n": 0.05, "r_vel_e": 0.05,
    "r_vel_d": 0.05, "q_gyro_arw_dpsh": 0.3 * VIBRATION, "q_accel_vrw_ugpsHz": 150.0 * VIBRATION,
}
#: the detector's thresholds for this IMU at rest (accel noise 0.018 m/s^2, rate 0.06 deg/s
#: per 50 Hz sample; five times that while moving)
DETECTOR = {"stationary_accel_std": 0.04, "stationary_rate_rms": math.radians(0.15)}


def outage_errors(run, outages):
    """Per outage: (RMS, end, max) of the horizontal position error [m] at the fix epochs
    of ``run`` (one row per receiver epoch, fixes or not) inside it."""
    t = run.sensors.time[run.rows]
    err = run.position_error_ned()
    horizontal = np.hypot(err[:, 0], err[:, 1])
    out = []
    for a, b in outages:
        k = np.flatnonzero((t > a) & (t <= b))
        out.append((float(np.sqrt(np.mean(horizontal[k] ** 2))), float(horizontal[k[-1]]),
                    float(horizontal[k].max())))
    return out
