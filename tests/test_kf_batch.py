"""The INS/GNSS filters' batches (navcore.components.filter_batch: the Kf and the UKF
families) against each filter alone.

Without any master: the inputs each filter sees are recorded from direct runs of
``aircraft_500s`` (one per seed), some runs' fixes are then delivered late (a rollback), from
the future (held back) or invalid, and B filters stepped alone are compared with one batch
of B stepped on the same inputs, output for output, bit for bit, every step.  The batched
propagation is also checked on its own against each engine's ``propagate``.
"""
from __future__ import annotations

import numpy as np
import pytest

from navcore.components.kf_components import Iakf, Kf, NewtonRobustKf, SageHusaFading
from navcore.components.ukf_components import CtfaUkf, ImmUkf, Ukf
from navcore.core.batch import BatchInputs
from navcore.filters.ins_gnss_kf import (KfConfig, KfEngine, add_noise_rows, compensate_rows,
                                         kalman_rows, predicted_rows, propagate_rows)
from navcore.ins.error_model import transition_template
from navcore.ins.strapdown import Strapdown
from orchestrator.cosim.master import Simulation
from orchestrator.running.scenarios import load_scenario, registry

from campaign_helpers import MODELS

STOP = 12.0


def _engines(runs, rng):
    engines = []
    for b in range(runs):
        config = KfConfig(p0=rng.uniform(0.1, 5.0, 15) * 1e-3, gyro_arw=1e-5 * (b + 1),
                          accel_vrw=1e-4, gyro_bias_sigma=1e-6, gyro_bias_tau=300.0,
                          accel_bias_sigma=1e-4, accel_bias_tau=300.0,
                          r_sigma=np.full(6, 3.0))
        nav = Strapdown.from_euler(0.6 + 0.01 * b, 2.0, 300.0 * b, rng.normal(0, 50, 3),
                                   *rng.uniform(-0.5, 0.5, 3))
        engine = KfEngine(config, nav)
        engine.gyro_bias = rng.normal(0, 1e-5, 3)
        engine.accel_bias = rng.normal(0, 1e-3, 3)
        engines.append(engine)
    return engines


def _bits(a):
    return np.ascontiguousarray(a).view(np.int64)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_interval_kernels_give_the_floats_of_the_numpy_expressions(compiled):
    """compensate_rows and add_noise_rows, compiled and as source, against the numpy
    expressions of the same arithmetic (IEEE operations one by one: the same floats), on
    strided views as the batch passes them."""
    rng = np.random.default_rng(5)
    runs = 40
    imu = rng.normal(0, 1e-2, (runs, 8))
    dtheta, dvel = imu[:, 2:5], imu[:, 5:8]
    gyro_bias, accel_bias = rng.normal(0, 1e-5, (runs, 3)), rng.normal(0, 1e-3, (runs, 3))
    dt = 0.0100000001
    compensate = compensate_rows if compiled else compensate_rows.py_func
    add_noise = add_noise_rows if compiled else add_noise_rows.py_func
    got = [np.empty((runs, 3)) for _ in range(4)]
    compensate(dtheta, dvel, gyro_bias, accel_bias, dt, *got)
    dtheta_c, dvel_c = dtheta - gyro_bias * dt, dvel - accel_bias * dt
    for a, b in zip(got, (dtheta_c, dvel_c, dtheta_c / dt, dvel_c / dt)):
        assert np.array_equal(_bits(a), _bits(b))
    q_acc, q_density = rng.normal(size=(runs, 15, 15)), rng.uniform(0, 1e-6, (runs, 15))
    expected = q_acc.copy()
    expected.reshape(runs, -1)[:, ::16] += q_density * dt
    add_noise(q_acc, q_density, dt)
    assert np.array_equal(_bits(q_acc), _bits(expected))


def test_the_batched_propagation_gives_each_engine_the_floats_of_its_own():
    """Compared with the engines' own ``propagate`` (which calls the same function with one
    run): this checks that numpy's stacked products round as each run's alone."""
    rng = np.random.default_rng(7)
    alone, batched = _engines(6, rng), _engines(6, np.random.default_rng(7))
    rows = np.concatenate([e.nav.rows for e in batched])
    stack = {n: np.stack([getattr(e, n) for e in batched])
             for n in ("gyro_bias", "accel_bias", "phi_acc", "q_acc")}
    q_density = np.stack([e.q_density for e in batched])
    dt = 0.01
    template = transition_template(dt, 300.0, 300.0)
    for _ in range(300):
        dtheta, dvel = rng.normal(0, 1e-3, (6, 3)), rng.normal(0, 0.1, (6, 3))
        for b, engine in enumerate(alone):
            engine.propagate(dtheta[b], dvel[b], dt)
        stack["phi_acc"], stack["q_acc"], rate = propagate_rows(
            rows, stack["gyro_bias"], stack["accel_bias"], stack["phi_acc"], stack["q_acc"],
            q_density, dtheta, dvel, dt, template)
    for b, engine in enumerate(alone):
        np.testing.assert_array_equal(rows[b], engine.nav.rows[0])
        np.testing.assert_array_equal(stack["phi_acc"][b], engine.phi_acc)
        np.testing.assert_array_equal(stack["q_acc"][b], engine.q_acc)
        np.testing.assert_array_equal(rate[b], engine.rate_ib)


def _filter_parameters():
    """The scenario's parameters of its filter (initial state, noise)."""
    model = load_scenario(MODELS / "aircraft_500s")
    return Simulation(model, backend="direct", registry=registry()).parameter_values["filter"]


def _recorded_inputs(runs):
    """Per run, the filter's inputs at every base step (list of dicts), from direct runs."""
    model = load_scenario(MODELS / "aircraft_500s")
    names = [p.name for p in Kf.inputs]
    per_run = []
    for b in range(runs):
        res = Simulation(model, backend="direct", registry=registry(),
                         parameters={"trajectory.seed": 3 + b, "gnss.seed": 40 + b}
                         ).run(stop_time=STOP)
        source = {**{c: res.column("trajectory", c) for c in res.columns["trajectory"]},
                  **{c: res.column("gnss", c) for c in res.columns["gnss"]}}
        steps = [{n: float(source[n][k]) if n in source else 0.0 for n in names}
                 for k in range(1, len(res.time))]
        for step in steps:
            for n in ("gnss_epoch",):
                step[n] = int(step[n])
            step["gnss_valid"] = bool(step["gnss_valid"])
        per_run.append(steps)
    return per_run


def _disturb(per_run):
    """Run 1: every fix reaches the filter 30 base steps late (rollbacks); run 2: the fix
    of epoch 3 is invalid and that of epoch 5 is stamped 0.2 s ahead (held back)."""
    late = per_run[1]
    for k in range(len(late) - 1, 29, -1):
        for n in late[k]:
            if n.startswith("gnss_"):
                late[k][n] = late[k - 30][n]
    for step in per_run[2]:
        if step["gnss_epoch"] == 3:
            step["gnss_valid"] = False
        if step["gnss_epoch"] == 5:
            step["gnss_time"] = step["gnss_time"] + 0.2


def _batch_inputs(steps):
    names = tuple(steps[0])
    real = tuple(n for n in names if isinstance(steps[0][n], float))
    values = {n: np.array([s[n] for s in steps]) for n in names}
    return BatchInputs(values, np.array([[s[n] for n in real] for s in steps]), real)


class _HalvedRateStrapdown(Strapdown):
    """A mechanization of a user's own: integrates half the angle increment."""

    def update(self, dtheta, dvel, dt):
        super().update([0.5 * x for x in dtheta], dvel, dt)


class _OwnMechanizationKf(Kf):
    """A Kf whose engine flies its own strapdown: the batch runs its own code."""

    def make_engine(self, config, nav):
        nav.__class__ = _HalvedRateStrapdown
        return super().make_engine(config, nav)


@pytest.mark.parametrize("component_class", [Kf, SageHusaFading, Iakf, NewtonRobustKf,
                                             _OwnMechanizationKf, Ukf, CtfaUkf, ImmUkf])
def test_a_batch_of_filters_steps_each_run_as_it_steps_alone(component_class):
    per_run = _recorded_inputs(3)
    _disturb(per_run)
    parameters = _filter_parameters()
    alone = [component_class(**parameters) for _ in per_run]
    batch = component_class.batch_class(component_class, len(per_run))
    batch.set_parameters([parameters] * len(per_run))
    first = batch.start(0.0)
    columns = [p.name for p in component_class.outputs]
    for b, component in enumerate(alone):
        out = component.start(0.0)
        assert first[b].tolist() == [float(out[n]) for n in columns]
    h = 0.01
    ages = []
    for k in range(len(per_run[0])):
        t = k * h
        outs = batch.advance(t, h, _batch_inputs([steps[k] for steps in per_run]))
        ages.append(outs[2, columns.index("fix_age")])
        for b, component in enumerate(alone):
            out = component.advance(t, h, per_run[b][k])
            assert outs[b].tolist() == [float(out[n]) for n in columns], (k, b)
        assert batch.take_failures() == {}
    assert batch._native == (component_class is not _OwnMechanizationKf)
    assert alone[1].late_fixes and alone[2].out["n_stale_fixes"] == 0
    assert min(ages) < -0.15            # run 2 held a fix from the future
    for b, component in enumerate(alone):
        assert batch.take_notices(b) == component.take_notices()


def _poison_velocity(batch):
    batch.rows[1, 4] = np.nan                  # run 1's east velocity


def _poison_ukf(batch):
    batch._ukf["P"][1, 2, 2] = np.nan          # run 1's covariance


def _poison_bank(batch):
    batch.members[1].engine.bank.filters[1].P[2, 2] = np.nan


@pytest.mark.parametrize("component_class, poison, message", [
    (Kf, _poison_velocity, "diverged"), (Ukf, _poison_ukf, "'P' contains NaN"),
    (ImmUkf, _poison_bank, "'P' contains NaN")])
def test_a_run_that_diverges_inside_a_batch_fails_alone(component_class, poison, message):
    """Run 1's state made non-finite: it fails with its own error (the Kf's solution check;
    the Ukf's prediction, by its own code once the batch sees a P it does not take; the IMM
    bank's, inside the batched prediction of the banks), the others go on as alone."""
    per_run = _recorded_inputs(3)
    parameters = _filter_parameters()
    batch = component_class.batch_class(component_class, 3)
    batch.set_parameters([parameters] * 3)
    batch.start(0.0)
    alone = component_class(**parameters)
    alone.start(0.0)
    h = 0.01
    for k in range(200):
        batch.advance(k * h, h, _batch_inputs([steps[k] for steps in per_run]))
        alone.advance(k * h, h, per_run[0][k])
        if k == 100:
            poison(batch)
    failures = batch.take_failures()
    assert list(failures) == [1]
    assert message in str(failures[1])
    batch.keep([0, 2])
    out = batch.advance(200 * h, h, _batch_inputs([per_run[b][200] for b in (0, 2)]))
    expected = alone.advance(200 * h, h, per_run[0][200])
    assert out[0].tolist() == [float(expected[p.name]) for p in component_class.outputs]


def _started_batch_and_alone(component_class, runs):
    """A started batch of ``runs`` filters of ``component_class`` with the test's
    parameters, the same filters started alone, and the output names."""
    parameters = _filter_parameters()
    alone = [component_class(**parameters) for _ in range(runs)]
    batch = component_class.batch_class(component_class, runs)
    batch.set_parameters([parameters] * runs)
    batch.start(0.0)
    for component in alone:
        component.start(0.0)
    return batch, alone, [p.name for p in component_class.outputs]


@pytest.mark.parametrize("component_class", [Kf, Ukf])
def test_a_batch_stepped_between_imu_samples_holds_each_run_s_outputs(component_class):
    """The filters stepped at twice the IMU's rate (every input step seen twice): at the
    steps without a new interval each run steps by its own code, which leaves its solution
    as it was; the batch gives it the solution of the batch's latest interval first (what
    the run alone wrote then), also after the fixes whose solution the batch wrote."""
    per_run = _recorded_inputs(2)
    batch, alone, columns = _started_batch_and_alone(component_class, len(per_run))
    h = 0.005
    for k in range(2 * 300):
        steps = [steps[k // 2] for steps in per_run]
        outs = batch.advance(k * h, h, _batch_inputs(steps))
        for b, component in enumerate(alone):
            out = component.advance(k * h, h, steps[b])
            assert outs[b].tolist() == [float(out[n]) for n in columns], (k, b)
    assert batch.take_failures() == {}


def test_the_kf_runs_fixes_at_one_step_update_in_one_call(monkeypatch):
    """The Kf runs that apply a fix at the same step update in one kalman_rows call (the
    function each engine's own kalman_update calls with one run); a run whose covariance
    turned non-finite makes that call fail, and then every run updates by its own code:
    that run fails alone with its own error, the others go on as alone."""
    import navcore.components.filter_batch as filter_batch
    calls = []
    stacked = filter_batch.kalman_rows

    def counted(P_pred, *args):
        calls.append(len(P_pred))
        return stacked(P_pred, *args)

    monkeypatch.setattr(filter_batch, "kalman_rows", counted)
    per_run = _recorded_inputs(3)
    batch, alone, columns = _started_batch_and_alone(Kf, len(per_run))
    epochs = [step["gnss_epoch"] for step in per_run[0]]
    fixes = [k for k in range(1, len(epochs)) if epochs[k] != epochs[k - 1]]
    poisoned = fixes[3] - 1                   # run 1's P, the step before a fix
    h = 0.01
    for k in range(fixes[4] + 5):
        if k == poisoned + 1:
            with pytest.raises(Exception) as failure:
                alone[1].advance(k * h, h, per_run[1][k])
        steps = [steps[k] for steps in per_run]
        outs = batch.advance(k * h, h, _batch_inputs(steps))
        for b, component in enumerate(alone):
            if b == 1 and k > poisoned:
                continue
            out = component.advance(k * h, h, steps[b])
            assert outs[b].tolist() == [float(out[n]) for n in columns], (k, b)
        if k == poisoned:
            batch.stack["P"][1, 2, 2] = np.nan
            alone[1].engine.P[2, 2] = np.nan
        if k == poisoned + 1:
            failures = batch.take_failures()
            assert list(failures) == [1]
            assert type(failures[1]) is type(failure.value)
            assert str(failures[1]) == str(failure.value)
            batch.keep([0, 2])
            per_run = [per_run[0], per_run[2]]
            alone = [alone[0], alone[2]]
    assert calls == [3, 3, 3, 3, 2]          # the fourth: failed, then each run alone
    assert batch.take_failures() == {}


def _kalman_update_2d(P, phi_acc, q_acc, z, R, m):
    """KfEngine's update arithmetic as 2-D products of one run (its code at 91ec9a2)."""
    P_pred = phi_acc @ P @ phi_acc.T + q_acc
    H = np.zeros((m, 15))
    H[:, :m] = np.eye(m)
    PHt = P_pred[:, :m]
    S = PHt[:m, :] + R
    K = np.linalg.solve(S, PHt.T).T
    IKH = np.eye(15) - K @ H
    P_new = IKH @ P_pred @ IKH.T + K @ R @ K.T
    return K @ z, 0.5 * (P_new + P_new.T), S, K


@pytest.mark.parametrize("m", [3, 6])
def test_the_stacked_update_gives_each_run_the_floats_of_its_2d_products(m):
    """predicted_rows and kalman_rows over 1 to 24 runs (random covariances, transitions,
    noise, measurements, each run its own R or one R for all) against each run's 2-D
    products, bit for bit."""
    rng = np.random.default_rng(5)
    for _ in range(60):
        runs = int(rng.integers(1, 25))
        A = rng.normal(size=(runs, 15, 15))
        P = A @ A.transpose(0, 2, 1) * rng.uniform(1e-6, 10.0)
        P = 0.5 * (P + P.transpose(0, 2, 1))
        phi = np.eye(15) + rng.normal(size=(runs, 15, 15)) * 1e-2
        noise = rng.normal(size=(runs, 15, 15)) * 1e-3
        q = noise @ noise.transpose(0, 2, 1)
        z = rng.normal(size=(runs, m))
        R = np.diag(rng.uniform(0.1, 10.0, m))
        Rs = R if rng.random() < 0.5 else R * rng.uniform(0.5, 2.0, (runs, 1, 1))
        H = np.zeros((m, 15))
        H[:, :m] = np.eye(m)
        dx, P_new, v, S, K = kalman_rows(predicted_rows(P, phi) + q, z, Rs, H)
        for b in range(runs):
            expected = _kalman_update_2d(P[b], phi[b], q[b], z[b], Rs if Rs.ndim == 2
                                         else Rs[b], m)
            for got, want in zip((dx[b], P_new[b], S[b], K[b]), expected):
                assert np.array_equal(_bits(got), _bits(want))
            assert np.array_equal(v[b], z[b])
