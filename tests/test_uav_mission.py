"""models/uav_mission: the closed loop as one exported FMU and as an SSP archive, and the
mission metrics against a hand computation on its recording."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from orchestrator.building import build as fmu_build
from test_export_package import export_equals_jacobi
from orchestrator.cosim.master import Simulation
from orchestrator.model.ssp_archive import load_model
from orchestrator.packaging.package import package
from orchestrator.running import scenarios

MODEL = Path(__file__).resolve().parents[1] / "models" / "uav_mission"


@pytest.fixture(scope="module")
def built():
    fmu_build.build(log=None)


def test_exported_mission_fmu_reproduces_the_jacobi_master_bit_for_bit(built, tmp_path):
    got = export_equals_jacobi(MODEL, tmp_path, stop=3.0, step=0.02)
    assert got["gnss.gnss_epoch"][-1] == 2 and np.ptp(got["vehicle.truth_lat"]) > 0


def test_packaged_mission_runs_as_the_folder_does(built, tmp_path):
    archive = package(MODEL, tmp_path / "mission.ssp")
    a = Simulation(load_model(archive)).run(2.0)
    b = Simulation(load_model(MODEL)).run(2.0)
    for c in b.components:
        np.testing.assert_array_equal(a.data[c], b.data[c], err_msg=c)


def test_mission_metrics_by_hand_on_a_recording():
    run = scenarios.simulate_scenario(scenarios.load_scenario(MODEL), backend="direct",
                                      stop_time=320.0, log=None)
    r, m = run.results, run.metrics["filter"]["mission"]
    cross = r.column("vehicle", "cross_track")
    valid = r.column("gnss", "gnss_valid") > 0.5
    first_fix = np.argmax(valid)
    outage = ~valid
    outage[:first_fix] = False
    assert m["cross_track_rms_m"] == pytest.approx(np.sqrt(np.mean(cross ** 2)))
    assert m["outage_cross_track_max_m"] == pytest.approx(np.max(np.abs(cross[outage])))
    # the scenario's outage (gnss.ssv: 240-300 s) seen from the recording
    assert m["outage_s"] == pytest.approx(60.0, abs=1.0)
    assert m["waypoints_reached"] == 2 and m["outage_position_error_max_m"] > 0.5


def test_the_fmus_and_the_navcore_objects_fly_the_same_mission(built):
    """Gauss-Seidel through the FMUs (the sensor's start sample read from the vehicle's
    outputs in initialization mode) and through the direct backend: the same numbers."""
    model = scenarios.load_scenario(MODEL)
    fmu = Simulation(model).run(20.0)
    direct = Simulation(model, backend="direct", registry=scenarios.registry()).run(20.0)
    for c in direct.components:
        np.testing.assert_array_equal(fmu.data[c], direct.data[c], err_msg=c)
    assert fmu.column("filter", "nav_time")[-1] == pytest.approx(20.0)
