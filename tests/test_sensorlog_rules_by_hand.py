"""The sensor-log rules at their edges, on logs written out by hand: each bound taken at
exactly its value and just past it, the line an error names when blank lines are skipped, the
time origin of a log that starts just below a whole second, the text the writer gives a log
held relative to an origin, and how the folder is written (next to the destination, with the
permissions of a folder made by mkdir)."""
from __future__ import annotations

import numpy as np
import pytest

from navcore.sensors import sensorlog
from navcore.sensors.sensorlog import LogError, SensorLog, check_log, read_log, write_log


def _imu(times, dt):
    """IMU columns with zero increments at the given interval ends and lengths."""
    n = len(times)
    return {"time": np.array(times, dtype=float), "dt": np.array(dt, dtype=float),
            **{f"dtheta_{a}": np.zeros(n) for a in "xyz"},
            **{f"dvel_{a}": np.zeros(n) for a in "xyz"}}


def _gnss(times, lat=0.7):
    n = len(times)
    return {"time": np.array(times, dtype=float), "lat": np.full(n, lat),
            "lon": np.full(n, 2.0), "h": np.full(n, 100.0), "valid": np.ones(n)}


def _small_log():
    """Ten intervals of 0.01 s ending at 0.01 ... 0.1 s, fixes at 0.05 and 0.1 s."""
    return SensorLog(_imu(0.01 * np.arange(1, 11), [0.01] * 10), _gnss([0.05, 0.1]))


@pytest.mark.parametrize("missing", ["imu", "gnss"])
def test_a_log_without_imu_or_gnss_data_is_not_written(tmp_path, missing):
    """Both files are required (read_log refuses a folder without one): writing a log that
    lacks one is refused naming it, and nothing is written."""
    log = _small_log()
    setattr(log, missing, None)
    with pytest.raises(LogError) as exc:
        write_log(tmp_path / "log", log)
    assert str(exc.value).startswith(f"{tmp_path / 'log'}/{missing}.csv: no data"), exc.value
    assert not (tmp_path / "log").exists()
