"""The per-process log cache: one parse per log over many runs and components, a changed file
read again, the same checks and errors as reading the log directly."""
from __future__ import annotations

import os
import shutil

import numpy as np
import pytest

from navcore.components.replay import ImuGnssReplay
from navcore.sensors import log_cache
from navcore.sensors.sensorlog import LogError, read_log
from orchestrator.building import build as fmu_build
from orchestrator.running import replay, scenarios

GIS_DATA = fmu_build.ROOT / "tests" / "data" / "gnss-ins-sim" / "motion_def-3d_mid_100Hz"
GIS_MODEL = fmu_build.ROOT / "models" / "replay_gnss_ins_sim"


@pytest.fixture
def log_copy(tmp_path):
    """A fresh log folder (converted from gnss-ins-sim's files) and an empty cache."""
    folder = tmp_path / "log"
    from orchestrator.cli.convert import convert_gnss_ins_sim
    convert_gnss_ins_sim(GIS_DATA, folder, 0, False)
    log_cache.clear()
    yield folder
    log_cache.clear()


def _replay(folder, stop_steps=3):
    c = ImuGnssReplay()
    c.set_parameter("log", str(folder))
    c.start(0.0)
    for k in range(stop_steps):
        c.step(k * 0.01, 0.01, {})
    return dict(c.out)


def test_one_parse_over_many_runs_and_components(log_copy):
    """Ten replay components and the master's model building read the log: one parse, and
    every component sees the numbers of the log read directly."""
    before = log_cache.parses
    outs = [_replay(log_copy) for _ in range(10)]
    model = scenarios.load_scenario(GIS_MODEL)
    replay.replay_model(model, log_copy)
    assert log_cache.parses - before == 1
    direct = read_log(log_copy)
    assert outs[0]["imu_time"] == direct.imu["time"][2]
    assert outs[0]["imu_dtheta_x"] == direct.imu["dtheta_x"][2]
    assert all(o == outs[0] for o in outs)
    # another jitter bound is checked on its own
    log_cache.shared_log(log_copy, 0.2)
    assert log_cache.parses - before == 2


def test_changed_file_is_read_again(log_copy):
    """A file rewritten with other values (same size, same modification time) is parsed
    again and its new values replayed; a file only touched is not parsed again."""
    first = _replay(log_copy)
    imu = log_copy / "imu.csv"
    stat = imu.stat()
    os.utime(imu, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10 ** 9))
    before = log_cache.parses
    assert _replay(log_copy) == first
    assert log_cache.parses == before
    lines = imu.read_text().splitlines()
    fields = lines[3].split(",")              # the third IMU line: the one replayed
    j = lines[0].split(",").index(next(t for t in lines[0].split(",") if t.startswith("dtheta_x")))
    old = fields[j]
    fields[j] = old[:-1] + ("1" if old[-1] != "1" else "2")     # same length, other value
    lines[3] = ",".join(fields)
    imu.write_text("\n".join(lines) + "\n")
    os.utime(imu, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    again = _replay(log_copy)
    assert log_cache.parses == before + 1
    assert again["imu_dtheta_x"] == float(fields[j]) != first["imu_dtheta_x"]


def test_errors_and_read_only_arrays(log_copy, tmp_path):
    """A bad log raises read_log's error each time (nothing kept); shared arrays refuse
    writes."""
    log = log_cache.shared_log(log_copy)
    with pytest.raises(ValueError):
        log.imu["time"][0] = 1.0
    bad = tmp_path / "bad"
    shutil.copytree(log_copy, bad)
    (bad / "gnss.csv").write_text("time [s]\n")
    for _ in range(2):
        with pytest.raises(LogError, match="gnss.csv"):
            log_cache.shared_log(bad)


def test_off_switch_parses_every_time(log_copy, monkeypatch):
    monkeypatch.setenv("NAVFMU_SHARED_LOGS", "0")
    before = log_cache.parses
    a = log_cache.shared_log(log_copy)
    b = log_cache.shared_log(log_copy)
    assert log_cache.parses - before == 2 and a is not b
    assert np.array_equal(a.imu["time"], b.imu["time"])


def test_a_comparison_on_a_log_parses_it_once(log_copy):
    """``compare --replay``'s runs (one per filter, direct backend) share one parse: the
    master's and every filter's replay component."""
    model = scenarios.load_scenario(GIS_MODEL)
    before = log_cache.parses
    for name in ("Kf", "Iakf"):
        run = scenarios.simulate_scenario(model, filter=name, backend="direct", replay=log_copy,
                                          stop_time=5.0, log=None)
        assert "replay" in run.results.components
    assert log_cache.parses - before == 1
