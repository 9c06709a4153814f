"""The GNSS antenna lever arm (navcore.ins.lever_arm): the filters' measurement model against
the rigid-body kinematics of an antenna on a turning vehicle (analytic: r = C l, v = omega x
r), in the Kf and the UKF family; the receiver's offset antenna against the same case; and
aircraft_500s flown with an offset antenna, with and without the lever arm in the filter; a
replayed log's truth is the IMU's point, the point of the filters' nav_* outputs."""
from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from navcore.components import registry as components
from navcore.ins import earth
from navcore.ins.rotations import euler_to_dcm
from navcore.ins.strapdown import Strapdown
from orchestrator.building import build as fmu_build
from orchestrator.model.receiver_wiring import connect_receiver_attitude
from orchestrator.cosim.master import Simulation
from orchestrator.errors import NavfmuWarning
from orchestrator.results import metrics
from orchestrator.running import scenarios
from orchestrator.running.replay import sensor_log_from_results
from navcore.sensors.sensorlog import SensorLog, write_log

LAT, LON, H = 0.7, 2.0, 100.0
YAW_RATE = 0.1                   # rad/s, a right turn
LEVER = np.array([1.0, 0.0, -0.5])  # 1 m ahead of the IMU, 0.5 m above it


def _turning_vehicle():
    """Heading east (yaw 90 deg) at 10 m/s, turning right: the antenna 1 m ahead and 0.5 m
    up is 1 m east and 0.5 m up of the IMU and moves south at YAW_RATE * 1 m relative to it."""
    v_imu = np.array([0.0, 10.0, 0.0])
    rn, re = earth.radii(LAT)
    antenna = (LAT, LON + 1.0 / ((re + H) * math.cos(LAT)), H + 0.5)
    return v_imu, antenna, v_imu + np.array([-YAW_RATE * 1.0, 0.0, 0.0])


@pytest.mark.parametrize("name", ["Kf", "Iakf", "NewtonRobustKf", "Ukf", "ImmUkf"])
def test_measurement_model_matches_the_rigid_body_antenna(name):
    v_imu, antenna, v_antenna = _turning_vehicle()
    filt = getattr(components, name)(lever_arm_x=LEVER[0], lever_arm_z=LEVER[2])
    nav = Strapdown.from_euler(LAT, LON, H, v_imu, 0.0, 0.0, math.pi / 2)
    engine = filt.make_engine(filt.make_config(), nav)
    C_nb = nav.C_bn.T
    engine.rate_ib = np.array([0.0, 0.0, YAW_RATE]) + C_nb @ earth.earth_rate_ned(LAT)
    z = engine.measurement(*antenna, v_antenna, 0.0)
    assert np.abs(z[:3]).max() < 1e-6 and np.abs(z[3:]).max() < 1e-12, z
    # without the lever arm the same fix is the lever arm itself
    plain = getattr(components, name)()
    z0 = plain.make_engine(plain.make_config(), nav).measurement(*antenna, v_antenna, 0.0)
    assert z0[:3] == pytest.approx([0.0, -1.0, 0.5], abs=1e-6)   # INS - fix, NED
    assert z0[3:] == pytest.approx([YAW_RATE, 0.0, 0.0], abs=1e-12)


def test_receiver_puts_its_fixes_at_the_antenna():
    v_imu, antenna, v_antenna = _turning_vehicle()
    rx = components.GnssReceiver(lever_arm_x=LEVER[0], lever_arm_z=LEVER[2], fix_interval=0.1)
    rx.initialize(0.0)
    yaw0 = math.pi / 2 - YAW_RATE * 0.1     # the attitude one step earlier
    truth = {"truth_lat": LAT, "truth_lon": LON, "truth_h": H, "truth_vn": v_imu[0],
             "truth_ve": v_imu[1], "truth_vd": v_imu[2], "truth_roll": 0.0, "truth_pitch": 0.0}
    rx.step(0.0, 0.05, {**truth, "truth_time": 0.05, "truth_yaw": yaw0})
    out = rx.step(0.05, 0.05, {**truth, "truth_time": 0.15, "truth_yaw": math.pi / 2})
    rn, re = earth.radii(LAT)
    assert (out["gnss_lat"] - antenna[0]) * rn == pytest.approx(0.0, abs=1e-6)
    assert (out["gnss_lon"] - antenna[1]) * re * math.cos(LAT) == pytest.approx(0.0, abs=1e-6)
    assert out["gnss_h"] == pytest.approx(antenna[2], abs=1e-9)
    got = np.array([out["gnss_vn"], out["gnss_ve"], out["gnss_vd"]])
    assert got == pytest.approx(v_antenna, abs=1e-9)


def test_offset_antenna_in_aircraft_500s():
    """The receiver's antenna 4 m ahead, 1 m right and 2 m above the IMU: a filter without
    the lever arm is off by the lever arm (its mean position error over 100-200 s moves by
    it: 4.1 m horizontally, 2 m up), with it the RMS errors are those of an antenna at the
    IMU within 10 % (+0.1 m)."""
    model = scenarios.load_scenario(fmu_build.ROOT / "models" / "aircraft_500s")
    arm = {"lever_arm_x": 4.0, "lever_arm_y": 1.0, "lever_arm_z": -2.0}
    rx = {f"gnss.{k}": v for k, v in arm.items()}
    runs = {
        "centred": {},
        "ignored": rx,
        "modelled": {**rx, **{f"filter.{k}": v for k, v in arm.items()}},
    }
    errors = {}
    for label, params in runs.items():
        run = scenarios.simulate_scenario(model, backend="direct", parameters=params,
                                          stop_time=200.0, window=(100.0, 200.0), log=None)
        e = metrics.navigation_errors(run.results, "filter")
        late = e["time"] >= 100.0
        errors[label] = (np.array([e[f"pos_{a}"][late].mean() for a in "ned"]),
                         run.metrics["filter"]["position_rms_m"])
    # the mean error of the ignored lever arm less that of the centred antenna (the same
    # noise realization): the lever arm in NED, mostly along the heading
    bias = errors["ignored"][0] - errors["centred"][0]
    assert math.hypot(bias[0], bias[1]) == pytest.approx(math.hypot(4.0, 1.0), rel=0.1)
    assert bias[2] == pytest.approx(-2.0, abs=0.3)          # 2 m up: down error -2 m
    for a in "ned":
        assert errors["modelled"][1][a] == pytest.approx(errors["centred"][1][a], rel=0.1,
                                                         abs=0.1), a
    # the numbers docs/guide/lever_arm.md states (north RMS: centred, ignored, modelled)
    assert [errors[k][1]["n"] for k in ("centred", "ignored", "modelled")] == pytest.approx(
        [0.875, 4.496, 0.879], abs=0.0015)


def test_replayed_truth_is_the_imus_point_not_the_antennas(tmp_path):
    """A run with the antenna 4 m ahead, 1 m right and 2 m above the IMU and noiseless fixes,
    recorded and replayed with the filter's lever arm: the recorded truth (the trajectory's,
    the IMU's point) scores the replay exactly as the simulation (N/E/D RMS over 60-120 s
    2.600/1.795/0.707 m); the same log with the antenna's fixes as its truth is off by the
    lever arm (4.667/2.628/1.860 m, mean error moved by -C_bn l: about 4 m south, 1 m west,
    2 m down), the mistake docs/guide/sensor_logs.md warns of."""
    model = scenarios.load_scenario(fmu_build.ROOT / "models" / "aircraft_500s")
    arm = {"lever_arm_x": 4.0, "lever_arm_y": 1.0, "lever_arm_z": -2.0}
    params = {f"{c}.{k}": v for k, v in arm.items() for c in ("gnss", "filter")}
    params.update({f"gnss.{q}_sigma_{a}": 0.0 for q in ("pos", "vel") for a in "ned"})
    window = (60.0, 120.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NavfmuWarning)      # the Kf's NIS warning
        sim = scenarios.simulate_scenario(model, backend="direct", parameters=params,
                                          stop_time=window[1], window=window, log=None)
    log = sensor_log_from_results(sim.results)
    fixes = {k: log.gnss[k] for k in ("time", "lat", "lon", "h", "vn", "ve", "vd")}
    antenna = {**fixes, **{k: 0.0 * fixes["time"] for k in ("roll", "pitch", "yaw")}}
    write_log(tmp_path / "imu", log)
    write_log(tmp_path / "antenna", SensorLog(log.imu, log.gnss, antenna))
    filter_arm = {f"filter.{k}": v for k, v in arm.items()}
    rms, mean = {}, {}
    for name in ("imu", "antenna"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NavfmuWarning)
            run = scenarios.simulate_scenario(model, backend="direct", parameters=filter_arm,
                                              replay=tmp_path / name, window=window, log=None)
        e = metrics.navigation_errors(run.results, "filter")
        late = e["valid"] & (e["time"] >= window[0])
        rms[name] = [run.metrics["filter"]["position_rms_m"][a] for a in "ned"]
        mean[name] = np.array([e[f"pos_{a}"][late].mean() for a in "ned"])
    expected = [sim.metrics["filter"]["position_rms_m"][a] for a in "ned"]
    assert rms["imu"] == pytest.approx(expected, abs=1e-9)
    assert rms["imu"] == pytest.approx([2.600, 1.795, 0.707], abs=0.002)
    assert rms["antenna"] == pytest.approx([4.667, 2.628, 1.860], abs=0.002)
    shift = mean["antenna"] - mean["imu"]
    assert math.hypot(shift[0], shift[1]) == pytest.approx(math.hypot(4.0, 1.0), rel=0.05)
    assert shift[2] == pytest.approx(2.0, abs=0.25)


@pytest.mark.parametrize("model_dir", sorted(p.parent.name for p in (
    fmu_build.ROOT / "models").glob("*/SystemStructure.ssd")))
def test_every_shipped_receiver_has_its_attitude_connected(model_dir):
    """Each shipped model feeds the receiver's lever arm its attitude (from the truth)."""
    model = scenarios.load_scenario(fmu_build.ROOT / "models" / model_dir)
    receivers = [c.name for c in model.components if c.source.stem == "GnssReceiver"]
    fed = {(c.end_component, c.end_connector) for c in model.connections}
    for rx in receivers:
        assert {(rx, f"truth_{a}") for a in ("roll", "pitch", "yaw")} <= fed, rx


def _without_receiver_attitude(model):
    """``model`` with the truth attitude to the receiver cut (as the models shipped before)."""
    cut = {("gnss", f"truth_{a}") for a in ("roll", "pitch", "yaw")}
    return dataclasses.replace(model, connections=[
        c for c in model.connections if (c.end_component, c.end_connector) not in cut])


def test_lever_arm_on_unconnected_attitude_warns_once():
    model = scenarios.load_scenario(fmu_build.ROOT / "models" / "aircraft_500s")
    arm = {"gnss.lever_arm_x": 4.0, "gnss.lever_arm_y": 1.0, "gnss.lever_arm_z": -2.0}
    registry = scenarios.registry()

    def messages(m, params):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            Simulation(m, backend="direct", registry=registry, parameters=params)
        return [str(w.message) for w in caught if issubclass(w.category, NavfmuWarning)]

    cut = _without_receiver_attitude(model)
    got = messages(cut, arm)
    assert len(got) == 1 and got[0].startswith("component 'gnss': its lever arm (4, 1, -2 m)")
    assert "truth_roll, truth_pitch, truth_yaw" in got[0]
    assert messages(model, arm) == []            # connected: nothing to say
    assert messages(cut, {}) == []               # no lever arm: nothing to say


def test_receiver_attitude_is_connected_or_refused_by_name():
    """The lever-arm wiring adds the truth attitude to the receiver once, from its truth
    source; a source without attitude outputs is an error naming it."""
    from orchestrator.errors import NavfmuError
    from orchestrator.model.receiver_wiring import ATTITUDE, receiver_has_attitude

    model = _without_receiver_attitude(
        scenarios.load_scenario(fmu_build.ROOT / "models" / "aircraft_500s"))
    assert not receiver_has_attitude(model)
    wired = connect_receiver_attitude(model)
    assert receiver_has_attitude(wired)
    assert connect_receiver_attitude(wired).connections == wired.connections
    added = [c for c in wired.connections if c.end_component == "gnss"
             and c.end_connector in ATTITUDE]
    assert {c.start_component for c in added} == {"trajectory"} and len(added) == 3
    src = model.component("trajectory")
    blind = dataclasses.replace(src, connectors={k: v for k, v in src.connectors.items()
                                                 if k not in ATTITUDE})
    model = dataclasses.replace(model, components=[blind if c.name == "trajectory" else c
                                                   for c in model.components])
    with pytest.raises(NavfmuError, match="'trajectory' does not output truth_roll"):
        connect_receiver_attitude(model)
