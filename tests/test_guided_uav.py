"""GuidedUav and its parts: Dryden turbulence against the MIL-F-8785C correlation functions,
the coordinated turn against the textbook radius, L1 guidance flying a route, the loop limits,
ImuSensor's rate form against its exact form, and the closed loop under both exchanges."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from navcore.components.registry import GuidedUav, ImuSensor
from navcore.errors import InputError, ParameterError
from navcore.ins.constants import G0
from navcore.vehicles.point_mass_uav import PointMassUav
from navcore.vehicles.turbulence import DrydenTurbulence, low_altitude
from orchestrator.cosim.master import Simulation
from orchestrator.results import mission_metrics
from orchestrator.running import scenarios

MISSION = Path(__file__).resolve().parents[1] / "models" / "uav_mission"
DT = 0.01


# -- turbulence ----------------------------------------------------------------------------
def _gusts(n, V=25.0, h=150.0, w20=7.7, seed=11, dt=DT):
    turbulence = DrydenTurbulence(w20, seed)
    turbulence.start(h)
    return np.array([turbulence.step(dt, V, h) for _ in range(n)])


def _autocorrelation(x, lags):
    x = x - x.mean()
    return np.array([np.mean(x[:len(x) - k] * x[k:]) for k in lags])


def test_dryden_gusts_have_the_mil_f_8785c_correlations():
    """R_u = s^2 exp(-tau/T), R_w = s^2 exp(-tau/T) (1 - tau/(2T)), T = L/V (MIL-F-8785C's
    Dryden forms), sampled every 0.1 s (the discretization is exact for any step) over
    20000 s, about 3000 correlation times at 30 m: a sampling error of about 0.02 s^2."""
    V, h, dt = 25.0, 30.0, 0.1
    gusts = _gusts(200_000, V, h, dt=dt)
    (L_u, _, L_w), (s_u, _, s_w) = low_altitude(h, 7.7)
    for axis, L, s, form in ((0, L_u, s_u, lambda a: np.exp(-a)),
                             (2, L_w, s_w, lambda a: np.exp(-a) * (1 - a / 2))):
        T = L / V
        lags = np.array([0, round(0.5 * T / dt), round(T / dt), round(2 * T / dt)])
        measured = _autocorrelation(gusts[:, axis], lags)
        np.testing.assert_allclose(measured, s * s * form(lags * dt / T), atol=0.06 * s * s)
    # the low-altitude intensities: sigma_w = 0.1 W20, sigma_u = sigma_w / (0.177 +
    # 0.000823 h_ft)^0.4 (h = 30 m = 98 ft)
    assert s_w == pytest.approx(0.77) and s_u == pytest.approx(0.77 / (0.177 + 0.000823 *
                                                                        30 / 0.3048) ** 0.4)


def test_no_turbulence_draws_nothing_and_stays_calm():
    assert np.all(_gusts(100, w20=0.0) == 0.0)


# -- dynamics ------------------------------------------------------------------------------
CONFIG = dict(bank_bandwidth=3.0, climb_bandwidth=2.0, loop_damping=0.8, tau_airspeed=3.0,
              altitude_gain=0.2, bank_limit=math.radians(35), load_factor_limit=2.0,
              climb_rate_limit=3.0, accel_limit=2.0, gust_response_time=0.5,
              wind=(0.0, 0.0, 0.0))


def test_a_held_bank_flies_the_coordinated_turn_radius():
    """Turn radius V^2 / (g tan(phi)) (the level coordinated turn)."""
    uav = PointMassUav(CONFIG, 0.7, 2.0, 150.0, 25.0, 0.0)
    bank = math.radians(30)
    calm = (0.0, 0.0, 0.0)
    for _ in range(2000):
        uav.step(DT, (bank, 25.0, 0.0), calm, calm)
    rate = uav.turn_rate()
    assert uav.phi == pytest.approx(bank, rel=1e-6)
    assert 25.0 / rate == pytest.approx(25.0 ** 2 / (G0 * math.tan(bank)), rel=1e-6)


def test_the_bank_command_is_limited_by_the_load_factor():
    config = dict(CONFIG, load_factor_limit=1.2)     # acos(1/1.2) = 33.6 deg < 35 deg
    uav = PointMassUav(config, 0.7, 2.0, 150.0, 25.0, 0.0)
    calm = (0.0, 0.0, 0.0)
    peak = 0.0
    for _ in range(1000):
        uav.step(DT, (1.0, 25.0, 0.0), calm, calm)
        peak = max(peak, uav.phi)
    # the second-order loop with damping 0.8 overshoots by exp(-pi zeta/sqrt(1-zeta^2)) = 1.5 %
    assert math.acos(1 / 1.2) <= peak <= math.acos(1 / 1.2) * 1.016


# -- guidance ------------------------------------------------------------------------------
def _fly_on_truth(n, **params):
    uav = GuidedUav(guide_on_truth=True, **params)
    rows = [uav.start(0.0)]
    for k in range(n):
        rows.append(dict(uav.advance(k * DT, DT, {})))
    return rows


def test_l1_guidance_flies_the_route_in_a_cross_wind():
    rows = _fly_on_truth(60_000, wind_e=5.0)      # 600 s: the default route, 11.4 km
    cross = np.array([r["cross_track"] for r in rows])
    reached = [r["waypoints_reached"] for r in rows]
    assert reached[-1] == 4
    # on the straight part of the first leg (after 60 s, before the turn) the L1 law holds
    # the leg against the 5 m/s cross wind (it steers the ground velocity): no offset
    first_leg = cross[6000:10_000]
    assert np.max(np.abs(first_leg)) < 0.01 and abs(cross[2000]) < 0.5
    # a vehicle guided on its truth switches where it meant to
    misses = [r["waypoint_miss"] for r, prev in zip(rows[1:], reached) if r["waypoints_reached"]
              > prev]
    assert len(misses) == 4 and max(abs(m) for m in misses) < 1.5


# -- the rate form of ImuSensor ---------------------------------------------------------------
def test_rate_form_increments_agree_with_the_exact_inverse_to_the_trapezoid_error():
    """The trapezoid of GuidedUav's body rates and specific force against the exact inverse
    strapdown of its truth, in light turbulence: measured 2.3e-6 rad and 8.8e-6 m/s at
    most over 600 s (the dt^3 w''/12 of a trapezoid with the accelerations of the turns
    and the gusts); the bounds below leave a factor of about 2."""
    uav = GuidedUav(guide_on_truth=True, turbulence_w20=7.7, wind_e=5.0)
    truth = uav.start(0.0)
    exact, rates = ImuSensor(), ImuSensor(input_form="rates")
    for s in (exact, rates):
        s.start(0.0)
        s.initial_inputs(truth)
    worst = np.zeros(2)
    for k in range(30_000):
        out = uav.advance(k * DT, DT, {})
        a, b = exact.advance(k * DT, DT, out), rates.advance(k * DT, DT, out)
        worst = np.maximum(worst, [max(abs(a[f"imu_dtheta_{c}"] - b[f"imu_dtheta_{c}"])
                                       for c in "xyz"),
                                   max(abs(a[f"imu_dvel_{c}"] - b[f"imu_dvel_{c}"])
                                       for c in "xyz")])
    assert worst[0] < 5e-6 and worst[1] < 2e-5
    assert worst[0] > 0 and worst[1] > 0


# -- refusals ------------------------------------------------------------------------------
def _nav(t, **change):
    nav = {"nav_time": t, "nav_lat": 0.6998770300497261, "nav_lon": 2.069960492865275,
           "nav_h": 150.0, "nav_vn": 25.0, "nav_ve": 0.0, "nav_vd": 0.0, "nav_yaw": 0.0}
    nav.update(change)
    return nav


@pytest.mark.parametrize("change, words", [
    ({"nav_time": -2.0}, ["'nav_time' = -2.0 s", "2 s old", "max_nav_age' = 1 s"]),
    ({"nav_time": 1.5}, ["'nav_time' = 1.5 s", "1.49 s ahead of the communication step's end"]),
    ({"nav_lat": 0.0}, ["'nav_lat'/'nav_lon'", "km from the nearest waypoint"]),
    ({"nav_vn": math.nan}, ["'nav_vn' = nan"]),
])
def test_a_bad_navigation_solution_is_refused_naming_the_input(change, words):
    uav = GuidedUav()
    uav.start(0.0)
    with pytest.raises(InputError) as err:
        uav.advance(0.0, DT, _nav(0.0, **change))
    for w in words:
        assert w in str(err.value)


@pytest.mark.parametrize("route, words", [
    ("0,0,150", ["at least two waypoints"]),
    ("0,0,150; 100,x,150", ["waypoint 2", "'100,x,150'"]),
    ("0,0,150; 0.5,0,150", ["waypoint 2 is within 1 m of waypoint 1"]),
])
def test_a_bad_route_is_refused_naming_the_parameter(route, words):
    with pytest.raises(ParameterError) as err:
        GuidedUav(route=route).start(0.0)
    assert "parameter 'route'" in str(err.value)
    for w in words:
        assert w in str(err.value)


# -- the closed loop -----------------------------------------------------------------------
def test_the_model_description_declares_no_output_dependency(tmp_path):
    from orchestrator.building import build as fmu_build

    fmu_build.build(log=None)
    md = read_model_description(str(fmu_build.DIST / "GuidedUav.fmu"))
    assert md.outputs and all(u.dependencies == [] for u in md.outputs)
    assert "do not depend on its inputs" in md.description


@pytest.fixture(scope="module")
def loops():
    model = scenarios.load_scenario(MISSION)
    runs = {}
    for algorithm in ("gauss-seidel", "jacobi"):
        sim = Simulation(model, backend="direct", registry=scenarios.registry(),
                         algorithm=algorithm)
        runs[algorithm] = (sim, sim.run(stop_time=170.0))
    return runs


def test_gauss_seidel_breaks_the_loop_at_the_vehicle_and_jacobi_runs_it(loops):
    sim, _ = loops["gauss-seidel"]
    delayed = {(c.start_component, c.end_component) for c in sim.delayed_connections}
    assert delayed == {("filter", "vehicle")} and len(sim.delayed_connections) == 8
    for algorithm, (_, results) in loops.items():
        m = mission_metrics.mission_metrics(results, "filter")
        # the first 170 s: the first leg and the first turn, flown on the filter's solution
        assert m["waypoints_reached"] == 1, algorithm
        assert m["cross_track_rms_m"] < 20.0, algorithm
    a = mission_metrics.mission_metrics(loops["gauss-seidel"][1], "filter")
    b = mission_metrics.mission_metrics(loops["jacobi"][1], "filter")
    # one step of exchange delay (20 ms) changes the flight by centimetres, not metres
    assert abs(a["cross_track_rms_m"] - b["cross_track_rms_m"]) < 0.5
