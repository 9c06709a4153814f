"""A sensor log's IMU clock calibrated once, offline (``navfmu convert time-offset LOG``), the
way a mounting angle is: the IMU's time offset to the GNSS clock estimated from the whole
log, then the IMU's stamps moved onto the GNSS clock in the log itself, so that every later
replay (real-time filters included) runs on one clock.

The estimate is the smoother's (:func:`orchestrator.running.smoothing.synchronized_run`,
:meth:`navcore.components.smoothing.SmoothingSession.synchronize`): the log replayed
through the Kf, the course-rate correlation of the IMU's heading with the fixes' course,
kept when the run with the fixes on the IMU's clock fits them better beyond chance, else
the likelihood search.  Only the fixes the log holds as valid count: a log with outages cut
in is calibrated from what a user of that log would have.

The calibrated log is written in the sensor-log format unchanged: ``imu.csv``'s times less
the offset (``tau > 0``: the stamps were late), through
:func:`navcore.sensors.sensorlog.write_log_file` (checked as a replay reads it, moved in
place whole), so a log read before is read again by its new content
(:mod:`navcore.sensors.log_cache`).  A calibrated log calibrated again is left as it is
(no offset fits better beyond chance).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from navcore.filters.imu_time_offset import MIN_EPOCHS
from navcore.filters.time_offset_search import OffsetSearch
from navcore.sensors.sensorlog import IMU_FILE, LogError, read_log, write_log_file

from ..errors import NavfmuError
from ..results.run_results import check_commit
from . import smoothing


@dataclass
class ClockCalibration:
    """The estimate of a log's IMU time offset: ``offset`` [s] the one taken (0 when none
    was), ``accepted`` whether one was, ``details`` the smoother's clock metadata
    (:func:`orchestrator.running.smoothing.clock_metadata`)."""

    offset: float
    accepted: bool
    details: dict

    def summary(self) -> str:
        """One line: the offset, the course estimate's correlation, the fits, the verdict."""
        d = self.details
        corr = d.get("imu_time_offset_correlation")
        course = (f"course estimate {d['imu_time_offset_estimate_s']:+.3f} s (correlation "
                  f"{corr:.3f}, {d['imu_time_offset_epochs']} fix epochs)"
                  if "imu_time_offset_not_estimated" not in d else
                  f"no course estimate ({d['imu_time_offset_not_estimated']})")
        fits = d.get("imu_time_offset_fit_per_fix", {})
        fit = (f"fit per fix {fits.get('+0.000')} at 0, {fits.get(f'{self.offset:+.3f}')} at "
               f"{self.offset:+.3f} s" if self.accepted else
               f"no offset fits the fixes better beyond chance ({len(fits)} runs)")
        verdict = (f"the IMU's stamps are {self.offset:+.3f} s off the GNSS clock: accepted"
                   if self.accepted else "not accepted")
        return f"{verdict}; {course}; {fit}"


def estimate(model, log, filter=None, parameters=None, search=OffsetSearch()) -> ClockCalibration:
    """The IMU time offset of the sensor log ``log`` replayed through ``model`` (a replay
    scenario) with ``filter`` (None: the model's own; a filter the smoother supports) and
    the parameter overrides ``parameters`` (the kept run's warnings raised: the fit means
    something only for a filter set up for the log); refused in one line when the log does not move
    enough to show it (fewer than :data:`navcore.filters.imu_time_offset.MIN_EPOCHS` fix
    epochs while moving)."""
    session, _, said = smoothing.synchronized_run(model, filter, True, search, replay=log,
                                                  parameters=parameters, log=None)
    smoothing.raise_held(said)        # a filter that does not fit the log says so (NIS)
    details = smoothing.clock_metadata(session)
    if session.clock.epochs < MIN_EPOCHS:
        raise NavfmuError(f"{log}: the IMU's time offset cannot be estimated: "
                          f"{session.clock.reason} (no motion)")
    offset = float(session.time_offset)
    return ClockCalibration(offset, offset != 0.0, details)


def apply(log, offset: float) -> Path:
    """Move the IMU's stamps of the sensor log ``log`` by ``-offset`` [s] onto the GNSS clock
    (``imu.csv`` rewritten whole, checked with the log's other files first); returns the
    file."""
    try:
        data = read_log(log)
        imu = {**data.imu, "time": data.imu["time"] - offset}
        return write_log_file(log, IMU_FILE, imu, data.time_origin, before_commit=check_commit)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None


def calibrate(model, log, filter=None, parameters=None, search=OffsetSearch()):
    """(:class:`ClockCalibration`, the file written or None): :func:`estimate`, then
    :func:`apply` when an offset was accepted."""
    found = estimate(model, log, filter, parameters, search)
    return found, (apply(log, found.offset) if found.accepted else None)


__all__ = ["ClockCalibration", "apply", "calibrate", "estimate"]
