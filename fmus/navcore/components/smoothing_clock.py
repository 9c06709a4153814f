"""What the smoother's runs keep to synchronize the IMU's clock with the GNSS clock
(:meth:`navcore.components.smoothing.SmoothingSession.synchronize`): the inputs the
estimate compares (:class:`ClockInputs`) and how well a run's fixes fit its filter
(:class:`FixFit`), which decides which run (which offset) is smoothed and is the cost the
likelihood search (:mod:`navcore.filters.time_offset_search`) minimizes."""
from __future__ import annotations

import math

import numpy as np

from ..filters import imu_time_offset
from ..filters.rts_smoother import GrowingRows


class ClockInputs:
    """The IMU intervals and the valid fixes a run's filter received, as they came: what
    :func:`navcore.filters.imu_time_offset.estimate` compares."""

    def __init__(self):
        self.imu = GrowingRows(8)         # imu_time, imu_dt, dtheta x/y/z, dvel x/y/z
        self.fixes = GrowingRows(3)       # gnss_time, lat, lon
        self.last_epoch = None

    def take(self, inputs):
        """The inputs of one step: a new IMU interval, a new valid fix."""
        imu = self.imu
        if inputs["imu_dt"] > 0 and (imu.n == 0 or inputs["imu_time"] > imu.rows[-1, 0]):
            imu.append(inputs["imu_time"], inputs["imu_dt"],
                       *(inputs[f"imu_dtheta_{a}"] for a in "xyz"),
                       *(inputs[f"imu_dvel_{a}"] for a in "xyz"))
        epoch = inputs["gnss_epoch"]
        if epoch != self.last_epoch:
            self.last_epoch = epoch
            if inputs["gnss_valid"] and np.isfinite(inputs["gnss_time"]):
                self.fixes.append(inputs["gnss_time"], inputs["gnss_lat"], inputs["gnss_lon"])

    def estimate(self):
        """The IMU's time offset (:class:`navcore.filters.imu_time_offset.TimeOffset`)."""
        i, f = self.imu.rows, self.fixes.rows
        return imu_time_offset.estimate(i[:, 0], i[:, 1], i[:, 2:5], i[:, 5:8], f[:, 0],
                                        f[:, 1], f[:, 2])

    def imu_interval(self):
        """[s] the median IMU interval received."""
        return float(np.median(self.imu.rows[:, 1])) if self.imu.n else 0.0


class FixFit:
    """The fixes' fit of a run: the innovation's negative log-likelihood per fix,
    ``(v' S^-1 v + ln det S) / 2`` summed over the fixes applied (the constant left out),
    the criterion of a maximum-likelihood choice between two models of the same fixes
    (Schweppe 1965, "Evaluation of likelihood functions for Gaussian signals", IEEE Trans.
    Inf. Theory 11(1): the prediction-error decomposition)."""

    def __init__(self):
        self.n = 0
        self.total = 0.0

    def add(self, result):
        """A fix's update (its :class:`navcore.filters.ins_gnss_kf.UpdateResult`)."""
        sign, logdet = np.linalg.slogdet(result.S)
        self.total += 0.5 * (result.nis + (logdet if sign > 0 else math.inf))
        self.n += 1

    def mean(self) -> float:
        """Per fix (inf without a fix)."""
        return self.total / self.n if self.n else math.inf


__all__ = ["ClockInputs", "FixFit"]
