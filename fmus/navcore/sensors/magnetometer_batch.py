"""The magnetometer models of a batch's runs (:mod:`navcore.core.batch`) sampled in one call.

:class:`MagnetometerBatch` stacks the per-run values of B
:class:`~navcore.sensors.magnetometer.MagnetometerModel` objects (noise, hard iron, the
vibration's switch, start, factor, noise, amplitude and frequency, the blocks of normals of
their own generators) and gives every run's reading of one sample, for one attitude shared
by the runs, and the vibration's extra specific force of the runs it acts on, with numpy
operations over the run axis.  Each of them is the operation a model alone does
(:meth:`~navcore.sensors.magnetometer.MagnetometerModel.measure`,
:meth:`~navcore.sensors.magnetometer.MagnetometerModel.accel_disturbance`) on the same
floats, so every row is its model's value bit for bit; the field in body axes is one product
per distinct field and soft iron.  Each generator draws its block of normals when the block is
used up, as a model alone does, so every row sees its model's stream; the stacked block and
its position are the batch's: the models' own ``_normals`` stay where the batch took them.
"""
from __future__ import annotations

import math
from typing import List, Sequence, Tuple

import numpy as np

from .magnetometer import _AXIS_PHASES, MagnetometerModel, _reading


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
        self.any_vibration = bool(self.vibration_on.any())
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

    def _next_normals(self) -> np.ndarray:
        """The 6 normals of a new sample of every run (B, 6): each generator's next block
        when the block is used up (:meth:`MagnetometerModel._next_normals`)."""
        n = self.n_used
        if n == self.normals.shape[1]:
            for b, m in enumerate(self.models):
                self.normals[b] = m.rng.standard_normal(m._normals.shape)
            n = 0
        self.n_used = n + 1
        return self.normals[:, n]

    def sample(self, t: float, C_bn: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One sample at time ``t`` for the attitude ``C_bn`` shared by the runs: every
        run's reading [T] (B, 3), the rows the vibration acts on (an index array) and their
        extra specific force [m/s^2] (one row each)."""
        z = self._next_normals()
        body = np.empty((len(self.models), 3))
        for model, rows in self.field_groups:
            body[rows] = model.soft_iron @ (C_bn.T @ model.field_ned)
        if not self.any_vibration:
            return _reading(body, self.hard_iron, self.noise[:, None], z[:, :3]), \
                np.zeros(0, dtype=np.intp), np.zeros((0, 3))
        vibrating = self.vibration_on & (t >= self.vibration_start)
        factor = np.where(vibrating, self.vibration_mag_factor, 1.0)
        reading = _reading(body, self.hard_iron, (self.noise * factor)[:, None], z[:, :3])
        rows = np.flatnonzero(vibrating)
        phase = 2.0 * math.pi * self.vibration_frequency[rows] * (t - self.vibration_start[rows])
        sine = self.vibration_amplitude[rows, None] * np.sin(phase[:, None] + _AXIS_PHASES)
        return reading, rows, sine + self.vibration_noise[rows, None] * z[rows, 3:]


__all__ = ["MagnetometerBatch"]
