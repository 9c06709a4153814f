"""The land aids (navcore.filters.land_aids): the NHC's linearization, the stationarity
detector against known stops, each aid's effect in a GNSS outage against the Kf without
aids (a simulated car with stops and a walk), the adaptive laws left alone, and a run on
the real drive's first seconds at rest (tests/data/rtklib_drive)."""
from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import butter, filtfilt

from direct_replay import FILTER_INPUT_NAMES, TRUTH_NAMES, run_filter
from land_vehicles import (CAR, CAR_OUTAGES, DETECTOR, FILTER_START, WALK, WALK_OUTAGES,
                           outage_errors, vehicle_sensors)
from navcore.core.state import capture
from navcore.filters.ins_gnss_kf import KfConfig, KfEngine
from navcore.filters.land_aids import (LAND_AID_PARAMETERS, LandAids, StationaryDetector,
                                       nhc_constraint, nhc_jacobian)
from navcore.ins import earth
from navcore.ins.error_model import N_STATES
from navcore.ins.rotations import euler_to_dcm
from navcore.ins.strapdown import Strapdown
from orchestrator.running.scenarios import registry

FAMILIES = ("Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf",
            "CtfaUkf", "ImmUkf")
ALL_AIDS = {"zupt": True, "zaru": True, "nhc": True}
DRIVE_IMU = Path(__file__).parent / "data" / "rtklib_drive" / "imu_1934_trimmed.csv"


def _aid_parameters(**values):
    return {**{q.name: q.default() for q in LAND_AID_PARAMETERS}, **values}


def _run(sensors, name="Kf", **aids):
    return run_filter(sensors, registry()[name], overrides={**FILTER_START, **DETECTOR, **aids})


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    return vehicle_sensors(CAR, CAR_OUTAGES, tmp_path_factory.mktemp("car"))


@pytest.fixture(scope="module")
def car_kf(car):
    """The Kf without aids: the reference of every outage comparison."""
    return outage_errors(_run(car[0]), CAR_OUTAGES)


# -- the NHC's measurement row ---------------------------------------------------------
def test_nhc_jacobian_is_the_derivative_of_the_constraint():
    """H of the NHC against central differences of the nonlinear constraint, with the INS
    errors made as the filters' feedback removes them (Strapdown.correct: position,
    velocity, attitude; a gyro bias error adds to the compensated rate): checks the
    linearization and its sign convention, column by column."""
    truth = Strapdown.from_euler(0.7, 0.2, 300.0, np.array([8.0, -5.0, 0.7]), 0.05, -0.08,
                                 2.3)
    C_vb = euler_to_dcm(0.03, -0.04, 0.06).T
    lever = np.array([-1.2, 0.3, 0.9])
    rate = np.array([0.02, -0.05, 0.3])

    def h(x):
        ins = copy.deepcopy(truth)
        ins.correct(-x[0:3], -x[3:6], -x[6:9])     # INS = truth + error x
        return nhc_constraint(ins.C_bn, ins.v_ned, rate + x[9:12], C_vb, lever)[0]

    H = nhc_jacobian(truth.C_bn, truth.v_ned, C_vb, lever)
    numeric = np.zeros((2, N_STATES))
    for i in range(N_STATES):
        e = np.zeros(N_STATES)
        e[i] = 1e-6
        numeric[:, i] = (h(e) - h(-e)) / 2e-6
    assert np.allclose(H, numeric, rtol=1e-6, atol=1e-7)
    assert np.abs(H[:, 6:9]).max() > 1.0 and np.abs(H[:, 9:12]).max() > 0.1  # not vacuous


# -- the detector against the car's known stops ----------------------------------------
def test_detector_finds_the_car_stops_and_nothing_while_it_drives(car):
    """Over the car's IMU samples: every decision (each 0.1 s) inside a stop, once a full
    window lies in it, says stationary; none while the car moves (true speed > 0.1 m/s)."""
    sensors, rests, _ = car
    col = {n: FILTER_INPUT_NAMES.index(n) for n in FILTER_INPUT_NAMES}
    x = sensors.filter_inputs
    new = np.r_[True, np.diff(x[:, col["imu_time"]]) != 0]
    imu = x[new]
    window = 0.5
    detector = StationaryDetector(window, DETECTOR["stationary_accel_std"],
                                  DETECTOR["stationary_rate_rms"])
    times, verdicts = [], []
    for k, row in enumerate(imu):
        dt = row[col["imu_dt"]]
        detector.add(np.array([row[col[f"imu_dvel_{a}"]] for a in "xyz"]) / dt,
                     np.array([row[col[f"imu_dtheta_{a}"]] for a in "xyz"]) / dt, dt)
        if k % 5 == 0:
            times.append(row[col["imu_time"]])
            verdicts.append(detector.stationary())
    times, verdicts = np.array(times), np.array(verdicts)
    vn, ve = (sensors.truth[:, TRUTH_NAMES.index(f"truth_v{a}")] for a in "ne")
    speed = np.interp(times, sensors.time, np.hypot(vn, ve))
    inside = np.zeros(len(times), bool)
    for a, b in rests:
        inside |= (times >= a + window + 0.05) & (times <= b)
    moving = speed > 0.1
    assert inside.sum() > 500 and moving.sum() > 1500
    assert verdicts[inside].mean() >= 0.99
    assert not verdicts[moving].any()


# -- each aid in an outage, against the Kf without aids --------------------------------
def test_zupt_and_zaru_hold_the_car_during_its_stop(car, car_kf):
    """The outage over the first stop (4 s of braking, 26 s at rest): ZUPT and ZARU keep the
    horizontal error at a tenth of the Kf's."""
    aided = outage_errors(_run(car[0], zupt=True, zaru=True), CAR_OUTAGES)[0]
    assert aided[0] < 0.1 * car_kf[0][0] and aided[2] < 0.1 * car_kf[0][2]


def test_nhc_halves_the_error_of_an_outage_while_driving(car, car_kf):
    """The outage while the car drives (a 60 deg turn and straight road): the NHC halves the
    Kf's RMS and largest error."""
    aided = outage_errors(_run(car[0], nhc=True), CAR_OUTAGES)[1]
    assert aided[0] < 0.5 * car_kf[1][0] and aided[2] < 0.5 * car_kf[1][2]


def test_zupt_on_a_walk_with_stops(tmp_path):
    """A 60 s outage over a walk with a 5 s stop every 12-16 s: ZUPT and ZARU at each stop
    keep the error below a fifth of the Kf's."""
    sensors, _, _ = vehicle_sensors(WALK, WALK_OUTAGES, tmp_path)
    base = outage_errors(_run(sensors), WALK_OUTAGES)[0]
    aided = outage_errors(_run(sensors, zupt=True, zaru=True), WALK_OUTAGES)[0]
    assert aided[0] < 0.2 * base[0] and aided[2] < 0.2 * base[2]


@pytest.mark.slow
@pytest.mark.parametrize("name", FAMILIES)
def test_every_filter_runs_with_the_aids(car, car_kf, name):
    """Every filter of both families with all three aids (about 10 s each, slow): below a
    fifth of the Kf's RMS without aids in the outage over the stop, below three quarters
    in the one while driving (CtfaUkf, whose Q scale the fixes before it raised, is the
    worst: 0.71)."""
    stop, driving = outage_errors(_run(car[0], name, **ALL_AIDS), CAR_OUTAGES)
    assert stop[0] < 0.2 * car_kf[0][0] and driving[0] < 0.75 * car_kf[1][0]


# -- the adaptive laws adapt on the fixes only -----------------------------------------
@pytest.mark.parametrize("name", FAMILIES)
def test_an_aid_update_leaves_the_adaptive_laws_alone(car, name):
    """After 10 s of the car at rest, one ZUPT through ``aid_update``: the filter's state moves
    (navigation, covariance, biases) and nothing of its law does (Sage-Husa R and index,
    fading, robust test statistics, CTFA Q scale, IMM model probabilities, guards); only
    NewtonRobustKf's stored observations follow the feedback, as after a fix: each shifted
    by the correction H dx (position and velocity), none added."""
    sensors = car[0]
    run = run_filter(sensors, registry()[name], overrides={**FILTER_START, **DETECTOR},
                     stop_row=int(round(10.0 / sensors.h)))
    engine = run.component.engine
    if hasattr(engine, "_predict"):
        engine._predict()                       # the prediction due is not the aid's
    before = capture(engine)
    mu = np.array(engine.bank.mu) if name == "ImmUkf" else None
    H = np.zeros((3, N_STATES))
    H[:, 3:6] = np.eye(3)
    engine.aid_update(H, np.array([0.05, -0.03, 0.01]), np.eye(3) * 1e-4)
    after = capture(engine)
    # blind_P: the covariance without the aids since the last fix (navcore.filters.aid_blind)
    moved = {"nav", "P", "gyro_bias", "accel_bias", "phi_acc", "q_acc", "n_updates", "ukf",
             "bank", "history", "blind_P"}
    stored = list(engine.history._values) if name == "NewtonRobustKf" else None
    lat, lon, h, v = engine.nav.lat, engine.nav.lon, engine.nav.h, engine.nav.v_ned.copy()
    assert before["nav"] != after["nav"]
    for field in before:
        if field not in moved:
            assert repr(after[field]) == repr(before[field]), field
    if mu is not None:
        assert np.array_equal(engine.bank.mu, mu)
    if stored is not None:             # z = INS - GNSS of position, velocity: less dr, dv
        rn, re = earth.radii(lat)
        dr = np.array([(lat - engine.nav.lat) * (rn + h),
                       (lon - engine.nav.lon) * (re + h) * math.cos(lat), engine.nav.h - h,
                       *(v - engine.nav.v_ned)])
        shifted = list(engine.history._values)
        assert len(shifted) == len(stored) > 0
        for new_z, old_z in zip(shifted, stored):
            assert np.allclose(new_z, old_z - dr, atol=1e-6)


@pytest.mark.parametrize("name", ("NewtonRobustKf", "Igg3RobustKf"))
def test_an_aid_never_makes_a_robust_law_reject_a_fix(car, name):
    """After 10 s of the car at rest (millimetre fixes from then on), a pseudo-measurement of
    the position at 0.1 mm shrinks P; a fix whose position is 2 sigma off for the filter
    without it (per component: chi2 = 4 < 6.635, an IGG-III u = 2 in the down-weighted band,
    not the rejected one) is more than 10 sigma off for the aided covariance, which would
    reject it, and is kept with the aid-blind test, which sees the covariance of the fixes
    alone; the update itself uses the aided P (the two runs differ), and after the fix the
    test's covariance is the filter's own again."""
    sensors = car[0]
    run = run_filter(sensors, registry()[name], overrides={**FILTER_START, **DETECTOR},
                     stop_row=int(round(10.0 / sensors.h)))
    plain = run.component.engine
    plain.R0 = np.eye(plain.m) * 1e-6              # millimetre fixes: P dominates S
    aided = copy.deepcopy(plain)
    H = np.zeros((3, N_STATES))
    H[:, 0:3] = np.eye(3)
    aided.aid_update(H, np.zeros(3), np.eye(3) * 1e-8)
    _, S = plain.predicted_innovation()
    z = np.zeros(plain.m)
    z[:3] = 2.0 * np.sqrt(np.diag(S)[:3])          # position 2 sigma off, velocity exact
    _, S_aided = aided.predicted_innovation()
    assert np.all(z[:3] / np.sqrt(np.diag(S_aided)[:3]) > 10.0)  # the aided P would reject
    assert aided.blind_P is not None
    for engine in (plain, aided):
        engine.update(z)
        assert int(engine.n_rejected) == 0, name
    assert aided.blind_P is None
    assert not np.allclose(aided.P, plain.P)


@pytest.mark.parametrize("name", ("CtfaUkf", "ImmUkf"))
def test_an_aid_never_makes_a_good_fix_drive_the_adaptation(car, name):
    """After 10 s of the car at rest (millimetre fixes from then on), a pseudo-measurement of
    the position at 0.1 mm shrinks P; a fix whose position is off by its own covariance's
    square root (CtfaUkf: NIS 3 for the filter without the aid, below the test's lower
    threshold; ImmUkf: twice that in each component) is far outside the aided covariance
    (NIS above 100), which would raise CTFA's Q to its maximum and give the IMM's Q x100
    model 0.007 more; against the covariance without the aids the adaptation is the one of
    the filter without the aid (the same chi-square and Q scale, the model probabilities to
    2e-3), while the update itself uses the aided P."""
    sensors = car[0]
    run = run_filter(sensors, registry()[name], overrides={**FILTER_START, **DETECTOR},
                     stop_row=int(round(10.0 / sensors.h)))
    plain = run.component.engine
    plain.R0 = np.eye(plain.m) * 1e-6              # millimetre fixes: P dominates S
    plain._predict()                               # the prediction due is not the aid's
    aided = copy.deepcopy(plain)
    H = np.zeros((3, N_STATES))
    H[:, 0:3] = np.eye(3)
    aided.aid_update(H, np.zeros(3), np.eye(3) * 1e-8)
    m = plain.m
    u = np.zeros(m)
    u[:3] = 1.0 if name == "CtfaUkf" else 2.0
    z = np.linalg.cholesky(plain.covariance()[:m, :m] + plain.R0) @ u   # NIS |u|^2
    S_aided = aided.covariance()[:m, :m] + aided.R0
    assert z @ np.linalg.solve(S_aided, z) > 100.0  # the aided P would call it a mismatch
    for engine in (plain, aided):
        engine.update(z)
    if name == "CtfaUkf":
        assert plain.chi2 == pytest.approx(3.0, rel=1e-6)
        assert aided.chi2 == pytest.approx(plain.chi2, rel=1e-3)
        assert aided.q_scale == plain.q_scale < aided.q_max_scale
    else:
        # against the aided P the Q x100 model gains 0.007 more (0.048 against 0.041)
        assert np.allclose(aided.bank.mu, plain.bank.mu, atol=2e-3)
    assert not np.allclose(aided.covariance(), plain.covariance())
    assert aided.blind_P is None


# -- the real drive's first seconds at rest --------------------------------------------
def test_zupt_and_zaru_on_the_real_car_at_rest():
    """The drive's first 12 s (the car at rest; its IMU prepared as the drive's own filter
    does: 10 Hz low pass, 5 Hz on the vertical, the sensor-to-body rotation): the detector
    says stationary at least 90 % of the time, ZARU brings the gyro bias within 0.01 deg/s of
    the mean body rate less the Earth rate, and ZUPT keeps the speed below 1 cm/s where the
    free INS reaches more than 10 cm/s."""
    raw = np.loadtxt(DRIVE_IMU, delimiter=",")
    t = (raw[:, 6] - raw[0, 6]) / 1000.0
    b, a = butter(4, 10.0, fs=100.0)
    bz, az = butter(4, 5.0, fs=100.0)
    acc = raw[:, :3] * 9.80665
    acc = np.column_stack([filtfilt(b, a, acc[:, 0]), filtfilt(b, a, acc[:, 1]),
                           filtfilt(bz, az, acc[:, 2])])
    gyr = filtfilt(b, a, np.radians(raw[:, 3:6]), axis=0)
    C = euler_to_dcm(*np.radians([180.0, -6.79, 185.35]))     # body = C' sensor
    acc, gyr = acc @ C, gyr @ C
    f = acc.mean(axis=0)
    roll, pitch = math.atan2(-f[1], -f[2]), math.atan2(f[0], math.hypot(f[1], f[2]))
    lat = math.radians(40.0966268)

    def engine(**aids):
        config = KfConfig(p0=np.r_[np.full(3, 0.01), np.full(3, 0.01), 0.01, 0.01, 1.0,
                                   np.full(3, math.radians(0.5)), np.full(3, 0.05)],
                          gyro_arw=math.radians(0.228) / 60.0, accel_vrw=140e-6 * 9.80665,
                          gyro_bias_sigma=0.0, gyro_bias_tau=0.0, accel_bias_sigma=0.0,
                          accel_bias_tau=0.0, r_sigma=np.full(3, 0.01), measurement="position")
        kf = KfEngine(config, Strapdown.from_euler(lat, -1.835, 1601.5, np.zeros(3), roll,
                                                   pitch, 0.0))
        kf.aids = LandAids(_aid_parameters(**aids)) if aids else None
        return kf

    aided, free = engine(zupt=True, zaru=True), engine()
    verdicts = []
    for k in range(1, len(t)):
        dt = t[k] - t[k - 1]
        dtheta, dvel = 0.5 * (gyr[k] + gyr[k - 1]) * dt, 0.5 * (acc[k] + acc[k - 1]) * dt
        for kf in (aided, free):
            kf.propagate(dtheta, dvel, dt)
        aided.aids.after_interval(aided, dtheta, dvel, dt, t[k])
        if aided.aids.elapsed == 0.0:
            verdicts.append(aided.aids.stationary(t[k]))
    assert np.mean(verdicts) >= 0.9
    nav = aided.nav
    rest_rate = gyr[len(t) // 2:].mean(axis=0) - nav.C_bn.T @ earth.earth_rate_ned(lat)
    assert np.abs(np.degrees(aided.gyro_bias - rest_rate)).max() < 0.01
    assert np.linalg.norm(aided.nav.v_ned) < 0.01 < 0.1 < np.linalg.norm(free.nav.v_ned)


@pytest.mark.parametrize("name", ("Kf", "ImmUkf"))
def test_a_saved_state_with_aids_continues_bit_identically(car, name):
    """The aids' detector window, accumulators and last fix are part of the filter's state:
    a component rebuilt from a state saved at rest in the first outage (ZUPT and ZARU
    applying, the NHC due when the car drives off) continues exactly like the original."""
    sensors = car[0]
    k = int(round(100.0 / sensors.h))
    overrides = {**FILTER_START, **DETECTOR, **ALL_AIDS}
    first = run_filter(sensors, registry()[name], overrides=overrides, stop_row=k).component
    assert first.engine.aids.n_zupt > 0
    copy_of = type(first).from_state(copy.deepcopy(first.get_state()))
    stop = k + int(round(30.0 / sensors.h))
    runs = [run_filter(sensors, component=c, start_row=k, stop_row=stop) for c in (first,
                                                                                   copy_of)]
    assert runs[0].component.engine.aids.n_nhc > 0
    for name_out, values in runs[0].outputs.items():
        assert np.array_equal(values, runs[1].outputs[name_out]), name_out
