"""benchmarks/real_drive.py on the trimmed real drive (tests/data/rtklib_drive): the raw
RTKLIB solution and IMU file through the converters, an outage cut in, every INS/GNSS filter
replayed and scored.  The trimmed drive is the car standing (12 s of IMU, 4 Hz RTK fixes of
1 cm): a static alignment at the first fix's position starts the filters, and the 2 s outage
at 9-11 s is what each must bridge.  With the drive's configuration (a consumer IMU's
datasheet figures times imu_noise_factor, the receiver's sigmas inflated for its correlated
errors) every filter stays within 2 times the Kf's error over the run and after the outage,
and 90 % or more of its errors per axis are inside its +/-3 sigma."""
from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DRIVE = ROOT / "tests" / "data" / "rtklib_drive"
#: the first fix of the trimmed drive (its .pos: 40.0966268 deg, -105.1474483 deg, 1601.474 m)
FIRST_FIX = (math.radians(40.0966268), math.radians(-105.1474483), 1601.474)
#: the IMU file's first sample, UNIX seconds on the GPST scale (its README)
IMU_START = 1752003261.854


def _benchmark():
    spec = importlib.util.spec_from_file_location("real_drive", ROOT / "benchmarks" /
                                                  "real_drive.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


pytestmark = pytest.mark.slow      # about 70 s on a busy machine (12 s of CPU)


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    work = tmp_path_factory.mktemp("real_drive")
    bench = _benchmark()
    lat, lon, h = FIRST_FIX
    assert bench.main([str(DRIVE), "--imu-start", str(IMU_START), "--outages", "9:11",
                       "--work", str(work), "--json", str(work / "rows.json"),
                       "--set", "filter.init_mode=align", "--set", "filter.align_time=3",
                       "--set", f"filter.init_lat={lat!r}", "--set", f"filter.init_lon={lon!r}",
                       "--set", f"filter.init_h={h!r}"]) == 0
    return json.loads((work / "rows.json").read_text()), bench


def test_every_filter_runs_and_its_numbers_are_the_standing_cars(rows):
    got, bench = rows
    assert list(got) == list(bench.FILTERS)
    for name, r in got.items():
        assert "error" not in r, (name, r)
        # 12 s of IMU, the first 3 s the alignment: some 35 scored fixes, 8 in the outage
        assert 30 <= r["n"] <= 40, (name, r["n"])
        # standing on 1-cm RTK fixes: centimetres, also after the 2 s outage
        assert max(r["rms"]) < 0.2 and max(r["rms_fix"]) < 0.1, (name, r)
        assert 0.0 < r["after"][0] < 0.2, (name, r["after"])
        assert r["warnings"] == [], (name, r["warnings"])


def test_every_filter_is_within_twice_the_kf_and_honest_about_its_error(rows):
    got, _ = rows
    kf = got["Kf"]
    for name, r in got.items():
        assert np.linalg.norm(r["rms"]) <= 2.0 * np.linalg.norm(kf["rms"]), name
        assert r["after"][0] <= 2.0 * kf["after"][0], (name, r["after"], kf["after"])
        assert min(r["inside_3sigma_pct"]) >= 90.0, (name, r["inside_3sigma_pct"])
        assert 0.0 < r["nees"] < 9.0, (name, r["nees"])
