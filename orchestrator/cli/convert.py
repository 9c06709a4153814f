"""``navfmu convert``: other tools' sensor data to the navfmu sensor-log format.

Thin layer over the readers of :mod:`navcore.sensors.log_converters` (which state the formats and
the rate-to-increment rule), :mod:`navcore.sensors.rtklib_pos` (RTKLIB solutions: the GNSS
file), :mod:`navcore.sensors.imu_csv` (plain IMU CSV: the IMU file) and
:func:`navcore.sensors.sensorlog.write_log` / ``write_log_file`` (which check the log, or the
one file and the log it completes, and write atomically: a conversion that fails leaves
nothing behind).
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from navcore.sensors.imu_csv import ImuCsvSpec, read_imu_csv
from navcore.sensors.log_converters import read_gnss_ins_sim, read_kf_gins
from navcore.sensors.log_time import absolute_text
from navcore.sensors.rtklib_pos import quality_factors, quality_names, read_rtklib_pos
from navcore.sensors.sensorlog import (GNSS_FILE, IMU_FILE, LogError, SensorLog, write_log,
                                       write_log_file)

from ..errors import NavfmuError
from .cli_options import read_yaml_mapping
from ..results.outputs import check_writable
from ..results.run_results import check_commit


def refuse_existing(destination, force: bool) -> None:
    """An existing destination is replaced only with ``force`` (``--force``)."""
    if Path(destination).exists() and not force:
        raise NavfmuError(f"convert: the destination {destination} exists; give --force to "
                          "replace it")


def _write(log: SensorLog, destination) -> SensorLog:
    write_log(destination, log, before_commit=check_commit)
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


def _check_part(destination, name: str, force: bool) -> None:
    """A writable destination folder whose file ``name`` is replaced only with ``force``
    (the log's other files are kept)."""
    path = Path(destination) / name
    if path.exists() and not force:
        raise NavfmuError(f"convert: {path} exists; give --force to replace it")
    check_writable(destination, "convert: destination", folder=True)


def _other_part(destination, name: str, command: str) -> str:
    """What the log still needs, if anything."""
    if (Path(destination) / name).is_file():
        return f"; {destination}/ is a complete log (replay it with --replay {destination})"
    return f"; {destination}/ has no {name} yet (add it with navfmu convert {command})"


def convert_rtklib(pos_file, destination, time_scale="week", keep=None, sigma_scale=None,
                   force=False) -> str:
    """Convert an RTKLIB ``.pos`` solution into ``destination/gnss.csv``; one line saying
    what was written."""
    _check_part(destination, GNSS_FILE, force)
    try:
        kept = None if keep is None else quality_names(keep, "--keep")
        factors = {} if sigma_scale is None else quality_factors(sigma_scale, "--sigma-scale")
        table, origin, counts = read_rtklib_pos(pos_file, time_scale, kept, factors)
        n, n_valid = len(table["time"]), int(table["valid"].sum())
        span = (f"{absolute_text(table['time'][0], origin)} to "
                f"{absolute_text(table['time'][-1], origin)} s")
        velocity = "with" if "vn" in table else "without"
        path = write_log_file(destination, GNSS_FILE, table, origin, source=pos_file,
                              before_commit=check_commit)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None
    qualities = ", ".join(f"{name} {count}" for name, count in counts.items())
    return (f"wrote {path}: {n} epochs ({qualities}; {n_valid} valid) over {span} "
            f"({'GPS seconds of the week' if time_scale == 'week' else 'UNIX seconds, GPST'}), "
            f"{velocity} velocity" + _other_part(destination, IMU_FILE, "imu-csv"))


def imu_csv_spec(config, options) -> ImuCsvSpec:
    """The column map of ``convert imu-csv``: the YAML file ``config`` (or None) with the
    command line's ``options`` (name -> value, None where not given) over it."""
    values, where = {}, "convert imu-csv"
    if config is not None:
        values, where = read_yaml_mapping(config, "keys (gyro, accel, ...)"), str(config)
    values = {**values, **{k: v for k, v in options.items() if v is not None}}
    try:
        return ImuCsvSpec.from_mapping(values, where)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None


def convert_imu_csv(csv_file, destination, spec: ImuCsvSpec, force=False) -> str:
    """Convert a plain IMU CSV file into ``destination/imu.csv``; one line saying what was
    written."""
    _check_part(destination, IMU_FILE, force)
    try:
        table, origin = read_imu_csv(csv_file, spec)
        log = SensorLog(table, {}, None, origin)
        period, start, stop = log.imu_period, log.start_time, log.stop_time
        path = write_log_file(destination, IMU_FILE, table, origin, source=csv_file,
                              before_commit=check_commit)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None
    return (f"wrote {path}: {len(table['time'])} IMU intervals of {period:g} s (median) over "
            f"[{absolute_text(start, origin)}, {absolute_text(stop, origin)}] s"
            + _other_part(destination, GNSS_FILE, "rtklib"))
