"""init_mode of the INS/GNSS filters (navcore.filters.initial_state): the coarse alignment
against the physics of gravity and Earth rate, a static alignment through Kf with a known gyro
bias against the textbook heading error bias / (Earth rate cos(lat)), a start from the first
fix on the gnss-ins-sim log (an independent simulator) with a wrong given state, and the
warning when a given state disagrees with the first fix."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.components import registry as components
from navcore.components.replay import ImuGnssReplay
from navcore.filters.initial_state import INIT_CHECK_SIGMAS, coarse_alignment, level
from navcore.ins import earth
from navcore.ins.constants import DPH
from navcore.ins.rotations import euler_to_dcm, wrap_angle
from orchestrator.building import build as fmu_build
from orchestrator.results import metrics
from orchestrator.running import scenarios

GIS_MODEL = fmu_build.ROOT / "models" / "replay_gnss_ins_sim"
GPS_SIGMA = {"n": 5.0, "e": 5.0, "d": 7.0}  # the gnss-ins-sim data's README


def _at_rest(lat, roll, pitch, yaw, h=0.0):
    """Specific force and angular rate (body) of a vehicle at rest on the rotating Earth."""
    c_nb = euler_to_dcm(roll, pitch, yaw).T
    return (c_nb @ -earth.gravity_ned(lat, h), c_nb @ earth.earth_rate_ned(lat))


@pytest.mark.parametrize("lat,roll,pitch,yaw", [(0.7, 0.03, -0.02, 2.4), (-0.5, -0.4, 0.3, -1.0),
                                                (1.2, 0.0, 0.0, 0.1)])
def test_coarse_alignment_recovers_the_attitude_from_gravity_and_earth_rate(lat, roll, pitch,
                                                                             yaw):
    f, w = _at_rest(lat, roll, pitch, yaw)
    got = coarse_alignment(f, w)
    assert got == pytest.approx((roll, pitch, yaw), abs=1e-12)
    assert level(f) == pytest.approx((roll, pitch), abs=1e-12)


def _drive(component, inputs_at, t0, t1, dt):
    """Step ``component`` over [t0, t1] at ``dt`` with ``inputs_at(t, h)``; its outputs."""
    out = component.initialize(t0)
    n = int(round((t1 - t0) / dt))
    for k in range(n):
        t = t0 + k * dt
        out = component.step(t, dt, inputs_at(t, dt))
    return out


def test_static_alignment_through_kf_has_the_textbook_heading_error():
    """A navigation-grade IMU at rest at 40 deg N, gyro bias 0.01 deg/h on body y: after
    the 60 s alignment Kf's roll and pitch are exact to 1e-6 rad and its yaw error is the
    gyrocompassing error of a level east gyro bias, b / (Omega cos(lat)) = 0.0497 deg."""
    lat, lon, h, roll, pitch, yaw = math.radians(40.0), 0.2, 50.0, 0.0, 0.0, 0.0
    f, w = _at_rest(lat, roll, pitch, yaw, h)
    bias = np.array([0.0, 0.01 * DPH, 0.0])
    fix = {"gnss_lat": lat, "gnss_lon": lon, "gnss_h": h, "gnss_vn": 0.0, "gnss_ve": 0.0,
           "gnss_vd": 0.0}

    def inputs(t, dt):
        end = t + dt
        x = {"imu_time": end, "imu_dt": dt, "gnss_epoch": int(end + 1e-9),
             "gnss_time": float(int(end + 1e-9)), "gnss_valid": end >= 1.0 - 1e-9, **fix}
        for i, a in enumerate("xyz"):
            x[f"imu_dtheta_{a}"] = (w[i] + bias[i]) * dt
            x[f"imu_dvel_{a}"] = f[i] * dt
            x[f"imu_gyro_{a}"], x[f"imu_accel_{a}"] = w[i] + bias[i], f[i]
        return x

    kf = components.Kf(init_mode="align", align_time=60.0, measurement="position",
                       p0_att_yaw=math.radians(5.0))
    before = _drive(kf, inputs, 0.0, 59.9, 0.1)
    assert not before["aligned"]
    out = _drive(components.Kf(init_mode="align", align_time=60.0, measurement="position"),
                 inputs, 0.0, 60.0, 0.1)
    assert out["aligned"]
    assert out["nav_lat"] == lat and out["nav_lon"] == lon
    expected = bias[1] / (earth.OMEGA_IE * math.cos(lat))
    assert math.degrees(expected) == pytest.approx(0.0497, abs=1e-4)
    assert abs(out["nav_roll"] - roll) < 1e-6 and abs(out["nav_pitch"] - pitch) < 1e-6
    assert abs(wrap_angle(out["nav_yaw"] - yaw)) == pytest.approx(abs(expected), rel=0.01)


def _gis_run(**filter_parameters):
    model = scenarios.load_scenario(GIS_MODEL)
    params = {f"filter.{k}": v for k, v in filter_parameters.items()}
    return scenarios.simulate_scenario(model, backend="direct", parameters=params,
                                       window=(30.0, 80.05), log=None)


@pytest.fixture(scope="module")
def given_run():
    return _gis_run()


def test_start_from_the_first_fix_needs_no_initial_state(given_run):
    """The gnss-ins-sim log (10 s at rest, then moving) with init_mode 'gnss' and a given
    state 2000 km and 170 deg off: the filter levels on the first 10 s, starts at the first
    fix once moving faster than 2 m/s (position, velocity, course as yaw) and then meets
    the targets of the correct given state: position RMS over 30-80 s below the GPS
    noise on every axis and within 1.5x (+0.3 m) of the given-state run's."""
    run = _gis_run(init_mode="gnss", init_lat=0.3, init_lon=1.8, init_yaw=-3.0)
    r = run.results
    aligned = r.column("filter", "aligned") > 0.5
    t_start = r.time[aligned][0]
    speed = np.hypot(r.column("replay", "truth_vn"), r.column("replay", "truth_ve"))
    assert 10.0 <= t_start < 20.0 and speed[aligned][0] >= 1.5
    assert not aligned[r.time < t_start].any() and aligned[r.time >= t_start].all()
    m, ref = run.metrics["filter"], given_run.metrics["filter"]
    for a, sigma in GPS_SIGMA.items():
        assert m["position_rms_m"][a] < sigma
        assert m["position_rms_m"][a] < 1.5 * ref["position_rms_m"][a] + 0.3
    assert m["attitude_rms_deg"]["yaw"] < 1.0


def _first_fix_notices(**parameters):
    """Kf fed by the gnss-ins-sim log's replay up to just after its first valid fix (10 s)."""
    replay = ImuGnssReplay(log=str(GIS_MODEL / "log"))
    replay.initialize(0.0)
    kf = components.Kf(**parameters)
    _drive(kf, lambda t, dt: replay.step(t, dt, {}), 0.0, 10.5, 0.01)
    return kf.take_notices()


def test_given_state_far_from_the_first_fix_is_warned_of():
    """Given state 300 m north of the truth (an inconsistent state, not another trajectory):
    one notice naming the axis, the distance in sigmas and init_mode; 1 deg (111 km) off:
    only the first-fix distance warning (another trajectory); the scenario's own state: none."""
    lat, lon = 0.5585053606381855, 2.0943951023931953   # the scenario's filter.ssv
    rn = earth.radii(lat)[0]
    notices = _first_fix_notices(init_lat=lat + 300.0 / rn, init_lon=lon,
                                 measurement="position")
    assert len(notices) == 1, notices
    text = notices[0]
    assert "given initial state is 304.9 m off the first fix" in text, text   # + GPS error
    assert " along N" in text and f"(more than {INIT_CHECK_SIGMAS:g})" in text
    assert "init_mode = 'gnss'" in text
    far = _first_fix_notices(init_lat=lat + math.radians(1.0), init_lon=lon,
                             measurement="position")
    assert len(far) == 1 and "km from the filter's position" in far[0], far
    assert _first_fix_notices(init_lat=lat, init_lon=lon, measurement="position") == []


def test_unknown_init_mode_is_a_parameter_error():
    from navcore.errors import ParameterError

    with pytest.raises(ParameterError, match=r"parameter 'init_mode' = 'fix' is not one of"):
        components.Kf(init_mode="fix").initialize(0.0)


INS_GNSS_FILTERS = ["Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf",
                    "CtfaUkf", "ImmUkf", "InsOnly"]


@pytest.mark.parametrize("name", INS_GNSS_FILTERS)
def test_every_filter_starts_from_the_first_fix(name):
    """init_mode 'gnss' in every INS/GNSS filter (the shell's, whatever the engine): on the
    gnss-ins-sim log with a given state 2000 km off, each starts at 12 s (the first fix
    above 2 m/s) at that fix (within 3 GPS sigmas); the GNSS-aided ones then stay within 1.5
    GPS sigmas to 40 s (InsOnly, free inertial after its start on a MEMS IMU, drifts)."""
    model = scenarios.load_scenario(GIS_MODEL)
    params = {"filter.init_mode": "gnss", "filter.init_lat": 0.3, "filter.init_lon": 1.8}
    run = scenarios.simulate_scenario(model, filter=name, backend="direct", parameters=params,
                                      stop_time=40.0, log=None)
    r = run.results
    aligned = r.column("filter", "aligned") > 0.5
    assert r.time[aligned][0] == pytest.approx(12.0)
    e = metrics.navigation_errors(r, "filter")
    first = int(np.flatnonzero(aligned)[0])
    for a, sigma in GPS_SIGMA.items():
        assert abs(e[f"pos_{a}"][first]) < 3.0 * sigma, (a, e[f"pos_{a}"][first])
    if name != "InsOnly":
        m = run.metrics["filter"]
        assert max(m["position_max_m"].values()) < 1.5 * max(GPS_SIGMA.values())
