"""Mission metric definitions: what a filter's errors did to a guided vehicle's flight.

They read recorded columns by the names of the vehicle contract (the component recording
``cross_track`` and ``waypoints_reached``, e.g. GuidedUav) and of the receiver
(``gnss_valid``), so they apply to any vehicle FMU with those outputs.

Definitions, over the recorded rows inside the metric window:

* cross-track error of the true path [m]: the vehicle's ``cross_track`` (the true position's
  distance from the route); RMS and max |.|;
* outage: the rows where the receiver's ``gnss_valid`` is false after its first valid fix (a
  receiver that has not fixed yet is not in an outage); the max |cross-track| over them, and
  the max horizontal position error of the filter over them (``sqrt(north^2 + east^2)`` of
  :func:`orchestrator.results.metrics.navigation_errors`, at the filter's nav_time), so the
  two orderings can be compared;
* waypoint capture: ``waypoints_reached`` at the end of the window, and ``waypoint_miss`` (the
  true distance to a waypoint when guidance switched past it, less the switching distance it
  meant) at each switch: mean and max |.|.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import NavfmuError
from . import metrics as nav_metrics

#: the signals that make a recorded component a guided vehicle
VEHICLE_SIGNALS = ("cross_track", "waypoints_reached", "waypoint_miss")


def find_vehicle(results):
    """Name of the component recording the vehicle signals, or None."""
    for comp in results.components:
        if all(results.has(comp, s) for s in VEHICLE_SIGNALS):
            return comp
    return None


def outage_rows(results, receiver=None):
    """Rows with no valid fix after the receiver's first valid one (module docstring)."""
    receiver = receiver or nav_metrics.find_component(results, "gnss_", ("valid",))
    valid = results.column(receiver, "gnss_valid") > 0.5
    started = np.cumsum(valid) > 0
    return started & ~valid


def _max_abs(x):
    return float(np.max(np.abs(x))) if len(x) else math.nan


def mission_metrics(results, filter_name, window=None, vehicle=None):
    """The mission metrics of a run (module docstring) as a plain dict."""
    vehicle = vehicle or find_vehicle(results)
    if vehicle is None:
        raise NavfmuError("no component records the vehicle signals "
                          f"{', '.join(VEHICLE_SIGNALS)}; mission metrics need a guided vehicle")
    inside = nav_metrics.time_mask(results.time, window)
    if not inside.any():
        raise NavfmuError(f"the metric window {window} contains no recorded row")
    cross = results.column(vehicle, "cross_track")
    outage = outage_rows(results) & inside
    reached = results.column(vehicle, "waypoints_reached")
    switches = np.zeros(len(reached), dtype=bool)
    switches[1:] = np.diff(reached) > 0
    misses = results.column(vehicle, "waypoint_miss")[switches & inside]
    e = nav_metrics.navigation_errors(results, filter_name)
    horizontal = np.hypot(e["pos_n"], e["pos_e"])
    out_nav = e["valid"] & (np.interp(e["time"], results.time, outage.astype(float)) > 0.5)
    return {
        "vehicle": vehicle,
        "cross_track_rms_m": float(np.sqrt(np.mean(cross[inside] ** 2))),
        "cross_track_max_m": _max_abs(cross[inside]),
        "outage_s": float(np.count_nonzero(outage) * _row_step(results)),
        "outage_cross_track_max_m": _max_abs(cross[outage]),
        "outage_position_error_max_m": _max_abs(horizontal[out_nav]),
        "waypoints_reached": int(reached[inside][-1]),
        "waypoint_miss_mean_m": float(np.mean(np.abs(misses))) if len(misses) else math.nan,
        "waypoint_miss_max_m": _max_abs(misses),
    }


def _row_step(results):
    t = results.time
    return float(t[1] - t[0]) if len(t) > 1 else 0.0


#: the columns of :func:`mission_table`: (key, title, unit)
COLUMNS = (("cross_track_rms_m", "xtrack RMS", "[m]"), ("cross_track_max_m", "xtrack max", "[m]"),
           ("outage_cross_track_max_m", "outage xtrack max", "[m]"),
           ("outage_position_error_max_m", "outage pos err max", "[m]"),
           ("waypoints_reached", "waypoints", ""),
           ("waypoint_miss_max_m", "wp miss max", "[m]"))


#: the campaign's short names of the metrics (orchestrator.campaigns.campaign_summary)
SHORT_LABELS = {"cross_track_rms_m": "xtrack RMS", "cross_track_max_m": "xtrack max",
                "outage_cross_track_max_m": "out xtrack", "outage_position_error_max_m":
                "out poserr", "waypoint_miss_max_m": "wp miss"}


def mission_table(rows):
    """Text table of ``rows`` = [(label, mission metrics), ...]."""
    width = max([len("mission")] + [len(label) for label, _ in rows]) + 2
    cells = [max(len(t), 9) + 2 for _, t, _ in COLUMNS]
    lines = ["mission".ljust(width) + "".join(t.rjust(c) for (_, t, _), c in zip(COLUMNS, cells)),
             " " * width + "".join(u.rjust(c) for (_, _, u), c in zip(COLUMNS, cells))]
    for label, m in rows:
        values = []
        for (key, _, _), c in zip(COLUMNS, cells):
            v = m[key]
            values.append((f"{v:d}" if isinstance(v, int) else f"{v:.2f}").rjust(c))
        lines.append(label.ljust(width) + "".join(values))
    return "\n".join(lines)


class MissionSink:
    """The mission metrics of a run whose rows stream in chunks (a campaign's): the chunks
    are kept (a mission is minutes long) and measured at ``close``; :attr:`metrics` maps
    filter component -> mission metrics (empty without a vehicle or a truth)."""

    def __init__(self, window=None):
        self.window = window
        self.metrics = {}
        self._chunks = []
        self._vehicle = None      # decided at the first chunk: no vehicle, nothing is kept

    def write(self, chunk) -> None:
        if self._vehicle is None:
            self._vehicle = find_vehicle(chunk) or ""
        if self._vehicle:         # a copy: the recorder may reuse its buffers
            self._chunks.append(type(chunk)(time=chunk.time.copy(),
                                            data={k: a.copy() for k, a in chunk.data.items()},
                                            columns=chunk.columns, units=chunk.units,
                                            metadata=chunk.metadata))

    def close(self, header):
        if not self._chunks:
            return self.metrics
        first = self._chunks[0]
        joined = type(first)(time=np.concatenate([c.time for c in self._chunks]),
                             data={k: np.concatenate([c.data[k] for c in self._chunks])
                                   for k in first.data},
                             columns=first.columns, units=first.units, metadata=header.metadata)
        self._chunks = []
        truth = any(joined.has(c, "truth_time") for c in joined.components)
        if truth:
            self.metrics = {f: mission_metrics(joined, f, self.window, self._vehicle)
                            for f in nav_metrics.filters_of(joined)}
        return self.metrics

    def abort(self) -> None:
        self._chunks = []
