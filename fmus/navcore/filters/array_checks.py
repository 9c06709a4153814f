"""Input checks of the adaptation laws: arrays of the expected shape, finite, as floats.

Cheap on purpose (the laws run once per filter update); every error is an
:class:`~navcore.errors.InputError` naming the argument.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..errors import InputError


def vector(name: str, x) -> np.ndarray:
    """``x`` as a finite float vector of shape (m,) (a scalar becomes shape (1,))."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise InputError(f"{name}: expected a vector of shape (m,), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf: {a}")
    return a


def matrix(name: str, x, rows: Optional[int] = None, cols: Optional[int] = None) -> np.ndarray:
    """``x`` as a finite float matrix with ``rows`` rows and ``cols`` columns (None: any
    number); a scalar is a 1x1 matrix where both are 1."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 and rows == 1 and cols == 1:
        a = a.reshape(1, 1)
    if a.ndim != 2 or rows not in (None, a.shape[0]) or cols not in (None, a.shape[1]):
        want = ", ".join("n" if d is None else str(d) for d in (rows, cols))
        raise InputError(f"{name}: expected shape ({want}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf")
    return a


def square(name: str, x, m: Optional[int] = None) -> np.ndarray:
    """``x`` as a finite float square matrix (of size ``m`` if given; a scalar is 1x1)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise InputError(f"{name}: expected a square matrix, got shape {a.shape}")
    if m is not None and a.shape[0] != m:
        raise InputError(f"{name}: expected shape ({m}, {m}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf")
    return a


def symmetrize(a: np.ndarray) -> np.ndarray:
    """``(a + a') / 2``."""
    return 0.5 * (a + a.T)
