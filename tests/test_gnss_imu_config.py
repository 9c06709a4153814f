"""benchmarks/gnss_imu_config.py reads the peer's configuration files (rtklibexplorer/GNSS_IMU's
drive_config.py, walk_config.py) without running them, and benchmarks/rtklib_tag.py times a
logger's IMU lines from RTKLIB's tag file.  The configs below are written here in the peer's
form (their values as in its public repository); the references are worked by hand."""
from __future__ import annotations

import importlib.util
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from peer_configs import DRIVE_CONFIG as DRIVE

ROOT = Path(__file__).resolve().parents[1]


def _module(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


CFG = _module("gnss_imu_config")
TAG = _module("rtklib_tag")



def _write(tmp_path, text, name="drive_config.py"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_drive_config_gives_the_peer_s_effective_process_noise(tmp_path):
    cfg = CFG.read_config(_write(tmp_path, DRIVE))
    assert cfg["imu_misalign"] == pytest.approx([180.0, -6.79, 185.35])    # the += is read
    assert CFG.imu_preparation(cfg) == (pytest.approx([180.0, -6.79, 185.35]), -0.125, 100.0)
    p = CFG.filter_parameters(cfg)
    # the densities times sqrt(100 Hz) times the factors: the drive's "Q x10" of the guide
    # (docs/guide/land_aids.md: 2.28 deg/sqrt(h), 1400 ug/sqrt(Hz), 1980 ug, 19.3 deg/h)
    assert p["filter.q_gyro_arw_dpsh"] == pytest.approx(0.0038 * 60 * 10 * 1)
    assert p["filter.q_accel_vrw_ugpsHz"] == pytest.approx(1400.0)
    assert p["filter.q_accel_bias_instability_ug"] == pytest.approx(1980.0, abs=0.5)
    assert p["filter.q_gyro_bias_instability_dph"] == pytest.approx(19.3, abs=0.05)
    assert p["filter.imu_noise_factor"] == 1.0
    # lever arm IMU -> antenna, NHC point = the system origin seen from the IMU
    assert [p[f"filter.lever_arm_{a}"] for a in "xyz"] == pytest.approx([0.0, -0.05, 0.0])
    assert [p[f"filter.nhc_lever_{a}"] for a in "xyz"] == pytest.approx([0.0, 0.0, 0.65])
    assert p["filter.p0_att_yaw"] == pytest.approx(math.radians(100.0))
    assert p["filter.p0_gyro_bias_dph"] == pytest.approx(720.0)
    assert p["filter.p0_accel_bias_ug"] == pytest.approx(0.2 / 9.80665e-6)
    assert p["filter.zaru_sigma"] == pytest.approx(math.radians(0.01))
    assert p["filter.stationary_window_s"] == pytest.approx(0.5)
    assert p["filter.stationary_rate_rms"] == pytest.approx(math.radians(0.25))
    assert p["filter.nhc_rate_max"] == pytest.approx(math.radians(20.0))
    assert CFG.sigma_scale(cfg) == "fix=1,float=2,single=5"


def test_the_schedule_is_the_peer_s_on_the_drive_and_on_the_walk(tmp_path):
    bench = _module("real_drive")
    drive = CFG.schedule(CFG.read_config(_write(tmp_path, DRIVE)))
    assert drive == bench.PEER_SCHEDULE
    # the drive: 549 s of fixes, eleven outages from 40 s, one every 45 s
    out = bench.peer_outages(0.0, 549.0, drive)
    assert len(out) == 11 and out[0] == (40.0, 55.0) and out[-1] == (490.0, 505.0)
    walk = DRIVE.replace("start_coast = 40", "start_coast = 25").replace(
        "end_coast = 30", "end_coast = 45")
    schedule = CFG.schedule(CFG.read_config(_write(tmp_path, walk, "walk_config.py")))
    # the walk: 133.75 s of fixes, outages until 45 s before the end: two
    assert bench.peer_outages(0.0, 133.75, schedule) == [(25.0, 40.0), (70.0, 85.0)]
    # an outage that starts before the margin is cut there, as GNSS_IMU.py marks it
    assert bench.peer_outages(0.0, 120.0, schedule) == [(25.0, 40.0), (70.0, 75.0)]


def test_a_config_without_a_needed_value_is_an_error_naming_it(tmp_path):
    cfg = CFG.read_config(_write(tmp_path, DRIVE.replace("coast_len = 15\n", "")))
    with pytest.raises(CFG.ConfigError, match="coast_len"):
        CFG.schedule(cfg, "drive_config.py")
    cfg = CFG.read_config(_write(tmp_path, DRIVE.replace("imu_sample_rate = 100",
                                                         "imu_sample_rate = rate()")))
    with pytest.raises(CFG.ConfigError, match="imu_sample_rate"):   # not a literal: unread
        CFG.filter_parameters(cfg, "drive_config.py")


def _tag_file(path, start, records):
    header = b"\0" * 60 + struct.pack("<IId", 0, int(start), start - int(start))
    path.write_bytes(header + np.asarray(records, dtype="<u4").tobytes())


def test_the_counter_is_fitted_to_the_arrivals_not_to_a_first_burst(tmp_path):
    # 2000 samples every 6 ms from 20 ms after the start; the link writes each line 4 ms
    # after its sample, except the first 17, written together at 113 ms (the walk's burst);
    # the log was written with CR LF and has LF now
    n, t0 = 2000, 20.0
    sample_ms = t0 + 6.0 * np.arange(n)
    counter = 3326339 + 6 * np.arange(n)
    lines = [f"0.01,-0.02,1.0,0.1,-0.1,0.2,{c}".encode() for c in counter]
    ends = np.cumsum([len(line) + 2 for line in lines])
    arrive = np.maximum(sample_ms + 4.0, np.where(np.arange(n) < 17, 113.0, 0.0))
    records = [(round(a), e) for a, e in zip(arrive, ends)]
    tag = tmp_path / "imu.csv.tag"
    start = 1756402240.961
    _tag_file(tag, start, records)
    times = TAG.sample_times(lines, counter.astype(float), np.arange(n), tag)
    # each sample at its time plus the link's 4 ms, within a millisecond; stretching the
    # counter over the first and last record would put the first sample 89 ms late
    assert np.max(np.abs(times - start - (sample_ms + 4.0) / 1000.0)) < 1e-3
    stretched = arrive[0] + (counter - counter[0]) * (arrive[-1] - arrive[0]) / (
        counter[-1] - counter[0])
    assert stretched[0] - (sample_ms[0] + 4.0) > 85.0
