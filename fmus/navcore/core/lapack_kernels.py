"""LAPACK inside kernels: the Cholesky routines ``scipy.linalg.lapack`` wraps, callable from
compiled code without a Python call per matrix.

A batch factors one small covariance per run (a 6 x 6 or 15 x 15 matrix); through the Python
wrappers each call costs a few microseconds of overhead, more than the factorization.  The
routines here are the same LAPACK library's (scipy's, whose Cython module
``scipy.linalg.cython_lapack`` exports the function pointers), so a kernel gets the floats the
Python wrapper gets for the same input bytes.  Each routine is a plain Python function that
calls ``scipy.linalg.lapack`` (what a kernel runs interpreted, ``NUMBA_DISABLE_JIT=1``) with a
compiled implementation (numba's ``overload``) that calls the routine by a symbol this module
gives the routine's address when it is imported; compiled code names the symbol, not the
address, so a kernel read from the cache in another process calls that process's routine.

Arrays are Fortran-ordered 2-D float arrays (as LAPACK reads them), overwritten in place:

* :func:`potrf_lower`: the lower Cholesky factor ``L`` of ``a`` (``dpotrf``, uplo L: only the
  lower triangle is read and written);
* :func:`potrs_lower`: ``b`` becomes ``A^-1 b`` for ``A = L L^T`` (``dpotrs``);
* :func:`trtrs_lower`: ``b`` becomes ``L^-1 b`` (``dtrtrs``, not transposed, not unit).

Each returns LAPACK's ``info`` (0: done; > 0 for ``dpotrf``: not positive definite).
"""
from __future__ import annotations

import llvmlite.binding
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import get_cython_function_address, intrinsic, overload
from scipy.linalg import lapack

from .kernels import jitable

_L, _N = ord("L"), ord("N")


def _symbol(routine: str) -> str:
    """The symbol of a LAPACK routine, given its address in this process."""
    symbol = f"navcore_lapack_{routine}"
    llvmlite.binding.add_symbol(
        symbol, get_cython_function_address("scipy.linalg.cython_lapack", routine))
    return symbol


def potrf_lower(a: np.ndarray) -> int:
    """``dpotrf`` (uplo L) of the Fortran-ordered ``a`` (n, n), in place; LAPACK's info."""
    c, info = lapack.dpotrf(a, lower=1, clean=0, overwrite_a=1)
    if c is not a:
        a[...] = c
    return int(info)


def potrs_lower(l: np.ndarray, b: np.ndarray) -> int:
    """``dpotrs`` (uplo L) with the factor ``l`` (n, n) on the Fortran-ordered ``b`` (n, k),
    in place; LAPACK's info."""
    x, info = lapack.dpotrs(l, b, lower=1, overwrite_b=1)
    if x is not b:
        b[...] = x
    return int(info)


def trtrs_lower(l: np.ndarray, b: np.ndarray) -> int:
    """``dtrtrs`` (uplo L, no transpose, not unit) with ``l`` (n, n) on the Fortran-ordered
    ``b`` (n, k), in place; LAPACK's info."""
    x, info = lapack.dtrtrs(l, b, lower=1, overwrite_b=1)
    if x is not b:
        b[...] = x
    return int(info)


def _caller(routine: str, count: int):
    """An intrinsic calling the LAPACK ``routine`` with the ``count`` addresses of its tuple
    argument (integers) as its pointer arguments."""
    symbol = _symbol(routine)

    @intrinsic
    def call(typingctx, pointers):
        if not (isinstance(pointers, types.BaseTuple) and len(pointers) == count
                and all(isinstance(t, types.Integer) for t in pointers)):
            return None

        def codegen(context, builder, signature, args):
            pointer = ir.IntType(8).as_pointer()
            function = cgutils.get_or_insert_function(
                builder.module, ir.FunctionType(ir.VoidType(), [pointer] * count), symbol)
            builder.call(function, [builder.inttoptr(builder.extract_value(args[0], i), pointer)
                                    for i in range(count)])
            return context.get_dummy_value()

        return types.void(pointers), codegen

    return call


_dpotrf, _dpotrs, _dtrtrs = _caller("dpotrf", 5), _caller("dpotrs", 8), _caller("dtrtrs", 10)


@jitable
def _check(a, b):
    """The arrays a compiled routine hands to LAPACK: ``a`` square, ``b`` with its rows, both
    Fortran-ordered (LAPACK reads memory, not strides)."""
    if a.shape[0] != a.shape[1] or b.shape[0] != a.shape[0]:
        raise ValueError("LAPACK kernel: the matrices' shapes do not agree")
    if not (a.flags.f_contiguous and b.flags.f_contiguous):
        raise ValueError("LAPACK kernel: the matrices must be Fortran-ordered")


@jitable
def _scalars(*values):
    """The int32 cells LAPACK reads its characters and sizes from (a character is the first
    byte of its cell) and writes ``info`` into (the last cell)."""
    cells = np.zeros(len(values) + 1, dtype=np.int32)
    for i, value in enumerate(values):
        cells[i] = value
    return cells


@overload(potrf_lower, jit_options={"nogil": True})
def _potrf_lower(a):
    def impl(a):
        _check(a, a)
        n = a.shape[0]
        cells = _scalars(_L, n, max(n, 1))
        p = cells.ctypes.data
        _dpotrf((p, p + 4, a.ctypes.data, p + 8, p + 12))
        return int(cells[3])
    return impl


@overload(potrs_lower, jit_options={"nogil": True})
def _potrs_lower(l, b):
    def impl(l, b):
        _check(l, b)
        n = l.shape[0]
        cells = _scalars(_L, n, b.shape[1], max(n, 1), max(n, 1))
        p = cells.ctypes.data
        _dpotrs((p, p + 4, p + 8, l.ctypes.data, p + 12, b.ctypes.data, p + 16, p + 20))
        return int(cells[5])
    return impl


@overload(trtrs_lower, jit_options={"nogil": True})
def _trtrs_lower(l, b):
    def impl(l, b):
        _check(l, b)
        n = l.shape[0]
        cells = _scalars(_L, _N, _N, n, b.shape[1], max(n, 1), max(n, 1))
        p = cells.ctypes.data
        _dtrtrs((p, p + 4, p + 8, p + 12, p + 16, l.ctypes.data, p + 20, b.ctypes.data,
                 p + 24, p + 28))
        return int(cells[7])
    return impl


__all__ = ["potrf_lower", "potrs_lower", "trtrs_lower"]
