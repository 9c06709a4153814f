"""The IMU error models of a batch's runs (:mod:`navcore.core.batch`) applied in one call.

:class:`ImuErrorBatch` stacks the per-run rows of B :class:`~navcore.sensors.imu_errors.
ImuErrorModel` objects (their increment matrices, constant terms, Gauss-Markov states, the
blocks of normals of their own generators) and applies them to one interval's ideal
increments, shared by every run, with one call of :func:`~navcore.sensors.imu_errors.
apply_rows`, the kernel each model's own :meth:`~navcore.sensors.imu_errors.ImuErrorModel.
apply` calls with one row.  The per-dt coefficients are each model's own
(:meth:`ImuErrorModel._set_dt`); each generator draws its block of normals when the block
is used up, as a model alone does, so every row sees its model's stream.  The stacked
Gauss-Markov state is the batch's: the models' own ``gm_bias`` stay at the start values.
"""
from __future__ import annotations

from typing import List, Sequence

import numpy as np

from .imu_errors import ImuErrorModel, apply_rows


class ImuErrorBatch:
    """B IMU error models as rows (module docstring); every model must be fresh (started
    together: the same position in its block of normals)."""

    def __init__(self, models: Sequence[ImuErrorModel]):
        self.models: List[ImuErrorModel] = list(models)
        if len({m._n_used for m in self.models}) != 1:
            raise ValueError("ImuErrorBatch: the models are not at the same sample")
        self.n_used = self.models[0]._n_used
        self._stack()
        self.cached_dt = None

    def _stack(self) -> None:
        models = self.models
        self.increment_matrix = np.stack([m._increment_matrix for m in models])
        self.level_bias = np.concatenate([m._level_bias for m in models])
        self.gm = np.concatenate([m.gm_bias for m in models])
        self.normals = np.stack([m._normals for m in models])
        self.gain = np.concatenate([m._gain_row for m in models])
        self.vibration_on = np.concatenate([m._vibration_row for m in models])
        self.unit_window = np.ones(len(models))
        self.windows = any(m.noise_level_windows for m in models)
        self.coefficients = np.concatenate([m._coefficients for m in models], axis=1)

    def keep(self, rows: Sequence[int]) -> None:
        """Keep the rows ``rows`` (the batch's runs), in that order."""
        rows = list(rows)
        self.models = [self.models[i] for i in rows]
        for name in ("increment_matrix", "level_bias", "gm", "normals", "gain",
                     "vibration_on", "unit_window"):
            setattr(self, name, getattr(self, name)[rows])
        self.coefficients = self.coefficients[:, rows]

    def apply(self, t_end: float, dt: float, x: np.ndarray, intensity: float) -> np.ndarray:
        """Measured increments ``(B, 6)`` (dtheta, dvel per run) for the ideal increments
        ``x`` (6,) of ``[t_end - dt, t_end]`` and the shared manoeuvre ``intensity``."""
        models = self.models
        if dt != self.cached_dt:
            for m in models:
                m._set_dt(dt)
            self.coefficients = np.concatenate([m._coefficients for m in models], axis=1)
            self.cached_dt = dt
        n = self.n_used
        if n == ImuErrorModel.NORMALS_BLOCK:
            for b, m in enumerate(models):
                self.normals[b] = m.rng.standard_normal(m._normals.shape)
            n = 0
        self.n_used = n + 1
        window = (np.array([m.noise_factor(t_end - 0.5 * dt) for m in models])
                  if self.windows else self.unit_window)
        out = np.empty((len(models), 6))
        phi, drive, white, vibration = self.coefficients
        apply_rows(out, self.increment_matrix @ x, self.normals, n, self.level_bias, self.gm,
                   phi, drive, white, vibration, window, self.gain, self.vibration_on,
                   float(intensity), float(dt))
        return out


__all__ = ["ImuErrorBatch"]
