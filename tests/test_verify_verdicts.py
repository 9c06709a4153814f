"""Every check's verdict, from cheap synthetic inputs to its judging function: a value
built to fail the check fails it and one built to pass passes, at the boundaries the
guide states.  The sensor checks get series of a known noise in SI units and declared
values in datasheet units (deg/sqrt(h), ug/sqrt(Hz), deg/h, ug), so a wrong conversion
would move the measured ratio off 1; the AHRS checks get runs whose errors sit on one side
of the disturbance and are judged in the windows the plan sets.  (Checks that need a real
FMU run are asserted in test_verify.py, test_verify_catalogue.py, test_verify_vehicle.py.)"""
from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from navcore.ins.constants import DPH, DPSH, UG
from orchestrator.verification import attitude_checks, filter_checks, sensor_checks
from orchestrator.verification import roles
from orchestrator.verification.fmi_checks import check_ports
from orchestrator.verification.setting import make_setting

DT = 0.01
SECONDS = 600.0


def _assert_failed_alone_else_passing(checks, failed, run_id, error_text, passing_ids):
    """A failed run gives its run check alone, failing with the run's error; a good run
    gives ``passing_ids``, all passing."""
    ids = [c.id for c in checks]
    if failed:
        assert ids == [run_id] and checks[0].verdict == "fail"
        assert error_text in checks[0].reason
    else:
        assert ids == passing_ids
        assert {c.verdict for c in checks} == {"pass"}


def _sensor_setting(**declared):
    return SimpleNamespace(datasheet=declared, parameters={},
                           facts=SimpleNamespace(variables={}))


def _gauss_markov(rng, n, sigma, tau):
    """First-order Gauss-Markov samples of steady-state ``sigma``, correlation time ``tau``."""
    phi = math.exp(-DT / tau)
    w = rng.normal(0.0, sigma * math.sqrt(1 - phi * phi), n)
    x = np.empty(n)
    x[0] = rng.normal(0.0, sigma)
    for k in range(1, n):
        x[k] = phi * x[k - 1] + w[k]
    return x


@pytest.fixture(scope="module")
def curves():
    """Allan deviations of 600 s at 100 Hz: gyro white 0.1 deg/sqrt(h) plus a Gauss-Markov
    bias of 10 deg/h, 20 s; accelerometer white 50 ug/sqrt(Hz) only."""
    rng = np.random.default_rng(7)
    n = int(SECONDS / DT)
    rates = {}
    for a in "xyz":
        rates["imu_dtheta_" + a] = (rng.normal(0, 0.1 * DPSH / math.sqrt(DT), n)
                                    + _gauss_markov(rng, n, 10 * DPH, 20.0)).tolist()
        rates["imu_dvel_" + a] = rng.normal(0, 50 * UG / math.sqrt(DT), n).tolist()
    return {k: tuple(v) for k, v in sensor_checks.allan_curves(rates, DT).items()}


GYRO_GM = {"gyro_bias_instability_dph": 10.0, "gyro_bias_tau_s": 20.0}


@pytest.mark.parametrize("declared,verdict", [(0.1, "pass"), (0.05, "fail"), (0.2, "fail"),
                                              (0.1 * DPSH, "fail")])   # SI given as deg/sqrt(h)
def test_gyro_arw_in_deg_per_root_hour(curves, declared, verdict):
    check = sensor_checks._density_check(
        _sensor_setting(gyro_arw_dpsh=declared, **GYRO_GM), "gyro", curves)
    assert check.verdict == verdict, check.measured
    if verdict == "pass":     # the Gauss-Markov part taken off: the white part is the 0.1
        assert all(0.9 < r < 1.1 for r in check.details["ratios"].values())


@pytest.mark.parametrize("declared,verdict", [(50.0, "pass"), (30.0, "fail"), (70.0, "fail")])
def test_accel_vrw_in_micro_g_per_root_hertz(curves, declared, verdict):
    check = sensor_checks._density_check(_sensor_setting(accel_vrw_ugpsHz=declared), "accel",
                                         curves)
    assert check.verdict == verdict, check.measured
    if verdict == "pass":
        assert all(0.9 < r < 1.1 for r in check.details["ratios"].values())


def test_arw_without_a_declared_density_is_skipped(curves):
    assert sensor_checks._density_check(_sensor_setting(), "gyro", curves).verdict == "skip"


@pytest.mark.parametrize("instability,tau,verdict", [(10.0, 20.0, "pass"), (30.0, 20.0, "fail"),
                                                     (3.0, 20.0, "fail"), (0.0, 20.0, "skip")])
def test_gauss_markov_bias_instability_in_deg_per_hour(curves, instability, tau, verdict):
    setting = _sensor_setting(gyro_arw_dpsh=0.1, gyro_bias_instability_dph=instability,
                              gyro_bias_tau_s=tau)
    check = sensor_checks._gm_check(setting, "gyro", curves)
    assert check.verdict == verdict, check.measured


def test_accel_bias_instability_in_micro_g():
    """An accelerometer Gauss-Markov bias of 300 ug, 30 s, declared in ug: passes; declared
    as 100 ug it fails (the flat part is three times the model's)."""
    rng = np.random.default_rng(11)
    n = int(SECONDS / DT)
    rates = {"imu_dvel_" + a: (rng.normal(0, 20 * UG / math.sqrt(DT), n)
                               + _gauss_markov(rng, n, 300 * UG, 30.0)).tolist() for a in "xyz"}
    curves = {k: tuple(v) for k, v in sensor_checks.allan_curves(rates, DT).items()}
    for declared, verdict in ((300.0, "pass"), (100.0, "fail")):
        setting = _sensor_setting(accel_vrw_ugpsHz=20.0, accel_bias_instability_ug=declared,
                                  accel_bias_tau_s=30.0)
        assert sensor_checks._gm_check(setting, "accel", curves).verdict == verdict


@pytest.mark.parametrize("failed", [False, True])
def test_imu_static_run_fails_only_a_sensor_that_did_not_run(curves, tmp_path, failed):
    """``imu.static_run`` stands alone when the standing-still run failed; a sensor that ran
    gets its four Allan checks (here all passing: the declared values are the generated ones)."""
    setting = _sensor_setting(gyro_arw_dpsh=0.1, accel_vrw_ugpsHz=50.0, **GYRO_GM)
    setting.role = "imu_sensor"
    run = ({"error": "doStep at t = 3 s: ZeroDivisionError"} if failed
           else {"allan": {k: list(v) for k, v in curves.items()}})
    checks, files = sensor_checks.judge_plan(setting, None, {("static", "imu", 0): run}, tmp_path)
    if failed:
        assert [c.id for c in checks] == ["imu.static_run"] and not files
        assert checks[0].verdict == "fail" and "ZeroDivisionError" in checks[0].reason
    else:
        assert len(checks) == 4 and "imu.static_run" not in [c.id for c in checks]
        assert files["allan.png"].exists()


# -- GNSS receiver -----------------------------------------------------------------------
SIGMAS = {"pos_sigma_n": 2.0, "pos_sigma_e": 2.0, "pos_sigma_d": 3.0, "vel_sigma_n": 0.1,
          "vel_sigma_e": 0.1, "vel_sigma_d": 0.1}


def _fixes(scale=1.0, bias=0.0, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(1.0, sensor_checks.RECEIVER_S + 1.0)
    fixes = {"time": t.tolist()}
    for key, sigma in SIGMAS.items():
        q, a = key.split("_sigma_")
        fixes[f"{q}_{a}"] = (rng.normal(bias * sigma, scale * sigma, len(t))).tolist()
    outage = (t >= sensor_checks.OUTAGE[0]) & (t < sensor_checks.OUTAGE[1])
    patch = (t >= sensor_checks.PATCH[0]) & (t < sensor_checks.PATCH[1])
    fixes["valid"], fixes["outlier"] = (~outage).tolist(), patch.tolist()
    return fixes


@pytest.mark.parametrize("scale,bias,verdict", [(1.0, 0.0, "pass"), (1.5, 0.0, "fail"),
                                                (0.6, 0.0, "fail"), (1.0, 0.5, "warn")])
def test_gnss_noise_against_the_declared_sigmas(scale, bias, verdict):
    check = sensor_checks._noise_check(_sensor_setting(**SIGMAS), _fixes(scale, bias))
    assert check.verdict == verdict, (check.measured, check.reason)


def test_a_correct_receiver_fails_gnss_noise_one_run_in_twenty():
    """The band holds all six axes together at 95 %: of 400 receivers with exactly the
    declared white noise, 5 % fail (with a 95 % band per axis it was 1 - 0.95^6 = 26 %)."""
    verdicts = [sensor_checks._noise_check(_sensor_setting(**SIGMAS), _fixes(seed=s)).verdict
                for s in range(400)]
    assert 0.025 < verdicts.count("fail") / 400 < 0.085


def _flag(fixes, cid, flag):
    setting = _sensor_setting()
    setting.facts.variables = {"outages": None, "outlier_patches": None}
    if cid == "gnss.outage":
        return sensor_checks._flag_check(setting, fixes, cid, "outage flag",
                                          sensor_checks.OUTAGE, "gnss_valid", False, "outages")
    return sensor_checks._flag_check(setting, fixes, cid, "outlier flag", sensor_checks.PATCH,
                                      "gnss_outlier", True, "outlier_patches")


@pytest.mark.parametrize("cid,key", [("gnss.outage", "valid"), ("gnss.outliers", "outlier")])
def test_gnss_flags_exactly_inside_the_window(cid, key):
    fixes = _fixes()
    assert _flag(fixes, cid, key).verdict == "pass"
    late = dict(fixes)
    window = sensor_checks.OUTAGE if key == "valid" else sensor_checks.PATCH
    late[key] = [v if t != window[1] else not v     # the flag one fix too long
                 for t, v in zip(fixes["time"], fixes[key])]
    check = _flag(late, cid, key)
    assert check.verdict == "fail" and check.measured.startswith("1 of")


@pytest.mark.parametrize("failed", [False, True])
def test_gnss_run_fails_only_a_receiver_that_did_not_run(failed):
    """``gnss.run`` stands alone (the receiver's error, no noise or flag verdicts) when the
    receiver's run failed; a receiver that ran gets its noise and flag checks instead."""
    setting = _sensor_setting(**SIGMAS)
    setting.role = "gnss_receiver"
    setting.facts.variables = {"outages": None, "outlier_patches": None}
    run = {"error": "doStep at t = 12 s: ValueError"} if failed else {"fixes": _fixes()}
    checks, _ = sensor_checks.judge_plan(setting, None, {("receiver", "gnss", 0): run}, None)
    _assert_failed_alone_else_passing(checks, failed, "gnss.run", "ValueError",
                                      ["gnss.noise", "gnss.outage", "gnss.outliers"])


# -- attitude filter -----------------------------------------------------------------------
def _ahrs_run(before_nrms, after_rms, after_nrms=1.0, ms=0.1):
    level = ("roll", "pitch", "yaw")
    return {"metrics": {"time_per_step_ms": ms},
            "windows": {"before": {"attitude_normalized_rms": {a: before_nrms for a in level}},
                        "after": {"attitude_rms_deg": {a: after_rms for a in level},
                                  "attitude_normalized_rms": {a: after_nrms for a in level}}}}


def test_ahrs_windows_split_at_the_disturbance():
    """The plan's windows: consistency before the disturbance (its first second left out),
    the disturbance check from it on."""
    facts = roles.read_fmu(filter_checks.MODELS.parent / "fmus" / "dist" / "UkfAhrs.fmu")
    planned = attitude_checks.plan(make_setting(facts, "attitude_filter"), 1)
    windows = planned.jobs[0][1]["windows"]
    assert windows["before"][1] < attitude_checks.DISTURBANCE_S == windows["after"][0]
    assert windows["after"][1] >= 240.0          # to the end of ahrs_turntable


@pytest.mark.parametrize("before,verdict", [(1.0, "pass"), (0.3, "fail"), (2.0, "fail")])
def test_ahrs_consistency_before_the_disturbance(before, verdict):
    mine = [_ahrs_run(before, after_rms=50.0, after_nrms=40.0)]   # after: not its business
    assert attitude_checks._consistency(mine).verdict == verdict


@pytest.mark.parametrize("after,nrms,verdict", [(1.0, 1.0, "pass"), (3.0, 1.0, "warn"),
                                                (6.0, 1.0, "fail"), (1.0, 4.0, "warn")])
def test_ahrs_disturbance_after_it(after, nrms, verdict):
    mine = [_ahrs_run(9.0, after_rms=after, after_nrms=nrms)]   # before: not its business
    theirs = [_ahrs_run(1.0, after_rms=1.0)]
    assert attitude_checks._disturbance(mine, theirs).verdict == verdict


@pytest.mark.parametrize("ms,verdict", [(1.0, "pass"), (3.0, "warn")])
def test_ahrs_timing(ms, verdict):
    check = attitude_checks._timing([_ahrs_run(1, 1, ms=ms)], [_ahrs_run(1, 1, ms=0.1)])
    assert check.verdict == verdict


@pytest.mark.parametrize("reference_failed", [False, True])
def test_ahrs_reference_fails_when_only_the_reference_did_not_run(reference_failed):
    """A reference that did not run gives ``ahrs.reference`` alone (no verdict on the filter
    under test from a comparison that cannot be made); a good pair gives the three checks."""
    good = _ahrs_run(1.0, after_rms=1.0)
    theirs = {"error": "reference: doStep failed"} if reference_failed else good
    results = {("ahrs", "filter", 0): good, ("ahrs", attitude_checks.REFERENCE, 0): theirs}
    checks, _ = attitude_checks.judge_plan(None, SimpleNamespace(seeds=1), results, None)
    _assert_failed_alone_else_passing(checks, reference_failed, "ahrs.reference",
                                      "doStep failed",
                                      ["ahrs.consistency", "ahrs.disturbance", "ahrs.timing"])


# -- INS/GNSS filter: robustness ratios and timing -----------------------------------------
@pytest.fixture(scope="module")
def kf_cases():
    facts = roles.read_fmu(filter_checks.MODELS.parent / "fmus" / "dist" / "Kf.fmu")
    return {c.name: c for c in filter_checks.plan(make_setting(facts, "ins_gnss_filter"), 1,
                                                  quick=True).cases}


def _run(case, value):
    metric = {"position_rms_m": {"n": value, "e": 0.0, "d": 0.0},
              "velocity_rms_mps": {"n": value, "e": 0.0, "d": 0.0}}
    run = {"nonfinite": [], "metrics": metric, "windows": {"case": metric},
           "growth": {"growth_m": value}}
    return run


ROBUST = ("noise_step", "outlier_patch", "late_fixes", "stationary_start", "high_dynamics",
          "mems_imu")


@pytest.mark.parametrize("name", ROBUST)
@pytest.mark.parametrize("ratio", [1.5, 3.0, 6.0])
def test_robustness_ratio_over_kf(kf_cases, name, ratio):
    case = kf_cases[name]
    results = {(name, who, 0): _run(case, ratio if who == "filter" else 1.0)
               for who in ("filter", *case.references)}
    check = filter_checks._judge_robustness(case, results)
    warn_up_to = filter_checks.RATIO_WARN if case.ratio_warn is None else case.ratio_warn
    expected = "pass" if ratio <= 2 else ("warn" if ratio <= warn_up_to else "fail")
    assert check.id == f"robust.{name}" and check.verdict == expected
    if name == "mems_imu":                  # no warn band
        assert check.verdict != "warn"


@pytest.mark.parametrize("growth,verdict", [(3.0, "pass"), (5.5, "fail")])
def test_outage_growth_bound(kf_cases, growth, verdict):
    """2 x max(Kf's 1 m, InsOnly's 2 m) + 1 m = 5 m."""
    case = kf_cases["outage"]
    results = {("outage", "filter", 0): _run(case, growth),
               ("outage", filter_checks.REFERENCE, 0): _run(case, 1.0),
               ("outage", filter_checks.FREE_INERTIAL, 0): _run(case, 2.0)}
    assert filter_checks._judge_robustness(case, results).verdict == verdict


@pytest.mark.parametrize("ms,verdict", [(1.0, "pass"), (2.5, "warn")])
def test_filter_timing_over_kf(ms, verdict):
    results = {("closure", "filter", 0): {"metrics": {"time_per_step_ms": ms}},
               ("closure", filter_checks.REFERENCE, 0): {"metrics": {"time_per_step_ms": 0.1}}}
    assert filter_checks._judge_timing(results).verdict == verdict


# -- FMI: the contract's ports -------------------------------------------------------------
def _ports_setting(changes):
    variables = {p.name: roles.Variable(p.name, p.causality, p.type, p.unit, None)
                 for p in roles.contract("vehicle")}
    variables.update(changes)
    facts = roles.FmuFacts(path=Path("V.fmu"), model_name="V", variables={
        k: v for k, v in variables.items() if v is not None}, can_get_set_state=False,
        can_serialize_state=False, can_variable_step=False, default_step=None)
    return SimpleNamespace(facts=facts, role="vehicle")


@pytest.mark.parametrize("changes,verdict", [
    ({}, "pass"),
    ({"truth_roll": roles.Variable("truth_roll", "output", "Real", "deg", None)}, "fail"),
    ({"truth_vn": roles.Variable("truth_vn", "input", "Real", "m/s", None)}, "fail"),
    ({"truth_lat": None}, "fail"),                                  # required, missing
    ({"body_rate_x": None}, "warn"),                                # optional, missing
    ({"truth_h": roles.Variable("truth_h", "output", "Real", "", None)}, "warn"),  # no unit
])
def test_ports_of_the_vehicle_contract(changes, verdict):
    check = check_ports(_ports_setting(changes))
    assert check.verdict == verdict, check.reason
