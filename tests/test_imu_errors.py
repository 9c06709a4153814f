"""Tests of navcore.sensors.imu_errors: statistics with fixed seeds, matrices, windows, errors."""
import copy
import math

import numpy as np
import pytest

from navcore.core.component import InputError, ParameterError
from navcore.sensors.imu_errors import DPH, DPSH, G0, UG, ImuErrorModel, parse_windows

ZERO3 = np.zeros(3)


def run(model, n, dt, t0=0.0, dtheta=ZERO3, dvel=ZERO3, intensity=0.0):
    """Apply the model over n consecutive intervals; return (n,3) gyro and accel arrays."""
    gyro = np.empty((n, 3))
    accel = np.empty((n, 3))
    for k in range(n):
        gyro[k], accel[k] = model.apply(t0 + (k + 1) * dt, dt, dtheta, dvel, intensity)
    return gyro, accel


def test_unit_conversions():
    assert DPH == pytest.approx(4.84813681109536e-06, rel=1e-12)     # 1 deg/h in rad/s
    assert DPSH == pytest.approx(2.908882086657216e-04, rel=1e-12)   # 1 deg/sqrt(h)
    assert UG == pytest.approx(9.80665e-06, rel=1e-12)               # 1 ug in m/s^2
    assert G0 == 9.80665


def test_arw_and_vrw_std_match_density_times_sqrt_dt():
    # paper 000 IMU noise, 100 Hz: angle noise sigma = ARW sqrt(dt), velocity VRW sqrt(dt)
    arw_dpsh, vrw_ug = 0.06, 10.0
    dt, n = 0.01, 20000
    model = ImuErrorModel({"gyro_arw_dpsh": arw_dpsh, "accel_vrw_ugpsHz": vrw_ug}, seed=1)
    gyro, accel = run(model, n, dt)
    expected_gyro = arw_dpsh * DPSH * math.sqrt(dt)        # 2.909e-6 rad
    expected_accel = vrw_ug * UG * math.sqrt(dt)           # 9.807e-6 m/s
    # 60000 samples: standard error of the std is 0.3 %, per axis 0.5 %
    assert gyro.std(axis=0) == pytest.approx(np.full(3, expected_gyro), rel=0.02)
    assert accel.std(axis=0) == pytest.approx(np.full(3, expected_accel), rel=0.02)
    assert gyro.std() == pytest.approx(expected_gyro, rel=0.01)
    assert accel.std() == pytest.approx(expected_accel, rel=0.01)
    assert abs(gyro.mean()) < 4 * expected_gyro / math.sqrt(3 * n)
    # white: lag-1 autocorrelation near zero
    g = gyro[:, 0]
    assert abs(np.corrcoef(g[:-1], g[1:])[0, 1]) < 0.03


def test_noise_sigma_scales_with_sqrt_dt():
    model_fast = ImuErrorModel({"gyro_arw_dpsh": 1.0}, seed=3)
    model_slow = ImuErrorModel({"gyro_arw_dpsh": 1.0}, seed=3)
    fast, _ = run(model_fast, 50, 0.01)
    slow, _ = run(model_slow, 50, 0.04)
    # same draws, so the ratio is exactly sqrt(0.04 / 0.01) = 2
    np.testing.assert_allclose(slow / fast, 2.0, rtol=1e-12)


def test_gauss_markov_steady_state_std_and_autocorrelation():
    sigma_dph, sigma_ug, tau, dt, n = 1.0, 50.0, 1.0, 0.1, 60000
    model = ImuErrorModel({"gyro_bias_instability_dph": sigma_dph, "gyro_bias_tau_s": tau,
                           "accel_bias_instability_ug": sigma_ug, "accel_bias_tau_s": tau},
                          seed=7)
    states = np.empty((n, 6))
    for k in range(n):
        model.apply((k + 1) * dt, dt, ZERO3, ZERO3)
        bg, ba = model.true_biases()
        states[k, :3], states[k, 3:] = bg, ba
    gyro = states[:, :3] / (sigma_dph * DPH)     # normalised to unit steady-state sigma
    accel = states[:, 3:] / (sigma_ug * UG)
    for x in (gyro, accel):
        # 3 axes x 60000 correlated samples: standard error of the std about 0.6 %
        assert x.std() == pytest.approx(1.0, rel=0.03)
        lag = round(tau / dt)
        rho = np.mean([np.corrcoef(x[:-lag, i], x[lag:, i])[0, 1] for i in range(3)])
        assert rho == pytest.approx(math.exp(-1.0), abs=0.03)
        rho1 = np.mean([np.corrcoef(x[:-1, i], x[1:, i])[0, 1] for i in range(3)])
        assert rho1 == pytest.approx(math.exp(-dt / tau), abs=0.01)


def test_gauss_markov_enters_the_increments_as_trapezoid_of_the_state():
    model = ImuErrorModel({"gyro_bias_instability_dph": 10.0, "gyro_bias_tau_s": 5.0}, seed=2)
    dt = 0.01
    before = model.true_biases()[0]
    gyro, _ = model.apply(dt, dt, ZERO3, ZERO3)
    after = model.true_biases()[0]
    np.testing.assert_allclose(gyro, 0.5 * (before + after) * dt, rtol=1e-12)


@pytest.mark.parametrize("params", [
    {"gyro_bias_instability_dph": 1.0, "gyro_bias_tau_s": 0.0},
    {"gyro_bias_instability_dph": 1.0, "gyro_bias_tau_s": -3.0},
    {"gyro_bias_instability_dph": 0.0, "gyro_bias_tau_s": 100.0},
])
def test_gauss_markov_disabled(params):
    model = ImuErrorModel(params, seed=4)
    gyro, accel = run(model, 100, 0.01)
    assert not gyro.any() and not accel.any()
    bg, ba = model.true_biases()
    assert not bg.any() and not ba.any()


def test_constant_bias_fixed_within_run_reproducible_by_seed():
    params = {"gyro_bias_dph": 5.0, "accel_bias_ug": 100.0}
    dt = 0.01
    model = ImuErrorModel(params, seed=11)
    gyro, accel = run(model, 200, dt)
    bg, ba = model.true_biases()
    # no noise: every interval carries exactly the same bias
    np.testing.assert_array_equal(gyro, np.tile(gyro[0], (200, 1)))
    np.testing.assert_allclose(gyro[0], bg * dt, rtol=1e-15)
    np.testing.assert_allclose(accel[0], ba * dt, rtol=1e-15)
    same = ImuErrorModel(params, seed=11)
    np.testing.assert_array_equal(same.true_biases()[0], bg)
    np.testing.assert_array_equal(same.true_biases()[1], ba)
    other = ImuErrorModel(params, seed=12)
    assert not np.array_equal(other.true_biases()[0], bg)


def test_constant_bias_distribution_over_seeds():
    biases = np.array([np.concatenate(ImuErrorModel({"gyro_bias_dph": 5.0,
                                                     "accel_bias_ug": 100.0}, s).true_biases())
                       for s in range(2000)])
    # 6000 draws per sensor: standard error of the std about 0.9 %
    assert biases[:, :3].std() == pytest.approx(5.0 * DPH, rel=0.04)
    assert biases[:, 3:].std() == pytest.approx(100.0 * UG, rel=0.04)


def test_scale_factor_and_misalignment_applied_as_a_matrix():
    params = {"gyro_scale_factor_ppm": 1000.0, "gyro_misalignment_urad": 500.0,
              "accel_scale_factor_ppm": 300.0, "accel_misalignment_urad": 200.0}
    model = ImuErrorModel(params, seed=5)
    Mg, Ma = model.gyro_matrix, model.accel_matrix
    # diagonal 1 + scale factor, off-diagonal the misalignment, no element left at 0
    assert np.all(np.abs(np.diag(Mg) - 1.0) < 5 * 1000e-6)
    assert np.all(Mg[~np.eye(3, dtype=bool)] != 0.0)
    assert np.all(np.abs(Mg[~np.eye(3, dtype=bool)]) < 5 * 500e-6)
    rng = np.random.default_rng(0)
    for _ in range(5):
        dtheta, dvel = rng.normal(0, 0.01, 3), rng.normal(0, 0.1, 3)
        g, a = model.apply(1.0, 0.01, dtheta, dvel)
        np.testing.assert_allclose(g, Mg @ dtheta, rtol=1e-13, atol=1e-18)
        np.testing.assert_allclose(a, Ma @ dvel, rtol=1e-13, atol=1e-18)
    # the drawn elements have the stated 1-sigma over many seeds
    mats = [ImuErrorModel(params, s) for s in range(1000)]
    off = ~np.eye(3, dtype=bool)
    assert np.std([np.diag(m.gyro_matrix) - 1 for m in mats]) == pytest.approx(1000e-6,
                                                                                rel=0.06)
    assert np.std([m.gyro_matrix[off] for m in mats]) == pytest.approx(500e-6, rel=0.06)
    assert np.std([np.diag(m.accel_matrix) - 1 for m in mats]) == pytest.approx(300e-6,
                                                                                 rel=0.06)
    assert np.std([m.accel_matrix[off] for m in mats]) == pytest.approx(200e-6, rel=0.06)


def test_g_sensitivity_uses_the_specific_force():
    model = ImuErrorModel({"g_sensitivity_dphpg": 10.0}, seed=6)
    dt = 0.01
    f = np.array([1.0, -2.0, -9.81])
    g, a = model.apply(dt, dt, ZERO3, f * dt)
    np.testing.assert_allclose(g, model.g_sensitivity @ f * dt, rtol=1e-13)
    np.testing.assert_allclose(a, f * dt, rtol=1e-15)
    elements = np.array([ImuErrorModel({"g_sensitivity_dphpg": 10.0}, s).g_sensitivity
                         for s in range(700)])
    assert elements.std() == pytest.approx(10.0 * DPH / G0, rel=0.05)


def test_level_reference_leaves_level_flight_with_the_bias_only():
    """level_reference_g = 1: at rest or in level flight (f = (0, 0, -g) FRD) the measured
    increments are the ideal ones plus the constant bias; a 2 g pull-up adds (S + M) df and
    G df for df = f - f_ref (hand-computed from the drawn matrices)."""
    params = {"gyro_bias_dph": 5.0, "accel_bias_ug": 100.0, "gyro_scale_factor_ppm": 5000.0,
              "gyro_misalignment_urad": 3000.0, "g_sensitivity_dphpg": 54.0,
              "accel_scale_factor_ppm": 5000.0, "accel_misalignment_urad": 3000.0}
    dt = 0.02
    f_level = np.array([0.0, 0.0, -G0])
    ref = ImuErrorModel({**params, "level_reference_g": 1.0}, seed=3)
    plain = ImuErrorModel(params, seed=3)
    bg, ba = ref.constant_bias[:3], ref.constant_bias[3:]
    g, a = ref.apply(dt, dt, ZERO3, f_level * dt)
    np.testing.assert_allclose(g, bg * dt, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(a, (f_level + ba) * dt, rtol=1e-12, atol=1e-15)
    g_plain, _ = plain.apply(dt, dt, ZERO3, f_level * dt)    # the same draws act on all of f
    np.testing.assert_allclose(g_plain, (bg + plain.g_sensitivity @ f_level) * dt, rtol=1e-12)
    f_pull = np.array([0.0, 0.0, -2.0 * G0])
    w = np.array([0.0, 0.2, 0.0])
    g, a = ref.apply(2 * dt, dt, w * dt, f_pull * dt)
    df = f_pull - f_level
    np.testing.assert_allclose(g, (ref.gyro_matrix @ w + bg + ref.g_sensitivity @ df) * dt,
                               rtol=1e-12)
    np.testing.assert_allclose(a, (f_pull + (ref.accel_matrix - np.eye(3)) @ df + ba) * dt,
                               rtol=1e-12)


def test_noise_windows_scale_noise_only_inside():
    base = {"gyro_arw_dpsh": 0.5, "accel_vrw_ugpsHz": 50.0, "gyro_bias_dph": 3.0}
    dt, n = 0.01, 3000
    plain = ImuErrorModel(base, seed=9)
    windowed = ImuErrorModel({**base, "noise_level_windows": "10,20,3; 25,26,0"}, seed=9)
    g0, a0 = run(plain, n, dt)
    g1, a1 = run(windowed, n, dt)
    bias = plain.true_biases()[0] * dt
    mid = (np.arange(n) + 0.5) * dt                  # interval midpoints
    inside = (mid >= 10) & (mid < 20)
    silent = (mid >= 25) & (mid < 26)
    outside = ~inside & ~silent
    np.testing.assert_array_equal(g1[outside], g0[outside])
    np.testing.assert_array_equal(a1[outside], a0[outside])
    np.testing.assert_allclose(g1[inside] - bias, 3.0 * (g0[inside] - bias), rtol=1e-9)
    np.testing.assert_allclose(a1[inside], 3.0 * a0[inside], rtol=1e-12)
    np.testing.assert_allclose(g1[silent], np.tile(bias, (silent.sum(), 1)), rtol=1e-12)
    assert not a1[silent].any()
    assert inside.sum() == 1000 and silent.sum() == 100


def test_intensity_gain_and_vibration():
    dt, n = 0.01, 200
    params = {"gyro_arw_dpsh": 0.2, "accel_vrw_ugpsHz": 20.0, "noise_intensity_gain": 0.5}
    g0, a0 = run(ImuErrorModel(params, 3), n, dt, intensity=0.0)
    g2, a2 = run(ImuErrorModel(params, 3), n, dt, intensity=2.0)
    np.testing.assert_allclose(g2, 2.0 * g0, rtol=1e-12)          # 1 + 0.5 * 2
    np.testing.assert_allclose(a2, 2.0 * a0, rtol=1e-12)
    vib = {**params, "vibration_gyro_rps": 0.01, "vibration_accel_mps2": 0.2}
    g3, a3 = run(ImuErrorModel(vib, 3), n, dt, intensity=0.0)
    np.testing.assert_array_equal(g3, g0)          # no vibration when intensity is 0
    g4, a4 = run(ImuErrorModel(vib, 3), n, dt, intensity=2.0)
    white_g = 0.2 * DPSH * math.sqrt(dt) * 2.0
    white_a = 20.0 * UG * math.sqrt(dt) * 2.0
    total_g = math.hypot(white_g, 0.01 * 2.0 * dt)
    total_a = math.hypot(white_a, 0.2 * 2.0 * dt)
    np.testing.assert_allclose(g4, g0 / (white_g / 2.0) * total_g, rtol=1e-12)
    np.testing.assert_allclose(a4, a0 / (white_a / 2.0) * total_a, rtol=1e-12)
    # vibration alone, statistically: sigma per sample = value * intensity on the mean rate
    gv, av = run(ImuErrorModel({"vibration_gyro_rps": 0.01,
                                "vibration_accel_mps2": 0.2}, 8), 10000, dt, intensity=1.5)
    assert (gv / dt).std() == pytest.approx(0.015, rel=0.02)
    assert (av / dt).std() == pytest.approx(0.3, rel=0.02)


FULL = {"gyro_bias_dph": 5, "gyro_arw_dpsh": 0.06, "gyro_bias_instability_dph": 1,
        "gyro_bias_tau_s": 100, "gyro_scale_factor_ppm": 100, "gyro_misalignment_urad": 50,
        "g_sensitivity_dphpg": 1, "accel_bias_ug": 100, "accel_vrw_ugpsHz": 10,
        "accel_bias_instability_ug": 50, "accel_bias_tau_s": 100,
        "accel_scale_factor_ppm": 100, "accel_misalignment_urad": 50,
        "noise_level_windows": "0.5,1,2", "noise_intensity_gain": 1.0,
        "vibration_gyro_rps": 0.01, "vibration_accel_mps2": 0.1}


def test_same_seed_identical_and_deepcopy_continues_bit_for_bit():
    dth, dv = np.array([1e-3, -2e-3, 5e-4]), np.array([0.01, 0.0, -0.098])
    g1, a1 = run(ImuErrorModel(FULL, 42), 200, 0.01, dtheta=dth, dvel=dv, intensity=0.7)
    g2, a2 = run(ImuErrorModel(FULL, 42), 200, 0.01, dtheta=dth, dvel=dv, intensity=0.7)
    np.testing.assert_array_equal(g1, g2)
    np.testing.assert_array_equal(a1, a2)
    g3, _ = run(ImuErrorModel(FULL, 43), 200, 0.01, dtheta=dth, dvel=dv, intensity=0.7)
    assert not np.array_equal(g1, g3)
    # FMU state save/restore: a deep copy taken mid-run continues identically
    model = ImuErrorModel(FULL, 42)
    run(model, 100, 0.01, dtheta=dth, dvel=dv, intensity=0.7)
    saved = copy.deepcopy(model)
    ga, aa = run(model, 100, 0.01, t0=1.0, dtheta=dth, dvel=dv, intensity=0.7)
    gb, ab = run(saved, 100, 0.01, t0=1.0, dtheta=dth, dvel=dv, intensity=0.7)
    np.testing.assert_array_equal(ga, gb)
    np.testing.assert_array_equal(aa, ab)
    np.testing.assert_array_equal(ga, g1[100:])



def test_serialized_state_in_a_fresh_model_continues_bit_for_bit_across_dt_changes():
    """The per-dt coefficients are state with the dt they belong to: a fresh model given the
    serialized state of one that ran at dt = 0.02 continues like the uninterrupted one, at
    that dt and after changing to 0.01 (uninterrupted run vs restored copy)."""
    from navcore.core import state, state_format

    dth, dv = np.array([1e-3, -2e-3, 5e-4]), np.array([0.01, 0.0, -0.098])
    model = ImuErrorModel(FULL, 42)
    run(model, 50, 0.02, dtheta=dth, dvel=dv, intensity=0.7)
    blob = state_format.encode(state.capture(model), ("ImuErrorModel", "test"))
    restored = ImuErrorModel(FULL, 42)
    state.restore(restored, state_format.decode(blob, ("ImuErrorModel", "test")))
    continued = [np.hstack(run(m, 20, 0.02, t0=1.0, dtheta=dth, dvel=dv, intensity=0.7)
                           + run(m, 20, 0.01, t0=1.4, dtheta=dth, dvel=dv, intensity=0.7))
                 for m in (model, restored)]
    np.testing.assert_array_equal(continued[0], continued[1])

@pytest.mark.parametrize("name,value", [
    ("gyro_bias_dph", -1.0), ("gyro_arw_dpsh", float("nan")), ("accel_vrw_ugpsHz", math.inf),
    ("accel_bias_ug", -0.1), ("gyro_bias_instability_dph", -2.0), ("gyro_bias_tau_s", math.inf),
    ("accel_bias_tau_s", float("nan")), ("gyro_scale_factor_ppm", -5.0),
    ("accel_misalignment_urad", -1.0), ("g_sensitivity_dphpg", -1.0),
    ("noise_intensity_gain", -0.5), ("vibration_accel_mps2", -1.0),
    ("vibration_gyro_rps", "abc"),
])
def test_bad_parameter_raises_naming_it(name, value):
    with pytest.raises(ParameterError, match=name):
        ImuErrorModel({name: value}, seed=0)


def test_unknown_parameter_rejected():
    with pytest.raises(ParameterError, match="gyro_bias_dps"):
        ImuErrorModel({"gyro_bias_dps": 1.0}, seed=0)


@pytest.mark.parametrize("text,fragment", [
    ("1,2", "1,2"), ("1,2,x", "factor"), ("2,1,3", "t1 must be after t0"),
    ("1,2,-1", "factor"), ("0,1,2; 3,nan,1", "3,nan,1"),
])
def test_bad_windows_raise_naming_parameter_and_record(text, fragment):
    with pytest.raises(ParameterError, match="noise_level_windows") as err:
        ImuErrorModel({"noise_level_windows": text}, seed=0)
    assert fragment in str(err.value)


def test_parse_windows():
    assert parse_windows("", "w") == []
    assert parse_windows(" 1, 2 ,3 ; 5,6.5,0.5; ", "w") == [(1.0, 2.0, 3.0), (5.0, 6.5, 0.5)]
    assert parse_windows([(1, 2, 3)], "w") == [(1.0, 2.0, 3.0)]
    with pytest.raises(ParameterError, match="'my_windows'"):
        parse_windows("1,2,3,4", "my_windows")


@pytest.mark.parametrize("kwargs", [
    {"dtheta": [np.nan, 0, 0]}, {"dvel": [0, np.inf, 0]}, {"dt": 0.0}, {"dt": -0.01},
    {"t_end": np.nan}, {"intensity": -1.0}, {"intensity": np.nan}, {"dvel": [0, 0]},
])
def test_bad_inputs_raise_input_error(kwargs):
    args = {"t_end": 1.0, "dt": 0.01, "dtheta": ZERO3, "dvel": ZERO3, "intensity": 0.0}
    args.update(kwargs)
    with pytest.raises(InputError):
        ImuErrorModel(FULL, 0).apply(**args)
