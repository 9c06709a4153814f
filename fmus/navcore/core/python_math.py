"""Python's own float functions that a compiled kernel does not give: written out for kernels
that must give, bit for bit, the floats of the interpreted code that calls Python's.

:func:`hypot` is ``math.hypot`` where interpreted code calls it and :func:`compiled_hypot`
compiled into the kernels that call it: CPython's algorithm for two floats (``vector_norm``
of its ``mathmodule.c``: exact squares and sums, then a differential correction of the
square root).  C's ``hypot``, which numba and numpy call, rounds otherwise for a fraction of a
percent of arguments.  Written from CPython 3.11, the interpreter this project is measured on; the
tests compare the two bit for bit (CPython 3.12 changed only the branch of subnormal
arguments, which no attitude reaches).
"""
from __future__ import annotations

import math

from numba.extending import overload

from .kernels import jitable

#: Veltkamp's splitting constant, 2 ** 27 + 1
_SPLITTER = 134217729.0


@jitable
def _split(x):
    """Dekker's split of ``x``: (hi, lo), hi holding its upper 26 bits, hi + lo == x."""
    t = x * _SPLITTER
    hi = t - (t - x)
    return hi, x - hi


@jitable
def _exact_product(x, y):
    """Dekker's product: (p, e) with p the rounded x * y and p + e == x * y exactly."""
    xh, xl = _split(x)
    yh, yl = _split(y)
    p = xh * yh
    q = xh * yl + xl * yh
    z = p + q
    return z, p - z + q + xl * yl


@jitable
def _exact_sum(a, b):
    """Fast two-sum (|a| >= |b|): (s, e) with s the rounded a + b and s + e == a + b."""
    s = a + b
    return s, b - (s - a)


@jitable
def _norm(x, y, largest):
    """CPython 3.11's ``vector_norm`` of the finite (|x|, |y|), ``largest`` their maximum
    > 0 (3.12 rescales subnormals instead of the branch below, the other floats alike)."""
    exponent = math.frexp(largest)[1]
    if exponent < -1023:          # CPython 3.11: ldexp(1, -e) would overflow, divide instead
        csum, frac = 1.0, 0.0
        for v in (x, y):
            v = v / largest
            v = v * v
            previous = csum
            csum += v
            frac += (previous - csum) + v
        return largest * math.sqrt(csum - 1.0 + frac)
    scale = math.ldexp(1.0, -exponent)
    csum, frac1, frac2 = 1.0, 0.0, 0.0
    for v in (x, y):
        v = v * scale                                 # lossless scaling
        square, square_low = _exact_product(v, v)
        csum, low = _exact_sum(csum, square)
        frac1 += square_low
        frac2 += low
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    square, square_low = _exact_product(-h, h)
    csum, low = _exact_sum(csum, square)
    frac1 += square_low
    frac2 += low
    h += (csum - 1.0 + (frac1 + frac2)) / (2.0 * h)   # differential correction
    return h / scale


@jitable
def compiled_hypot(x, y):
    """:func:`hypot` as kernels compute it: CPython 3.11's algorithm, bit for bit."""
    x, y = abs(x), abs(y)
    largest = 0.0                     # CPython's maximum: a NaN never is larger
    if x > largest:
        largest = x
    if y > largest:
        largest = y
    if math.isinf(largest):
        return largest
    if x != x or y != y:
        return math.nan
    if largest == 0.0:
        return largest
    return _norm(x, y, largest)


def hypot(x, y):
    """``math.hypot(x, y)``, in interpreted code and in kernels alike (there
    :func:`compiled_hypot`)."""
    return math.hypot(x, y)


@overload(hypot)
def _hypot_in_kernels(x, y):
    return compiled_hypot


__all__ = ["compiled_hypot", "hypot"]
