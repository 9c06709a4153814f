"""The IMU error model's arithmetic as a kernel over a run axis (navcore.sensors.imu_errors).

A batch of runs (other seeds, other parameters, vibration on in some) through one call of
``apply_rows`` equals each model's own ``apply``, bit for bit; the compiled kernel gives the
floats of its interpreted source; the normals drawn in blocks are the stream one draw per call
gives, also across a saved and restored state in the middle of a block.
"""
from __future__ import annotations

import copy

import numpy as np

from navcore.core import state
from navcore.sensors.imu_errors import ImuErrorModel, apply_rows


def _params(**changes):
    p = {name: spec[0] for name, spec in ImuErrorModel.PARAMETERS.items()}
    p.update(gyro_bias_dph=10.0, accel_bias_ug=500.0, gyro_arw_dpsh=0.1, accel_vrw_ugpsHz=50.0,
             gyro_bias_instability_dph=1.0, accel_bias_instability_ug=20.0,
             gyro_bias_tau_s=300.0, accel_bias_tau_s=600.0, gyro_scale_factor_ppm=300.0,
             accel_scale_factor_ppm=200.0, gyro_misalignment_urad=100.0,
             accel_misalignment_urad=100.0)
    p.update(changes)
    return p


def _bits(a):
    return np.ascontiguousarray(a).view(np.int64)


def _inputs(rng, n):
    dtheta = rng.normal(0, 1e-3, (n, 3))
    dvel = rng.normal(0, 0.05, (n, 3)) + [0.0, 0.0, -0.098]
    return dtheta, dvel


def test_the_normals_drawn_in_blocks_are_the_stream_of_one_draw_per_call():
    """The measured increments of a model equal the error model's equations written out
    here, on normals drawn 12 at a time from a generator of the same seed."""
    model = ImuErrorModel(_params(), seed=7)
    twin = copy.deepcopy(model)           # before any block is drawn: the same generator
    rng = twin.rng
    dtheta, dvel = _inputs(np.random.default_rng(1), 150)        # more than two blocks
    gm = twin.gm_bias[0].copy()
    M = twin._increment_matrix
    level = twin._level_bias[0]
    phi = np.exp(-0.01 / twin._gm_tau)
    drive = twin._gm_sigma * np.sqrt(1.0 - phi * phi)
    white = twin._white_density * np.sqrt(0.01)
    for k in range(150):
        got = np.concatenate(model.apply((k + 1) * 0.01, 0.01, dtheta[k], dvel[k]))
        z = rng.standard_normal(12)
        gm_end = phi * gm + drive * z[6:]
        expected = (M @ np.concatenate((dtheta[k], dvel[k])) + (level + 0.5 * (gm + gm_end))
                    * 0.01) + white * z[:6]
        gm = gm_end
        assert np.array_equal(got, expected), k


def test_a_batch_of_models_in_one_call_equals_each_model_alone():
    rng = np.random.default_rng(2)
    models = [ImuErrorModel(_params(vibration_gyro_rps=1e-3 * (i % 2),
                                    vibration_accel_mps2=0.02 * (i % 2),
                                    noise_intensity_gain=0.5 * i,
                                    noise_level_windows="0.2,0.5,3; 0.4,0.6,0.5" if i == 3
                                    else ""), seed=100 + i)
              for i in range(5)]
    batch = [copy.deepcopy(m) for m in models]
    dtheta, dvel = _inputs(rng, 80)
    # the manoeuvre intensity is the trajectory's, shared by the runs (zero: no vibration)
    intensity = np.where(rng.random(80) < 0.2, 0.0, rng.uniform(0, 2, 80))
    for k in range(80):
        t_end = (k + 1) * 0.01
        alone = np.array([np.concatenate(m.apply(t_end, 0.01, dtheta[k], dvel[k],
                                                 intensity[k]))
                          for m in models])
        ideal, normals = [], []
        for m in batch:            # the per-run parts apply() computes
            if m._cached_dt != 0.01:
                m._set_dt(0.01)
            if m._n_used == m.NORMALS_BLOCK:
                m._normals, m._n_used = m.rng.standard_normal(m._normals.shape), 0
            ideal.append(m._increment_matrix @ np.concatenate((dtheta[k], dvel[k])))
            normals.append(m._normals[m._n_used])
            m._n_used += 1
        out = np.empty((5, 6))
        gm = np.concatenate([m.gm_bias for m in batch])
        coefficients = np.concatenate([m._coefficients for m in batch], axis=1)
        apply_rows(out, np.array(ideal), np.array(normals)[:, None], 0,
                   np.concatenate([m._level_bias for m in batch]), gm, *coefficients,
                   np.array([m.noise_factor(t_end - 0.005) for m in batch]),
                   np.array([m.noise_intensity_gain for m in batch]),
                   np.array([m._vibration_on for m in batch]), float(intensity[k]), 0.01)
        for i, m in enumerate(batch):
            m.gm_bias[0] = gm[i]
        assert np.array_equal(_bits(out), _bits(alone)), k


def test_the_compiled_kernel_gives_the_floats_of_its_interpreted_source():
    """Compiled against interpreted: the same source (the compiler, not the equations)."""
    rng = np.random.default_rng(3)
    n = 500
    args = [rng.normal(0, 1e-2, (n, 6)), rng.normal(size=(n, 3, 12)), 1,
            rng.normal(0, 1e-3, (n, 6)), rng.normal(0, 1e-4, (n, 6)),
            rng.uniform(0.9, 1, (n, 6)), rng.uniform(0, 1e-4, (n, 6)),
            rng.uniform(0, 1e-3, (n, 6)), rng.uniform(0, 1e-3, (n, 6))]
    per_run = (rng.uniform(0.5, 3, n), rng.uniform(0, 2, n), rng.random(n) < 0.5)
    for intensity in (0.0, 0.7):
        compiled, interpreted = np.empty((n, 6)), np.empty((n, 6))
        gm_c, gm_i = args[4].copy(), args[4].copy()
        apply_rows(compiled, *args[:4], gm_c, *args[5:], *per_run, intensity, 0.01)
        apply_rows.py_func(interpreted, *args[:4], gm_i, *args[5:], *per_run, intensity, 0.01)
        assert np.array_equal(_bits(compiled), _bits(interpreted))
        assert np.array_equal(_bits(gm_c), _bits(gm_i))


def test_a_state_restored_in_the_middle_of_a_block_continues_the_same_stream():
    rng = np.random.default_rng(4)
    dtheta, dvel = _inputs(rng, 100)
    model = ImuErrorModel(_params(), seed=11)
    for k in range(37):
        model.apply((k + 1) * 0.01, 0.01, dtheta[k], dvel[k])
    saved = state.capture(model)
    fresh = ImuErrorModel(_params(), seed=11)
    state.restore(fresh, saved)
    for k in range(37, 100):
        a = model.apply((k + 1) * 0.01, 0.01, dtheta[k], dvel[k])
        b = fresh.apply((k + 1) * 0.01, 0.01, dtheta[k], dvel[k])
        assert np.array_equal(np.concatenate(a), np.concatenate(b)), k
