"""``navfmu convert``: other tools' sensor data as a navfmu sensor log (gnss-ins-sim, KF-GINS,
RTKLIB solutions, plain IMU CSV files); the conversions themselves are
:mod:`orchestrator.cli.convert` and the readers of :mod:`navcore.sensors`."""
from __future__ import annotations

from pathlib import Path

import click

from ..errors import NavfmuError
from .cli_options import nonempty_path
from .option_groups import SSV_HELP


@click.group()
def convert():
    """Convert other tools' sensor data into a navfmu sensor log (imu.csv, gnss.csv,
    truth.csv), replayable with --replay."""


@convert.command("gnss-ins-sim")
@click.argument("src_dir", type=click.Path(), callback=nonempty_path)
@click.argument("dst", type=click.Path(file_okay=False), callback=nonempty_path)
@click.option("--run", "run_index", type=int, default=0, show_default=True,
              help="Which simulation run (the R of gyro-R.csv).")
@click.option("--force", is_flag=True, help="Replace DST if it exists.")
def convert_gnss_ins_sim(src_dir, dst, run_index, force):
    """A gnss-ins-sim output folder SRC_DIR (ref_frame=0; rates at the sample instants;
    increments by the trapezoid rule) into the sensor-log folder DST."""
    from . import convert as conv

    click.echo(conv.describe(conv.convert_gnss_ins_sim(src_dir, dst, run=run_index,
                                                       force=force), dst))


@convert.command("kf-gins")
@click.argument("imu_file", type=click.Path(), callback=nonempty_path)
@click.argument("gnss_file", type=click.Path(), callback=nonempty_path)
@click.argument("rest", nargs=-1, type=click.Path(), callback=nonempty_path)
@click.option("--force", is_flag=True, help="Replace DST (and the --config .ssv) if they exist.")
@click.option("--config", "config", type=click.Path(dir_okay=False),
              help="KF-GINS's YAML configuration: also write its initial state, noise, lever "
              "arm and start time as DST/filter.ssv.")
def convert_kf_gins(imu_file, gnss_file, rest, force, config):
    """KF-GINS IMU_FILE and GNSS_FILE text (7 or 13 columns; and optionally a .nav
    TRUTH_FILE) into the sensor-log folder DST: IMU_FILE GNSS_FILE [TRUTH_FILE] DST."""
    from . import convert as conv

    if len(rest) not in (1, 2):
        raise NavfmuError("convert kf-gins: expected IMU_FILE GNSS_FILE [TRUTH_FILE] DST")
    truth, dst = (rest[0], rest[1]) if len(rest) == 2 else (None, rest[0])
    settings = None
    if config is not None:
        from .kf_gins_config import read_config

        settings = read_config(config)        # a bad configuration is refused first
    log = conv.convert_kf_gins(imu_file, gnss_file, truth, dst, force=force)
    click.echo(conv.describe(log, dst))
    if settings is not None:
        from .kf_gins_config import with_gnss_velocity, write_filter_ssv

        click.echo(write_filter_ssv(with_gnss_velocity(settings, log.gnss), dst))
    else:
        from .kf_gins_config import remove_stale_ssv

        click.echo(remove_stale_ssv(dst), nl=False)


@convert.command("rtklib")
@click.argument("pos_file", type=click.Path(), callback=nonempty_path)
@click.argument("dst", type=click.Path(file_okay=False), callback=nonempty_path)
@click.option("--time", "time_scale", type=click.Choice(["week", "unix"]), default="week",
              show_default=True, help="The log's time: GPS seconds of the week, or seconds "
              "since 1970 on the GPST scale (as RTKLIB's time tags); the IMU file must use "
              "the same.")
@click.option("--keep", help="Qualities used as fixes, e.g. fix,float (default all: fix, "
              "float, sbas, dgps, single, ppp); the others become invalid lines (outages).")
@click.option("--sigma-scale", help="Factor on the receiver's sigmas per quality, e.g. "
              "fix=1,float=3,single=10 (R scales by its square; default 1).")
@click.option("--force", is_flag=True, help="Replace DST/gnss.csv if it exists.")
def convert_rtklib(pos_file, dst, time_scale, keep, sigma_scale, force):
    """An RTKLIB solution POS_FILE (.pos: GPST, lat/lon/height or ECEF, sigmas, quality Q,
    velocity when present) as DST/gnss.csv, with per-epoch sigmas; the log's other files
    are kept."""
    from . import convert as conv

    click.echo(conv.convert_rtklib(pos_file, dst, time_scale, keep, sigma_scale, force))


@convert.command("imu-csv")
@click.argument("csv_file", type=click.Path(), callback=nonempty_path)
@click.argument("dst", type=click.Path(file_okay=False), callback=nonempty_path)
@click.option("--config", "config", type=click.Path(dir_okay=False),
              help="YAML file with the keys below (options given here override it).")
@click.option("--gyro", help="Body axes from columns, e.g. x=col4,y=-col5,z=-col6.")
@click.option("--accel", help="Body axes from columns, e.g. x=col1,y=-col2,z=-col3.")
@click.option("--gyro-unit", "gyro_unit", help="deg/s or rad/s (rates), deg or rad "
              "(increments).")
@click.option("--accel-unit", "accel_unit", help="g or m/s^2 (rates), m/s (increments).")
@click.option("--time", "time", type=int, help="The time column (from 1).")
@click.option("--time-unit", "time_unit", help="s (default), ms, us or ns.")
@click.option("--rate", type=float, help="Fixed sample rate [Hz] instead of a time column.")
@click.option("--start", help="Time of the first sample [s] in the log's time scale.")
@click.option("--header-lines", "header_lines", type=int, help="Title lines to skip "
              "(default 0).")
@click.option("--force", is_flag=True, help="Replace DST/imu.csv if it exists.")
def convert_imu_csv(csv_file, dst, config, force, **options):
    """A plain IMU CSV_FILE (a column map and units, on the command line or in --config) as
    DST/imu.csv; the log's other files are kept."""
    from . import convert as conv

    spec = conv.imu_csv_spec(config, options)
    click.echo(conv.convert_imu_csv(csv_file, dst, spec, force))


@convert.command("time-offset")
@click.argument("log", type=click.Path(file_okay=False), callback=nonempty_path)
@click.option("--scenario", type=click.Path(), callback=nonempty_path,
              help="The replay scenario the log runs through (default: "
              "models/replay_gnss_ins_sim, its own filter swapped for the Kf).")
@click.option("--set", "sets", multiple=True, metavar="COMP.VAR=VALUE",
              help="Override a parameter of the replay (repeatable): the filter's settings "
              "for this log (lever arm, noise, init_mode).")
@click.option("--ssv", "ssv", multiple=True, metavar="[COMPONENT=]FILE", help=SSV_HELP)
def convert_time_offset(log, scenario, sets, ssv):
    """Calibrate the IMU clock of the sensor log LOG: estimate the IMU's time offset to the
    GNSS clock from the whole log (replayed through the Kf, as the smoother does) and,
    when accepted, rewrite LOG/imu.csv with the IMU's times on the GNSS clock."""
    from ..building.build import ROOT
    from ..running import clock_calibration, scenarios
    from ..running.ssv_bindings import overrides
    from .cli_options import parse_sets

    if not Path(log).is_dir():
        raise NavfmuError(f"convert time-offset: the sensor log {log} is not a folder")
    model = scenarios.load_scenario(scenario or ROOT / "models" / "replay_gnss_ins_sim")
    found, written = clock_calibration.calibrate(model, log, "Kf",
                                                 overrides(ssv, model, parse_sets(sets)))
    click.echo(found.summary())
    click.echo(f"wrote {written}: the IMU's times moved by {-found.offset:+.3f} s"
               if written else f"{log}: unchanged")


__all__ = ["convert"]
