"""The kernels' copy of Python's ``math.hypot`` (navcore.core.python_math) against CPython's own,
bit for bit: compiled into a kernel, and as its Python source."""
import math
import sys

import numpy as np
import pytest

from navcore.core.kernels import kernel
from navcore.core.python_math import compiled_hypot, hypot


@kernel
def _hypots(x, y, out):
    for i in range(x.shape[0]):
        out[i] = hypot(x[i], y[i])


def _bits(values):
    return np.asarray(values, dtype=float).view(np.uint64)


def _same(got, expected):
    got, expected = np.asarray(got, dtype=float), np.asarray(expected, dtype=float)
    return (_bits(got) == _bits(expected)) | (np.isnan(got) & np.isnan(expected))


def _arguments(subnormal):
    """Pairs over 20 decades, pairs of very different size, the special floats, and (on
    ``subnormal``) pairs of subnormal floats."""
    rng = np.random.default_rng(11)
    n = 200_000
    x = rng.standard_normal(n) * 10.0 ** rng.integers(-10, 10, n)
    y = rng.standard_normal(n) * 10.0 ** rng.integers(-10, 10, n)
    y[:1000] = x[:1000] * rng.uniform(1e-12, 1e-6, 1000)
    special = [0.0, -0.0, 1.0, 3.0, 1.7976931348623157e308, math.inf, -math.inf, math.nan]
    if subnormal:
        x[1000:6000] *= 1e-310
        y[1000:6000] *= 1e-311
        special += [5e-324, 1e-310, 2.2250738585072014e-308]
    x = np.concatenate((x, [a for a in special for _ in special]))
    y = np.concatenate((y, [b for _ in special for b in special]))
    return x, y


@pytest.mark.parametrize("subnormal", [
    False, pytest.param(True, marks=pytest.mark.skipif(
        sys.version_info[:2] != (3, 11), reason="CPython 3.11's branch of subnormal floats"))])
def test_compiled_hypot_is_python_s_bit_for_bit(subnormal):
    x, y = _arguments(subnormal)
    expected = list(map(math.hypot, x.tolist(), y.tolist()))
    got = np.empty(x.size)
    _hypots(x, y, got)
    assert _same(got, expected).all()
    interpreted = list(map(compiled_hypot, x[:20000].tolist(), y[:20000].tolist()))
    assert _same(interpreted, expected[:20000]).all()
    # the case for it: C's hypot (numpy's) rounds otherwise now and then
    assert not _same(np.hypot(x, y), expected).all()
