"""The IMU's clock against the GNSS clock: the time offset of a recorded run, estimated from
its turns, for the smoother (:mod:`navcore.components.smoothing`).

A logger stamps the IMU samples when they reach it, late by a latency no datasheet gives
(serial buffers, a USB poll, the stretch of a counter to a tag file's times).  An INS whose
samples are stamped ``tau`` seconds late is the true trajectory delayed by ``tau``: at a fix
its position is off by about ``-v tau`` (6 m/s and 0.13 s: 0.8 m), which the fixes absorb
while they come; in an outage the error ``-tau (v(t) - v(t0))`` grows with every change of
the velocity since the last fix (a 140 deg turn at 6 m/s: 11 m/s of change), a bulge in
the middle of the outage that no state of the 15-state model explains.  A smoother sees the
whole run and can measure ``tau`` before it smooths.

The estimate compares two measures of the same turning (the cross-correlation of a signal
the IMU measures with one the GNSS measures, as the temporal calibration of Furgale,
Rehder and Siegwart 2013, "Unified temporal and spatial calibration for multi-sensor
systems", IROS, is started from the correlation of the angular rates):

* the IMU's heading about the local vertical, ``psi(t) = -sum dtheta_k . u_k``, with ``u_k``
  the direction of the specific force averaged over :data:`GRAVITY_WINDOW` (gravity's, up,
  in the body axes; the minus makes it the rotation about the down axis, as the yaw);
* the course over ground of the fixes, ``chi_j = atan2(v_e, v_n)`` with the velocity
  ``v_j = (p_{j+1} - p_{j-1}) / (t_{j+1} - t_{j-1})`` of the positions, where the speed is
  at least :data:`MIN_SPEED` (a wheeled vehicle's course is its heading, a walker's on
  average);

both turned into a rate by the same central difference over the fixes ``k - m`` and
``k + m`` (``m`` fixes make half of :data:`RATE_SPAN`, at least one)::

    r_gnss(k)      = (chi_{k+m} - chi_{k-m}) / (t_{k+m} - t_{k-m})
    r_imu(k, lag)  = (psi(t_{k+m} + lag) - psi(t_{k-m} + lag)) / (t_{k+m} - t_{k-m})
    tau            = argmax over lag of corr(r_imu(., lag), r_gnss)        (Pearson)

(a symmetric difference on both keeps the lag of the peak unbiased).  The lag is searched
over +/-:data:`MAX_OFFSET` on a 10 ms grid, then 1 ms around the best, the peak refined
by a parabola through its neighbours.  The estimate is taken only when the run turns
enough to carry it: at least :data:`MIN_EPOCHS` fix epochs, an RMS course rate of
:data:`MIN_TURN_RATE`, a peak correlation of :data:`MIN_CORRELATION` inside the search range;
otherwise the offset is 0 and the reason is kept.  ``tau > 0``: the IMU's stamps are late,
the IMU's time of an instant is its GNSS time plus ``tau``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
from scipy.ndimage import uniform_filter1d

from ..ins import earth

#: [m/s] the slowest speed whose course over ground counts
MIN_SPEED = 1.0
#: [s] the largest offset searched, either sign
MAX_OFFSET = 1.0
#: [s] the span of the central difference that makes the course a rate (the fixes'
#: noise, differentiated twice, averaged; a turn lasts several seconds)
RATE_SPAN = 1.0
#: [s] the window of the specific force averaged for the vertical
GRAVITY_WINDOW = 1.0
#: the fewest fix epochs with a course rate
MIN_EPOCHS = 40
#: [rad/s] the smallest RMS course rate (a run without turns carries no offset)
MIN_TURN_RATE = math.radians(2.0)
#: the smallest peak correlation taken
MIN_CORRELATION = 0.5
#: the solution's columns that are angles (interpolated unwrapped)
ANGLES = ("roll", "pitch", "yaw")


@dataclass
class TimeOffset:
    """An estimate: ``tau`` [s] (0 when not estimated), the peak ``correlation``, the fix
    ``epochs`` it used, and ``reason`` it was not taken (None when it was)."""

    tau: float
    correlation: float
    epochs: int
    reason: Optional[str] = None

    def applies(self, imu_dt: float) -> bool:
        """Worth a second pass: estimated and at least half an IMU interval (below it the
        fixes already fall on the IMU epoch nearest their instant)."""
        return self.reason is None and abs(self.tau) >= 0.5 * imu_dt


def imu_heading(time, dt, dtheta, dvel):
    """(node times, heading [rad]): the rotation about the local vertical integrated over the
    IMU intervals ending at ``time`` (n,) of lengths ``dt`` (n,), with the increments
    ``dtheta``, ``dvel`` (n, 3) in body axes (module docstring); node 0 is the start of the
    first interval."""
    dt = np.asarray(dt, dtype=float)
    f = np.asarray(dvel, dtype=float) / dt[:, None]
    size = max(1, int(round(GRAVITY_WINDOW / float(np.median(dt)))))
    up = uniform_filter1d(f, size, axis=0, mode="nearest")
    up /= np.linalg.norm(up, axis=1)[:, None]
    psi = -np.einsum("ij,ij->i", np.asarray(dtheta, dtype=float), up)
    nodes = np.concatenate([[time[0] - dt[0]], time])
    return nodes, np.concatenate([[0.0], np.cumsum(psi)])


def course_rates(time, lat, lon):
    """(indices k, half-span m, rates r_gnss(k)) of the fixes at ``time`` (sorted, valid
    ones only) with a course rate over ``k - m .. k + m`` (:data:`RATE_SPAN`): every
    velocity from ``k - m`` to ``k + m`` defined in one stretch of consecutive fixes (no gap
    over 1.5 intervals) with a speed of at least :data:`MIN_SPEED`."""
    t = np.asarray(time, dtype=float)
    n = len(t)
    if n < 5:
        return np.zeros(0, dtype=int), 1, np.zeros(0)
    rn, re = earth.radii(float(lat[0]))
    p = np.column_stack([(np.asarray(lat) - lat[0]) * rn,
                         (np.asarray(lon) - lon[0]) * re * math.cos(float(lat[0]))])
    gap = np.diff(t)
    interval = float(np.median(gap))
    m = max(1, int(round(0.5 * RATE_SPAN / interval)))
    joined = gap <= 1.5 * interval                          # fix j and j + 1 in one stretch
    v = np.full((n, 2), np.nan)
    mid = joined[:-1] & joined[1:]                          # j - 1, j, j + 1 joined
    v[1:-1][mid] = ((p[2:] - p[:-2]) / (t[2:] - t[:-2])[:, None])[mid]
    course = np.arctan2(v[:, 1], v[:, 0])
    fast = np.hypot(v[:, 0], v[:, 1]) >= MIN_SPEED          # False for NaN
    window = np.lib.stride_tricks.sliding_window_view(fast, 2 * m + 1).all(axis=1)
    k = np.flatnonzero(window) + m
    turn = np.angle(np.exp(1j * (course[k + m] - course[k - m])))
    return k, m, turn / (t[k + m] - t[k - m])


def _correlations(nodes, psi, t_minus, t_plus, r_gnss, lags):
    """Pearson correlation of r_imu(., lag) with ``r_gnss`` for every lag (NaN where the
    shifted epochs leave the IMU's span)."""
    out = np.full(len(lags), np.nan)
    span = t_plus - t_minus
    for i, lag in enumerate(lags):
        if t_minus[0] + lag < nodes[0] or t_plus[-1] + lag > nodes[-1]:
            continue
        r = (np.interp(t_plus + lag, nodes, psi) - np.interp(t_minus + lag, nodes, psi)) / span
        out[i] = np.corrcoef(r, r_gnss)[0, 1]
    return out


def _peak(lags, c):
    """The lag of the largest correlation, refined by a parabola through its neighbours."""
    i = int(np.nanargmax(c))
    if 0 < i < len(c) - 1 and np.isfinite(c[i - 1]) and np.isfinite(c[i + 1]):
        den = c[i - 1] - 2.0 * c[i] + c[i + 1]
        if den < 0:
            return float(lags[i] + 0.5 * (c[i - 1] - c[i + 1]) / den * (lags[1] - lags[0]))
    return float(lags[i])


def estimate(imu_time, imu_dt, dtheta, dvel, fix_time, fix_lat, fix_lon) -> TimeOffset:
    """The IMU's time offset to the GNSS clock (module docstring) from the IMU intervals
    (ending at ``imu_time``, arrays (n,) and (n, 3)) and the valid fixes (``fix_time``,
    ``fix_lat``, ``fix_lon`` [rad], on one time scale with the IMU's)."""
    if len(imu_time) < 2 or len(fix_time) < 5:
        return TimeOffset(0.0, math.nan, 0, "too few IMU intervals or fixes")
    nodes, psi = imu_heading(np.asarray(imu_time, float), imu_dt, dtheta, dvel)
    ft = np.asarray(fix_time, dtype=float)
    k, m, r_gnss = course_rates(ft, fix_lat, fix_lon)
    inside = (ft[k - m] - MAX_OFFSET >= nodes[0]) & (ft[k + m] + MAX_OFFSET <= nodes[-1])
    k, r_gnss = k[inside], r_gnss[inside]
    if len(k) < MIN_EPOCHS:
        return TimeOffset(0.0, math.nan, len(k), f"{len(k)} fix epochs while moving "
                          f"(at least {MIN_EPOCHS})")
    rms = float(np.sqrt(np.mean(r_gnss ** 2)))
    if rms < MIN_TURN_RATE:
        return TimeOffset(0.0, math.nan, len(k), f"RMS course rate {math.degrees(rms):.2g} "
                          f"deg/s (at least {math.degrees(MIN_TURN_RATE):.2g}): no turns")
    t_minus, t_plus = ft[k - m], ft[k + m]
    coarse = np.linspace(-MAX_OFFSET, MAX_OFFSET, int(round(2 * MAX_OFFSET / 0.01)) + 1)
    c = _correlations(nodes, psi, t_minus, t_plus, r_gnss, coarse)
    best = float(coarse[int(np.nanargmax(c))])
    fine = best + np.linspace(-0.01, 0.01, 21)
    cf = _correlations(nodes, psi, t_minus, t_plus, r_gnss, fine)
    tau, peak = _peak(fine, cf), float(np.nanmax(cf))
    if abs(best) >= MAX_OFFSET - 0.01:
        return TimeOffset(0.0, peak, len(k), f"the correlation peaks at the search's edge "
                          f"({best:+.2f} s)")
    if peak < MIN_CORRELATION:
        return TimeOffset(0.0, peak, len(k), f"peak correlation {peak:.2f} (at least "
                          f"{MIN_CORRELATION})")
    return TimeOffset(tau, peak, len(k))


def on_gnss_clock(solution, tau):
    """``solution`` (dict of per-epoch arrays, ``time`` the IMU's stamps) at the same
    stamps read as GNSS times: every array interpolated at ``time + tau`` (the angles
    unwrapped), the epochs whose ``time + tau`` is past the last stamp left out."""
    t = solution["time"]
    keep = t + tau <= t[-1] + 1e-9
    keep &= t + tau >= t[0] - 1e-9
    at = t[keep] + tau
    out = {"time": t[keep].copy()}
    for key, value in solution.items():
        if key == "time" or not isinstance(value, np.ndarray) or len(value) != len(t):
            out.setdefault(key, value)
            continue
        cols = value.reshape(len(t), -1)
        if key in ANGLES:
            cols = np.unwrap(cols, axis=0)
        res = np.column_stack([np.interp(at, t, c) for c in cols.T])
        if key in ANGLES:
            res = np.angle(np.exp(1j * res))
        out[key] = res.reshape((len(at),) + value.shape[1:])
    return out


__all__ = ["TimeOffset", "course_rates", "estimate", "imu_heading", "on_gnss_clock"]
