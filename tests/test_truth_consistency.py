"""navcore.ins.truth_consistency against a trajectory it did not make: the closed-form
kinematic aircraft of tests/verify_fmus/KinematicAircraft.py (its own WGS-84, gravity and
rotation formulas, no navcore code), sampled at 0.02 s.  Its truth agrees with itself to
far below the verify tolerances, and each known defect shows as the size it has."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from navcore.ins import truth_consistency as tc

sys.path.insert(0, str(Path(__file__).resolve().parent / "verify_fmus"))
import KinematicAircraft as aircraft  # noqa: E402  (a plain script, not a package)

H = 0.02
SUBSTEPS = 10


@pytest.fixture(scope="module")
def track():
    """Samples of 20 s: time, position, velocity, attitude, body rates, specific force."""
    lat, lon, h = aircraft.LAT0, aircraft.LON0, aircraft.H0
    rows = []
    for k in range(1001):
        t = k * H
        vel, att, rate, force = aircraft.truth(t, lat, h)
        rows.append((t, lat, lon, h, *vel, *att, *rate, *force))
        dt = H / SUBSTEPS
        for j in range(SUBSTEPS):         # the aircraft's midpoint rule on a finer grid
            s = t + j * dt
            k1 = aircraft.position_rate(lat, h, aircraft.velocity(s))
            k2 = aircraft.position_rate(lat + 0.5 * dt * k1[0], h + 0.5 * dt * k1[2],
                                        aircraft.velocity(s + 0.5 * dt))
            lat, lon, h = lat + dt * k2[0], lon + dt * k2[1], h + dt * k2[2]
    a = np.array(rows)
    return {"t": a[:, 0], "lat": a[:, 1], "lon": a[:, 2], "h": a[:, 3], "v": a[:, 4:7],
            "att": (a[:, 7], a[:, 8], a[:, 9]), "rate": a[:, 10:13], "force": a[:, 13:16]}


def test_a_consistent_trajectory_is_consistent(track):
    s = track
    mis, allow = tc.velocity_mismatch(s["t"], s["lat"], s["lon"], s["h"], s["v"])
    assert np.max(mis) < 1e-4 and np.max(allow) > 1e-3   # the check's tolerance: 0.01 m/s
    mis, _ = tc.body_rate_mismatch(s["t"], s["lat"], s["h"], s["v"], *s["att"], s["rate"])
    assert np.max(mis) < 1e-6                              # tolerance 1e-4 rad/s
    mis, _ = tc.specific_force_mismatch(s["t"], s["lat"], s["h"], s["v"], *s["att"],
                                        s["force"])
    assert np.max(mis) < 1e-4                              # tolerance 0.05 m/s2
    drift = tc.integrated_attitude_error(s["t"], s["lat"], s["h"], s["v"], *s["att"],
                                         s["rate"])
    # the trapezoid's own error, ~ (d2w/dt2) dt^2 / 12 ~ 2e-7 rad/s here, over 20 s
    assert drift[0] == 0.0 and np.max(drift) < 1e-5


def test_a_velocity_ten_percent_high_is_ten_percent_of_the_speed_off(track):
    s = track
    mis, _ = tc.velocity_mismatch(s["t"], s["lat"], s["lon"], s["h"], 1.1 * s["v"])
    speed = np.linalg.norm(0.5 * (s["v"][1:] + s["v"][:-1]), axis=1)
    assert np.allclose(mis, 0.1 * speed, rtol=1e-4)


def test_rates_without_the_earth_rate_are_off_by_the_earth_rate(track):
    s = track
    lat = s["lat"]
    w_ie = np.stack([aircraft.OMEGA * np.cos(lat), 0 * lat, -aircraft.OMEGA * np.sin(lat)], -1)
    c = np.array([aircraft.body_to_ned(*a) for a in zip(*s["att"])])
    rate = s["rate"] - np.einsum("kji,kj->ki", c, w_ie)          # C_nb w_ie taken off
    mis, _ = tc.body_rate_mismatch(s["t"], lat, s["h"], s["v"], *s["att"], rate)
    assert np.allclose(mis, aircraft.OMEGA, rtol=0.02)


def test_a_constant_gravity_is_off_by_the_normal_gravity_difference(track):
    s = track
    c = np.array([aircraft.body_to_ned(*a) for a in zip(*s["att"])])
    g = np.array([aircraft.gravity(la, h) for la, h in zip(s["lat"], s["h"])])
    down = np.einsum("kji,j->ki", c, np.array([0.0, 0.0, 1.0]))   # NED down in body axes
    force = s["force"] + (g - 9.81)[:, None] * down
    mis, _ = tc.specific_force_mismatch(s["t"], s["lat"], s["h"], s["v"], *s["att"], force)
    assert np.allclose(mis, 9.81 - 0.5 * (g[1:] + g[:-1]), rtol=1e-3)   # g changes as it climbs
    assert 0.007 < abs(9.81 - g[0]) < 0.009                  # 40.1 deg N, 150 m


def test_longitude_crossing_the_antimeridian_is_wrapped():
    t = np.array([0.0, 1.0])
    lat = np.zeros(2)
    lon = np.array([math.pi - 1e-6, -math.pi + 1e-6])      # 2e-6 rad east at the equator
    v = np.array([[0.0, 2e-6 * 6378137.0, 0.0]] * 2)
    mis, _ = tc.velocity_mismatch(t, lat, lon, np.zeros(2), v)
    assert mis[0] < 1e-6
