"""The UKF family's batch (navcore.components.ukf_batch) and the time-update functions it
shares with each engine alone (navcore.filters.ukf_time_update: accumulate_rows,
error_dynamics over the points of many runs, predict_rows).

The whole batch is compared with each filter alone, bit for bit, in tests/test_kf_batch.py and
tests/test_batch_simulation.py; here: the pieces against independent references (the
pointwise process model of tests/test_ukf_process_model.py, a trapezoid sum by hand), the
measurement update of many filters (navcore.filters.unscented_rows.update_filters) and of many
IMM banks (navcore.filters.imm.update_banks) against each one's own update, and that the runs
of a batch do predict and update in one call.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_ukf_process_model import TAU_A, TAU_G, reference_derivative

from navcore.components import ukf_batch
from navcore.components.ukf_components import CtfaUkf, ImmUkf, Ukf
from navcore.errors import InputError
from navcore.filters import ukf_filters, ukf_time_update
from navcore.filters.imm import ImmBank, imm_probabilities_rows, update_banks
from navcore.filters.ukf_time_update import (N_SUMS, NominalInterval, accumulate_rows,
                                             error_dynamics, interval_means,
                                             predict_filter_groups, predict_rows,
                                             propagate_points)
from navcore.filters.unscented import UnscentedKalmanFilter
from navcore.filters.unscented_rows import update_filters
from orchestrator.cosim.batch import BatchSimulation
from orchestrator.running.scenarios import load_scenario, registry, swap_filter

from campaign_helpers import MODELS


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def _nominals(runs, rng):
    """B runs' intervals, each different (latitude, height, velocity, attitude, force)."""
    C = Rotation.from_euler("ZYX", rng.uniform(-1, 1, (runs, 3))).as_matrix()
    return NominalInterval(np.full(runs, 0.1), rng.uniform(-1.2, 1.2, runs),
                           rng.uniform(0, 3000, runs), rng.normal(0, 40, (runs, 3)), C,
                           rng.normal([0, 0, -9.8], 1.0, (runs, 3)))


def _one(nom, b):
    return NominalInterval(nom.T[b], nom.lat[b], nom.h[b], nom.v[b], nom.C[b], nom.f[b])


def _points(runs, rng, per_run=31):
    scale = np.array([5.0] * 3 + [0.2] * 3 + [3e-3] * 3 + [2e-5] * 3 + [2e-3] * 3)
    X = rng.standard_normal((runs * per_run, 15)) * scale
    X[1, 6:9] = [0.2, -0.3, 0.1]                  # a large attitude error
    X[2, 6:9] = [3e-9, 0.0, -1e-9]                # inside the series branches
    return X


def _assert_each_block_alone(together, X, alone, blocks):
    """Block k of ``together`` (31 points) equals ``alone(points of block k, k)``, bit for
    bit."""
    for k in range(blocks):
        rows = slice(31 * k, 31 * (k + 1))
        assert np.array_equal(_bits(together[rows]), _bits(alone(X[rows], k))), k


def test_error_dynamics_of_many_runs_is_each_run_alone_and_the_pointwise_reference():
    rng = np.random.default_rng(31)
    nom, X = _nominals(5, rng), _points(5, rng)
    together = error_dynamics(X, nom, TAU_G, TAU_A)
    _assert_each_block_alone(together, X,
                             lambda x, b: error_dynamics(x, _one(nom, b), TAU_G, TAU_A), 5)
    for b in range(5):
        rows = slice(31 * b, 31 * (b + 1))
        ref = np.array([reference_derivative(x, _one(nom, b)) for x in X[rows]])
        # position, velocity and bias rows as in test_ukf_process_model (another form of the
        # same equations, rounding level); attitude rows against central differences
        np.testing.assert_allclose(together[rows, 0:6], ref[:, 0:6], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(together[rows, 9:15], ref[:, 9:15], rtol=1e-9, atol=1e-15)
        for got, want in zip(together[rows][3:, 6:9], ref[3:, 6:9]):
            assert np.linalg.norm(got - want) <= 1e-8 * np.linalg.norm(want)


def test_the_process_model_compiled_is_its_interpreted_source(monkeypatch):
    """The process model's kernels against their Python source (math's sin, cos, sqrt on
    the same operations), bit for bit, series branches included."""
    rng = np.random.default_rng(35)
    nom, X = _nominals(4, rng), _points(4, rng)
    compiled = propagate_points(X, nom, TAU_G, TAU_A), error_dynamics(X, nom, 0.0, TAU_A)
    for name in ("_derivative_rows", "_step_rows"):
        monkeypatch.setattr(ukf_time_update, name, getattr(ukf_time_update, name).py_func)
    interpreted = propagate_points(X, nom, TAU_G, TAU_A), error_dynamics(X, nom, 0.0, TAU_A)
    for got, want in zip(compiled, interpreted):
        assert np.array_equal(_bits(got), _bits(want))


def test_one_nominal_serves_the_points_of_several_filters():
    """The IMM bank: one run's interval, three models' points in one call."""
    rng = np.random.default_rng(32)
    nom, X = _nominals(1, rng), _points(3, rng)
    _assert_each_block_alone(propagate_points(X, nom, TAU_G, TAU_A), X,
                             lambda x, j: propagate_points(x, _one(nom, 0), TAU_G, TAU_A), 3)


def test_predict_rows_is_each_filters_own_prediction():
    rng = np.random.default_rng(33)
    runs = 4
    nom = _nominals(runs, rng)
    filters = []
    for b in range(runs):
        A = rng.normal(0, 1, (15, 15)) * np.logspace(-4, 0, 15)
        flt = UnscentedKalmanFilter(15, P0=A @ A.T + 1e-12 * np.eye(15),
                                    x0=rng.normal(0, 1e-3, 15))
        filters.append(flt)
    Q = np.stack([np.diag(rng.uniform(1e-12, 1e-6, 15)) for _ in range(runs)])
    q_scale = np.array([1.0, 2.5, 1.0, 10.0])
    x, P, fallback, finite = predict_rows(
        np.stack([f.x for f in filters]), np.stack([f.P for f in filters]), nom, Q, q_scale,
        filters[0].Wm, filters[0].Wc, filters[0]._spread, TAU_G, TAU_A)
    assert finite.all() and not fallback.any()
    for b, flt in enumerate(filters):
        flt.predict(propagate_points, Q[b], _one(nom, b), TAU_G, TAU_A, q_scale=q_scale[b],
                    vectorized=True)
        assert np.array_equal(_bits(x[b]), _bits(flt.x)), b
        assert np.array_equal(_bits(P[b]), _bits(flt.P)), b


def test_the_interval_sums_are_the_trapezoids_of_the_rows_compiled_or_not():
    """accumulate_rows against a trapezoid sum written out here, and its compiled code
    against its interpreted source, bit for bit."""
    rng = np.random.default_rng(34)
    runs, steps = 3, 7
    rows = rng.normal(0, 1, (steps + 1, runs, 24))
    dvel = rng.normal(0, 0.1, (steps, runs, 3))
    dt = np.full(runs, 0.02)
    compiled, interpreted = np.zeros((runs, N_SUMS)), np.zeros((runs, N_SUMS))
    for k in range(steps):
        accumulate_rows(compiled, rows[k], rows[k + 1], dvel[k], dt)
        accumulate_rows.py_func(interpreted, rows[k], rows[k + 1], dvel[k], dt)
    assert np.array_equal(_bits(compiled), _bits(interpreted))
    half = 0.5 * (rows[:-1] + rows[1:]) * 0.02
    np.testing.assert_allclose(compiled[:, 0], steps * 0.02, rtol=1e-15)
    np.testing.assert_allclose(compiled[:, 1], half[:, :, 0].sum(axis=0), rtol=1e-13)
    np.testing.assert_allclose(compiled[:, 2], half[:, :, 2].sum(axis=0), rtol=1e-13)
    np.testing.assert_allclose(compiled[:, 3:15], half[:, :, 3:15].sum(axis=0), rtol=1e-12,
                               atol=1e-15)
    dv_ned = np.einsum("kbij,kbj->bi", rows[:-1, :, 6:15].reshape(steps, runs, 3, 3), dvel)
    np.testing.assert_allclose(compiled[:, 15:18], dv_ned, rtol=1e-12, atol=1e-15)
    means = interval_means(compiled)
    np.testing.assert_allclose(means.C * (steps * 0.02), compiled[:, 6:15].reshape(runs, 3, 3),
                               rtol=1e-15)


def _random_filter(rng):
    A = rng.normal(0, 1, (15, 15)) * np.logspace(-4, 0, 15)
    return UnscentedKalmanFilter(15, P0=A @ A.T + 1e-12 * np.eye(15), x0=rng.normal(0, 1e-3, 15))


def _position(X):
    return X[..., :3]


def _assert_same_filter(a, b):
    for name in ("x", "P"):
        assert np.array_equal(_bits(getattr(a, name)), _bits(getattr(b, name))), name
    for name in ("last_nis", "last_log_likelihood", "sqrt_fallbacks"):
        assert getattr(a, name) == getattr(b, name), name


def test_update_filters_is_each_filters_own_update():
    """The filters of one update_filters call (a covariance not symmetric, one not finite,
    a measurement not finite, an innovation covariance not positive definite among them)
    end as each filter's own UnscentedKalmanFilter.update leaves it, bit for bit, with its
    results or its error."""
    import copy
    rng = np.random.default_rng(35)
    filters = [_random_filter(rng) for _ in range(7)]
    filters[1].P = filters[1].P + np.triu(np.full((15, 15), 1e-12), 1)   # not symmetric
    filters[2].P = filters[2].P.copy()
    filters[2].P[4, 4] = np.nan
    z = rng.normal(0, 1e-2, (7, 3))
    z[3, 1] = np.inf
    R = np.stack([np.diag(rng.uniform(1e-4, 1e-2, 3)) for _ in range(7)])
    R[5] = -10.0 * np.eye(3)                     # S not positive definite
    alone = copy.deepcopy(filters)
    corrections, errors = update_filters(filters, z, R, _position)
    for i, (flt, own) in enumerate(zip(filters, alone)):
        try:
            result = own.update(z[i], _position, R[i], vectorized=True)
        except InputError as exc:
            assert corrections[i] is None and str(errors[i]) == str(exc), i
            continue
        assert errors[i] is None, i
        _assert_same_filter(flt, own)
        assert np.array_equal(_bits(corrections[i].v), _bits(result["innovation"]))
        assert np.array_equal(_bits(corrections[i].S), _bits(result["S"]))
        assert (corrections[i].nis, corrections[i].log_likelihood) == (
            result["nis"], result["log_likelihood"])
    assert [e is None for e in errors] == [True, True, False, False, True, False, True]


def test_update_banks_is_each_banks_own_update():
    """update_banks (the probabilities of every bank, all combinations in one call) leaves
    each bank as its own ImmBank.update does, bit for bit; a bank with a NaN likelihood
    fails alone with its own error."""
    import copy
    rng = np.random.default_rng(36)
    Pi = np.array([[0.95, 0.05], [0.05, 0.95]])
    banks = [ImmBank([_random_filter(rng) for _ in range(2)], Pi) for _ in range(5)]
    log_liks = rng.normal(-5.0, 3.0, (5, 2))
    log_liks[3, 0] = np.nan
    for bank in banks:              # mixed and predicted: the update ends the cycle
        bank.needs_mixing = False
    alone = copy.deepcopy(banks)
    errors = update_banks(banks, log_liks.tolist())
    for i, (bank, own) in enumerate(zip(banks, alone)):
        try:
            own.update(lambda flt, j, i=i: log_liks[i, j])
        except InputError as exc:
            assert str(errors[i]) == str(exc), i
            continue
        assert errors[i] is None
        for name in ("mu", "x", "P"):
            assert np.array_equal(_bits(getattr(bank, name)), _bits(getattr(own, name))), name
        assert bank.needs_mixing and own.needs_mixing
    assert [e is None for e in errors] == [True, True, True, False, True]


def _probabilities_of_one_bank(c_bar, log_lik, floor):
    """The IMM probability update of one bank written out (imm module docstring, step 3)."""
    a = np.log(c_bar, out=np.full(len(c_bar), -np.inf), where=c_bar > 0.0) + log_lik
    a_max = a.max()
    if a_max == -np.inf:
        mu = c_bar / c_bar.sum()
    else:
        mu = np.exp(a - a_max)
        mu /= mu.sum()
    if floor > 0.0:
        mu = np.maximum(mu, floor)
        mu /= mu.sum()
    return mu


def test_the_probabilities_of_many_banks_are_each_banks_own():
    """imm_probabilities_rows on 1 to 24 banks of 1 to 3 models (zero probabilities, zero
    likelihoods, floors of 0 and not) against one bank's update written out, bit for bit."""
    rng = np.random.default_rng(37)
    for trial in range(600):
        r, runs = rng.integers(1, 4), rng.integers(1, 25)
        c_bar = rng.dirichlet(np.ones(r), runs)
        if trial % 7 == 0 and r > 1:
            c_bar[0] = np.r_[0.0, c_bar[0, 1:] / c_bar[0, 1:].sum()]
        log_lik = rng.normal(-10.0, 200.0, (runs, r))
        if trial % 11 == 0:
            log_lik[-1] = -np.inf
        floor = np.full(runs, [0.0, 1e-12, 1e-3][trial % 3])
        floor[0] = 0.0 if trial % 5 == 0 else floor[0]
        mu, infinite = imm_probabilities_rows(c_bar, log_lik, floor)
        assert not infinite.any()
        for b in range(runs):
            own = _probabilities_of_one_bank(c_bar[b], log_lik[b], floor[b])
            assert np.array_equal(_bits(mu[b]), _bits(own)), (trial, b)


@pytest.mark.parametrize("filter_name, models", [("Ukf", 1), ("CtfaUkf", 1), ("ImmUkf", 2)])
def test_the_runs_of_a_batch_update_in_one_call(monkeypatch, filter_name, models):
    calls = []

    def counting(filters, *args):
        calls.append(len(filters))
        return update_filters(filters, *args)

    monkeypatch.setattr(ukf_batch, "update_filters", counting)
    model = swap_filter(load_scenario(MODELS / "uav_maneuver"), filter_name)
    sets = [{"trajectory.seed": 3 + b, "gnss.seed": 40 + b} for b in range(4)]
    BatchSimulation(model, registry(), sets).run(stop_time=4.0)
    # a fix per second: every run's filters in one call
    assert len(calls) >= 3 and set(calls) == {4 * models}


@pytest.mark.parametrize("filter_name, models", [("Ukf", 1), ("CtfaUkf", 1), ("ImmUkf", 2),
                                                  ("ImmUkf", 3)])
def test_the_runs_of_a_batch_predict_in_one_call(monkeypatch, filter_name, models):
    calls = []

    def counting(x, *args):
        calls.append(len(x))
        return predict_rows(x, *args)

    def counting_groups(filters, *args):
        calls.append(len(filters))
        return predict_filter_groups(filters, *args)

    monkeypatch.setattr(ukf_batch, "predict_rows", counting)
    monkeypatch.setattr(ukf_batch, "predict_filter_groups", counting_groups)
    model = swap_filter(load_scenario(MODELS / "uav_maneuver"), filter_name)
    sets = [{"trajectory.seed": 3 + b, "gnss.seed": 40 + b} for b in range(4)]
    if filter_name == "ImmUkf":
        for s in sets:
            s["filter.imm_models"] = models
    BatchSimulation(model, registry(), sets).run(stop_time=3.0)
    # 50 Hz IMU, a prediction every 0.1 s: the 4 runs together (every model of an IMM
    # bank), but for the prediction before each fix, which each run's own update makes
    assert len(calls) >= 20 and set(calls) == {4 * models}


def test_every_filter_of_the_family_names_the_ukf_batch():
    for component_class in (Ukf, CtfaUkf, ImmUkf):
        assert component_class.batch_class is ukf_batch.UkfFilterBatch
    assert ukf_filters.UkfEngine.predict_filters is not ukf_filters.ImmUkfEngine.predict_filters
