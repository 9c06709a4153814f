"""The error model's matrices against the equations written out with numpy.

``system_matrix`` and ``transition_matrix`` are built from one list of state-dependent
entries (``error_model._state_entries``); these tests check that list, entry by entry,
against F assembled from the module docstring's equations with skew matrices and the
earth model's functions (an independent writing of the same equations), and that the
transition matrix the filters use every IMU step is ``I + F dt`` to the last bit, signs of
zeros included (the two share the entries, so only the assembly is checked there).
"""
from __future__ import annotations

import numpy as np
import pytest

from navcore.ins import earth
from navcore.ins.error_model import N_STATES, system_matrix, transition_matrix
from navcore.ins.rotations import euler_to_dcm


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _textbook_F(lat, h, v, C, f, tau_g, tau_a):
    """F of the module docstring, block by block (Titterton & Weston ch. 12 phi-angle form)."""
    rn, re = earth.radii(lat)
    w_ie = earth.earth_rate_ned(lat)
    w_en = earth.transport_rate_ned(lat, h, v)
    F = np.zeros((N_STATES, N_STATES))
    F[0:3, 3:6] = np.eye(3)
    F[3:6, 6:9] = _skew(f)
    F[3:6, 12:15] = C
    F[3:6, 3:6] = -_skew(2 * w_ie + w_en)
    F[5, 2] = 2.0 * earth.gravity(lat, h) / np.sqrt(rn * re)
    F[6:9, 6:9] = -_skew(w_ie + w_en)
    F[6:9, 3:6] = [[0.0, 1.0 / (re + h), 0.0], [-1.0 / (rn + h), 0.0, 0.0],
                   [0.0, -np.tan(lat) / (re + h), 0.0]]
    F[6, 0] = -earth.OMEGA_IE * np.sin(lat) / (rn + h)
    F[8, 0] = -earth.OMEGA_IE * np.cos(lat) / (rn + h)
    F[6:9, 9:12] = -C
    for first, tau in ((9, tau_g), (12, tau_a)):
        if tau > 0:
            F[first:first + 3, first:first + 3] = -np.eye(3) / tau
    return F


def _states(n, seed=3):
    rng = np.random.default_rng(seed)
    for i in range(n):
        v = rng.normal(0.0, 80.0, 3)
        if i % 5 == 0:
            v[:] = 0.0    # at rest: zero entries (and their signs) in F
        yield (rng.uniform(-1.4, 1.4), rng.uniform(-50.0, 15000.0), v,
               euler_to_dcm(*rng.uniform(-3.0, 3.0, 3)), rng.normal(0.0, 12.0, 3),
               [0.01, 0.02, 0.005][i % 3], [(0.0, 0.0), (3600.0, 0.0), (100.0, 300.0)][i % 3])


def test_system_matrix_matches_the_equations_block_by_block():
    for lat, h, v, C, f, _, (tg, ta) in _states(300):
        ref = _textbook_F(lat, h, v, C, f, tg, ta)
        F = system_matrix(lat, h, v, C, f, tg, ta)
        assert np.array_equal(F == 0.0, ref == 0.0)
        np.testing.assert_allclose(F, ref, rtol=1e-13, atol=1e-30)


@pytest.mark.parametrize("seed", [3, 4])
def test_transition_matrix_is_eye_plus_F_dt_bit_for_bit(seed):
    for lat, h, v, C, f, dt, (tg, ta) in _states(500, seed):
        expected = np.eye(N_STATES) + system_matrix(lat, h, v, C, f, tg, ta) * dt
        phi = transition_matrix(lat, h, v, C, f, dt, tg, ta)
        assert np.array_equal(phi, expected)
        assert np.array_equal(np.signbit(phi), np.signbit(expected))
        assert phi.flags.writeable and phi.flags.c_contiguous
