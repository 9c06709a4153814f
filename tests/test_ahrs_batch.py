"""The AHRS filters' batch (navcore.components.ahrs_batch) and the row functions it shares
with one filter alone (navcore.filters.unscented_rows: measurement_moments_rows, correct_rows).

Each run of a batch against the same component stepped alone on the same inputs, bit for
bit, with per-run parameters, a late start, a shadow-set switch, inputs one step late, a
refused input and a covariance made non-finite; that the runs' updates are one call; the
row functions against the textbook gain ``K = Pxz S^-1`` written with numpy's inverse.  The
whole simulation in batches against single runs is in tests/test_batch_simulation.py.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from test_ahrs import AHRS_PARAMS, SENSORS, TABLE, _trajectory, profiles  # noqa: F401

from navcore.components import ahrs_batch
from navcore.components.ahrs_components import FuzzyUkfAhrs, UkfAhrs
from navcore.core.batch import BatchInputs
from navcore.core.kernels import kernel
from navcore.core.timing import same_instant
from navcore.errors import InputError
from navcore.filters import unscented
from navcore.filters import unscented_rows
from navcore.filters.unscented_rows import correct_rows, measurement_moments_rows

STEP = 0.02


def _bits(a):
    return np.ascontiguousarray(a, dtype=float).view(np.uint64)


def _feeds(profile, seeds, steps, delay=0):
    """Per run, the filter inputs of every step (``delay`` steps late, Jacobi-like)."""
    feeds = []
    for seed in seeds:
        traj, out = _trajectory(profile, **{**SENSORS, "seed": seed})
        names = [p.name for p in UkfAhrs.inputs]
        rows = [{n: out[n] for n in names}] * (delay + 1)
        for k in range(steps):
            out = traj.step(k * STEP, STEP, {})
            rows.append({n: out[n] for n in names})
        feeds.append(rows[1:steps + 1])
    return feeds


def _batch_inputs(feeds, k):
    names = tuple(p.name for p in UkfAhrs.inputs)
    real = np.array([[feed[k][n] for n in names] for feed in feeds])
    return BatchInputs({n: real[:, j] for j, n in enumerate(names)}, real, names)


def _batch(cls, run_parameters):
    batch = cls.batch_class(cls, len(run_parameters))
    batch.set_parameters([{**AHRS_PARAMS, **p} for p in run_parameters])
    return batch


def _started(cls, run_parameters):
    """The batch of the runs and each run alone, started."""
    batch = _batch(cls, run_parameters)
    batch.start(0.0)
    singles = []
    for p in run_parameters:
        single = cls(**{**AHRS_PARAMS, **p})
        single.start(0.0)
        singles.append(single)
    return batch, singles


def _run_both(cls, run_parameters, feeds, steps, meddle=None):
    """The batch and each run alone on ``feeds``; ``meddle(k, batch, singles)`` may change
    both before step k.  Returns the batch's outputs, the singles' and the batch."""
    batch, singles = _started(cls, run_parameters)
    names = [p.name for p in cls.outputs]
    together, alone = [], []
    for k in range(steps):
        if meddle is not None:
            meddle(k, batch, singles)
        together.append(batch.advance(k * STEP, STEP, _batch_inputs(feeds, k)).copy())
        row = []
        for b, f in enumerate(singles):
            if alone and isinstance(alone[-1][b], Exception):
                row.append(alone[-1][b])             # a failed run stops
                continue
            try:
                out = f.advance(k * STEP, STEP, feeds[b][k])
                row.append([float(out[n]) for n in names])
            except InputError as exc:
                row.append(exc)
        alone.append(row)
    return together, alone, batch


def _assert_rows_equal(together, alone, failed=()):
    for k, (out, row) in enumerate(zip(together, alone)):
        for b, single in enumerate(row):
            if b in failed and isinstance(single, Exception):
                continue
            assert np.array_equal(_bits(out[b]), _bits(single)), (k, b)


RUNS = [{}, {"r_accel_mps2": 0.05, "update_interval": 0.06},
        {"q_gyro_arw_dpsh": 2.0, "init_attitude": "parameters", "init_roll": 0.1,
         "init_pitch": -0.2, "init_yaw": 3.0},
        {"max_mag_age": 0.0, "p0_att": math.radians(20.0)}]


@pytest.mark.parametrize("cls, delay", [(UkfAhrs, 0), (FuzzyUkfAhrs, 1)])
def test_every_run_of_a_batch_steps_as_it_does_alone(cls, delay, profiles):  # noqa: F811
    """Four runs with their own parameters and seeds through the TABLE profile (a rotation of
    200 deg: the shadow switch), one of them started from parameters."""
    runs = RUNS if cls is UkfAhrs else [{**p, "fuzzy_window": 5 + 3 * i}
                                        for i, p in enumerate(RUNS)]
    feeds = _feeds(profiles(TABLE), [3, 4, 5, 6], 1000, delay)
    together, alone, batch = _run_both(cls, runs, feeds, 1000)
    _assert_rows_equal(together, alone)
    assert batch.switches.min() >= 1 and batch.take_failures() == {}
    # the runs differ: the comparison is not of equal runs
    assert not np.array_equal(together[-1][0], together[-1][1])


def test_the_runs_update_together_in_one_call(monkeypatch, profiles):  # noqa: F811
    calls = []
    real = ahrs_batch.correct_rows
    monkeypatch.setattr(ahrs_batch, "correct_rows",
                        lambda *a: calls.append(len(a[0])) or real(*a))
    feeds = _feeds(profiles(TABLE), [3, 4, 5], 100)
    _run_both(FuzzyUkfAhrs, [{}, {"r_accel_mps2": 0.03}, {"fuzzy_window": 4}], feeds, 100)
    assert len(calls) >= 15 and set(calls) == {3}


@pytest.mark.parametrize("cls", [UkfAhrs, FuzzyUkfAhrs])
def test_a_refused_input_and_a_broken_covariance_fail_their_run_alone(cls, profiles):  # noqa: F811
    feeds = _feeds(profiles(TABLE), [3, 4, 5], 300)
    feeds[0][120] = {**feeds[0][120], "imu_dt": -1.0}            # refused: imu_dt > 0

    def meddle(k, batch, singles):
        if k == 200:                                             # run 2's P not finite
            batch.P[2, 1, 1] = math.nan
            singles[2].engine.ukf.P = batch.P[2].copy()

    together, alone, batch = _run_both(cls, [{}, {}, {}], feeds, 300, meddle)
    failures = batch.take_failures()
    assert sorted(failures) == [0, 2]
    assert "imu_dt" in str(failures[0]) and "'P' contains NaN" in str(failures[2])
    first_error = [next(k for k, row in enumerate(alone) if isinstance(row[b], Exception))
                   for b in (0, 2)]
    assert first_error[0] == 120 and 200 <= first_error[1] < 205     # its next update
    for b, k in zip((0, 2), first_error):
        assert str(alone[k][b]) == str(failures[b])
    # run 1 goes on as alone; the failed runs match up to their error
    _assert_rows_equal([t[[1]] for t in together], [[r[1]] for r in alone])
    _assert_rows_equal([t[[0, 2]] for t in together[:120]], [r[::2] for r in alone[:120]])
    _assert_rows_equal([t[[2]] for t in together[:first_error[1]]],
                       [[r[2]] for r in alone[:first_error[1]]])


def _filters(runs, rng, n=6, m=6):
    x = rng.normal(0, 0.3, (runs, n))
    A = rng.normal(0, 0.1, (runs, n, n))
    P = A @ A.transpose(0, 2, 1) + 1e-3 * np.eye(n)
    X = x[:, None, :] + rng.normal(0, 0.2, (runs, 2 * n + 1, n))
    Y = np.sin(X) @ rng.normal(0, 1, (n, m))
    return x, P, X, Y


def test_measurement_moments_and_correction_of_many_filters_against_the_textbook():
    """Each filter of five: the moments as sums written out, K = Pxz inv(S), x + K v,
    P - K S K^T (numpy's inverse), NIS v^T inv(S) v; and each row equal to the filter
    computed alone, bit for bit."""
    rng = np.random.default_rng(7)
    x, P, X, Y = _filters(5, rng)
    Wm, Wc, _ = unscented.sigma_weights(6, 0.5, 2.0, 1.0)
    z_pred, Pzz, Pxz = measurement_moments_rows(X, Y, x, Wm, Wc)
    R = np.diag(rng.uniform(0.01, 0.1, 6))
    z = z_pred + rng.normal(0, 0.1, z_pred.shape)
    result = correct_rows(x, P, z, z_pred, Pzz + R, Pxz)
    for b in range(5):
        mean = sum(w * y for w, y in zip(Wm, Y[b]))
        dz = Y[b] - mean
        dx = X[b] - x[b]
        Szz = sum(w * np.outer(d, d) for w, d in zip(Wc, dz))
        Sxz = sum(w * np.outer(a, d) for w, a, d in zip(Wc, dx, dz))
        np.testing.assert_allclose(z_pred[b], mean, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(Pzz[b], Szz, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(Pxz[b], Sxz, rtol=1e-12, atol=1e-15)
        S = Szz + R
        K = Sxz @ np.linalg.inv(S)
        v = z[b] - mean
        np.testing.assert_allclose(result.x[b], x[b] + K @ v, rtol=1e-11, atol=1e-14)
        np.testing.assert_allclose(result.P[b], P[b] - K @ S @ K.T, rtol=1e-10, atol=1e-14)
        assert result.nis[b] == pytest.approx(v @ np.linalg.inv(S) @ v, rel=1e-11)
        alone = correct_rows(x[b:b + 1], P[b:b + 1], z[b:b + 1], z_pred[b:b + 1],
                             Pzz[b:b + 1] + R, Pxz[b:b + 1])
        moments = measurement_moments_rows(X[b:b + 1], Y[b:b + 1], x[b:b + 1], Wm, Wc)
        for together, one in zip((z_pred, Pzz, Pxz, *result[:7]), (*moments, *alone[:7])):
            assert np.array_equal(_bits(together[b]), _bits(one[0]))
    assert result.status.tolist() == [0] * 5


def test_a_filter_that_cannot_be_corrected_is_flagged_alone():
    rng = np.random.default_rng(8)
    x, P, X, Y = _filters(3, rng)
    Wm, Wc, _ = unscented.sigma_weights(6, 1.0, 2.0, 0.0)
    z_pred, Pzz, Pxz = measurement_moments_rows(X, Y, x, Wm, Wc)
    S = Pzz + np.eye(6) * 0.01
    S[0] = -np.eye(6)                        # not positive definite
    z = z_pred.copy()
    z[2, 3] = math.inf                       # not finite
    result = correct_rows(x, P, z, z_pred, S, Pxz)
    assert result.status[1] == 0 and result.status[0] and result.status[2]
    assert "positive definite" in str(unscented_rows.correction_error(result.status[0]))
    assert "NaN or inf" in str(unscented_rows.correction_error(result.status[2]))


def test_magnetometer_batch_rows_are_each_model_alone():
    """Runs with their own field, hard and soft iron, noise and vibration (noise, a
    sinusoid, the magnetometer factor, each from its own start): over more than one block of
    normals, the readings of MagnetometerBatch.sample are each model's own measure and the
    extra specific force of the rows it names each model's own accel_disturbance, bit for
    bit, after a row is dropped too."""
    from scipy.spatial.transform import Rotation

    from navcore.sensors.magnetometer import MagnetometerModel
    from navcore.sensors.magnetometer_batch import MagnetometerBatch
    base = dict(mag_field_T=5e-5, mag_noise_T=1e-7)
    params = [base, base, {**base, "mag_inclination": 0.3, "mag_hard_iron_y": 2e-6},
              {**base, "mag_soft_iron": "1.01,0.002,0,0,0.99,0.001,0,0,1",
               "vibration_start_s": 0.5, "vibration_accel_noise_mps2": 0.2,
               "vibration_mag_factor": 3.0},
              {**base, "vibration_start_s": 2.0, "vibration_accel_amplitude_mps2": 0.4,
               "vibration_frequency_hz": 7.3, "vibration_accel_noise_mps2": 0.1},
              {"vibration_start_s": 1.0, "vibration_mag_factor": 2.0}]
    seeds = range(1, len(params) + 1)
    batch = MagnetometerBatch([MagnetometerModel(p, seed) for p, seed in zip(params, seeds)])
    alone = [MagnetometerModel(p, seed) for p, seed in zip(params, seeds)]
    vibrated = set()
    for k in range(MagnetometerModel.NORMALS_BLOCK + 40):
        if k == 100:                                       # drop run 1
            batch.keep([0, 2, 3, 4, 5])
            alone.pop(1)
        t = 0.01 * k
        C_bn = Rotation.from_euler("ZYX", [0.03 * k, 0.1, -0.2]).as_matrix()
        reading, rows, extra = batch.sample(t, C_bn)
        expected = [m.measure(t, C_bn) for m in alone]
        assert np.array_equal(_bits(reading), _bits(np.array(expected))), k
        assert rows.tolist() == [b for b, m in enumerate(alone) if m.vibrating(t)]
        for i, b in enumerate(rows.tolist()):
            assert np.array_equal(_bits(extra[i]), _bits(alone[b].accel_disturbance(t))), (k, b)
            vibrated.add(b)
    assert vibrated == {2, 3, 4}                  # after the drop: rows of runs 3, 4, 5
    assert not np.array_equal(reading[0], reading[1])     # own seeds


def test_magnetometer_draws_each_sample_s_numbers_from_its_own_stream():
    """Over more than one block of normals (MagnetometerModel.NORMALS_BLOCK samples), each
    reading is the field in body axes plus the hard iron plus the noise times the next 3 of
    6 normals the model's generator gives one sample at a time (numpy's default_rng of
    [seed, 3003]), the vibration noise the other 3."""
    from navcore.sensors.magnetometer import MagnetometerModel
    params = dict(mag_field_T=5e-5, mag_noise_T=1e-7, mag_hard_iron_x=1e-6,
                  vibration_start_s=0.0, vibration_accel_noise_mps2=0.2)
    model = MagnetometerModel(params, 7)
    stream = np.random.default_rng([7, 3003])
    field = 5e-5 * np.array([math.cos(math.radians(60.0)), 0.0, math.sin(math.radians(60.0))])
    C_bn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    for k in range(MagnetometerModel.NORMALS_BLOCK + 50):
        z = stream.standard_normal(6)
        reading = model.measure(0.01 * k, C_bn)
        expected = C_bn.T @ field + np.array([1e-6, 0.0, 0.0]) + 1e-7 * z[:3]
        np.testing.assert_allclose(reading, expected, rtol=0, atol=1e-20)
        assert np.array_equal(model.accel_disturbance(0.01 * k), 0.2 * z[3:])


@pytest.mark.parametrize("compiled", [True, False], ids=["kernel", "source"])
def test_quaternion_kernels_of_rows_are_the_single_engine_s_floats(compiled):
    """accumulate_rows against _qmul and _rotvec_quat of each row (the single engine's
    accumulate) and the shell's test of a due update, solution_rows against quat_euler of
    the single engine's _state_quat (its current_quat) and the state's bias and scales, and
    the time update's kernel against its Python source, bit for bit, compiled and as their
    Python source, on both sides of the small-angle series (|v| = 1e-6), at zero and with
    no pending interval."""
    from navcore.filters.ahrs import (_propagate_rows, _qmul, _rotvec_quat, _state_quat,
                                      accumulate_rows, quat_euler, solution_rows)
    accumulate = accumulate_rows if compiled else accumulate_rows.py_func
    solutions = solution_rows if compiled else solution_rows.py_func
    rng = np.random.default_rng(5)
    v = rng.normal(size=(800, 3)) * np.repeat([1e-9, 1e-7, 6e-7, 1e-5, 1e-3, 0.1, 1.0, 3.0],
                                              100)[:, None]
    v[0] = 0.0
    dq = rng.normal(size=(800, 4))
    # every run but the first steps: its interval's end, the increment and whether an
    # update is due (the magnetometer's age and the update interval, at and around each
    # bound of 1e-9 s)
    rows = np.arange(1, 800)
    imu_time, dt = rng.uniform(0, 100, 799), rng.uniform(0.001, 0.02, 799)
    last_update = imu_time - rng.choice([0.1, 0.1 - 1e-9, 0.1 - 2e-9, 0.05, 0.2], 799)
    mag_time = imu_time + rng.choice([0.0, 0.05 + 1e-9, 0.05 + 2e-9, -0.06], 799)
    nav_time, interval = np.zeros(800), rng.uniform(0, 0.1, 800)
    got, due = dq.copy(), np.zeros(799, dtype=bool)
    accumulate(rows, imu_time, dt, v[1:], mag_time, nav_time, got, interval.copy(),
               np.concatenate(([0.0], last_update)), np.full(800, 0.1), np.full(800, 0.05),
               due)
    assert np.array_equal(_bits(got[1:]), _bits([_qmul(tuple(a), _rotvec_quat(*b))
                                                 for a, b in zip(dq[1:].tolist(),
                                                                 v[1:].tolist())]))
    assert np.array_equal(got[0], dq[0]) and nav_time[0] == 0.0
    assert np.array_equal(nav_time[1:], imu_time)
    expected = [abs(m - t) <= 0.05 + 1e-9 and t - u >= 0.1 - 1e-9       # AhrsFilter.step
                for m, t, u in zip(mag_time.tolist(), imu_time.tolist(), last_update.tolist())]
    assert due.tolist() == expected and 0 < sum(expected) < 799
    norms = np.linalg.norm(v, axis=1)
    assert (norms < 1e-6).any() and (norms > 1e-6).any()
    # the outputs of 800 runs, every second one written, a quarter with no pending interval
    x = np.concatenate((rng.normal(size=(800, 3)) * 0.7, v * 3e-3), axis=1)
    interval = rng.uniform(0.0, 0.1, 800) * (np.arange(800) % 4 != 0)
    nav_time, r_scale = rng.uniform(0, 100, 800), rng.uniform(0.5, 2.0, (800, 2))
    rows = np.arange(0, 800, 2)
    out = np.zeros((800, 12))
    solutions(out, rows, x, interval, dq, nav_time, r_scale, np.arange(10))
    for b in rows.tolist():
        roll, pitch, yaw = quat_euler(_state_quat(*x[b].tolist(), interval[b].item(),
                                                  tuple(dq[b].tolist())))
        expected = [nav_time[b], 1.0, roll, pitch, yaw, *x[b, 3:], *r_scale[b]]
        assert np.array_equal(_bits(out[b, :10]), _bits(expected)), b
    assert not out[1::2].any()
    # the time update over the points of 50 filters, spread wide enough to need the shadow
    X = rng.normal(size=(50, 13, 6)) * [1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3]
    T = rng.uniform(0.0, 0.2, 50)
    compiled_out, source_out = np.empty(X.shape), np.empty(X.shape)
    _propagate_rows(X, dq[:50], T, compiled_out)
    _propagate_rows.py_func(X, dq[:50], T, source_out)
    assert np.array_equal(_bits(compiled_out), _bits(source_out))


def test_same_instant_in_a_kernel_is_same_time():
    """Long runs (1e5 s), short ones, exact zeros, differences around the tolerance: the
    compiled test (same_instant, in a kernel) against same_time."""
    from navcore.core.timing import same_time
    rng = np.random.default_rng(0)
    a = np.concatenate([rng.uniform(-1e5, 1e5, 5000), rng.uniform(0, 1, 5000), np.zeros(5)])
    b = a + rng.choice([0, 1e-15, 1e-12, 1e-11, 1e-9, -1e-13], a.size) * rng.uniform(
        0, 3, a.size)
    period = rng.choice([0.02, 0.01, 1.0, 0.005], a.size)
    got = np.empty(a.size, dtype=bool)
    _same_instants(a, b, period, got)
    expected = [same_time(*v) for v in zip(a.tolist(), b.tolist(), period.tolist())]
    assert got.tolist() == expected
    assert 0.3 < got.mean() < 0.95                     # both answers occur


@kernel
def _same_instants(a, b, period, out):
    for i in range(a.shape[0]):
        out[i] = same_instant(a[i], b[i], period[i])


def test_euler_angles_of_sigma_points_are_those_of_each_point():
    """The Euler angles of the sigma points' MRPs of many filters (_mrp_euler_rows) against
    quat_euler of each point's quaternion bit for bit: random attitudes, the shadow set,
    pitch at +-90 deg and yaw at -180 deg (reported as +180)."""
    from navcore.filters.ahrs import _mrp_euler_rows, quat_euler
    from navcore.ins.mrp import quat_of_mrp, quat_to_mrp
    rng = np.random.default_rng(3)
    X = rng.normal(size=(40, 13, 6))
    X[20:, :, :3] *= 3.0                               # |sigma| > 1: the shadow set
    half = math.sqrt(0.5)
    X[0, 0, :3] = quat_to_mrp(np.array([half, 0.0, half, 0.0]))       # pitch +90 deg
    X[0, 1, :3] = quat_to_mrp(np.array([0.0, 0.0, 0.0, 1.0]))         # yaw -180 deg
    angles = np.empty((40, 13, 3))
    _mrp_euler_rows(X, angles)
    expected = [quat_euler(quat_of_mrp(*p[:3].tolist())) for p in X.reshape(-1, 6)]
    assert np.array_equal(_bits(angles.reshape(-1, 3)), _bits(expected))
    assert angles[0, 1, 2] == math.pi and abs(angles[0, 0, 1] - math.pi / 2) < 1e-8


def test_accepted_rows_is_each_input_s_declared_range():
    """ComponentBatch.accepted_rows (open bounds from closed ones by nextafter) against
    Limits.contains per value: closed, open and one-sided ranges, values at each bound, one
    float either side of it, NaN and the infinities."""
    from types import SimpleNamespace

    from navcore.core.batch import ComponentBatch
    from navcore.core.limits import Limits
    limits = {"a": Limits(0.0, 1.0), "b": Limits(0.0, 1.0, low_open=True, high_open=True),
              "c": Limits(low=-2.5), "d": Limits(high=1e-3, high_open=True), "e": Limits()}
    ports = {n: SimpleNamespace(limits=x) for n, x in limits.items()}
    fake = SimpleNamespace(component_class=SimpleNamespace(_input_ports=lambda: ports))
    fake._open_bounds = lambda names: ComponentBatch._open_bounds(fake, names)
    candidates = [0.0, 1.0, -2.5, 1e-3, 0.5, -1.0, 2.0, math.nan, math.inf, -math.inf]
    candidates += [math.nextafter(x, s) for x in (0.0, 1.0, -2.5, 1e-3) for s in (-1, 2)]
    rng = np.random.default_rng(2)
    names = tuple(limits)
    values = rng.choice(candidates, size=(400, len(names)))
    rows = ComponentBatch.accepted_rows(fake, values, names)
    expected = [all(limits[n].contains(v) for n, v in zip(names, row)) for row in values.tolist()]
    assert rows.tolist() == expected
    assert 0 < sum(expected) < len(expected)


@pytest.mark.parametrize("m", [3, 6, 15])
def test_stacked_row_column_products_are_each_row_s_dot(m):
    """The batch's |sigma|^2 of every run and correct_rows' NIS |u|^2 of every filter
    (numpy's stacked (1, m) x (m, 1) products) against one run's float(v @ v), bit for bit,
    over 16 decades (a stacked einsum, by contrast, rounds otherwise)."""
    rng = np.random.default_rng(8)
    mrp = rng.normal(size=(20000, m)) * 10.0 ** rng.integers(-8, 8, (20000, 1))
    stacked = np.matmul(mrp[:, None, :], mrp[:, :, None])[:, 0, 0]
    assert np.array_equal(_bits(stacked), _bits([float(r @ r) for r in mrp]))
    assert not np.array_equal(_bits(np.einsum("bi,bi->b", mrp, mrp)), _bits(stacked))


@pytest.mark.parametrize("cls", [UkfAhrs, FuzzyUkfAhrs])
def test_the_runs_a_batch_keeps_go_on_as_alone(cls, profiles):  # noqa: F811
    """Three runs (their own fuzzy windows), the middle one dropped from the batch after 60
    steps (as the master drops a failed run): the two kept runs' outputs stay their single
    runs', bit for bit, through the updates after it."""
    runs = [{"fuzzy_window": w} for w in (4, 6, 8)] if cls is FuzzyUkfAhrs else [{}, {}, {}]
    feeds = _feeds(profiles(TABLE), [3, 4, 5], 200)
    kept = [0, 2]
    batch, singles = _started(cls, runs)
    names = [p.name for p in cls.outputs]
    for k in range(200):
        if k == 60:
            batch.keep(kept)
            singles = [singles[b] for b in kept]
            feeds = [feeds[b] for b in kept]
        out = batch.advance(k * STEP, STEP, _batch_inputs(feeds, k))
        for b, single in enumerate(singles):
            expected = single.advance(k * STEP, STEP, feeds[b][k])
            assert np.array_equal(_bits(out[b]), _bits([float(expected[n]) for n in names]))
    assert batch.take_failures() == {} and batch.runs == 2
