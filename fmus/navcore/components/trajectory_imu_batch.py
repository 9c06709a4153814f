"""TrajectoryImu's batch (:mod:`navcore.core.batch`): B runs of one motion profile with their
own IMU and magnetometer errors.

The runs of a batch fly the same profile on the same grid (parameters ``profile``,
``imu_period`` and ``extend_profile`` equal to the first run's; a run that sets them
otherwise fails, naming the parameter), so one trajectory generator gives every run's truth
and ideal increments, and the IMU errors of all runs are applied in one kernel call
(:class:`~navcore.sensors.imu_error_batch.ImuErrorBatch`); so are the magnetometer samples and
the vibration's extra specific force of the runs that have them switched on
(:class:`~navcore.sensors.magnetometer_batch.MagnetometerBatch`).
"""
from __future__ import annotations

import copy
from typing import List

import numpy as np

from ..core import signals
from ..core.batch import ComponentBatch
from ..core.kernels import kernel
from ..core.timing import samples_reached
from ..errors import ParameterError
from ..sensors.imu_error_batch import ImuErrorBatch
from ..sensors.imu_errors import INTENSITY_REFERENCE_RATE
from ..sensors.magnetometer_batch import MagnetometerBatch
from ..ins.rotations import _euler_rows

#: the parameters every run of a batch shares (one trajectory)
SHARED_PARAMETERS = ("profile", "imu_period", "extend_profile")
_TRUTH_KEYS = ("lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw")


class TrajectoryImuBatch(ComponentBatch):
    """B runs of :class:`~navcore.components.sensor_components.TrajectoryImu` (module
    docstring)."""

    def _started(self, start_time: float) -> np.ndarray:
        members = self.members
        failed = self._failures
        ref = next((b for b in range(self.runs) if b not in failed), None)
        out = np.zeros((self.runs, len(self.columns)))
        if ref is None:
            return out
        first = members[ref]
        for b, member in enumerate(members):
            differ = [n for n in SHARED_PARAMETERS if member.params[n] != first.params[n]]
            if differ and b not in failed:
                self.fail(b, ParameterError(
                    f"{self.model_name}: parameter '{differ[0]}' = {member.params[differ[0]]!r}"
                    f" differs from the batch's first run ({first.params[differ[0]]!r}); the "
                    "runs of a batch fly one trajectory"))
        alive = [b not in failed for b in range(self.runs)]
        # a failed run's row computes with a copy of the first run's models (never read)
        self.models = [members[b] if alive[b] else copy.deepcopy(first)
                       for b in range(self.runs)]
        self.generator = first.generator
        self.errors = ImuErrorBatch([m.errors for m in self.models])
        self.mag_rows = [b for b, m in enumerate(self.models) if alive[b] and m.mag_on]
        self.magnetometers = MagnetometerBatch([self.models[b].magnetometer
                                                for b in self.mag_rows])
        self.dt, self.start_time, self.n = first.dt, start_time, 0
        for b, m in enumerate(self.models):
            out[b] = self._outputs_of(m)
        self.out = out
        c = self.columns
        # the columns every run shares (truth_time, imu_time, imu_dt, the truth), their
        # values of a sample, and the IMU's columns
        self._shared_cols = np.array([c["truth_time"], c["imu_time"], c["imu_dt"]]
                                     + [c[f"truth_{k}"] for k in _TRUTH_KEYS], dtype=np.intp)
        self._shared = np.zeros(len(self._shared_cols))
        self._imu_cols = np.array([c[n] for n in signals.IMU_DTHETA_NAMES
                                   + signals.IMU_DVEL_NAMES], dtype=np.intp)
        self._rate_cols = np.array([c[n] for n in signals.IMU_GYRO_NAMES
                                    + signals.IMU_ACCEL_NAMES], dtype=np.intp)
        self._mag_cols = [c["mag_time"]] + [c[n] for n in signals.MAG_NAMES]
        self._mag_rows_changed()
        return out.copy()

    def _kept(self, rows: List[int]) -> None:
        if not hasattr(self, "errors"):
            return
        self.models = [self.models[i] for i in rows]
        self.errors.keep(rows)
        self.magnetometers.keep([i for i, b in enumerate(self.mag_rows) if b in rows])
        self.mag_rows = [rows.index(b) for b in self.mag_rows if b in rows]
        self._mag_rows_changed()
        self.out = self.out[rows]

    def _mag_rows_changed(self) -> None:
        self._mag_array = np.array(self.mag_rows, dtype=np.intp)
        self._mag_index = np.ix_(self._mag_array, self._mag_cols[1:])

    def advance(self, t, h, inputs) -> np.ndarray:
        for _ in range(samples_reached(self.start_time, self.dt, t + h) - self.n):
            self._sample()
        return self.out

    def _sample(self) -> None:
        truth, dtheta, dvel = self.generator.step()
        self.n += 1
        dt = self.dt
        t_end = self.start_time + self.n * dt
        intensity = self.generator.last_rate_norm / INTENSITY_REFERENCE_RATE
        measured = self.errors.apply(t_end, dt, np.concatenate((dtheta, dvel)), intensity)
        out = self.out
        if self.mag_rows:
            self._magnetometer(out, measured, t_end, dt, truth)
        shared = self._shared
        shared[0], shared[1], shared[2] = self.start_time + truth["time"], t_end, dt
        shared[3:] = [truth[k] for k in _TRUTH_KEYS]
        _sample_rows(out, self._shared_cols, shared, self._imu_cols, self._rate_cols, measured,
                     dt)

    def _magnetometer(self, out, measured, t_end, dt, truth) -> None:
        """The magnetometer rows and the vibration's extra specific force, as each run's
        ImuMeasurement.measure adds them (:class:`MagnetometerBatch`)."""
        C_bn = np.array(_euler_rows(truth["roll"], truth["pitch"], truth["yaw"]))
        reading, vibrating, extra = self.magnetometers.sample(t_end, C_bn)
        out[self._mag_array, self._mag_cols[0]] = t_end
        out[self._mag_index] = reading
        if vibrating.size:
            vibrating = self._mag_array[vibrating]
            measured[vibrating, 3:] = measured[vibrating, 3:] + extra * dt


@kernel
def _sample_rows(out, shared_cols, shared, imu_cols, rate_cols, measured, dt):
    """One sample's outputs of every run: the values ``shared`` by the runs in their
    columns, each run's measured increments (B, 6) and rates (increments / ``dt``)."""
    for b in range(out.shape[0]):
        o = out[b]
        for j in range(shared_cols.shape[0]):
            o[shared_cols[j]] = shared[j]
        for j in range(6):
            o[imu_cols[j]] = measured[b, j]
            o[rate_cols[j]] = measured[b, j] / dt


__all__ = ["TrajectoryImuBatch", "SHARED_PARAMETERS"]
