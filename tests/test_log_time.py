"""Sensor-log times as recorded (navcore.log_time): UNIX-stamped and jittered IMU logs, gaps
and overlaps named by line, GNSS/truth that miss the IMU's span, the truth's span in the
metrics, and --start/--stop in the log's time.  The references are the gnss-ins-sim log
(an independent simulator) replayed as it comes: a re-stamped or re-cut copy of it must give
the filter the numbers the original gives, or errors within a stated bound of them."""
from __future__ import annotations

import math
import shutil
from decimal import Decimal

import numpy as np
import pytest

from navcore.components.replay import ImuGnssReplay
from navcore.sensors.log_time import replay_step
from navcore.sensors.sensorlog import LogError, SensorLog, read_log, write_log
from orchestrator.building import build as fmu_build
from orchestrator.running import replay, scenarios
from orchestrator.errors import NavfmuError

GIS_MODEL = fmu_build.ROOT / "models" / "replay_gnss_ins_sim"
GIS_LOG = GIS_MODEL / "log"
UNIX = 1_700_000_000   # a UNIX time stamp of 2023 [s]


def _shift_times(src, dst, seconds):
    """Copy of the log ``src`` with every time stamp plus ``seconds``, added to the text
    exactly (as a logger stamping in another time scale would have written it)."""
    dst.mkdir()
    for path in src.iterdir():
        lines = path.read_text().splitlines()
        j = lines[0].split(",").index("time [s]")
        out = [lines[0]]
        for line in lines[1:]:
            fields = line.split(",")
            fields[j] = str(Decimal(seconds) + Decimal(fields[j]))
            out.append(",".join(fields))
        (dst / path.name).write_text("\n".join(out) + "\n")


def _kf_run(log, **replay_options):
    model = scenarios.load_scenario(GIS_MODEL)
    return scenarios.simulate_scenario(model, backend="direct", replay=log, log=None,
                                       replay_options=replay_options)


@pytest.fixture(scope="module")
def original():
    return _kf_run(GIS_LOG)


def test_unix_stamped_copy_replays_bit_for_bit(tmp_path, original):
    """The gnss-ins-sim log re-stamped in UNIX time: parsed as floats its 100 Hz intervals
    would differ by up to 2e-5 relative (2.4e-7 s steps of float64 at 1.7e9 s); held relative
    to the origin they are exact, and Kf computes the very numbers of the original."""
    _shift_times(GIS_LOG, tmp_path / "unix", UNIX)
    naive = np.array([float(x.split(",")[0]) for x in
                      (tmp_path / "unix" / "imu.csv").read_text().splitlines()[1:]])
    assert np.abs(np.diff(naive) / 0.01 - 1).max() > 1e-5      # what a float parse would see
    log = read_log(tmp_path / "unix")
    assert log.time_origin == UNIX
    assert np.array_equal(log.imu["time"], read_log(GIS_LOG).imu["time"])
    shifted = _kf_run(tmp_path / "unix")
    assert shifted.time_origin == UNIX
    assert np.array_equal(shifted.results.data["filter"], original.results.data["filter"])
    # writing adds the origin back exactly: the files read back to the same log
    write_log(tmp_path / "again", log)
    assert (tmp_path / "again" / "imu.csv").read_text().splitlines()[1].startswith(
        "1700000000.01,")
    again = read_log(tmp_path / "again")
    assert again.time_origin == UNIX and np.array_equal(again.imu["time"], log.imu["time"])


def _merge_intervals(log, groups):
    """``log`` with consecutive IMU intervals merged into one per group of lengths
    ``groups`` (cycled): the increments of a merged interval are the sums, exactly the
    integrals over it, as an IMU with that stamping would have delivered them."""
    n = len(log.imu["time"])
    ends, k, g = [], 0, 0
    while k < n:
        k = min(n, k + groups[g % len(groups)])
        ends.append(k - 1)
        g += 1
    ends = np.array(ends)
    starts = np.concatenate([[0], ends[:-1] + 1])
    imu = {"time": log.imu["time"][ends],
           "dt": log.imu["time"][ends] - np.concatenate([[log.start_time],
                                                         log.imu["time"][ends[:-1]]])}
    for key in ("dtheta_x", "dtheta_y", "dtheta_z", "dvel_x", "dvel_y", "dvel_z"):
        imu[key] = np.add.reduceat(log.imu[key], starts)
    return SensorLog(imu, log.gnss, log.truth, log.time_origin)


def test_jittered_intervals_are_integrated_as_recorded(tmp_path, original):
    """The log re-cut into intervals of 10, 20 and 10 ms, 30 ms in turn (merged increments,
    exact): the default bound refuses the first 20 ms interval (2 times the median, a lost
    sample?) naming its line; with max_dt_jitter = 2 it replays, stepped at the shortest
    interval, every interval integrated once, and Kf's errors within 10 % (+2 cm) of the
    original's (the difference: the coning and sculling of longer intervals)."""
    write_log(tmp_path / "jitter", _merge_intervals(read_log(GIS_LOG), (1, 2, 1, 3)))
    with pytest.raises(LogError, match=r"imu.csv, line 3: dt = 0.0199.* 2 times the nominal "
                       r"interval 0.01.* a gap .* beyond max_dt_jitter = 0.75"):
        read_log(tmp_path / "jitter")
    log = read_log(tmp_path / "jitter", max_dt_jitter=2.0)
    assert replay_step(log.imu["time"], log.imu["dt"]) == pytest.approx(0.01, abs=1e-12)
    run = _kf_run(tmp_path / "jitter", max_dt_jitter=2.0)
    nav_time = run.results.column("filter", "nav_time")
    assert len(np.unique(nav_time)) == len(log.imu["time"]) + 1   # the start, then each one
    a, b = original.metrics["filter"], run.metrics["filter"]
    for group in ("position_rms_m", "velocity_rms_mps"):
        for axis in "ned":
            assert b[group][axis] == pytest.approx(a[group][axis], rel=0.1, abs=0.02), group
    assert run.results.column("filter", "updated").sum() == 41      # every valid fix used


def test_replay_component_outputs_each_jittered_interval_once(tmp_path):
    """Stepped at the replay step of a 6/9/3 ms log, each communication step reaches at most
    one interval end, and every interval is output, in order, once."""
    dt = np.tile([0.006, 0.009, 0.003, 0.006], 25)
    t = 0.5 + np.cumsum(dt)        # relative to the origin UNIX: exact at any time scale
    imu = {"time": t, "dt": dt, **{f"d{q}_{a}": np.zeros(len(t)) for q in ("theta", "vel")
                                   for a in "xyz"}}
    gnss = {"time": np.array([t[0]]), "lat": np.array([0.8]), "lon": np.array([0.1]),
            "h": np.array([10.0]), "valid": np.array([1.0])}
    write_log(tmp_path / "log", SensorLog(imu, gnss, None, time_origin=UNIX))
    log = read_log(tmp_path / "log")
    assert log.time_origin == UNIX and np.array_equal(log.imu["time"], t)
    step = log.replay_step
    assert step == pytest.approx(0.003)
    c = ImuGnssReplay(log=str(tmp_path / "log"))
    seen = [c.initialize(log.start_time)["imu_time"]]      # the start, no interval yet
    for k in range(int(round((log.stop_time - log.start_time) / step))):
        out = c.step(log.start_time + k * step, step, {})
        if out["imu_time"] != seen[-1]:
            seen.append(out["imu_time"])
    assert seen[0] == log.start_time and np.array_equal(seen[1:], log.imu["time"])


@pytest.mark.parametrize("dt_factor,kind", [(2.0, "a gap"), (0.2, "an overlap")])
def test_gap_and_overlap_name_the_line(tmp_path, dt_factor, kind):
    log = read_log(GIS_LOG)
    imu = {k: v.copy() for k, v in log.imu.items()}
    # one interval of another length, the later stamps moved so the intervals still tile
    imu["dt"][40] *= dt_factor
    imu["time"][40:] += imu["dt"][40] - log.imu["dt"][40]
    write_log(tmp_path / "log", SensorLog(imu, log.gnss, log.truth))
    with pytest.raises(LogError, match=rf"imu.csv, line 42: dt = .* {dt_factor:g} times the "
                       rf"nominal interval .*: {kind}"):
        read_log(tmp_path / "log")


def test_gnss_and_truth_outside_the_imu_span_are_refused(tmp_path):
    log = read_log(GIS_LOG)
    gnss = dict(log.gnss, time=log.gnss["time"] + 1000.0)
    with pytest.raises(LogError, match=r"gnss.csv: times 1000.0 to 1080.0 s do not overlap the "
                       r"IMU's 0.0 to 80.05 s \(.*imu.csv\)"):
        write_log(tmp_path / "log", SensorLog(log.imu, gnss, log.truth))
    assert not (tmp_path / "log").exists()
    write_log(tmp_path / "log", log)
    _shift_times(GIS_LOG / ".." / "log", tmp_path / "other", 339_750)   # another week's time
    shutil.copy(tmp_path / "other" / "truth.csv", tmp_path / "log" / "truth.csv")
    with pytest.raises(LogError, match=r"log/truth.csv: times 339750.0 to 339830.05 s do not "
                       "overlap the IMU's"):
        read_log(tmp_path / "log")


def test_metrics_only_over_the_truth_span(tmp_path, original):
    """A truth file covering 20-60 s of the log: the replay's truth outputs are NaN outside
    it (never zeros), the metrics count only the samples inside and state the span, and
    they equal the full-truth run's metrics over the window 20-60 s."""
    log = read_log(GIS_LOG)
    inside = (log.truth["time"] >= 20.0 - 1e-9) & (log.truth["time"] <= 60.0 + 1e-9)
    truth = {k: v[inside] for k, v in log.truth.items()}
    write_log(tmp_path / "log", SensorLog(log.imu, log.gnss, truth))
    run = _kf_run(tmp_path / "log")
    r = run.results
    t = r.time
    for name in ("truth_time", "truth_lat", "truth_yaw"):
        x = r.column("replay", name)
        assert np.isnan(x[t < 20.0 - 1e-6]).all() and np.isnan(x[t > 60.0 + 1e-6]).all()
        assert np.isfinite(x[(t >= 20.0) & (t <= 60.0)]).all()
    m = run.metrics["filter"]
    assert m["truth_span_s"] == pytest.approx([20.0, 60.0])
    assert m["window_s"] == pytest.approx([20.0, 60.0])
    model = scenarios.load_scenario(GIS_MODEL)
    full = scenarios.simulate_scenario(model, backend="direct", replay=GIS_LOG, log=None,
                                       window=(20.0, 60.0)).metrics["filter"]
    assert m["samples"] == full["samples"]
    for group in ("position_rms_m", "velocity_rms_mps", "attitude_rms_deg"):
        for axis in m[group]:
            assert m[group][axis] == pytest.approx(full[group][axis], rel=1e-12), group


def test_start_and_stop_in_the_log_time(tmp_path):
    """--start/--stop take the log's own time (here UNIX): the run starts at the first
    interval beginning at or after --start, on the log's relative time axis."""
    _shift_times(GIS_LOG, tmp_path / "unix", UNIX)
    model = scenarios.load_scenario(GIS_MODEL)
    new, notes = replay.replay_model(model, tmp_path / "unix", start_time=UNIX + 30.004,
                                     stop_time=UNIX + 50.0)
    assert notes["time_origin"] == UNIX
    assert new.start_time == pytest.approx(30.01) and new.stop_time == pytest.approx(50.0)
    run = _kf_run(tmp_path / "unix", start_time=UNIX + 30.004)
    assert run.results.time[0] == pytest.approx(30.01)
    assert math.isfinite(run.metrics["filter"]["position_rms_m"]["n"])
    with pytest.raises(NavfmuError, match=r"--start 1700000090.0: after the last IMU "
                       r"interval of the log .*, which ends at 1700000080.05 s"):
        replay.replay_model(model, tmp_path / "unix", start_time=UNIX + 90.0)


def test_cli_start_needs_replay(tmp_path, navfmu_cli):
    code, _, err = navfmu_cli("run", GIS_MODEL, "--start", "3", "--backend", "direct",
                              "--out", tmp_path / "out")
    assert code == 2 and err.startswith("navfmu: error: --start needs --replay"), err
    assert not (tmp_path / "out").exists()
