"""Every INS/GNSS filter on a real drive, from the raw files to one table.

The drive is a folder of RTKLIB's files of a car, laid out as the public drive_0708 of
rtklibexplorer/GNSS_IMU (``docs/guide/your_real_log.md``): an
RTKLIB solution ``gnss_*.pos`` (the reference: centimetre RTK fixes), the logger's IMU file
``imu_*.csv`` (accel in g, gyro in deg/s, a millisecond counter) and its RTKLIB time-tag file
``imu_*.csv.tag``.  The script

1. writes ``gnss.csv`` with ``navfmu convert rtklib --time unix`` (the receiver's per-epoch
   sigmas);
2. prepares the IMU as the drive's own filter does (its ``convert_imu_file.py``): times from
   the tag file (the counter fitted to the lines' arrivals, :mod:`rtklib_tag`), a zero-phase
   4th-order Butterworth low pass (10 Hz; 5 Hz on the vertical accelerometer), the sensor to
   body rotation ``--misalign`` (Groves' Euler angles) and the logging delay
   ``--time-offset``; resampled to a uniform grid (``--rate``) and written as ``imu.csv`` by
   ``navfmu convert imu-csv`` (rates to increments by the trapezoid rule);
3. cuts GNSS outages into the fixes (``--outages``, seconds after the first fix) and keeps
   the uncut fixes as the truth;
4. replays the log through every filter (direct backend, ``models/replay_gnss_ins_sim``,
   the drive's parameters :data:`DRIVE_PARAMETERS`, the ones of the peer's configuration
   file ``--config`` over them (:mod:`gnss_imu_config`: a walk as well as the drive), and
   ``--set`` over both) and scores each
   at the epochs of the reference fixes (its solution carried to the antenna by the lever
   arm, as the fixes are the antenna's): RMS N/E/D over the run, RMS with fixes (outside the
   outages), the 3-D error five fixes after each outage, the share of epochs inside +/-3
   sigma per axis, the mean position NEES (diagonal sigmas) and the warnings of the run.

    python benchmarks/real_drive.py DRIVE
    python benchmarks/real_drive.py DRIVE --filters Kf,Iakf --set filter.gnss_corr_time=8 \\
        --json out.json
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tempfile
import warnings
from functools import partial
from pathlib import Path

import numpy as np
from scipy.signal import butter, filtfilt

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "fmus"), str(ROOT / "benchmarks")]

import gnss_imu_config  # noqa: E402
import rtklib_tag  # noqa: E402
from navcore.filters.correlated_gnss import MEASURED_CORR_TIME  # noqa: E402
from navcore.filters.process_noise_factor import CONSUMER_IMU_NOISE_FACTOR  # noqa: E402
from navcore.errors import NavcoreError  # noqa: E402
from navcore.filters.time_offset_search import OffsetSearch  # noqa: E402
from navcore.ins import earth  # noqa: E402
from navcore.ins.lever_arm import antenna_position_offset  # noqa: E402
from navcore.ins.rotations import euler_to_dcm, euler_to_dcm_array  # noqa: E402
from navcore.sensors.sensorlog import SensorLog, read_log, write_log  # noqa: E402
from orchestrator.cli.convert import convert_imu_csv, convert_rtklib, imu_csv_spec  # noqa: E402
from orchestrator.errors import NavfmuWarning  # noqa: E402
from orchestrator.running import clock_calibration, scenarios, smoothing  # noqa: E402

G0 = 9.80665                       # m/s^2 per g (the logger's unit)
GPS_EPOCH_UNIX = 315964800.0       # 1980-01-06 in UNIX seconds
FILTERS = ("Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf",
           "CtfaUkf", "ImmUkf")
#: the drive's configuration as a user sets it (docs/guide/your_real_log.md says why)
DRIVE_PARAMETERS = {
    "filter.init_mode": "gnss", "filter.r_from_receiver": True,
    "filter.measurement": "position", "filter.lever_arm_y": -0.05,
    "filter.p0_att_level": 0.1745, "filter.p0_att_yaw": 1.745,
    "filter.p0_gyro_bias_dph": 720.0, "filter.p0_accel_bias_ug": 20000.0,
    "filter.q_gyro_arw_dpsh": 0.228, "filter.q_accel_vrw_ugpsHz": 140.0,
    "filter.q_gyro_bias_instability_dph": 10.0, "filter.q_gyro_bias_tau_s": 100.0,
    "filter.q_accel_bias_instability_ug": 200.0, "filter.q_accel_bias_tau_s": 100.0,
    "filter.r_vel_n": 0.1, "filter.r_vel_e": 0.1, "filter.r_vel_d": 0.1,
    "filter.imu_noise_factor": CONSUMER_IMU_NOISE_FACTOR,
    "filter.gnss_corr_time": MEASURED_CORR_TIME,
}
OUTAGES = "120:130,220:250,440:500"
AFTER_FIXES = 5
#: the drive's own outage schedule (its drive_config.py: start_coast, coast_len, end_coast;
#: GNSS_IMU.py waits twice the outage's length between outages): 15 s outages from 40 s
#: after the first fix, one every 45 s, the last ending at least 30 s before the last fix
PEER_SCHEDULE = (40.0, 15.0, 45.0, 30.0)
#: the land aids of ``--aids`` (docs/guide/land_aids.md) and the drive's NHC geometry: the
#: body frame is the car's (``--misalign``), the non-holonomic point 0.65 m below the IMU
#: (the drive's ``imu_offset``)
AIDS = ("zupt", "zaru", "nhc")
NHC_PARAMETERS = {"filter.nhc_lever_z": 0.65}


# -- the IMU ----------------------------------------------------------------------------
def imu_samples(csv_file: Path, tag_file: Path, start=None):
    """(UNIX GPST times [s], accel [m/s^2], gyro [rad/s]) in the sensor's axes: the counter
    of the logger (column 7, ms) fitted to the arrival times of the lines in the tag file
    (:func:`rtklib_tag.sample_times`), or with ``start`` (UNIX GPST [s] of the first sample)
    taken as it is; lines without seven numbers (a cut-off first or last line) are left
    out."""
    lines = csv_file.read_bytes().split(b"\n")
    rows, where = [], []
    for k, line in enumerate(lines):
        parts = line.split(b",")
        try:
            if len(parts) == 7:
                rows.append([float(p) for p in parts])
                where.append(k)
        except ValueError:
            continue
    rows = np.array(rows)
    counter = rows[:, 6]
    if start is not None:
        times = start + (counter - counter[0]) / 1000.0
    else:
        times = rtklib_tag.sample_times(lines, counter, np.array(where), tag_file)
    return times, rows[:, :3] * G0, np.radians(rows[:, 3:6])


def body_imu(t, acc, gyr, misalign_deg, time_offset, fs=100.0):
    """The drive's own preparation: zero-phase 4th-order Butterworth low pass (10 Hz; 5 Hz on
    the vertical accelerometer), the sensor-to-body rotation of Groves' Euler angles
    ``misalign_deg`` (its Euler-to-matrix, the transpose of navcore's body-to-NED DCM) and
    the logging delay ``time_offset`` added to the times."""
    b, a = butter(4, 10.0, fs=fs)
    bz, az = butter(4, 5.0, fs=fs)
    acc = np.column_stack([filtfilt(b, a, acc[:, 0]), filtfilt(b, a, acc[:, 1]),
                           filtfilt(bz, az, acc[:, 2])])
    gyr = filtfilt(b, a, gyr, axis=0)
    C = euler_to_dcm(*np.radians(misalign_deg)).T
    return t + time_offset, acc @ C.T, gyr @ C.T


def write_uniform_csv(path: Path, t, acc, gyr, rate: float) -> None:
    """Rates on a uniform grid of ``rate`` Hz (exact decimal times) by linear interpolation,
    one line per sample: time [s], gyro x/y/z [rad/s], accel x/y/z [m/s^2]."""
    k0, k1 = math.ceil(t[0] * rate), math.floor(t[-1] * rate)
    ticks = np.arange(k0, k1 + 1)
    grid = ticks / rate
    values = np.column_stack([np.interp(grid, t, col) for col in (*gyr.T, *acc.T)])
    digits = max(0, math.ceil(math.log10(rate)))
    with open(path, "w") as f:
        for k, row in zip(ticks, values):
            f.write(f"{k / rate:.{digits}f}," + ",".join(f"{v:.9g}" for v in row) + "\n")


# -- the log ----------------------------------------------------------------------------
def parse_outages(text: str):
    """``"120:130,220:250"`` -> [(120.0, 130.0), (220.0, 250.0)]."""
    return [tuple(float(x) for x in part.split(":")) for part in text.split(",") if part]


def peer_outages(first_fix: float, last_fix: float, schedule=PEER_SCHEDULE):
    """The outages (s after ``first_fix``) of the peer's schedule ``schedule`` (start,
    length, period, margin before the end: :data:`PEER_SCHEDULE`, the drive's, or
    :func:`gnss_imu_config.schedule`) over fixes from ``first_fix`` to ``last_fix`` (seconds
    on one scale): as its ``GNSS_IMU.py`` marks them, every outage that starts before the
    margin, the last one cut there."""
    start, length, period, end_margin = schedule
    last = last_fix - first_fix - end_margin
    out, a = [], start
    while a < last:
        out.append((a, min(a + length, last)))
        a += period
    return out


def build_log(drive: Path, dst: Path, outages, misalign, time_offset, rate,
              imu_start=None, sigma_scale=None) -> SensorLog:
    """The sensor log of ``drive`` in ``dst`` with ``outages`` (s after the first fix) cut
    into the fixes and the uncut fixes as its truth (``imu_start``: :func:`imu_samples`'s
    ``start``; ``sigma_scale``: ``convert rtklib --sigma-scale``)."""
    pos = next(drive.glob("*.pos"))
    imu_csv = next(p for p in drive.glob("imu*.csv"))
    raw = dst / "raw"
    raw.mkdir(parents=True, exist_ok=True)
    print(convert_rtklib(pos, raw, time_scale="unix", sigma_scale=sigma_scale, force=True))
    t, acc, gyr = body_imu(*imu_samples(imu_csv, imu_csv.with_suffix(".csv.tag"), imu_start),
                           misalign, time_offset, fs=rate)
    with tempfile.TemporaryDirectory() as tmp:
        body = Path(tmp) / "imu_body.csv"
        write_uniform_csv(body, t, acc, gyr, rate)
        spec = imu_csv_spec(None, {"time": 1, "gyro": "x=col2,y=col3,z=col4",
                                   "accel": "x=col5,y=col6,z=col7", "gyro_unit": "rad/s",
                                   "accel_unit": "m/s^2"})
        print(convert_imu_csv(body, raw, spec, force=True))
    log = read_log(raw)
    g = dict(log.gnss)
    first = math.floor(log.time_origin + g["time"][0])
    rel = log.time_origin + g["time"] - first
    inside = (g["time"] > log.imu["time"][0]) & (g["time"] < log.imu["time"][-1])
    g = {k: v[inside] for k, v in g.items()}
    rel = rel[inside]
    truth = {"time": g["time"].copy(), "lat": g["lat"].copy(), "lon": g["lon"].copy(),
             "h": g["h"].copy(), "vn": g["vn"].copy(), "ve": g["ve"].copy(),
             "vd": g["vd"].copy(), "roll": 0 * rel, "pitch": 0 * rel, "yaw": 0 * rel}
    for a, b in outages:
        g["valid"] = np.where((rel > a) & (rel <= b), 0.0, g["valid"])
    cut = dst / "log"
    write_log(cut, SensorLog(log.imu, g, truth, log.time_origin))
    return read_log(cut), first


# -- the runs ---------------------------------------------------------------------------
def offset_search(text: str, parser):
    """The ``--offset-search`` text as an :class:`OffsetSearch` (None for 'off')."""
    if text.strip() == "off":
        return None
    fields = [f.name for f in dataclasses.fields(OffsetSearch)]
    values = {}
    for item in filter(None, (x.strip() for x in text.split(","))):
        key, _, value = (x.strip() for x in item.partition("="))
        if key not in fields:
            parser.error(f"--offset-search: no setting {key!r} (one of {', '.join(fields)})")
        try:
            values[key] = (int if key == "refinements" else float)(value)
        except ValueError:
            parser.error(f"--offset-search: {item!r} is not {key}=NUMBER")
    try:
        return OffsetSearch(**values)
    except NavcoreError as exc:
        parser.error(f"--offset-search: {exc}")


def calibrate_clock(log_dir: Path, parameters) -> dict:
    """Calibrate the IMU clock of the log in ``log_dir`` in place
    (:func:`orchestrator.running.clock_calibration.calibrate` through the Kf with
    ``parameters``, on the fixes the log holds: the outages cut); the offset taken."""
    model = scenarios.load_scenario(ROOT / "models" / "replay_gnss_ins_sim")
    found, _ = clock_calibration.calibrate(model, log_dir, "Kf", parameters)
    print("clock calibration:", found.summary(), flush=True)
    return {"imu_time_offset_calibrated_s": round(found.offset, 4)}


def run_filter(log_dir: Path, name: str, parameters, smooth=False, synchronize=True,
               search=OffsetSearch()):
    """One replay of ``log_dir`` through filter ``name`` (its smoothed solution with
    ``smooth``, :mod:`orchestrator.running.smoothing`, the IMU's clock synchronized with
    ``synchronize``, the likelihood search ``search``): (run, the warnings it raised)."""
    model = scenarios.load_scenario(ROOT / "models" / "replay_gnss_ins_sim")
    simulate = (partial(smoothing.smoothed_run, synchronize=synchronize, search=search)
                if smooth
                else partial(scenarios.simulate_scenario, backend="direct"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = simulate(model, filter=name, log=None, replay=log_dir, parameters=parameters)
    said = [str(w.message) for w in caught if issubclass(w.category, NavfmuWarning)]
    return run, list(dict.fromkeys(said))


def fix_epoch_errors(run, first: float, lever=None):
    """(seconds after the first fix, NED position error [m], reported sigmas [m]) at the
    rows where a new reference fix has just arrived (the truth holds between fixes); on an
    IMU grid that the fixes do not fall on, the solution at that row less its velocity
    times the time since the fix.

    The reference fixes are the antenna's, the filters' position the IMU's: with the lever
    arm ``lever`` (body FRD, IMU to antenna [m], :func:`lever_arm`) the solution is carried
    to the antenna with its own attitude (``r + C_bn l``) before it is compared, as the
    filters compare it with the fixes they take."""
    col = run.results.column
    tt = col("replay", "truth_time")
    fresh = np.r_[False, np.diff(tt) != 0]
    ok = fresh & (col("filter", "aligned") > 0.5) & np.isfinite(col("replay", "truth_lat"))
    late = col("filter", "nav_time") - tt        # the first IMU epoch at or after the fix
    ok &= np.abs(late) < run.model.base_step + 1e-9
    lat, h = col("replay", "truth_lat")[ok], col("replay", "truth_h")[ok]
    rn, re = earth.radii(lat)
    err = np.column_stack([(col("filter", "nav_lat")[ok] - lat) * (rn + h),
                           (col("filter", "nav_lon")[ok] - col("replay", "truth_lon")[ok])
                           * (re + h) * np.cos(lat),
                           -(col("filter", "nav_h")[ok] - h)])
    # an IMU grid off the fixes' (a calibrated clock): the solution carried back to the fix
    err -= np.column_stack([col("filter", f"nav_v{a}")[ok] for a in "ned"]) * late[ok, None]
    if lever is not None and np.any(lever):
        C_bn = euler_to_dcm_array(*(col("filter", f"nav_{a}")[ok]
                                    for a in ("roll", "pitch", "yaw")))
        err += antenna_position_offset(C_bn, np.asarray(lever, dtype=float))
    std = np.column_stack([col("filter", f"std_p{a}")[ok] for a in "ned"])
    return run.time_origin + tt[ok] - first, err, std


def lever_arm(parameters) -> np.ndarray:
    """The antenna's lever arm ``filter.lever_arm_x/y/z`` of ``parameters`` [m] (0 unset)."""
    return np.array([float(parameters.get(f"filter.lever_arm_{a}", 0.0)) for a in "xyz"])


def score(t, err, std, outages):
    """The table's numbers of one run (module docstring)."""
    in_outage = np.zeros(len(t), bool)
    for a, b in outages:
        in_outage |= (t > a) & (t <= b)
    after = []
    for _, b in outages:
        k = np.flatnonzero(t > b)
        after.append(float(np.linalg.norm(err[k[AFTER_FIXES - 1]])) if len(k) >= AFTER_FIXES
                     else float("nan"))
    ratio2 = (err / std) ** 2
    inside = ratio2 <= 9.0
    return {"rms": np.sqrt(np.mean(err ** 2, axis=0)).tolist(),
            "rms_fix": np.sqrt(np.mean(err[~in_outage] ** 2, axis=0)).tolist(),
            "after": after,
            "inside_3sigma_pct": (100.0 * np.mean(inside, axis=0)).tolist(),
            "inside_3sigma_fix_pct": (100.0 * np.mean(inside[~in_outage], axis=0)).tolist(),
            "inside_3sigma_outage_pct": (100.0 * np.mean(inside[in_outage], axis=0)).tolist(),
            "nees": float(np.mean(ratio2.sum(axis=1))),
            "max": float(np.max(np.linalg.norm(err, axis=1))), "n": int(len(t))}


def outage_score(t, err, outages):
    """The issue's scoring of the outages ``outages`` (the drive's own: its 2nd to last):
    horizontal error at the reference fixes inside them: RMS, the mean over the outages of
    the error at the last fix inside each (the outage's end), the largest."""
    horizontal = np.hypot(err[:, 0], err[:, 1])
    inside, ends = [], []
    for a, b in outages:
        k = np.flatnonzero((t > a) & (t <= b))
        if len(k):
            inside.append(horizontal[k])
            ends.append(float(horizontal[k[-1]]))
    if not inside:
        return {}
    every = np.concatenate(inside)
    return {"outage_rms": float(np.sqrt(np.mean(every ** 2))),
            "outage_end_mean": float(np.mean(ends)), "outage_max": float(every.max())}


def correlation_time(t, err, outages) -> float:
    """[s] the median over the axes and the stretches between outages of the 1/e time of the
    autocorrelation of the filter's error at the fixes: run on the Kf without
    ``gnss_corr_time``, the correlation time of what the fixes' errors leave in the solution
    (the value the guide's recipe gives ``gnss_corr_time``)."""
    interval = float(np.median(np.diff(t)))     # the fix interval
    edges = [t[0] - 1.0] + [x for a, b in outages for x in (a, b + 5.0)] + [t[-1] + 1.0]
    times = []
    for a, b in zip(edges[::2], edges[1::2]):
        part = err[(t > a) & (t <= b)]
        if len(part) < 40:
            continue
        for y in (part - part.mean(axis=0)).T:
            ac = np.correlate(y, y, "full")[len(y) - 1:]
            times.append(float(np.argmax(ac / ac[0] < math.exp(-1.0))) * interval)
    return float(np.median(times)) if times else float("nan")


def short_warning(text: str) -> str:
    """A run's warning as a table cell: the NIS warning's time and the imu_noise_factor it
    suggests, the inconsistency share."""
    if "NIS above" in text:
        _, said, factor = text.partition("try imu_noise_factor = ")
        return ("NIS@" + text.split("at t = ")[1].split(" s")[0] + "s"
                + (f" (factor {factor.split(' ')[0]})" if said else ""))
    if "is inconsistent" in text:
        return "inconsistent " + text.split(": ")[1].split(" of")[0]
    return text[:60]


def table(rows) -> str:
    """The markdown table of every filter, ratios to the Kf where it ran."""
    kf = rows.get("Kf")
    head = ("| filter | RMS N/E/D [m] | x Kf | RMS with fixes N/E/D [m] | after 10/30/60 s [m] "
            "| x Kf | inside 3 sigma N/E/D [%] | NEES | warnings |\n"
            + "|---" * 9 + "|")
    lines = [head]
    for name, r in rows.items():
        if "error" in r:
            lines.append(f"| {name} | failed: {r['error']} | | | | | | | |")
            continue
        x = (f"{np.linalg.norm(r['rms']) / np.linalg.norm(kf['rms']):.2f}" if kf and "rms" in kf
             else "-")
        xa = ("/".join(f"{a / b:.1f}" for a, b in zip(r["after"], kf["after"]))
              if kf and "after" in kf else "-")
        lines.append(
            f"| {name} | {'/'.join(f'{v:.2f}' for v in r['rms'])} | {x} | "
            f"{'/'.join(f'{v:.3f}' for v in r['rms_fix'])} | "
            f"{'/'.join(f'{v:.2f}' for v in r['after'])} | {xa} | "
            f"{'/'.join(f'{v:.0f}' for v in r['inside_3sigma_pct'])} | {r['nees']:.3g} | "
            f"{'; '.join(short_warning(w) for w in r['warnings']) or '-'} |")
    return "\n".join(lines)


def outage_table(rows) -> str:
    """The issue's scoring (:func:`outage_score`) of every filter as a markdown table."""
    lines = ["| filter | RMS in outages [m] | mean error at outage end [m] | max [m] |",
             "|---|---:|---:|---:|"]
    for name, r in rows.items():
        if "outage_rms" in r:
            lines.append(f"| {name} | {r['outage_rms']:.2f} | {r['outage_end_mean']:.2f} | "
                         f"{r['outage_max']:.1f} |")
    return "\n".join(lines)


def peer_fixes_outages(drive: Path, schedule=PEER_SCHEDULE):
    """:func:`peer_outages` of ``schedule`` over the fixes of the drive's RTKLIB solution."""
    pos = next(drive.glob("*.pos"))
    times = [line.split()[1] for line in pos.read_text().splitlines()
             if line.strip() and not line.startswith("%")]
    seconds = [sum(float(x) * f for x, f in zip(hms.split(":"), (3600.0, 60.0, 1.0)))
               for hms in times]
    shift = seconds[0] - math.floor(seconds[0])    # build_log counts from the whole second
    return [(a + shift, b + shift) for a, b in peer_outages(seconds[0], seconds[-1], schedule)]


def _value(text: str):
    """A ``--set`` value: a JSON number or true/false, else the text."""
    try:
        return json.loads(text)
    except ValueError:
        return text


def _setup(args, parser) -> dict:
    """The run's IMU preparation, outage schedule, fix sigma gains and parameters over
    :data:`DRIVE_PARAMETERS`: from ``--config`` when given, else the drive's; the
    ``--misalign``, ``--time-offset`` and ``--rate`` given over them."""
    misalign, time_offset, rate = [180.0, -6.79, 185.35], -0.125, 100.0
    out = {"schedule": PEER_SCHEDULE, "sigma_scale": None, "parameters": {}, "config": None}
    if args.config is not None:
        try:
            out["config"] = cfg = gnss_imu_config.read_config(args.config)
            misalign, time_offset, rate = gnss_imu_config.imu_preparation(cfg, args.config)
            out.update(schedule=gnss_imu_config.schedule(cfg, args.config),
                       sigma_scale=gnss_imu_config.sigma_scale(cfg),
                       parameters=gnss_imu_config.filter_parameters(cfg, args.config))
        except gnss_imu_config.ConfigError as exc:
            parser.error(f"--config: {exc}")
    if args.misalign is not None:
        misalign = [float(x) for x in args.misalign.split(",")]
    return {**out, "misalign": misalign,
            "time_offset": time_offset if args.time_offset is None else args.time_offset,
            "rate": rate if args.rate is None else args.rate}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("drive", type=Path, help="folder with the .pos, imu csv and .tag files")
    p.add_argument("--outages", default=OUTAGES,
                   help="a:b,... seconds after the first fix, or 'peer': the peer's own "
                        "schedule (the drive's, 15 s every 45 s from 40 s, or --config's)")
    p.add_argument("--scored-from", type=int, default=2, metavar="N",
                   help="with --outages peer, score its outages from the N-th (default 2: the "
                        "drive's scoring, outages 2 to 11; 1 scores them all)")
    p.add_argument("--aids", default="",
                   help="land aids to switch on: any of zupt,zaru,nhc (with nhc the drive's "
                        "NHC point, NHC_PARAMETERS; --set over it)")
    p.add_argument("--filters", default=",".join(FILTERS))
    p.add_argument("--set", action="append", default=[], metavar="COMPONENT.NAME=VALUE",
                   help="a parameter over the drive's (repeatable)")
    p.add_argument("--config", type=Path, default=None,
                   help="the peer's configuration of the log (its drive_config.py, "
                        "walk_config.py): filter parameters, IMU mounting, delay and rate, "
                        "fix sigma gains and the 'peer' outage schedule from it "
                        "(benchmarks/gnss_imu_config.py); --set and the options over it")
    p.add_argument("--misalign", default=None,
                   help="sensor-to-body Euler angles roll,pitch,yaw [deg] (default: the "
                        "config's, else the drive's 180,-6.79,185.35)")
    p.add_argument("--time-offset", type=float, default=None,
                   help="[s] added to the IMU times (default: the config's, else -0.125)")
    p.add_argument("--rate", type=float, default=None,
                   help="[Hz] the IMU grid (default: the config's, else 100)")
    p.add_argument("--imu-start", type=float, default=None,
                   help="[s] UNIX GPST time of the IMU file's first sample (without a .tag "
                   "file: the counter taken as it is)")
    p.add_argument("--work", type=Path, default=None,
                   help="folder for the logs (default: temporary)")
    p.add_argument("--json", type=Path, default=None, help="write the numbers here too")
    p.add_argument("--smooth", action="store_true",
                   help="add each filter's smoothed solution (a row '<filter>-smoothed')")
    p.add_argument("--no-sync", action="store_true",
                   help="smooth without estimating the IMU's time offset to the GNSS clock")
    p.add_argument("--offset-search", default="",
                   help="the smoother's likelihood search of the IMU's time offset: 'off' "
                   "(the course estimate only) or KEY=VALUE,... of OffsetSearch (bound, step, "
                   "tolerance, refinements, around_start)")
    p.add_argument("--calibrate-clock", action="store_true",
                   help="calibrate the log's IMU clock first (navfmu convert time-offset: "
                   "estimated through the Kf on the log with the outages cut, the IMU's "
                   "times moved onto the GNSS clock), then run every filter on it")
    args = p.parse_args(argv)
    setup = _setup(args, p)
    search = offset_search(args.offset_search, p)
    peer = args.outages == "peer"
    outages = (peer_fixes_outages(args.drive, setup["schedule"]) if peer
               else parse_outages(args.outages))
    work = args.work or Path(tempfile.mkdtemp(prefix="real_drive_"))
    log, first = build_log(args.drive, work, outages, setup["misalign"], setup["time_offset"],
                           setup["rate"], args.imu_start, setup["sigma_scale"])
    parameters = {**DRIVE_PARAMETERS, **setup["parameters"]}
    if setup["config"] is not None:
        parameters.update(gnss_imu_config.velocity_sigmas(setup["config"], log.gnss))
    for aid in filter(None, args.aids.split(",")):
        if aid not in AIDS:
            p.error(f"--aids: {aid!r} is not one of {', '.join(AIDS)}")
        parameters[f"filter.{aid}"] = True
        if aid == "nhc" and args.config is None:
            parameters.update(NHC_PARAMETERS)
    for item in args.set:
        key, _, value = item.partition("=")
        parameters[key] = _value(value)
    calibrated = {}
    if args.calibrate_clock:
        calibrated = calibrate_clock(work / "log", parameters)
    rows = {}
    runs = [(name, False) for name in args.filters.split(",")]
    if args.smooth:
        runs += [(name, True) for name in args.filters.split(",")]
    for name, smooth in runs:
        label = name + smoothing.SMOOTHED_SUFFIX if smooth else name
        try:
            run, said = run_filter(work / "log", name, parameters, smooth, not args.no_sync,
                                   search)
            t, err, std = fix_epoch_errors(run, first, lever_arm(parameters))
            smoother = run.results.metadata.get("smoother", {})
            clock = {k: v for k, v in smoother.items() if k in (
                "imu_time_offset_s", "imu_time_offset_runs", "imu_time_offset_fit_per_fix")}
            rows[label] = {**score(t, err, std, outages), "warnings": said, **clock,
                           **calibrated,
                           "residual_corr_time_s": correlation_time(t, err, outages),
                           **outage_score(t, err, outages[args.scored_from - 1:] if peer
                                          else outages)}
        except Exception as exc:  # a filter that stops is a row of the table, not the end
            rows[label] = {"error": str(exc).splitlines()[0][:120]}
        print(label, json.dumps(rows[label]), flush=True)
    print(table(rows))
    print(outage_table(rows))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
