"""The adaptive and robust laws over a run axis (navcore.filters.adaptive_filters.RowUpdates):
engines of one class updating together in one call get, bit for bit, what each gets updating
alone -- results and whole state -- through faded, compressed, replaced, left-out and
re-acquired fixes, missed fixes and a run whose update fails; and the row statistics of
navcore.filters.innovation_stats give each run the floats of its 1-D calls.
"""
from __future__ import annotations

import copy
from collections import deque

import numpy as np
import pytest

from navcore.core import state
from navcore.filters.adaptive_filters import IakfEngine, SageHusaFadingEngine
from navcore.filters.robust_filters import NewtonRobustKfEngine
from navcore.filters.innovation_stats import cholesky_nis_rows, dot_rows, nis_rows, trace_rows

from test_kf_engine_by_hand import DT, config, increments, strapdown


def _bits(a):
    return np.ascontiguousarray(a, dtype=float).view(np.int64)


def _same(got, want, where):
    """Two state trees (or values) equal, floats bit for bit."""
    if isinstance(want, dict):
        assert got.keys() == want.keys(), where
        for key in want:
            _same(got[key], want[key], f"{where}.{key}")
    elif isinstance(want, (list, tuple, deque)):
        assert len(got) == len(want), where
        for i, (g, w) in enumerate(zip(got, want)):
            _same(g, w, f"{where}[{i}]")
    elif isinstance(want, np.ndarray) and want.dtype != float:
        assert got.dtype == want.dtype and np.array_equal(got, want), where
    elif isinstance(want, (np.ndarray, float)):
        assert np.shape(got) == np.shape(want), where
        assert np.array_equal(_bits(got), _bits(want)), where
    else:
        assert got == want, where


def test_the_row_statistics_give_each_run_the_floats_of_its_1d_calls():
    rng = np.random.default_rng(11)
    for _ in range(300):
        runs, m = int(rng.integers(1, 25)), int(rng.choice([3, 6]))
        v = rng.normal(size=(runs, m)) * 10.0 ** rng.uniform(-6, 6, (runs, 1))
        A = rng.normal(size=(runs, m, m)) * 10.0 ** rng.uniform(-4, 4, (runs, 1, 1))
        S = A @ A.transpose(0, 2, 1) + 1e-3 * np.eye(m)
        L = np.linalg.cholesky(S)
        got = (dot_rows(v, v), trace_rows(S + A), nis_rows(v, S), cholesky_nis_rows(L, v))
        for b in range(runs):
            u = np.linalg.solve(L[b], v[b])
            want = (v[b] @ v[b], np.trace(S[b] + A[b]),
                    v[b] @ np.linalg.solve(S[b], v[b]), u @ u)
            for g, w in zip(got, want):
                assert np.array_equal(_bits(g[b]), _bits(w))


SHF = dict(forgetting_factor=0.9, reserve_gamma=2.0, r_floor_fraction=0.04,
           max_fading_factor=None, r_max_scale=4.0, recovery=True, recovery_epochs=2,
           r_floor_nominal=False)
NEWTON = dict(chi2_threshold=6.635, newton_order=2, replacement_variance="propagated",
              recovery=True, recovery_epochs=2)


@pytest.mark.parametrize("engine_class, options", [
    (SageHusaFadingEngine, SHF),
    (SageHusaFadingEngine, dict(SHF, r_floor_nominal=True)),
    (SageHusaFadingEngine, dict(SHF, max_fading_factor=3.0, recovery=False)),
    (IakfEngine, dict(SHF, outlier_alpha=0.02)),
    (NewtonRobustKfEngine, NEWTON),
    (NewtonRobustKfEngine, dict(NEWTON, replacement_variance="nominal", recovery=False))])
def test_engines_updating_together_give_each_the_floats_of_its_update_alone(engine_class,
                                                                            options):
    """Six engines over 40 epochs, each run with its own noise, outliers (single ones and
    bursts, which the guard re-acquires), missed fixes (run b skips the epochs with
    (epoch + b) % 9 == 0) and, at epoch 25, a non-finite measurement of run 3, which fails
    alone with the error of its update alone and leaves the engine unchanged."""
    rng = np.random.default_rng(3)
    runs = 6
    together = [engine_class(config(), strapdown(), **options) for _ in range(runs)]
    alone = copy.deepcopy(together)
    outcomes = set()
    for epoch in range(40):
        for k in range(10):
            for engine in together + alone:
                engine.propagate(*increments(k), DT)
        z = rng.normal(0.0, 1.0, (runs, 6)) * np.array([2.0, 3.0, 4.0, 0.1, 0.2, 0.3])
        z += np.where(rng.random((runs, 6)) < 0.1, rng.uniform(-300.0, 300.0, (runs, 6)), 0.0)
        if 12 <= epoch < 18:
            z[0] += 500.0                                   # a burst: re-acquired
        if epoch == 25:
            z[3, 1] = np.nan
        rows = [b for b in range(runs) if (epoch + b) % 9]
        results = engine_class.updates(
            [together[b] for b in rows], z[rows], np.array([together[b].P for b in rows]),
            np.array([together[b].phi_acc for b in rows]),
            np.array([together[b].q_acc for b in rows]))
        for b, got in zip(rows, results):
            try:
                want = alone[b].update(z[b])
            except Exception as error:      # the run's own error, the engine unchanged
                assert type(got) is type(error) and str(got) == str(error)
                outcomes.add("failed")
            else:
                _same(vars(got), vars(want), "result")
                outcomes.add(("outlier", want.outlier))
                outcomes.add(("faded", want.fading_factor > 1.0))
            _same(state.capture(together[b]), state.capture(alone[b]), f"run {b}")
    assert "failed" in outcomes
    if engine_class is SageHusaFadingEngine:
        assert ("faded", True) in outcomes
    else:
        assert {("outlier", True), ("outlier", False)} <= outcomes
    if options["recovery"] and engine_class is not SageHusaFadingEngine:
        assert together[0].guard.n_reacquired > 0
