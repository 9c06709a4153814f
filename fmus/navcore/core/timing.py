"""Times on a component's sample grid and between communication points: the one time tolerance.

A discrete-time component (an IMU sampling every ``period``, a filter driven by the IMU's
time tags) meets times from elsewhere: a master's communication points ``t0 + k h`` carry
rounding (``0.01 * 3`` is not ``0.03``), and the last step of a run is often a remainder of
a few 1e-14 s.  Two instants closer than :func:`time_tolerance` are the same instant
everywhere in navcore: a relative ``TIME_TOLERANCE`` of the period involved, plus a few units
in the last place of the time itself (so that a grid epoch of a long run, ``t0 + n period``
at t = 1e5 s, still matches the master's ``t0 + k h``).

Sample grid (:func:`samples_reached`): the component's epochs are ``start + n period``,
n = 1, 2, ...; a communication step ending at ``t_end`` reaches every epoch up to
``t_end + time_tolerance``.  A step that reaches several epochs sub-steps through all of
them; one that reaches none (shorter than the time left to the next epoch) changes nothing
and the outputs hold, the time being carried by the next step.
"""
from __future__ import annotations

import math

import numpy as np

from .kernels import jitable

#: relative tolerance on times, as a fraction of the period they are compared on
TIME_TOLERANCE = 1e-9
#: units in the last place of the compared time added to the tolerance (master rounding)
_ULPS = 8.0


def time_tolerance(period: float, t: float = 0.0) -> float:
    """Largest difference [s] between two times that are the same instant, for a grid of
    ``period`` seconds near time ``t`` (see the module docstring)."""
    return TIME_TOLERANCE * abs(period) + _ULPS * math.ulp(abs(t))


def time_tolerance_rows(period, t):
    """:func:`time_tolerance` of arrays, element by element (``np.spacing`` of a
    non-negative time is its ``math.ulp``)."""
    return TIME_TOLERANCE * np.abs(period) + _ULPS * np.spacing(np.abs(t))


def same_time(a: float, b: float, period: float) -> bool:
    """``a`` and ``b`` are the same instant on a grid of ``period`` seconds."""
    return abs(a - b) <= time_tolerance(period, max(abs(a), abs(b)))


@jitable
def same_instant(a, b, period):
    """:func:`same_time` in a kernel (``np.spacing`` of a non-negative time is its
    ``math.ulp``, as in :func:`time_tolerance_rows`)."""
    return abs(a - b) <= TIME_TOLERANCE * abs(period) + _ULPS * np.spacing(max(abs(a), abs(b)))


def samples_reached(start: float, period: float, t_end: float) -> int:
    """Number n of the last grid epoch ``start + n period`` reached at ``t_end`` (0 before
    the first one)."""
    n = math.floor((t_end - start + time_tolerance(period, t_end)) / period)
    return max(0, n)
