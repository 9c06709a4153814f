"""Strapdown mechanization: closure against analytic and generated truth, the physics of the
inverse increments, closed-loop correction, state capture."""
import copy
import math
import pickle

import numpy as np
import pytest

from navcore.ins import earth
from navcore.ins.rotations import euler_to_dcm, rotvec_to_dcm, wrap_angle
from navcore.ins.strapdown import Strapdown, _gravity, _radii, integrate_position
from navcore.ins.trajectory import TrajectoryGenerator

LAT0 = math.radians(40.1)
LON0 = math.radians(118.6)
H0 = 100.0
DT = 0.01


def ned_position_error(sd, lat, lon, h):
    """computed - true position in NED metres."""
    rn, re = earth.radii(lat)
    return np.array(
        [(sd.lat - lat) * (rn + h), (sd.lon - lon) * (re + h) * math.cos(lat), h - sd.h]
    )


def test_scalar_earth_helpers_match_earth_module():
    for lat in np.radians([-89.0, -45.0, 0.0, 12.3, 40.1, 80.0]):
        for h in (-400.0, 0.0, 100.0, 12000.0):
            assert _gravity(lat, h) == pytest.approx(float(earth.gravity(lat, h)), rel=1e-15)
        rn, re = earth.radii(lat)
        assert _radii(lat) == pytest.approx((float(rn), float(re)), rel=1e-15)


def test_integrate_position_constant_velocity():
    v = [100.0, 50.0, -10.0]
    lat, lon, h = integrate_position(LAT0, LON0, H0, v, v, 1.0)
    rn, re = earth.radii(LAT0)
    assert (lat - LAT0) * (rn + H0 + 5.0) == pytest.approx(100.0, rel=1e-5)
    assert (lon - LON0) * (re + H0 + 5.0) * math.cos(LAT0) == pytest.approx(50.0, rel=1e-4)
    assert h == pytest.approx(H0 + 10.0, abs=1e-12)


def stationary_run(minutes, euler_deg=(2.0, -3.0, 135.0)):
    """Analytic ideal increments at rest (independent of inverse_update):
    dtheta = C_nb omega_ie^n dt, dvel = -C_nb g^n dt."""
    C = euler_to_dcm(*np.radians(euler_deg))
    dtheta = C.T @ earth.earth_rate_ned(LAT0) * DT
    dvel = -C.T @ earth.gravity_ned(LAT0, H0) * DT
    sd = Strapdown(LAT0, LON0, H0, np.zeros(3), C)
    for _ in range(int(round(minutes * 60 / DT))):
        sd.update(dtheta, dvel, DT)
    dr = ned_position_error(sd, LAT0, LON0, H0)
    phi = np.array([wrap_angle(a - b) for a, b in zip(sd.euler(), np.radians(euler_deg))])
    return dr, sd.v_ned, phi


def check_stationary(dr, v, phi):
    assert math.hypot(dr[0], dr[1]) < 1e-3
    assert abs(dr[2]) < 1e-2
    assert np.abs(v).max() < 1e-5
    assert np.abs(phi).max() < 1e-9


def test_stationary_closure_10_min():
    dr, v, phi = stationary_run(10)
    check_stationary(dr, v, phi)
    # measured: horizontal 0, vertical ~3e-7 m, velocity ~1e-9 m/s, attitude ~1e-13 rad
    assert abs(dr[2]) < 1e-5


@pytest.mark.slow
def test_stationary_closure_1_h():
    dr, v, phi = stationary_run(60)
    check_stationary(dr, v, phi)


def closure_run(profile, duration, dt=DT):
    """Increments from the trajectory generator integrated by a fresh Strapdown; returns the
    worst position errors (horizontal, vertical) and the final velocity/attitude errors."""
    gen = TrajectoryGenerator(profile, dt)
    s0 = gen.state()
    sd = Strapdown.from_euler(s0["lat"], s0["lon"], s0["h"], [s0["vn"], s0["ve"], s0["vd"]],
                              s0["roll"], s0["pitch"], s0["yaw"])
    worst_h = worst_v = 0.0
    for k in range(int(round(duration / dt))):
        s, dtheta, dvel = gen.step()
        sd.update(dtheta, dvel, dt)
        if k % 100 == 0:
            dr = ned_position_error(sd, s["lat"], s["lon"], s["h"])
            worst_h = max(worst_h, math.hypot(dr[0], dr[1]))
            worst_v = max(worst_v, abs(dr[2]))
    dv = sd.v_ned - [s["vn"], s["ve"], s["vd"]]
    datt = [wrap_angle(a - b) for a, b in zip(sd.euler(), (s["roll"], s["pitch"], s["yaw"]))]
    return worst_h, worst_v, np.abs(dv).max(), np.abs(datt).max()


def test_manoeuvring_closure_aircraft_500s():
    h_err, v_err, dv, datt = closure_run("aircraft_500s", 500.0)
    assert h_err < 0.1 and v_err < 3.0
    # measured: ~2e-8 m, ~3e-9 m, ~1e-10 m/s, ~2e-14 rad: the inverse is exact to rounding
    assert h_err < 1e-5 and v_err < 1e-5 and dv < 1e-7 and datt < 1e-10


def test_manoeuvring_closure_uav_strong_phase():
    h_err, v_err, dv, datt = closure_run("uav_maneuver", 180.0)
    assert h_err < 0.1 and v_err < 3.0
    assert h_err < 1e-5 and v_err < 1e-5 and dv < 1e-7 and datt < 1e-10


@pytest.mark.slow
@pytest.mark.parametrize("profile", ["manoeuvre_1h", "uav_maneuver"])
def test_manoeuvring_closure_1_h(profile):
    h_err, v_err, dv, datt = closure_run(profile, 3600.0)
    assert h_err < 0.1 and v_err < 3.0
    assert dv < 1e-4 and datt < 1e-8


def mid_dcm(C0, C1):
    """The rotation nearest (Frobenius norm) to the mean of two DCMs: the polar factor U V'
    of its SVD (both rotations are close, so det > 0)."""
    u, _, vt = np.linalg.svd(0.5 * (C0 + C1))
    return u @ vt


def test_inverse_increments_coordinated_turn_physics():
    """In the steady part of the aircraft_500s turn (180 deg in 60 s, 4 s ramps) the gyro
    rate rotated to NED is psi_dot about down plus earth and transport rate, and the
    accelerometer measures dv/dt + (2 w_ie + w_en) x v - g."""
    gen = TrajectoryGenerator("aircraft_500s", DT)
    turn_rate = math.radians(180.0) / 56.0
    while gen.time < 446.0 - 1e-9:
        gen.step()
    rate_err, force_err = [], []
    prev = gen.state()
    C0 = euler_to_dcm(prev["roll"], prev["pitch"], prev["yaw"])
    while gen.time < 494.0 - 1e-9:
        s, dtheta, dvel = gen.step()
        C1 = euler_to_dcm(s["roll"], s["pitch"], s["yaw"])
        Cm = mid_dcm(C0, C1)
        lat, h = 0.5 * (prev["lat"] + s["lat"]), 0.5 * (prev["h"] + s["h"])
        v0 = np.array([prev["vn"], prev["ve"], prev["vd"]])
        v1 = np.array([s["vn"], s["ve"], s["vd"]])
        vm = 0.5 * (v0 + v1)
        w_ie, w_en = earth.earth_rate_ned(lat), earth.transport_rate_ned(lat, h, vm)
        expected_rate = np.array([0.0, 0.0, turn_rate]) + w_ie + w_en
        rate_err.append(Cm @ dtheta / DT - expected_rate)
        f_n = (v1 - v0) / DT + np.cross(2 * w_ie + w_en, vm) - earth.gravity_ned(lat, h)
        force_err.append(Cm @ dvel / DT - f_n)
        prev, C0 = s, C1
    rate_err, force_err = np.array(rate_err), np.array(force_err)
    assert np.abs(rate_err.mean(axis=0)).max() < 1e-8  # rad/s (turn rate is 0.056 rad/s)
    assert np.abs(rate_err).max() < 1e-7
    assert np.abs(force_err.mean(axis=0)).max() < 1e-5  # m/s^2 (centripetal ~11 m/s^2)
    assert np.abs(force_err).max() < 1e-4


def test_inverse_increments_static_attitude():
    """At rest on a turntable attitude the accelerometer reads -g in body axes and the gyro
    reads the earth rate."""
    profile = {"start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 100.0},
               "segments": [{"type": "hold_attitude", "duration": 10.0, "roll_deg": 10.0,
                             "pitch_deg": -5.0, "yaw_deg": 30.0, "transition": 4.0}]}
    gen = TrajectoryGenerator(profile, DT)
    while gen.time < 5.0:
        gen.step()
    C = euler_to_dcm(*np.radians([10.0, -5.0, 30.0]))
    f_expected = -C.T @ earth.gravity_ned(LAT0, H0)
    w_expected = C.T @ earth.earth_rate_ned(LAT0)
    for _ in range(300):
        s, dtheta, dvel = gen.step()
        np.testing.assert_allclose(dvel / DT, f_expected, rtol=0, atol=1e-9)
        np.testing.assert_allclose(dtheta / DT, w_expected, rtol=0, atol=1e-12)
    assert gen.last_accel_norm == 0.0


def test_correct_restores_true_state():
    C_true = euler_to_dcm(0.05, -0.1, 2.5)
    v_true = np.array([120.0, -40.0, 3.0])
    lat, lon, h = LAT0, LON0, 1500.0
    dr = np.array([12.0, -7.5, 4.0])        # computed - true, NED [m]
    dv = np.array([0.3, -0.2, 0.1])
    phi = np.array([2e-3, -1e-3, 5e-3])     # C_computed = (I - [phi x]) C_true
    rn, re = earth.radii(lat)
    sd = Strapdown(lat + dr[0] / (rn + h), lon + dr[1] / ((re + h) * math.cos(lat)), h - dr[2],
                   v_true + dv, rotvec_to_dcm(-phi) @ C_true)
    sd.correct(dr, dv, phi)
    assert np.abs(ned_position_error(sd, lat, lon, h)).max() < 1e-4
    np.testing.assert_allclose(sd.v_ned, v_true, atol=1e-12)
    np.testing.assert_allclose(sd.C_bn, C_true, atol=1e-15)
    with pytest.raises(ValueError):
        sd.correct([np.nan, 0, 0], [0, 0, 0], [0, 0, 0])


def test_correct_shifts_velocity_memory():
    """A velocity error present at both stored epochs is removed from both by correct(), so
    the next update continues exactly as from the error-free state (the correction does not
    look like an acceleration to the mid-interval extrapolation)."""
    C = euler_to_dcm(0.0, 0.0, 1.0)
    a = Strapdown(LAT0, LON0, H0, [50.0, 10.0, 0.0], C)
    b = Strapdown(LAT0, LON0, H0, [50.0, 10.0, 0.0], C)
    inc = (np.array([1e-4, -2e-4, 3e-4]), np.array([0.01, 0.02, -0.098]))
    a.update(*inc, DT)
    b.update(*inc, DT)
    err = np.array([1.0, -0.5, 0.25])
    b.v_ned = b.v_ned + err
    b._v_prev = tuple(np.array(b._v_prev) + err)
    b.correct([0.0, 0.0, 0.0], err, [0.0, 0.0, 0.0])
    a.update(*inc, DT)
    b.update(*inc, DT)
    np.testing.assert_allclose(b.v_ned, a.v_ned, rtol=0, atol=1e-13)
    np.testing.assert_allclose(b.C_bn, a.C_bn, rtol=0, atol=1e-15)


def test_inverse_update_rejects_inconsistent_position():
    sd = Strapdown(LAT0, LON0, H0, [10.0, 0.0, 0.0], np.eye(3))
    with pytest.raises(ValueError, match="integrate_position"):
        sd.inverse_update(LAT0, LON0, H0, [10.0, 0.0, 0.0], np.eye(3), DT)


def test_state_is_captured_by_deepcopy_and_pickle():
    gen = TrajectoryGenerator("aircraft_500s", DT)
    s0 = gen.state()
    sd = Strapdown.from_euler(s0["lat"], s0["lon"], s0["h"], [0, 0, 0], 0, 0, s0["yaw"])
    incs = [gen.step()[1:] for _ in range(600)]
    for dtheta, dvel in incs[:300]:
        sd.update(dtheta, dvel, DT)
    saved = copy.deepcopy(sd.__dict__)
    pickled = pickle.dumps(sd)
    for dtheta, dvel in incs[300:]:
        sd.update(dtheta, dvel, DT)
    for restored in (Strapdown.__new__(Strapdown), pickle.loads(pickled)):
        if not restored.__dict__:
            restored.__dict__.update(copy.deepcopy(saved))
        for dtheta, dvel in incs[300:]:
            restored.update(dtheta, dvel, DT)
        assert (restored.lat, restored.lon, restored.h) == (sd.lat, sd.lon, sd.h)
        np.testing.assert_array_equal(restored.v_ned, sd.v_ned)
        np.testing.assert_array_equal(restored.C_bn, sd.C_bn)
