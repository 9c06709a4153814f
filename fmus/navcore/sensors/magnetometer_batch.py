"""The magnetometer models of a batch's runs (:mod:`navcore.core.batch`) sampled in one call.

:class:`MagnetometerBatch` stacks the per-run values of B
:class:`~navcore.sensors.magnetometer.MagnetometerModel` objects (noise, hard iron, the
vibration's switch, start, factor, noise, amplitude and frequency, the blocks of normals of
their own generators) and gives every run's reading of one sample, for one attitude shared
by the runs, and the vibration's extra specific force of the runs it acts on, in one
kernel call over the run axis.  Each of them is the formula a model alone evaluates
(:meth:`~navcore.sensors.magnetometer.MagnetometerModel.measure`,
:meth:`~navcore.sensors.magnetometer.MagnetometerModel.accel_disturbance`) on the same
floats, so every row is its model's value bit for bit; the field in body axes is one product
per distinct field and soft iron.  Each generator draws its block of normals when the block is
used up, as a model alone does, so every row sees its model's stream; the stacked block and
its position are the batch's: the models' own ``_normals`` stay where the batch took them.
"""
from __future__ import annotations

from typing import List, Sequence, Tuple

import numpy as np

from ..core.kernels import kernel
from .magnetometer import MagnetometerModel, _disturbance, _reading


class MagnetometerBatch:
    """B magnetometer models as rows (module docstring); every model must be at the same
    sample of its block of normals (started together)."""

    def __init__(self, models: Sequence[MagnetometerModel]):
        self.models: List[MagnetometerModel] = list(models)
        if len({m._n_used for m in self.models}) > 1:
            raise ValueError("MagnetometerBatch: the models are not at the same sample")
        self.n_used = self.models[0]._n_used if self.models else MagnetometerModel.NORMALS_BLOCK
        self.normals = np.stack([m._normals for m in self.models]) if self.models else \
            np.zeros((0, MagnetometerModel.NORMALS_BLOCK, 6))
        self._stack()

    def _stack(self) -> None:
        models = self.models

        def column(name):
            return np.array([getattr(m, name) for m in models], dtype=float)

        self.noise = column("noise")
        self.hard_iron = np.array([m.hard_iron for m in models]).reshape(-1, 3)
        self.vibration_on = np.array([m.vibration_on for m in models], dtype=bool)
        self.vibration_start = column("vibration_start")
        self.vibration_mag_factor = column("vibration_mag_factor")
        self.vibration_noise = column("vibration_noise")
        self.vibration_amplitude = column("vibration_amplitude")
        self.vibration_frequency = column("vibration_frequency")
        groups = {}
        for b, m in enumerate(models):
            groups.setdefault(m.field_key, (m, []))[1].append(b)
        #: (a model of the group, its rows): the runs that share a field and soft iron
        self.field_groups = [(m, np.array(rows, dtype=np.intp)) for m, rows in groups.values()]

    def keep(self, rows: Sequence[int]) -> None:
        """Keep the rows ``rows`` (the batch's runs), in that order."""
        rows = list(rows)
        self.models = [self.models[i] for i in rows]
        self.normals = self.normals[rows]
        self._stack()

    def _next_sample(self) -> int:
        """The index of a new sample's 6 normals in every run's block: each generator's next
        block when the block is used up (:meth:`MagnetometerModel._next_normals`)."""
        n = self.n_used
        if n == self.normals.shape[1]:
            for b, m in enumerate(self.models):
                self.normals[b] = m.rng.standard_normal(m._normals.shape)
            n = 0
        self.n_used = n + 1
        return n

    def sample(self, t: float, C_bn: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One sample at time ``t`` for the attitude ``C_bn`` shared by the runs: every
        run's reading [T] (B, 3), the rows the vibration acts on (an index array) and their
        extra specific force [m/s^2] (one row each)."""
        n = self._next_sample()
        runs = len(self.models)
        body = np.empty((runs, 3))
        for model, rows in self.field_groups:
            body[rows] = model.soft_iron @ (C_bn.T @ model.field_ned)
        reading, extra = np.empty((runs, 3)), np.empty((runs, 3))
        vibrating = np.empty(runs, dtype=np.intp)
        count = _sample_rows(float(t), self.normals, n, body, self.hard_iron, self.noise,
                             self.vibration_on, self.vibration_start,
                             self.vibration_mag_factor, self.vibration_frequency,
                             self.vibration_amplitude, self.vibration_noise, reading, extra,
                             vibrating)
        return reading, vibrating[:count], extra[:count]


@kernel
def _sample_rows(t, normals, n, body, hard_iron, noise, vibration_on, start, mag_factor,
                 frequency, amplitude, vibration_noise, reading, extra, vibrating):
    """:meth:`MagnetometerModel.measure` and :meth:`MagnetometerModel.accel_disturbance` of
    every run at time ``t`` on its normals of sample ``n`` (``normals`` (B, block, 6)), the
    field in body axes of each in ``body``: the readings into ``reading``, the extra
    specific force of the vibrating runs into the first rows of ``extra`` and their rows
    into ``vibrating``; returns how many vibrate."""
    count = 0
    for b in range(reading.shape[0]):
        z = normals[b, n]
        on = vibration_on[b] and t >= start[b]
        scale = noise[b] * (mag_factor[b] if on else 1.0)
        for i in range(3):
            reading[b, i] = _reading(body[b, i], hard_iron[b, i], scale, z[i])
        if on:
            extra[count, 0], extra[count, 1], extra[count, 2] = _disturbance(
                amplitude[b], frequency[b], t - start[b], vibration_noise[b], z[3], z[4], z[5])
            vibrating[count] = b
            count += 1
    return count


__all__ = ["MagnetometerBatch"]
