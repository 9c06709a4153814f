"""FMI honesty and a hostile host, through raw fmpy calls on the built FMUs.

Variable communication steps: a doStep of k sample periods equals k doSteps of one period
bit for bit; a floating-point remainder of a period is accepted; a step shorter than a
period holds the outputs.  Hostile calls (tests/fmi_probe.py, run in its own process): each
is refused with a logged message naming the variable or time, and the instance survives.

Statuses (fmushell's docstring): with the FMUs' patched pythonfmu library every refused call
returns fmi2Error and the next legal call works; the hostile-call tests skip, saying why,
where the FMUs carry pythonfmu's own library (tests/test_native_library.py tests that
fallback).  A skipped IMU interval is an input error of the filter: fmi2Error, and the
instance is in FMI's error state, so every later doStep is fmi2Error too (a lost sample
cannot be recovered).
"""
from __future__ import annotations

import json
import math
import subprocess
import sys
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from orchestrator.building import build as fmu_build
from test_fmus import FMU_NAMES, TRAJ_PARAMS, _Fmu
from test_native_library import require_patched

OK, ERROR, FATAL = 0, 3, 4
LAT = math.radians(40.0)


@pytest.fixture(scope="module")
def dist():
    fmu_build.build(log=None)
    return fmu_build.DIST


def _outputs(f):
    md = f.md
    names = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    return names, f.reals(names)


# -- variable communication step ---------------------------------------------------------
@pytest.mark.parametrize("name", FMU_NAMES)
def test_capability_flag_says_variable_steps_work(dist, name):
    with zipfile.ZipFile(dist / f"{name}.fmu") as z:
        cosim = ET.fromstring(z.read("modelDescription.xml")).find("CoSimulation")
    assert cosim.get("canHandleVariableCommunicationStepSize") == "true"


def test_trajectory_one_step_of_k_periods_equals_k_steps(dist):
    a = _Fmu(dist / "TrajectoryImu.fmu", "a", TRAJ_PARAMS)
    b = _Fmu(dist / "TrajectoryImu.fmu", "b", TRAJ_PARAMS)
    try:
        for k in range(7):
            a.fmu.doStep(k * 0.01, 0.01)
        b.fmu.doStep(0.0, 0.07)
        names, out_a = _outputs(a)
        _, out_b = _outputs(b)
        assert np.array_equal(out_a, out_b)
        assert out_b[names.index("imu_time")] == pytest.approx(0.07, abs=1e-12)
        # and the internal state too: one more period each
        a.fmu.doStep(0.07, 0.01)
        b.fmu.doStep(0.07, 0.01)
        assert np.array_equal(_outputs(a)[1], _outputs(b)[1])
    finally:
        a.close()
        b.close()


def test_trajectory_floating_point_remainder_and_partial_last_step(dist):
    f = _Fmu(dist / "TrajectoryImu.fmu", "t", TRAJ_PARAMS)
    try:
        f.fmu.doStep(0.0, 0.05)
        held = f.reals(["imu_time", "truth_lat", "imu_dvel_z"])
        f.fmu.doStep(0.05, 6.2e-14)               # a master's rounding remainder: accepted
        assert np.array_equal(f.reals(["imu_time", "truth_lat", "imu_dvel_z"]), held)
        f.fmu.doStep(0.05 + 6.2e-14, 0.004)       # shorter than a period: outputs hold
        assert np.array_equal(f.reals(["imu_time", "truth_lat", "imu_dvel_z"]), held)
        t = 0.054 + 6.2e-14
        f.fmu.doStep(t, 0.06 - t - 6.2e-14)       # ends 6.2e-14 s before the epoch 0.06
        assert f.reals(["imu_time"])[0] == pytest.approx(0.06, abs=1e-12)
    finally:
        f.close()


def test_receiver_one_step_of_k_periods_equals_k_steps(dist):
    params = {"output_delay": 1.5, "seed": 3}
    a = _Fmu(dist / "GnssReceiver.fmu", "a", params)
    b = _Fmu(dist / "GnssReceiver.fmu", "b", params)
    try:
        for f in (a, b):
            for n, v in (("truth_time", 3.0), ("truth_lat", LAT), ("truth_h", 80.0),
                         ("truth_vn", 20.0)):
                f.set(n, v)
        for k in range(5):
            a.fmu.doStep(float(k), 1.0)
        b.fmu.doStep(0.0, 5.0)
        assert np.array_equal(_outputs(a)[1], _outputs(b)[1])
        names, out = _outputs(b)
        assert out[names.index("gnss_time")] == 3.0    # taken at 3.0, published at 5.0 >= 4.5
        assert b.fmu.getInteger([b.vr["gnss_epoch"]]) == a.fmu.getInteger([a.vr["gnss_epoch"]]) \
            == [1]
    finally:
        a.close()
        b.close()


@pytest.mark.parametrize("name", ["Kf", "Ukf"])
def test_filter_one_step_of_k_periods_equals_k_steps(dist, name):
    """A filter is driven by the time tags of its inputs: one IMU interval and one fix held
    over a step of 5 IMU periods give what 5 steps of one period give."""
    params = {"init_lat": LAT, "init_h": 100.0}
    a = _Fmu(dist / f"{name}.fmu", "a", params)
    b = _Fmu(dist / f"{name}.fmu", "b", params)
    try:
        for f in (a, b):
            for n, v in (("imu_time", 0.01), ("imu_dt", 0.01), ("imu_dvel_z", -0.098),
                         ("imu_dtheta_x", 1e-6), ("gnss_time", 0.01), ("gnss_lat", LAT + 1e-6),
                         ("gnss_h", 100.0), ("gnss_valid", True), ("gnss_epoch", 1)):
                f.set(n, v)
        for k in range(5):
            a.fmu.doStep(k * 0.01, 0.01)
        b.fmu.doStep(0.0, 0.05)
        assert np.array_equal(_outputs(a)[1], _outputs(b)[1])
        assert a.fmu.getBoolean([a.vr["updated"]]) == [False]   # the update was in step 1
        names, out = _outputs(b)
        assert out[names.index("nav_time")] == 0.01
    finally:
        a.close()
        b.close()


# -- hostile host ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def probe(dist, tmp_path_factory):
    require_patched(dist / "Kf.fmu")
    out = tmp_path_factory.mktemp("probe") / "probe.json"
    proc = subprocess.run([sys.executable, str(Path(__file__).with_name("fmi_probe.py")),
                           str(dist), str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, (proc.returncode, proc.stderr[-3000:])
    return json.loads(out.read_text())


def _logged(case, *words):
    return any(all(w in m for w in words) for m in case["logs"])


def _survives(case, first_follow):
    """The legal doSteps after the hostile call: ``first_follow`` for the first, then OK
    (or, after a component error, refused again); never fatal, and a get still works."""
    assert case["follow"][0] == first_follow
    assert case["follow"][1] in (OK, ERROR)
    assert case["get_after"] == OK


def test_unknown_value_reference_is_refused(probe):
    case = probe["unknown_value_reference"]
    assert case["status"] == ERROR
    assert _logged(case, "valueReference 99999", "no variable of Kf")
    _survives(case, OK)                             # the legal calls after it work
    assert case["follow"][1] == OK


def test_wrong_type_value_reference_is_refused(probe):
    case = probe["wrong_type_value_reference"]
    assert case["status"] == ERROR
    assert _logged(case, "'gnss_epoch', of type Integer, not Real")
    _survives(case, OK)
    assert case["follow"][1] == OK


def test_setting_an_output_is_refused(probe):
    case = probe["set_output"]
    assert case["status"] == ERROR
    assert case["values"][0] == case["values"][1]   # nav_lat unchanged
    assert _logged(case, "'nav_lat'", "is an output")
    _survives(case, OK)
    assert case["follow"][1] == OK


def test_setting_a_fixed_parameter_after_initialization_is_refused(probe):
    case = probe["set_fixed_parameter"]
    assert case["status"] == ERROR
    assert _logged(case, "parameter 'init_lat'", "before fmi2ExitInitializationMode")
    _survives(case, OK)
    assert case["follow"][1] == OK
    assert case["nav_after"][1] == pytest.approx(LAT, abs=1e-6)  # the filter kept init_lat


@pytest.mark.parametrize("which", ["step_back", "step_ahead"])
def test_communication_point_that_jumps_is_refused(probe, which):
    case = probe[which]
    assert case["status"] == ERROR
    t = "-5.0" if which == "step_back" else "10.0"
    assert _logged(case, f"doStep at t = {t} s", "previous step ended at t = 0.01 s")
    _survives(case, OK)                             # nothing changed: legal steps go on
    assert case["follow"][1] == OK
    assert case["nav_after"][0] == pytest.approx(0.03)


def test_step_size_not_positive_is_refused(probe):
    case = probe["step_size_not_positive"]
    assert case["status"] == ERROR
    assert _logged(case, "step size -0.01 s")
    _survives(case, OK)


def test_skipped_imu_interval_is_refused(probe):
    case = probe["skipped_imu_interval"]
    assert case["status"] == ERROR
    assert _logged(case, "'imu_time' = 0.03", "nav_time = 0.01", "1 IMU intervals skipped")
    _survives(case, ERROR)                  # a lost sample cannot be recovered: error state
    assert any("fmi2DoStep is not allowed in state error" in m for m in case["later_logs"])


def test_probe_ran_every_case(probe):
    assert set(probe) == {"unknown_value_reference", "wrong_type_value_reference", "set_output",
                          "set_fixed_parameter", "step_back", "step_ahead",
                          "step_size_not_positive", "skipped_imu_interval"}
    assert not any(c["status"] == FATAL or FATAL in c["follow"] for c in probe.values())


def test_stale_fix_is_logged_once_through_the_fmi_logger(dist):
    logs = []
    f = _Fmu(dist / "Kf.fmu", "kf", {"init_lat": LAT, "init_h": 100.0, "max_fix_age": 0.02},
             logs=logs)
    try:
        for k in range(6):
            f.set("imu_time", (k + 1) * 0.01)
            f.set("imu_dt", 0.01)
            f.set("imu_dvel_z", -0.098)
            if k in (3, 5):                       # fixes taken at 0.0 s: 0.04 and 0.06 s old
                f.set("gnss_lat", LAT)
                f.set("gnss_h", 100.0)
                f.set("gnss_valid", True)
                f.set("gnss_epoch", k)
            f.fmu.doStep(k * 0.01, 0.01)
        assert f.fmu.getInteger([f.vr["n_stale_fixes"]]) == [2]
        assert f.fmu.getBoolean([f.vr["updated"]]) == [False]
    finally:
        f.close()
    stale = [m for m in logs if "max_fix_age" in m]
    assert len(stale) == 1 and "gnss_time = 0 s" in stale[0], logs


def test_nis_warning_is_logged_once_through_the_fmi_logger(dist):
    """A Kf told its GNSS is 100 times better than it is: the NIS stays far above its band and
    the FMU says so once, as a warning of its logger, on one line."""
    logs = []
    f = _Fmu(dist / "Kf.fmu", "kf", {"init_lat": LAT, "init_h": 100.0, "r_pos_n": 0.01,
                                      "r_pos_e": 0.01, "r_pos_d": 0.01,
                                      "measurement": "position", "nis_warning_s": 20.0},
             logs=logs)
    rng = np.random.default_rng(3)
    try:
        for k in range(4000):
            f.set("imu_time", (k + 1) * 0.01)
            f.set("imu_dt", 0.01)
            f.set("imu_dvel_z", -0.098)
            if (k + 1) % 100 == 0:                  # 1 Hz fixes with 1 m of noise
                f.set("gnss_time", (k + 1) * 0.01)
                f.set("gnss_lat", LAT + rng.normal() / 6.4e6)
                f.set("gnss_h", 100.0 + rng.normal())
                f.set("gnss_valid", True)
                f.set("gnss_epoch", (k + 1) // 100)
            f.fmu.doStep(k * 0.01, 0.01)
    finally:
        f.close()
    warned = [(status, m) for status, m in f.records if "chi-square band" in m]
    assert len(warned) == 1 and warned[0][0] == 1, logs        # 1: fmi2Warning
    assert "\n" not in warned[0][1].strip() and warned[0][1].startswith("kf: Kf: at t = ")
