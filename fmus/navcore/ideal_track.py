"""The ideal samples of a motion profile, recorded once per process and read back by every
generator that flies the same profile with the same step.

The truth and the ideal IMU increments of :class:`navcore.trajectory.TrajectoryGenerator`
are a function of the profile and the step ``dt`` alone: the random errors are added after
them (:mod:`navcore.imu_errors`).  The runs of a Monte Carlo campaign, of a filter
comparison or of a tuning loop therefore recompute the same samples again and again, the
inverse strapdown step included.  A *track* holds, for one (profile, dt), every sample some
generator of this process has computed: the first generator to reach sample ``k`` records
it, the others read it.  A track starts with the second generator of its profile and step
in the process, so a single run (or a host that flies a profile once) records nothing.  A sample is read only by a generator whose state is the recorded
one of sample ``k - 1`` (its position and velocity are compared), so a generator restored
from a state that is not on the track simply computes, as it would without the track.
The recorded values are the floats the computation produced: reading them gives the same
numbers, bit for bit.

Memory: ``ROW`` floats (8 bytes each) per sample, at most ``MAX_SAMPLES`` samples per
process over all tracks (beyond it samples are computed and not recorded) and at most
``MAX_TRACKS`` tracks (the oldest is dropped first).  :func:`clear` drops every track.

The environment variable ``NAVFMU_SHARED_SAMPLES=0`` (read when a generator starts) starts no
track: every run then costs what a single run costs, which is what a benchmark comparing two
runs in one process must measure (``navfmu bench`` and ``benchmarks/ab_speed.py --flat`` set
it).
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
        #: position and velocity of the last row
        self.last = tuple(start_row[:6])
        self.lock = threading.Lock()

    def row(self, k: int, state) -> Optional[tuple]:
        """Row ``k`` if it is recorded and row ``k - 1`` holds ``state`` (lat, lon, h, vn,
        ve, vd)."""
        if k >= self.n:
            return None
        offset = (k - 1) * _ROW.size
        if _STATE.unpack_from(self.values, offset) != state:
            return None
        return _ROW.unpack_from(self.values, offset + _ROW.size)

    def record(self, k: int, state, row) -> None:
        """Append ``row`` as row ``k`` if the track ends at row ``k - 1`` and that row
        holds ``state`` (lat, lon, h, vn, ve, vd), the state ``row`` was computed from."""
        global _recorded
        if _recorded >= MAX_SAMPLES:
            return
        with self.lock:
            if k != self.n or state != self.last:
                return
            self.values.frombytes(_ROW.pack(*row))
            self.n = k + 1
            self.last = row[:6]
            _recorded += 1


_TRACKS: Dict[Key, IdealTrack] = {}
#: generators started per key (tracks start at the second)
_SEEN: Dict[Key, int] = {}
#: samples recorded in the tracks kept
_recorded = 0
_TRACKS_LOCK = threading.Lock()


def track_key(profile: dict, dt: float) -> Key:
    """The key of a profile's track: its canonical JSON text and the step."""
    return json.dumps(profile, sort_keys=True, default=repr), float(dt)


def register(key: Key, start_row) -> None:
    """A generator of ``key`` starts at ``start_row`` (its state at sample 0).  The second
    one in this process starts the track: a profile flown once records nothing."""
    if key in _TRACKS or os.environ.get(SWITCH, "1") == "0":
        return
    with _TRACKS_LOCK:
        _SEEN[key] = _SEEN.get(key, 0) + 1
        if len(_SEEN) > MAX_SEEN:
            del _SEEN[next(iter(_SEEN))]
        if _SEEN[key] >= 2 and key not in _TRACKS:
            while len(_TRACKS) >= MAX_TRACKS:
                _drop(next(iter(_TRACKS)))
            _TRACKS[key] = IdealTrack(start_row)


def find(key: Key) -> Optional[IdealTrack]:
    """The track of ``key`` if there is one."""
    return _TRACKS.get(key)


def clear() -> None:
    """Drop every track."""
    with _TRACKS_LOCK:
        for key in list(_TRACKS):
            _drop(key)
        _SEEN.clear()


def _fresh_locks_in_child() -> None:
    """A forked child starts with unlocked locks: a lock held by another thread of the parent
    at the fork would otherwise never be released in the child."""
    global _TRACKS_LOCK
    _TRACKS_LOCK = threading.Lock()
    for t in _TRACKS.values():
        t.lock = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_fresh_locks_in_child)


def _drop(key: Key) -> None:
    global _recorded
    _recorded -= _TRACKS.pop(key).n - 1
