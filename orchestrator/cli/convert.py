"""``navfmu convert``: other tools' sensor data to the navfmu sensor-log format.

Thin layer over the readers of :mod:`navcore.sensors.log_converters` (which state the formats and
the rate-to-increment rule) and :func:`navcore.sensors.sensorlog.write_log` (which checks the log
and writes it atomically: a conversion that fails leaves nothing behind).
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from navcore.sensors.log_time import absolute_text
from navcore.sensors.log_converters import read_gnss_ins_sim, read_kf_gins
from navcore.sensors.sensorlog import LogError, SensorLog, write_log

from ..errors import NavfmuError
from ..results.outputs import check_writable


def refuse_existing(destination, force: bool) -> None:
    """An existing destination is replaced only with ``force`` (``--force``)."""
    if Path(destination).exists() and not force:
        raise NavfmuError(f"convert: the destination {destination} exists; give --force to "
                          "replace it")


def _write(log: SensorLog, destination) -> SensorLog:
    write_log(destination, log)
    return log


def _check_destination(destination, force: bool) -> None:
    """A writable destination; an existing one is replaced only with ``force``."""
    refuse_existing(destination, force)
    check_writable(destination, "convert: destination", folder=True)


def convert_gnss_ins_sim(source_dir, destination, run: int = 0, force=False) -> SensorLog:
    """Convert run ``run`` of a gnss-ins-sim output folder into a sensor log."""
    _check_destination(destination, force)
    try:
        return _write(read_gnss_ins_sim(source_dir, run=run), destination)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None


def convert_kf_gins(imu_file, gnss_file, truth_file: Optional[Path], destination,
                    force=False) -> SensorLog:
    """Convert KF-GINS IMU and GNSS text files (and a ``.nav`` reference) into a sensor log."""
    _check_destination(destination, force)
    try:
        return _write(read_kf_gins(imu_file, gnss_file, truth_file), destination)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None


def describe(log: SensorLog, destination) -> str:
    """One line saying what was written."""
    n_valid = int(log.gnss["valid"].sum())
    span = (f"[{absolute_text(log.start_time, log.time_origin)}, "
            f"{absolute_text(log.stop_time, log.time_origin)}]")
    return (f"wrote {destination}/: {len(log.imu['time'])} IMU intervals of "
            f"{log.imu_period:g} s over {span} s, "
            f"{len(log.gnss['time'])} GNSS lines ({n_valid} valid)"
            + (f", {len(log.truth['time'])} truth samples" if log.truth is not None
               else ", no truth"))
