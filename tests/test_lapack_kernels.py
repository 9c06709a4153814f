"""LAPACK inside kernels (navcore.core.lapack_kernels) and the row functions of the unscented
filters that call it (sigma_points_rows, correct_rows), against scipy's Python wrappers of the same
routines (scipy.linalg.lapack), bit for bit: the wrappers are the path every single filter
took before, so equal bits mean the batch's factorizations changed no number.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import lapack

from navcore.core.kernels import kernel
from navcore.core.lapack_kernels import potrf_lower, potrs_lower, trtrs_lower
from navcore.filters.unscented_rows import correct_rows, points_from_sqrt_rows, sigma_points_rows

ROOT = Path(__file__).resolve().parents[1]


def _bits(a):
    return np.ascontiguousarray(a, dtype=float).view(np.uint64)


def _spd(rng, runs, n, spread=1.0):
    A = rng.normal(size=(runs, n, n)) * spread
    return A @ A.transpose(0, 2, 1) + 1e-3 * np.eye(n)


@kernel
def _factor_solve(S, B, v, info):
    """potrf, potrs and trtrs of every S[b] (Fortran-ordered slices) on B[b] and v[b]."""
    for b in range(S.shape[0]):
        info[b, 0] = potrf_lower(S[b])
        info[b, 1] = potrs_lower(S[b], B[b])
        info[b, 2] = trtrs_lower(S[b], v[b])


def _fortran_slices(values):
    """``values`` (B, n, k) as B Fortran-ordered slices."""
    out = np.empty((values.shape[0], values.shape[2], values.shape[1])).transpose(0, 2, 1)
    out[...] = values
    return out


@pytest.mark.parametrize("compiled", [True, False], ids=["kernel", "source"])
@pytest.mark.parametrize("n", [3, 6, 15])
def test_routines_give_the_wrappers_floats(compiled, n):
    rng = np.random.default_rng(n)
    S = _spd(rng, 300, n, np.repeat([1e-4, 1.0, 1e3], 100)[:, None, None])
    S[7] = -np.eye(n)                                  # not positive definite
    B, v = rng.normal(size=(300, n, 4)), rng.normal(size=(300, n, 1))
    S_f, B_f, v_f = _fortran_slices(S), _fortran_slices(B), _fortran_slices(v)
    info = np.zeros((300, 3), dtype=np.int64)
    (_factor_solve if compiled else getattr(_factor_solve, "py_func", _factor_solve))(
        S_f, B_f, v_f, info)
    assert info[7, 0] > 0
    for b in range(300):
        if b == 7:
            continue
        L, i1 = lapack.dpotrf(S[b], lower=1, clean=1)
        X, i2 = lapack.dpotrs(L, B[b], lower=1)
        u, i3 = lapack.dtrtrs(L, v[b], lower=1)
        assert (i1, i2, i3) == (0, 0, 0) and not info[b].any()
        assert np.array_equal(_bits(np.tril(S_f[b])), _bits(L))
        assert np.array_equal(_bits(B_f[b]), _bits(X))
        assert np.array_equal(_bits(v_f[b]), _bits(u))


def test_a_matrix_in_c_order_is_refused():
    S = np.eye(3)[None] * 2.0
    with pytest.raises(ValueError, match="Fortran"):
        _factor_solve(np.ascontiguousarray(S.transpose(0, 2, 1) + np.triu(np.ones(3), 1)),
                      np.zeros((1, 3, 2)), np.zeros((1, 3, 1)), np.zeros((1, 3), np.int64))


@pytest.mark.parametrize("n", [6, 15])
def test_sigma_points_rows_spread_each_matrix_s_wrapper_factor(n):
    """The eigenvalue fallback included (a singular matrix)."""
    rng = np.random.default_rng(10 + n)
    P = _spd(rng, 60, n)
    P[3] = 0.0
    P[3, 0, 0] = 1.0
    x = rng.normal(size=(60, n))
    X, fallback = sigma_points_rows(x, P, 1.5)
    assert fallback.tolist() == [b == 3 for b in range(60)]
    for b in range(60):
        if b == 3:
            dev = (X[b, 1:n + 1] - x[b]) / 1.5               # the root's columns
            np.testing.assert_allclose(dev.T @ dev, P[b], atol=1e-15)
            continue
        expected, info = lapack.dpotrf(P[b], lower=1, clean=1)
        assert info == 0
        spread = points_from_sqrt_rows(x[b:b + 1], expected[None] * 1.5)[0]
        assert np.array_equal(_bits(X[b]), _bits(spread))


def test_correct_rows_is_each_filter_s_wrapper_path():
    """The gain by dpotrs, the NIS by dtrtrs and numpy's dot, log det S from the factor's
    diagonal: what each filter computed through the wrappers, bit for bit; a filter whose S
    is not positive definite and one whose innovation is not finite keep their status."""
    from navcore.filters.innovation_stats import gaussian_log_likelihood
    rng = np.random.default_rng(4)
    runs, n, m = 40, 6, 6
    x, P = rng.normal(size=(runs, n)), _spd(rng, runs, n)
    S = _spd(rng, runs, m)
    S[5] = -np.eye(m)
    z, z_pred, Pxz = rng.normal(size=(runs, m)), rng.normal(size=(runs, m)), \
        rng.normal(size=(runs, n, m)) * 0.1
    z[9, 2] = np.nan
    got = correct_rows(x, P, z, z_pred, S, Pxz)
    assert got.status[5] == 2 and got.status[9] == 1
    for b in range(runs):
        if b in (5, 9):
            continue
        Ss = 0.5 * (S[b] + S[b].T)
        L, _ = lapack.dpotrf(Ss, lower=1, clean=1)
        Kt, _ = lapack.dpotrs(L, Pxz[b].T, lower=1)
        u, _ = lapack.dtrtrs(L, z[b] - z_pred[b], lower=1)
        nis = float(u @ u)
        log_det = 2.0 * sum(np.log(L[i, i]).item() for i in range(m))
        assert np.array_equal(_bits(got.K[b]), _bits(Kt.T))
        assert got.nis[b] == nis
        assert got.log_likelihood[b] == gaussian_log_likelihood(nis, log_det, m)


def test_a_kernel_read_from_the_cache_calls_this_process_s_routine(tmp_path):
    """The compiled code names the routine's symbol, not its address: a second process
    loading the kernels from the cache (another address of the library) gets the same
    factors."""
    script = textwrap.dedent("""
        import numpy as np
        from navcore.filters.unscented_rows import sigma_points_rows
        rng = np.random.default_rng(0)
        A = rng.normal(size=(5, 6, 6))
        P = A @ A.transpose(0, 2, 1) + np.eye(6)
        print(sigma_points_rows(np.zeros((5, 6)), P, 1.0)[0].sum().hex())
    """)
    env = {**os.environ, "NAVFMU_KERNEL_CACHE": str(tmp_path),
           "PYTHONPATH": os.pathsep.join([str(ROOT / "fmus"), str(ROOT)])}
    runs = [subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                           text=True, check=True).stdout for _ in range(2)]
    assert runs[0] == runs[1] and runs[0].startswith("0x")
    assert any(tmp_path.rglob("*.nbi"))                  # the second run read the cache


def test_sigma_points_rows_are_each_filter_s_own_points():
    """sigma_points_rows against UnscentedKalmanFilter.sigma_points of each filter, bit for
    bit: covariances of 6 and 15 states, one not symmetric (symmetrized for its points), one
    singular (the eigenvalue fallback)."""
    from navcore.filters.unscented import UnscentedKalmanFilter
    rng = np.random.default_rng(21)
    for n in (6, 15):
        P = _spd(rng, 30, n)
        P[4, 0, 1] += 1e-9                                  # not symmetric
        P[7] = 0.0
        P[7, 1, 1] = 2.0                                    # singular
        x = rng.normal(size=(30, n))
        single = UnscentedKalmanFilter(n, 0.5, 2.0, 1.0)
        X, fallback = sigma_points_rows(x, P, single._spread)
        assert fallback.tolist() == [b == 7 for b in range(30)]
        for b in range(30):
            single.x, single.P = x[b].copy(), P[b].copy()
            assert np.array_equal(_bits(X[b]), _bits(single.sigma_points())), (n, b)
