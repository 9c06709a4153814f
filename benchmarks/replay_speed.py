"""Campaigns on a recorded log against a compiled C++ filter: CPU ms per run per simulated second.

One invocation runs, per pair, every task of :data:`TASKS` in this checkout and in another
one (``--other``), and KF-GINS (the open-source C++ loosely coupled INS/GNSS filter of
i2Nav-WHU) on the same log when its binary is given; the order of the two checkouts swaps
from pair to pair.  Each task is one process (``python -m orchestrator.cli ...`` on the
checkout's own sources); its cost is the CPU time of that process (user + system, from
``os.wait4``: the core-seconds it took, steadier than wall time on a shared machine) divided
by its runs and their simulated seconds, and its peak memory the process's largest resident
set.  Printed: per task the median over the pairs, the ratio this / other and, with KF-GINS,
each side's ratio to KF-GINS.

Tasks (the table of docs/speed.md "Campaigns on a recorded log"):

* ``run``, ``run-direct``: ``navfmu run models/replay_gnss_ins_sim --replay LOG`` through the
  FMUs and with ``--backend direct`` (one run; CSV written, no plots);
* ``mc-B1``, ``mc-B8``, ``mc-B20``, ``mc-B64``: ``navfmu montecarlo`` of the same replay with
  ``--batch B`` (``B`` runs, 4 for B = 1), one worker; every run replays the log through the
  filter with the parameters of :data:`PARAMETERS`;
* ``sim-B20``, ``sim-B64``: ``navfmu montecarlo models/aircraft_500s --filters Kf`` with B
  runs in one batch (simulated sensors);
* ``compare``, ``compare-direct``: ``navfmu compare models/replay_gnss_ins_sim --replay LOG
  --filters`` the four filters of :data:`COMPARED` (CSV written, no plots), through the FMUs
  and with ``--backend direct``; its runs: the filters.

The log: ``--log`` (a navfmu sensor log folder), else ``--drive`` (a folder of RTKLIB files
laid out as the public drive_0708 of rtklibexplorer/GNSS_IMU, converted by
``benchmarks/real_drive.py``'s ``build_log``; 549 s of a car at 100 Hz, 4 Hz RTK fixes with
outages cut in). The log is cut to start at a whole second of its time (the replay scenario
starts at 0) and written once, untimed, before the pairs. Every run of the filter uses
position-only fixes with a fixed R (:data:`PARAMETERS`), and KF-GINS the same sigmas, the
same noise figures and the same lever arm (its own 21-state filter, scale factors included).

KF-GINS: ``--kf-gins PATH`` or the environment variable ``NAVFMU_KF_GINS`` names its binary;
without it the KF-GINS column is skipped with a message.  It cannot be part of the repository
or CI: get the source from https://github.com/i2Nav-WHU/KF-GINS and build it yourself as its
README says (CMake, Release).  The script writes KF-GINS's input files (IMU increments and
GNSS fixes as its text formats, a YAML configuration) from the log.

    python benchmarks/replay_speed.py --other ../ref --drive path/to/drive_0708 \\
        --kf-gins ~/KF-GINS/bin/KF-GINS --pairs 3
    python benchmarks/replay_speed.py --other ../ref --log LOG --tasks mc-B20 --stop 200
"""
from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from real_drive import DRIVE_PARAMETERS, OUTAGES, build_log, parse_outages
from checkouts import alternating, argument_parser, build_fmus, checkout_env, other_checkout

HERE = Path(__file__).resolve().parents[1]
SCENARIO = "models/replay_gnss_ins_sim"
#: the filter's parameters of every replay run: the drive's (real_drive.py), position-only
#: fixes with a fixed R (the scenario does not wire the receiver's sigmas)
PARAMETERS = {**{k: v for k, v in DRIVE_PARAMETERS.items() if not k.startswith("filter.r_vel")},
              "filter.r_from_receiver": False, "filter.r_pos_n": 0.1, "filter.r_pos_e": 0.1,
              "filter.r_pos_d": 0.2}
#: task -> (kind, batch size); runs: the batch size (4 for B = 1), a comparison's filters
TASKS = {"run": ("run", 1), "run-direct": ("run", 1), "mc-B1": ("replay", 1),
         "mc-B8": ("replay", 8), "mc-B20": ("replay", 20), "mc-B64": ("replay", 64),
         "sim-B20": ("sim", 20), "sim-B64": ("sim", 64),
         "compare": ("compare", 4), "compare-direct": ("compare", 4)}
#: the filters of the ``compare`` tasks (every one takes the parameters of PARAMETERS)
COMPARED = ("Kf", "Iakf", "SageHusaFading", "Ukf")
SIM_SCENARIO, SIM_STOP = "models/aircraft_500s", 500.0
#: simulated seconds of the untimed warm-up campaign (the drive's filter starts at its first
#: valid fix, 36 s in)
WARM_UP_STOP = 60.0
UG = 9.80665e-6          # m/s^2 per micro-g
MGAL = 1e-5              # m/s^2 per mGal


def measured(args, cwd: Path, env, what: str):
    """(CPU seconds, peak resident set [MB]) of one process; a failure ends the benchmark."""
    with tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(args, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode:
            err.seek(0)
            raise SystemExit(f"replay_speed: {what} failed:\n{err.read().decode()[-2000:]}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def _sets():
    """``PARAMETERS`` as ``--set`` options."""
    text = {k: str(v).lower() if isinstance(v, bool) else str(v) for k, v in PARAMETERS.items()}
    return [a for k, v in text.items() for a in ("--set", f"{k}={v}")]


def task_args(task: str, log: Path, stop: float, out: Path, origin: float = 0.0):
    """(arguments of ``python``, runs, simulated seconds per run) of ``task``; ``origin``:
    the log's time origin (``run --replay --stop`` takes the log's time)."""
    kind, batch = TASKS[task]
    cli = [sys.executable, "-m", "orchestrator.cli"]
    backend = ["--backend", "direct"] if task.endswith("-direct") else []
    replayed = ["--replay", str(log), "--stop", repr(origin + stop), "--out", str(out),
                "--no-plots", *backend, *_sets()]
    if kind == "run":
        return cli + ["run", SCENARIO, *replayed], 1, stop
    if kind == "compare":
        return (cli + ["compare", SCENARIO, "--filters", ",".join(COMPARED), *replayed],
                batch, stop)
    runs = 4 if batch == 1 else batch
    if kind == "replay":
        return (cli + ["montecarlo", SCENARIO, "--runs", str(runs), "--filters", "Kf",
                       "--batch", str(batch), "--stop", str(stop), "--out", str(out),
                       "--set", f"replay.log={log}", *_sets()], runs, stop)
    sim_stop = min(stop, SIM_STOP)
    return (cli + ["montecarlo", SIM_SCENARIO, "--runs", str(runs), "--filters", "Kf",
                   "--batch", str(batch), "--stop", str(sim_stop), "--out", str(out)],
            runs, sim_stop)


# -- the log ------------------------------------------------------------------------------
def prepare_log(args, work: Path) -> Path:
    """The log of the benchmark, cut to begin at a whole second of its time (untimed)."""
    import numpy as np
    from navcore.sensors.sensorlog import SensorLog, read_log, write_log

    source = args.log
    if source is None:
        build_log(args.drive, work / "drive", parse_outages(OUTAGES), [180.0, -6.79, 185.35],
                  -0.125, 100.0)
        source = work / "drive" / "log"
    log = read_log(source)
    begins = log.imu["time"] - log.imu["dt"]
    k = int(np.searchsorted(begins, math.ceil(begins[0] - 1e-9) - 1e-9))
    imu = {c: v[k:] for c, v in log.imu.items()}
    return write_log(work / "log", SensorLog(imu, log.gnss, log.truth, log.time_origin))


def kf_gins_inputs(log_dir: Path, work: Path, stop: float) -> Path:
    """KF-GINS's IMU and GNSS text files and its YAML configuration for ``log_dir``: the
    same fixes (position, the filter's fixed sigmas), noise figures and lever arm as
    :data:`PARAMETERS`; the initial state from the first valid fix (velocity from the fix,
    yaw from its course).  Returns the configuration file."""
    import numpy as np
    from navcore.sensors.sensorlog import read_log

    log = read_log(log_dir)
    imu, g = log.imu, log.gnss
    np.savetxt(work / "imu.txt", np.column_stack(
        [imu["time"], imu["dtheta_x"], imu["dtheta_y"], imu["dtheta_z"], imu["dvel_x"],
         imu["dvel_y"], imu["dvel_z"]]), fmt="%.17g")
    valid = g["valid"] == 1
    sigma = [PARAMETERS[f"filter.r_pos_{a}"] for a in "ned"]
    n = int(valid.sum())
    np.savetxt(work / "gnss.txt", np.column_stack(
        [g["time"][valid], np.degrees(g["lat"][valid]), np.degrees(g["lon"][valid]),
         g["h"][valid]] + [np.full(n, s) for s in sigma]), fmt="%.17g")
    start = float(imu["time"][0] - imu["dt"][0])
    first = int(np.flatnonzero(valid & (g["time"] >= start))[0])
    vn, ve, vd = (float(g[k][first]) if k in g else 0.0 for k in ("vn", "ve", "vd"))
    yaw = math.degrees(math.atan2(ve, vn)) if math.hypot(vn, ve) > 1.0 else 0.0
    p = PARAMETERS
    vrw = p["filter.q_accel_vrw_ugpsHz"] * UG * 60.0        # ug/sqrt(Hz) -> m/s/sqrt(h)
    config = {
        "imupath": str(work / "imu.txt"), "gnsspath": str(work / "gnss.txt"),
        "outputpath": str(work / "out"), "imudatalen": 7,
        "imudatarate": round(1.0 / float(np.median(imu["dt"]))),
        "starttime": float(g["time"][first]), "endtime": min(stop, log.stop_time),
        "initpos": [math.degrees(g["lat"][first]), math.degrees(g["lon"][first]),
                    float(g["h"][first])],
        "initvel": [vn, ve, vd], "initatt": [0.0, 0.0, yaw],
        "initgyrbias": [0] * 3, "initaccbias": [0] * 3, "initgyrscale": [0] * 3,
        "initaccscale": [0] * 3,
        "initposstd": sigma, "initvelstd": [0.1] * 3,
        "initattstd": [math.degrees(p["filter.p0_att_level"])] * 2
        + [math.degrees(p["filter.p0_att_yaw"])],
        "initbgstd": [p["filter.p0_gyro_bias_dph"]] * 3,
        "initbastd": [p["filter.p0_accel_bias_ug"] * UG / MGAL] * 3,
        "imunoise": {"arw": [p["filter.q_gyro_arw_dpsh"]] * 3, "vrw": [vrw] * 3,
                     "gbstd": [p["filter.q_gyro_bias_instability_dph"]] * 3,
                     "abstd": [p["filter.q_accel_bias_instability_ug"] * UG / MGAL] * 3,
                     "gsstd": [1000.0] * 3, "asstd": [1000.0] * 3,
                     "corrtime": p["filter.q_gyro_bias_tau_s"] / 3600.0},
        "antlever": [0.0, p["filter.lever_arm_y"], 0.0],
    }
    (work / "out").mkdir(exist_ok=True)
    path = work / "kf-gins.yaml"
    path.write_text("".join(f"{k}: {json.dumps(v)}\n" for k, v in config.items()))
    return path


def kf_gins_binary(args):
    binary = args.kf_gins or os.environ.get("NAVFMU_KF_GINS")
    if not binary:
        print("replay_speed: KF-GINS skipped: no binary given.  Get the source from "
              "https://github.com/i2Nav-WHU/KF-GINS, build it as its README "
              "says (a Release build), and pass --kf-gins PATH or set "
              "NAVFMU_KF_GINS=PATH.", flush=True)
        return None
    binary = Path(binary).expanduser().resolve()
    if not os.access(binary, os.X_OK):
        raise SystemExit(f"replay_speed: --kf-gins {binary}: not an executable file")
    return binary


# -- the pairs ----------------------------------------------------------------------------
def measure(args, log: Path, work: Path, binary, config, stop: float, origin: float):
    checkouts = {"this": HERE, "other": args.other}
    tasks = args.tasks
    cost = {t: {"this": [], "other": []} for t in tasks}
    peak = {t: {"this": [], "other": []} for t in tasks}
    kf = []
    for label, checkout in checkouts.items():
        # untimed: FMUs built, and the compiled kernels of every task kind in the disk cache
        # (a first run after a change to navcore compiles them, several seconds)
        build_fmus(checkout, "replay_speed")
        compared = [t for t in tasks if TASKS[t][0] == "compare"]
        for task in ("run", "run-direct", "mc-B8", "sim-B20", *compared):
            argv, _, _ = task_args(task, log, WARM_UP_STOP, work / f"warm-{label}-{task}",
                                   origin)
            measured(argv, checkout, checkout_env(checkout), "the warm-up")
    for i, order in alternating(args.pairs, ("this", "other")):
        if binary is not None:
            cpu, _ = measured([str(binary), str(config)], work, None, "KF-GINS")
            kf.append(1000.0 * cpu / stop)
            print(f"pair {i + 1}: KF-GINS {kf[-1]:.3f} ms", flush=True)
        for task in tasks:
            for label in order:
                out = work / f"{label}-{i}-{task}"
                argv, runs, seconds = task_args(task, log, stop, out, origin)
                cpu, rss = measured(argv, checkouts[label], checkout_env(checkouts[label]),
                                    f"{task} in {checkouts[label]}")
                cost[task][label].append(1000.0 * cpu / (runs * seconds))
                peak[task][label].append(rss)
            print(f"pair {i + 1}: {task:10s} this {cost[task]['this'][-1]:7.3f} ms  other "
                  f"{cost[task]['other'][-1]:7.3f} ms  (peak {peak[task]['this'][-1]:.0f} / "
                  f"{peak[task]['other'][-1]:.0f} MB)", flush=True)
    return cost, peak, kf


def summary(cost, peak, kf) -> str:
    ref = statistics.median(kf) if kf else None
    head = "/ KF-GINS this, other" if ref else ""
    lines = [f"CPU ms per run per simulated second, medians over the pairs"
             + (f"; KF-GINS {ref:.3f} ms" if ref else ""),
             f"{'task':10s} {'this':>8s} {'other':>8s} {'ratio':>6s} {'peak MB':>15s}  {head}"]
    for task in cost:
        this, other = (statistics.median(cost[task][k]) for k in ("this", "other"))
        ratios = [a / b for a, b in zip(cost[task]["this"], cost[task]["other"])]
        mem = "/".join(f"{statistics.median(peak[task][k]):.0f}" for k in ("this", "other"))
        kfs = f"  {this / ref:.2f}, {other / ref:.2f}" if ref else ""
        lines.append(f"{task:10s} {this:8.3f} {other:8.3f} {statistics.median(ratios):6.3f} "
                     f"{mem:>15s}{kfs}")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argument_parser(__doc__, pairs=3, other=True)
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--log", type=Path, help="a navfmu sensor log folder")
    source.add_argument("--drive", type=Path, help="a folder of RTKLIB drive files "
                        "(benchmarks/real_drive.py)")
    parser.add_argument("--kf-gins", help="the KF-GINS binary (default: $NAVFMU_KF_GINS)")
    parser.add_argument("--stop", type=float, help="simulated seconds of every replay run "
                        "(default: the whole log)")
    parser.add_argument("--tasks", default=",".join(TASKS),
                        help=f"comma-separated, of {', '.join(TASKS)}")
    parser.add_argument("--json", type=Path, help="also write every number to this file")
    args = parser.parse_args(argv)
    args.other = other_checkout(parser, args)
    args.tasks = [t for t in args.tasks.split(",") if t]
    unknown = [t for t in args.tasks if t not in TASKS]
    if unknown:
        parser.error(f"--tasks: unknown {unknown[0]!r} (one of {', '.join(TASKS)})")
    binary = kf_gins_binary(args)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="navfmu-replay-speed-") as tmp:
        work = Path(tmp)
        log = prepare_log(args, work)
        from navcore.sensors.sensorlog import read_log
        read = read_log(log)
        end, origin = read.stop_time, read.time_origin
        stop = end if args.stop is None else min(args.stop, end)
        stop = math.floor(stop * 100.0) / 100.0
        config = kf_gins_inputs(log, work, stop) if binary else None
        cost, peak, kf = measure(args, log, work, binary, config, stop, origin)
    print(summary(cost, peak, kf))
    print(f"({time.perf_counter() - t0:.0f} s in all)")
    if args.json:
        args.json.write_text(json.dumps({"other": str(args.other), "pairs": args.pairs,
                                         "stop": stop, "cost_ms": cost, "peak_mb": peak,
                                         "kf_gins_ms": kf}, indent=2))


if __name__ == "__main__":
    main()
