"""Batches whose runs differ in everything a run can own, against the same runs alone.

A campaign's runs differ in their seeds only, but ``tune`` and the sweep batch runs that
differ in parameters; a batch bug that mixes up two runs' values (a shared parameter, a
start value of an input taken from run 0, a row kept after a run failed, metadata of the
wrong run) shows only when the runs differ.  Here, per batched family (the INS/GNSS filters,
the UKF family, the AHRS filters, the sensors, the replay), the runs of one batch differ in
their seeds, their filter's noise (R) and initial covariance (P0), their sensors' error
parameters, the start values of the filter's unconnected inputs, and one run is refused in
the middle of the run; every run that finishes must record the arrays, warnings and metadata
of its single run, bit for bit, and the refused run fail with its single run's error.
"""
from __future__ import annotations

import shutil

import numpy as np
import pytest

from orchestrator.cosim.batch import BatchSimulation
from orchestrator.cosim.master import Simulation
from orchestrator.errors import NavfmuError
from orchestrator.running.scenarios import load_scenario, registry, swap_filter

from campaign_helpers import MODELS

RUNS = 4
REFUSED = 2          # the run refused in the middle
REFUSAL_AT = 2.5     # [s] the AHRS run's refusal


def _ins_sets(model, short_log=None):
    """INS/GNSS runs: R from the receiver's sigma (the unconnected gnss_std_* inputs, a
    start value per run) or from r_pos_*, P0 per run; run REFUSED starts with gnss_std_n =
    0 and takes R from it: refused at its first fix."""
    names = [c.name for c in model.components]
    sets = []
    for b in range(RUNS):
        p = {"filter.p0_pos": 4.0 + b, "filter.p0_att_yaw": 0.02 + 0.01 * b,
             "filter.r_pos_n": 3.0 + 0.5 * b, "filter.r_pos_e": 2.5 + 0.25 * b,
             "filter.r_from_receiver": b % 2 == 0,
             "filter.gnss_std_n": 0.0 if b == REFUSED else 1.5 + 0.5 * b,
             "filter.gnss_std_e": 1.0 + 0.5 * b, "filter.gnss_std_d": 3.0 + b}
        if "trajectory" in names:
            p.update({"trajectory.seed": 11 + 7 * b, "trajectory.gyro_bias_dph": 0.5 + b,
                      "trajectory.accel_vrw_ugpsHz": 40.0 + 10.0 * b})
        if "gnss" in names:
            p.update({"gnss.seed": 1011 + 7 * b, "gnss.pos_sigma_n": 1.0 + 0.5 * b,
                      "gnss.output_delay": 0.1 * (b % 2)})
        if short_log is not None:
            p["replay.log"] = str(short_log if b == 1 else MODELS / "replay_gnss_ins_sim" / "log")
        sets.append(p)
    return sets


def _ahrs_sets(model, short_log=None):
    """AHRS runs: P0, R of both sensors, Q per run, their IMU and magnetometer errors and a
    window of louder gyro noise each (``noise_level_windows``); run REFUSED's window, from
    REFUSAL_AT on, makes its angle increments larger than pi: its filter refuses the input
    in the middle of the run (the AHRS inputs are all connected)."""
    return [{"trajectory.seed": 11 + 7 * b, "trajectory.gyro_bias_dph": 1.0 + b,
             "trajectory.gyro_arw_dpsh": 200.0 if b == REFUSED else 0.5 + 0.1 * b,
             "trajectory.noise_level_windows": (f"{REFUSAL_AT},1000,1000" if b == REFUSED
                                                else f"{1 + b},{2 + b},{2 + b}"),
             "trajectory.mag_noise_T": (0.5 + 0.25 * b) * 1e-7,
             "filter.p0_att": 0.02 + 0.01 * b,
             "filter.r_accel_mps2": 0.1 + 0.05 * b, "filter.r_mag_T": (1.0 + b) * 1e-7,
             "filter.q_gyro_arw_dpsh": 0.1 + 0.05 * b} for b in range(RUNS)]


def _single(model, parameters, stop):
    return Simulation(model, backend="direct", registry=registry(),
                      parameters=parameters).run(stop_time=stop)


@pytest.fixture(scope="module")
def short_log(tmp_path_factory):
    """The replay scenario's log cut after 12 s of IMU lines: its run fails at 12 s."""
    folder = tmp_path_factory.mktemp("short") / "log"
    shutil.copytree(MODELS / "replay_gnss_ins_sim" / "log", folder)
    lines = (folder / "imu.csv").read_text().splitlines()
    (folder / "imu.csv").write_text("\n".join(lines[:1201]) + "\n")
    return folder


@pytest.mark.parametrize("scenario, filter_name, stop, make_sets", [
    ("aircraft_500s", "Kf", 6.0, _ins_sets),
    ("aircraft_outliers", "Igg3RobustKf", 6.0, _ins_sets),
    pytest.param("mems_outages", "SageHusaFading", 6.0, _ins_sets, marks=pytest.mark.slow),
    ("uav_maneuver", "Ukf", 4.0, _ins_sets),
    pytest.param("uav_maneuver", "ImmUkf", 4.0, _ins_sets, marks=pytest.mark.slow),
    ("ahrs_turntable", "UkfAhrs", 5.0, _ahrs_sets),
    pytest.param("ahrs_turntable", "FuzzyUkfAhrs", 5.0, _ahrs_sets, marks=pytest.mark.slow),
    ("replay_gnss_ins_sim", "Kf", 14.0, "replay"),
])
def test_runs_differing_in_all_they_own_record_their_single_runs(scenario, filter_name, stop,
                                                                 make_sets, short_log):
    model = swap_filter(load_scenario(MODELS / scenario), filter_name)
    if make_sets == "replay":
        # the replay family: run 1 replays another log, cut short: refused at 12 s
        sets, refused = _ins_sets(model, short_log), (1, REFUSED)
    else:
        sets, refused = make_sets(model), (REFUSED,)
    outcomes = BatchSimulation(model, registry(), sets).run(stop_time=stop)
    for b, (parameters, batched) in enumerate(zip(sets, outcomes)):
        if b in refused:
            with pytest.raises(NavfmuError) as alone:
                _single(model, parameters, stop)
            assert isinstance(batched, NavfmuError), b
            assert str(batched) == str(alone.value)
            continue
        single = _single(model, parameters, stop)
        assert batched.columns == single.columns
        np.testing.assert_array_equal(batched.time, single.time)
        for comp in single.data:
            assert np.array_equal(batched.data[comp], single.data[comp], equal_nan=True), \
                (b, comp)
        assert batched.metadata["warnings"] == single.metadata["warnings"]
        assert batched.metadata["parameters"] == single.metadata["parameters"]
        assert batched.metadata["batch_runs"] == RUNS
    # the runs do differ, and the refused runs were refused in the middle where they can be
    finished = [o for o in outcomes if not isinstance(o, Exception)]
    assert not np.array_equal(finished[0].data["filter"], finished[1].data["filter"])
    if make_sets is _ahrs_sets:
        assert "input 'imu_dtheta_" in str(outcomes[REFUSED])
        assert f"(step from t = {REFUSAL_AT} s" in str(outcomes[REFUSED])   # mid-run
    else:
        assert "gnss_std_n" in str(outcomes[REFUSED])
        assert "(step from t = " in str(outcomes[REFUSED])       # refused while stepping
    if make_sets == "replay":
        assert "ends at" in str(outcomes[1])
