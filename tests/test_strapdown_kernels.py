"""The compiled kernels of the mechanization over a run axis (navcore.core.kernels).

A run inside a batch must equal the same run alone, bit for bit, and the compiled code must give
the floats CPython gives for the same source (no fused multiply-add, the same libm): both are
checked here on random states.  The kernel cache is keyed by navcore's content, so a copy of
navcore in another folder (an FMU unpacked anew) finds the machine code compiled for the first.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from navcore.ins import error_model, strapdown
from navcore.ins.rotations import euler_to_dcm
from navcore.ins.strapdown import N_COLUMNS, Strapdown, update_rows

FMUS = Path(__file__).resolve().parents[1] / "fmus"


def _random_navs(rng, n):
    return [Strapdown.from_euler(rng.uniform(-1.4, 1.4), rng.uniform(-3, 3),
                                 rng.uniform(-100, 9000), rng.normal(0, 80, 3),
                                 *rng.uniform(-3, 3, 3)) for _ in range(n)]


def _bits(a):
    return np.ascontiguousarray(a).view(np.int64)


def test_a_batch_of_runs_equals_each_run_alone_bit_for_bit():
    rng = np.random.default_rng(11)
    B, steps = 7, 400
    navs = _random_navs(rng, B)
    rows = np.concatenate([nav.rows for nav in navs])
    dtheta = rng.normal(0, 2e-3, (steps, B, 3))
    dvel = rng.normal(0, 0.2, (steps, B, 3)) + [0.0, 0.0, -0.098]
    dt = rng.choice([0.005, 0.01, 0.02], B)
    for k in range(steps):
        update_rows(rows, dtheta[k], dvel[k], dt)
        for b, nav in enumerate(navs):
            nav.update(dtheta[k, b], dvel[k, b], dt[b])
    assert np.array_equal(_bits(rows), _bits(np.concatenate([nav.rows for nav in navs])))


def test_the_compiled_update_gives_the_floats_of_its_interpreted_source():
    """Compiled against interpreted: the same source, so this checks the compiler (no
    contraction into multiply-adds, the same sin/cos/sqrt), not the equations."""
    rng = np.random.default_rng(12)
    rows = np.concatenate([nav.rows for nav in _random_navs(rng, 50)])
    rows[:, 15:] = rng.normal(0, 1e-2, (50, 9))          # some memory of earlier intervals
    compiled, interpreted = rows.copy(), rows.copy()
    dtheta = rng.normal(0, 0.3, (50, 3))                   # large and small rotation angles
    dtheta[:10] *= 1e-5
    dvel = rng.normal(0, 1.0, (50, 3))
    dt = np.full(50, 0.01)
    update_rows(compiled, dtheta, dvel, dt)
    update_rows.py_func(interpreted, dtheta, dvel, dt)
    assert np.array_equal(_bits(compiled), _bits(interpreted))


def test_a_batch_of_transition_matrices_equals_each_one_alone_and_i_plus_f_dt():
    rng = np.random.default_rng(13)
    navs = _random_navs(rng, 6)
    rows = np.concatenate([nav.rows for nav in navs])
    f_ned = rng.normal(0, 10, (6, 3))
    dt = np.full(6, 0.01)
    out = np.empty((6, 15, 15))
    error_model.transition_rows(out, rows, f_ned, dt,
                                error_model.transition_template(0.01, 300.0, 0.0))
    for b, nav in enumerate(navs):
        alone = error_model.transition_matrix(nav.lat, nav.h, nav.v_ned, nav.C_bn, f_ned[b],
                                              0.01, 300.0, 0.0)
        formula = np.eye(15) + error_model.system_matrix(nav.lat, nav.h, nav.v_ned, nav.C_bn,
                                                         f_ned[b], 300.0, 0.0) * 0.01
        assert np.array_equal(_bits(out[b]), _bits(alone))
        assert np.array_equal(_bits(out[b]), _bits(formula))   # -0.0 and +0.0 told apart


def test_the_state_row_holds_what_the_attributes_say():
    C = euler_to_dcm(0.1, -0.2, 2.0)
    nav = Strapdown(0.7, -1.2, 150.0, [10.0, -2.0, 0.5], C)
    assert nav.rows.shape == (1, N_COLUMNS) == (1, len(strapdown.COLUMNS))
    named = dict(zip(strapdown.COLUMNS, nav.rows[0].tolist()))
    assert (named["lat"], named["lon"], named["h"]) == (0.7, -1.2, 150.0)
    assert (named["vn"], named["ve"], named["vd"]) == (10.0, -2.0, 0.5)
    assert named["c12"] == C[1, 2] and named["c20"] == C[2, 0]
    assert (named["vn_prev"], named["ve_prev"], named["vd_prev"]) == (10.0, -2.0, 0.5)
    C_before = nav.C_bn
    nav.update([0.01, 0.0, 0.0], [0.0, 0.0, -0.098], 0.01)
    assert np.array_equal(C_before, C)             # an attribute read is a copy
    assert nav._dtheta_prev == (0.01, 0.0, 0.0) and nav._v_prev == (10.0, -2.0, 0.5)
    assert nav.solution() == (nav.lat, nav.lon, nav.h, *nav.v_ned.tolist(), *nav.euler())


_PROBE = """
import sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from navcore.ins.strapdown import Strapdown, update_rows
nav = Strapdown(0.5, 0.1, 10.0, [1.0, 0.0, 0.0], np.eye(3))
nav.update([1e-3, 0.0, 0.0], [0.0, 0.0, -0.098], 0.01)
print(sum(update_rows.stats.cache_hits.values()),
      float(nav.rows[0, 0]))
"""


def _probe(tree, cache):
    env = dict(os.environ, NAVFMU_KERNEL_CACHE=str(cache))
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", _PROBE, str(tree)], capture_output=True,
                         text=True, env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    hits, lat = out.stdout.split()
    return int(hits), lat


def test_a_copy_of_navcore_elsewhere_finds_the_compiled_kernels(tmp_path):
    for name in ("a", "b"):
        shutil.copytree(FMUS / "navcore", tmp_path / name / "navcore",
                        ignore=shutil.ignore_patterns("__pycache__"))
    cache = tmp_path / "cache"
    first = _probe(tmp_path / "a", cache)
    second = _probe(tmp_path / "b", cache)
    assert first[0] == 0 and second[0] >= 1     # compiled once, then loaded from the cache
    assert first[1] == second[1]
    (tmp_path / "b" / "navcore" / "ins" / "earth.py").write_text(
        (FMUS / "navcore" / "ins" / "earth.py").read_text() + "\n# changed\n")
    assert _probe(tmp_path / "b", cache)[0] == 0   # any change in navcore: a new entry


def test_kernels_run_without_a_writable_cache_folder(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    hits, lat = _probe(FMUS, blocked / "cache")
    assert hits == 0 and float(lat) == pytest.approx(0.5, abs=1e-6)


def test_the_compiled_transition_entries_give_the_floats_of_their_interpreted_source():
    """Compiled against interpreted, as above, over many states (a compiled ``x ** 2`` is
    ``x * x``, which rounds apart from CPython's ``pow`` about once in a thousand)."""
    rng = np.random.default_rng(14)
    n = 4000
    rows = np.zeros((n, N_COLUMNS))
    rows[:, 0] = rng.uniform(-1.5, 1.5, n)
    rows[:, 2] = rng.uniform(-500, 20000, n)
    rows[:, 3:6] = rng.normal(0, 150, (n, 3))
    rows[:, 6:15] = euler_to_dcm_rows(rng.uniform(-3, 3, (n, 3)))
    f_ned = rng.normal(0, 15, (n, 3))
    dt = np.full(n, 0.01)
    template = error_model.transition_template(0.01, 100.0, 500.0)
    compiled, interpreted = np.empty((n, 15, 15)), np.empty((n, 15, 15))
    error_model.transition_rows(compiled, rows, f_ned, dt, template)
    error_model.transition_rows.py_func(interpreted, rows, f_ned, dt, template)
    assert np.array_equal(_bits(compiled), _bits(interpreted))
    navs = np.concatenate([nav.rows for nav in _random_navs(rng, n)])
    compiled, interpreted = navs.copy(), navs.copy()
    update_rows(compiled, np.full((n, 3), 1e-3), np.full((n, 3), 0.05), dt)
    update_rows.py_func(interpreted, np.full((n, 3), 1e-3), np.full((n, 3), 0.05), dt)
    assert np.array_equal(_bits(compiled), _bits(interpreted))


def euler_to_dcm_rows(angles):
    return np.array([euler_to_dcm(*a).ravel() for a in angles])


def test_a_batch_of_inverse_steps_equals_each_alone_and_the_interpreted_source():
    rng = np.random.default_rng(15)
    B = 9
    navs = _random_navs(rng, B)
    rows = np.concatenate([nav.rows for nav in navs])
    interpreted = rows.copy()
    targets = np.concatenate([nav.rows for nav in _random_navs(rng, B)])[:, :15]
    targets[:, :15] = rows[:, :15] + rng.normal(0, 1e-6, (B, 15))   # near the current state
    targets[:, 6:15] = np.array([euler_to_dcm(*a).ravel() for a in rng.uniform(-3, 3, (B, 3))])
    dt = np.full(B, 0.01)
    increments, expected = np.empty((B, 6)), np.empty((B, 6))
    strapdown.inverse_rows(rows, targets, dt, increments)
    strapdown.inverse_rows.py_func(interpreted, targets, dt, expected)
    assert np.array_equal(_bits(increments), _bits(expected))
    assert np.array_equal(_bits(rows), _bits(interpreted))
    for b, nav in enumerate(navs):
        t = targets[b]
        dtheta, dvel = nav._inverse_to(t[0], t[1], t[2], t[3:6], t[6:15].reshape(3, 3), 0.01)
        assert np.array_equal(np.concatenate([dtheta, dvel]), increments[b])
        assert np.array_equal(nav.rows[0], rows[b])
