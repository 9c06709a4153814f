"""ImuGnssReplay: a recorded sensor log played through the outputs of TrajectoryImu and
GnssReceiver, so every filter runs on real or foreign data unchanged.

Stepping rule (time tags decide, never call order): a step ``(t, t + h]`` outputs

* the IMU interval of the log that ends in ``(t, t + h]`` (``imu_time``, ``imu_dt`` and the
  increments exactly as logged; ``imu_gyro_*``/``imu_accel_*`` = increment / dt); the
  component must be stepped at the log's replay step
  (:func:`navcore.sensors.log_time.replay_step`: its IMU period, or the shortest interval of
  a jittered log), so each step holds at most
  one interval, and a step past the end of the log is an error;
* the latest GNSS line with ``time <= t + h``: its values, ``gnss_valid`` from the log's
  ``valid``, and ``gnss_epoch`` = the number of GNSS lines reached so far (a filter updates
  when it changes); a log without velocity columns outputs velocity 0 (run such a log with
  a filter's ``measurement`` = ``position``), and the log's ``std_n/e/d`` as
  ``gnss_std_*`` (0 without them);
* the latest truth line with ``time <= t + h`` (``truth_*``), when the log has a truth file
  and ``t + h`` lies within the truth's span; before its first sample and after its last
  every truth output (``truth_time`` too) is NaN: no truth, never a zero a metric would
  score; without a truth file the truth outputs stay 0 and ``truth_time`` stays at the start
  time (a run then records no truth).

Times are the log's relative to its origin (:attr:`navcore.sensors.sensorlog.SensorLog.time_origin`,
the whole second at or below its first IMU stamp), so the run's time axis starts near 0
whatever the log's stamps.

Any communication step works: a step reaching several IMU lines outputs the last of them
(a filter downstream then sees the skipped intervals and stops with an error naming
``imu_time``), a step reaching none holds the outputs.  Times are compared with
:func:`navcore.core.timing.time_tolerance` on the log's IMU period, as in the other components.  At
initialization the outputs are the log's state at the start time (no IMU interval yet, ``imu_dt`` =
0).  Everything the component needs comes from its ``log`` parameter (a folder in the format of
:mod:`navcore.sensors.sensorlog`), read at initialization, once per process and content of
the log (:mod:`navcore.sensors.log_cache`).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..core import signals
from ..core.component import Component, InputError, Limits, ParameterError, real, string
from ..core.timing import time_tolerance
from ..sensors.log_time import DEFAULT_MAX_DT_JITTER, MAX_DT_JITTER_LIMIT
from ..sensors.log_cache import derived, shared_log
from .replay_batch import ImuGnssReplayBatch

_TRUTH_NAMES = ("lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw")
_GNSS_VALUES = ("lat", "lon", "h", "vn", "ve", "vd")
_GNSS_STD = ("std_n", "std_e", "std_d")
_GNSS_STD_NAMES = tuple(p.name for p in signals.GNSS_STD)
# output names, built once: the step writes them per IMU line
_TRUTH_OUTPUTS = tuple("truth_" + name for name in _TRUTH_NAMES)
_GNSS_NAMES = tuple("gnss_" + name for name in _GNSS_VALUES)
#: per body axis: the (dtheta, dvel, gyro, accel) output names
_IMU_NAMES = tuple(zip(signals.IMU_DTHETA_NAMES, signals.IMU_DVEL_NAMES, signals.IMU_GYRO_NAMES,
                       signals.IMU_ACCEL_NAMES))


def _tables(log):
    """The replay's IMU, GNSS and truth tables (one row per line, the columns the step
    reads); read-only, as they are shared by every replay of the log."""
    imu = np.column_stack([log.imu[k] for k in ("time", "dt", "dtheta_x", "dtheta_y",
                                                "dtheta_z", "dvel_x", "dvel_y", "dvel_z")])
    g = log.gnss
    zeros = np.zeros_like(g["time"])
    gnss = np.column_stack([g["time"]] + [g.get(k, zeros) for k in _GNSS_VALUES]
                           + [g["valid"], g.get("outlier", zeros)]
                           + [g.get(k, zeros) for k in _GNSS_STD])
    truth = (None if log.truth is None else
             np.column_stack([log.truth["time"]] + [log.truth[k] for k in _TRUTH_NAMES]))
    for table in (imu, gnss, truth):
        if table is not None:
            table.setflags(write=False)
    return imu, gnss, truth


class ImuGnssReplay(Component):
    """Plays a sensor log through the IMU, GNSS and truth outputs (module docstring)."""

    file_parameters = ("log",)
    description = ("Replays a recorded sensor log (IMU increments, GNSS fixes, optional truth; "
                   "the navfmu sensor-log format) through the outputs of TrajectoryImu and "
                   "GnssReceiver, so any INS/GNSS filter runs on recorded or foreign data.")
    parameters = (
        string("log", "folder of the sensor log (imu.csv, gnss.csv, optional truth.csv)", ""),
        real("max_dt_jitter", "", "largest relative deviation of an IMU interval from the "
             "log's nominal (median) interval; beyond it the log is refused as having a gap "
             "or an overlap", DEFAULT_MAX_DT_JITTER, Limits(0.0, MAX_DT_JITTER_LIMIT)),
    )
    inputs = ()
    #: the runs of a batch replaying one log step once (navcore.core.batch)
    batch_class = ImuGnssReplayBatch
    outputs = (signals.TRUTH + signals.IMU + signals.GNSS + signals.GNSS_INJECTED
               + signals.GNSS_STD)
    default_experiment = (0.0, 10.0, 0.01)
    # the log's arrays are re-read from the `log` parameter on restore; only the read
    # positions and the held outputs change while stepping (navcore.core.state)
    state_fields = ("next_imu", "n_gnss", "n_truth", "out")
    derived_fields = ("log_folder", "imu", "gnss", "truth", "period", "start_time",
                      "truth_end")

    def initialize(self, start_time):
        folder = self.params["log"]
        if not folder:
            raise ParameterError(f"{self.model_name}: parameter 'log' is empty (give the folder "
                                 "of a sensor log)")
        self.log_folder = str(Path(folder).resolve())
        log = shared_log(self.log_folder, self.params["max_dt_jitter"])
        self.imu, self.gnss, self.truth = derived(log, "replay_tables", _tables)
        self.start_time = float(start_time)
        self.period = log.replay_step
        self.truth_end = None if self.truth is None else float(self.truth[-1, 0])
        # first IMU interval ending after the start
        limit = self._limit(self.start_time)
        self.next_imu = int(np.searchsorted(self.imu[:, 0], limit, side="right"))
        self.n_gnss = 0
        self.n_truth = 0
        self.out = {p.name: p.default() for p in self.outputs}
        self.out["imu_time"] = self.start_time
        self.out["gnss_time"] = self.start_time
        self.out["truth_time"] = self.start_time
        if self.truth is not None:
            self._no_truth()
        self._advance(limit)
        return dict(self.out)

    def _limit(self, t):
        return t + time_tolerance(self.period, t)

    def _advance(self, limit):
        """GNSS and truth lines up to ``limit`` (a step's end plus the time tolerance)."""
        out = self.out
        n = int(np.searchsorted(self.gnss[:, 0], limit, side="right"))
        if n != self.n_gnss:
            self.n_gnss = n
            row = self.gnss[n - 1].tolist()
            out["gnss_time"] = row[0]
            for name, value in zip(_GNSS_NAMES, row[1:7]):
                out[name] = value
            out["gnss_valid"] = row[7] == 1.0
            out["gnss_outlier"] = row[8] == 1.0
            out["gnss_epoch"] = n
            for name, value in zip(_GNSS_STD_NAMES, row[9:12]):
                out[name] = value
        if self.truth is not None:
            n = int(np.searchsorted(self.truth[:, 0], limit, side="right"))
            if limit - 2.0 * time_tolerance(self.period, limit) > self.truth_end:
                if self.n_truth <= len(self.truth):
                    self.n_truth = len(self.truth) + 1     # past the truth's span
                    self._no_truth()
            elif n != self.n_truth and n > 0:
                self.n_truth = n
                row = self.truth[n - 1].tolist()
                out["truth_time"] = row[0]
                for name, value in zip(_TRUTH_OUTPUTS, row[1:]):
                    out[name] = value

    def _no_truth(self):
        for name in ("truth_time",) + _TRUTH_OUTPUTS:
            self.out[name] = math.nan

    def step(self, t, h, inputs):
        t_end = t + h
        limit = self._limit(t_end)
        n = int(np.searchsorted(self.imu[:, 0], limit, side="right"))
        if n == self.next_imu:
            due = float(self.imu[-1, 0]) + self.period          # the next line, were there one
            if n == len(self.imu) and limit >= due:
                raise InputError(f"{self.model_name}: the log {self.log_folder} ends at "
                                 f"{float(self.imu[-1, 0])!r} s; no IMU interval in "
                                 f"({float(t)!r}, {float(t_end)!r}] s")
            self._advance(limit)
            return self.out        # no IMU line reached: the outputs hold
        self.next_imu = n
        row = self.imu[n - 1].tolist()
        out = self.out
        dt = row[1]
        out["imu_time"] = row[0]
        out["imu_dt"] = dt
        for i, (dtheta, dvel, gyro, accel) in enumerate(_IMU_NAMES):
            out[dtheta] = row[2 + i]
            out[dvel] = row[5 + i]
            out[gyro] = row[2 + i] / dt
            out[accel] = row[5 + i] / dt
        self._advance(limit)
        return out
