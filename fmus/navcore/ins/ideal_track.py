"""The ideal samples of a motion profile, recorded once per process and read back by every
generator that flies the same profile with the same step.

The truth and the ideal IMU increments of :class:`navcore.ins.trajectory.TrajectoryGenerator`
are a function of the profile and the step ``dt`` alone: the random errors are added after
them (:mod:`navcore.sensors.imu_errors`).  The runs of a Monte Carlo campaign, of a filter
comparison or of a tuning loop therefore recompute the same samples again and again, the
inverse strapdown step included.  A *track* holds, for one (profile, dt), every sample some
generator of this process has computed: the first generator to reach sample ``k`` records
it, the others read it.  A track starts with the second generator of its profile and step
in the process, so a single run (or a host that flies a profile once) records nothing.
A sample is read only by a generator whose state is the recorded one of sample ``k - 1`` (its
position and velocity are compared), so a generator restored from a state that is not on the track
simply computes, as it would without the track. The recorded values are the floats the computation
produced: reading them gives the same numbers, bit for bit.

Memory: ``ROW`` floats (8 bytes each) per sample, at most ``MAX_SAMPLES`` samples per
process over all tracks (beyond it samples are computed and not recorded) and at most
``MAX_TRACKS`` tracks (the oldest is dropped first).  :func:`clear` drops every track.

The environment variable ``NAVFMU_SHARED_SAMPLES=0`` (read at each generator's first sample)
turns the tracks off: no track starts, none is read or extended, and every run costs what a
single run costs, which is what a benchmark comparing two runs in one process must measure
(``navfmu bench`` and ``benchmarks/ab_speed.py --flat`` set it).
"""
from __future__ import annotations

import json
import os
import struct
import threading
from array import array
from typing import Dict, Optional, Tuple

#: floats per sample: lat, lon, h, v_ned (3), unwrapped roll, pitch, yaw, dtheta (3),
#: dvel (3), rate norm, acceleration norm, segment index
ROW = 18
_ROW = struct.Struct(f"{ROW}d")       # native doubles: packing and unpacking are exact
_STATE = struct.Struct("6d")
#: samples kept per process over all tracks (8 bytes x ROW each: about 72 MB)
MAX_SAMPLES = 500_000
#: tracks kept per process
MAX_TRACKS = 8
#: profiles whose generators are counted (to start a track at the second)
MAX_SEEN = 64

Key = Tuple[str, float]

#: the environment variable that, set to 0, starts no track
SWITCH = "NAVFMU_SHARED_SAMPLES"


class IdealTrack:
    """The recorded samples of one (profile, dt): row ``k`` is the state after sample ``k``
    (row 0 the start)."""

    def __init__(self, start_row):
        self.values = array("d", start_row)
        self.n = 1

    def _holds(self, k: int, state) -> bool:
        """Whether row ``k`` holds ``state`` (lat, lon, h, vn, ve, vd)."""
        return _STATE.unpack_from(self.values, k * _ROW.size) == state

    def row(self, k: int, state) -> Optional[tuple]:
        """Row ``k`` if it is recorded and row ``k - 1`` holds ``state``."""
        if k >= self.n or not self._holds(k - 1, state):
            return None
        return _ROW.unpack_from(self.values, k * _ROW.size)

    def record(self, k: int, state, row) -> None:
        """Append ``row`` as row ``k`` if the track ends at row ``k - 1`` and that row
        holds ``state``, the state ``row`` was computed from."""
        global _recorded
        if _recorded >= MAX_SAMPLES:
            return
        with _LOCK:
            if k != self.n or not self._holds(k - 1, state):
                return
            self.values.frombytes(_ROW.pack(*row))
            self.n = k + 1
            _recorded += 1


_TRACKS: Dict[Key, IdealTrack] = {}
#: generators started per key (tracks start at the second)
_SEEN: Dict[Key, int] = {}
#: samples recorded in the tracks kept
_recorded = 0
#: the switch as read at the latest generator's first sample
_enabled = True
#: guards the tracks, their rows and the counts (threads of one process may share a track)
_LOCK = threading.Lock()


def track_key(profile: dict, dt: float) -> Key:
    """The key of a profile's track: its canonical JSON text and the step."""
    return json.dumps(profile, sort_keys=True, default=repr), float(dt)


def register(key: Key, start_row) -> None:
    """A generator of ``key`` takes its first sample from ``start_row`` (its state at sample
    0).  The second one in this process starts the track: a profile flown once records
    nothing."""
    global _enabled
    _enabled = os.environ.get(SWITCH, "1") != "0"
    if key in _TRACKS or not _enabled:
        return
    with _LOCK:
        _SEEN[key] = _SEEN.get(key, 0) + 1
        if len(_SEEN) > MAX_SEEN:
            del _SEEN[next(iter(_SEEN))]
        if _SEEN[key] >= 2 and key not in _TRACKS:
            while len(_TRACKS) >= MAX_TRACKS:
                _drop(next(iter(_TRACKS)))
            _TRACKS[key] = IdealTrack(start_row)


def find(key: Key) -> Optional[IdealTrack]:
    """The track of ``key`` if there is one and tracks are on (the switch as the latest
    generator to start found it: off, no generator reads or extends a track)."""
    return _TRACKS.get(key) if _enabled else None


def clear() -> None:
    """Drop every track."""
    with _LOCK:
        for key in list(_TRACKS):
            _drop(key)
        _SEEN.clear()


def _fresh_lock_in_child() -> None:
    """A forked child starts with an unlocked lock: a lock held by another thread of the
    parent at the fork would otherwise never be released in the child."""
    global _LOCK
    _LOCK = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_fresh_lock_in_child)


def _drop(key: Key) -> None:
    global _recorded
    _recorded -= _TRACKS.pop(key).n - 1
