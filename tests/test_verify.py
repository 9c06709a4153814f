"""``navfmu verify`` on FMUs with known defects: each broken filter fails the check meant
to catch it (and the correct Kf passes that check on the same runs), a broken IMU fails the
Allan-deviation ARW check, a filter written without navfmu is verified end to end, a
crashing FMU fails its checks with the report still written, bad input exits 2.

The broken FMUs are navcore components with one defect (tests/verify_fmus/), built once per
session.  The default run keeps to the checks and seeds that decide; the full verification
of every broken filter (all checks, showing the others pass) is slow-marked."""
from __future__ import annotations

import json
import math

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.cli.cli_options import parse_named_sets
from orchestrator.campaigns.executor import Executor, Task
from orchestrator.verification import filter_checks, roles, sensor_checks
from orchestrator.verification.fmi_checks import run_fmi_checks
from orchestrator.verification.scenario_run import run_job
from orchestrator.verification.setting import make_setting

from verify_helpers import build_test_fmus

IMU_SETS = ("gyro_arw_dpsh=0.1", "accel_vrw_ugpsHz=50", "imu_period=0.01")


@pytest.fixture(scope="session")
def dist():
    fmu_build.build(log=None)
    return fmu_build.DIST


@pytest.fixture(scope="session")
def broken(tmp_path_factory, dist):
    return build_test_fmus(tmp_path_factory.mktemp("verify_fmus"))


def _setting(path, sets=None):
    facts = roles.read_fmu(path)
    return make_setting(facts, roles.detect_role(facts), (), sets)


def _case_results(setting, names, runs):
    """The runs of the filter cases ``names`` (serially) and those cases."""
    planned = filter_checks.plan(setting, runs)
    cases = [c for c in planned.cases if c.name in names]
    jobs = [j for j in planned.jobs if j[0][0] in names]
    with Executor() as ex:
        results = dict(ex.run([Task(k, run_job, (job, iso)) for k, job, iso in jobs]))
    return cases, results


def _as_filter(results, who):
    """The results with reference ``who``'s runs in the place of the filter's."""
    return {**results, **{(c, "filter", i): r for (c, w, i), r in results.items() if w == who}}


def _verdicts(checks):
    return {c.id: c for c in checks}


@pytest.mark.parametrize("name,role", [("Kf", "ins_gnss_filter"), ("Ukf", "ins_gnss_filter"),
                                       ("UkfAhrs", "attitude_filter"),
                                       ("FuzzyUkfAhrs", "attitude_filter"),
                                       ("TrajectoryImu", "imu_sensor"),
                                       ("GnssReceiver", "gnss_receiver"),
                                       ("GuidedUav", "vehicle")])
def test_role_is_detected_from_the_variables(dist, name, role):
    assert roles.detect_role(roles.read_fmu(dist / f"{name}.fmu")) == role


def test_bad_input_is_one_line_and_exit_2(navfmu_cli, dist, tmp_path):
    not_fmu = tmp_path / "notes.fmu"
    not_fmu.write_text("not a zip")
    cases = [([not_fmu], "not an FMU"),
             ([dist / "ImuGnssReplay.fmu"], "no known role"),
             ([dist / "Kf.fmu", "--scenario", "ahrs_turntable"], "does not fit"),
             ([dist / "Kf.fmu", "--runs", "0"], "--runs"),
             ([dist / "Kf.fmu", "--set", "no_such=1"], "no parameter 'no_such'"),
             ([tmp_path / "missing.fmu"], "not found")]
    for args, text in cases:
        status, out, err = navfmu_cli("verify", *args, "--out", tmp_path / "out")
        assert status == 2, (args, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("navfmu: error: "), err
        assert text in lines[0]
        assert not (tmp_path / "out").exists()


def test_inexact_state_restore_fails_fmi_state_only(broken, dist):
    mine = _verdicts(run_fmi_checks(_setting(broken / "InexactRestoreKf.fmu")))
    assert mine["fmi.state"].verdict == "fail"
    assert "set_state" in mine["fmi.state"].reason and "deserialize" in mine["fmi.state"].reason
    for other in ("fmi.validate", "fmi.ports", "fmi.variable_step", "fmi.hostile"):
        assert mine[other].verdict == "pass", mine[other]
    kf = _verdicts(run_fmi_checks(_setting(dist / "Kf.fmu")))
    assert {c.verdict for c in kf.values()} == {"pass"}


def test_wrong_coriolis_sign_fails_the_noiseless_closure(broken):
    cases, results = _case_results(_setting(broken / "WrongCoriolisKf.fmu"), {"closure"}, 1)
    mine = filter_checks.judge(cases, results)[0]
    kf = filter_checks.judge(cases, _as_filter(results, "Kf"))[0]
    assert mine.verdict == "fail" and kf.verdict == "pass"
    # 2 |omega_ie x v| ~ 0.015 m/s^2 at 100 m/s: metres in the 120 s flight, Kf at 1e-9 m
    assert mine.details["largest_errors"]["position_max_m"] > 0.5
    assert kf.details["largest_errors"]["position_max_m"] < 1e-6


def test_overconfident_r_fails_consistency(broken):
    cases, results = _case_results(_setting(broken / "OverconfidentKf.fmu"),
                                   {"consistency"}, 2)
    mine = filter_checks.judge(cases, results)[0]
    assert mine.verdict == "fail"
    # R / 10 on 6 observations: the NIS is near 10 times its dof's band
    assert mine.details["nis"] > 3 * mine.details["nis_band"][1]
    assert mine.details["nees_position"] > filter_checks.NEES_BAND[1]


def test_ignoring_gnss_valid_fails_the_outage(broken):
    cases, results = _case_results(_setting(broken / "IgnoresValidKf.fmu"), {"outage"}, 1)
    mine = filter_checks.judge(cases, results)[0]
    kf = filter_checks.judge(cases, _as_filter(results, "Kf"))[0]
    assert mine.verdict == "fail" and kf.verdict == "pass"
    # the invalid fixes carry 200 m errors: the error grows by tens of metres
    assert mine.details["filter"][0] > 20.0 > kf.details["filter"][0]


def test_noisy_imu_fails_arw_and_trajectory_imu_passes(broken, dist):
    def checks(path):
        setting = _setting(path, parse_named_sets(IMU_SETS))
        planned = sensor_checks.plan(setting, 1)
        results = {key: run_job(job, iso) for key, job, iso in planned.jobs}
        return _verdicts(sensor_checks.judge_plan(setting, planned, results,
                                                  path.parent)[0])

    noisy = checks(broken / "NoisyImu.fmu")
    assert noisy["imu.gyro_arw"].verdict == "fail"
    assert all(2.6 < r < 3.4 for r in noisy["imu.gyro_arw"].details["ratios"].values())
    assert noisy["imu.accel_vrw"].verdict == "pass"
    good = checks(dist / "TrajectoryImu.fmu")
    assert good["imu.gyro_arw"].verdict == good["imu.accel_vrw"].verdict == "pass"
    assert all(0.9 < r < 1.1 for r in good["imu.gyro_arw"].details["ratios"].values())


def test_filter_written_without_navfmu_is_verified_end_to_end(broken, navfmu_cli, tmp_path):
    out, junit = tmp_path / "report", tmp_path / "junit.xml"
    status, stdout, err = navfmu_cli("verify", broken / "PvFilter.fmu", "--runs", 1,
                                     "--workers", 2, "--out", out, "--junit", junit)
    document = json.loads((out / "verify.json").read_text())
    checks = {c["id"]: c for c in document["checks"]}
    assert document["role"] == "ins_gnss_filter"
    assert status == (1 if document["counts"]["fail"] else 0)
    assert set(checks) >= {"fmi.validate", "fmi.ports", "fmi.state", "fmi.hostile",
                           "filter.closure", "filter.consistency", "robust.outage",
                           "robust.late_fixes", "robust.high_dynamics", "filter.timing"}
    # no FMU state declared by plain pythonfmu: skipped, not failed
    assert checks["fmi.state"]["verdict"] == "skip"
    # plain pythonfmu's library accepts a set of an output and a step back (our FMUs carry
    # a patched one that refuses them): a finding, not a crash of the verification
    assert checks["fmi.hostile"]["verdict"] == "fail"
    assert "set of an output" in checks["fmi.hostile"]["reason"]
    assert checks["fmi.ports"]["verdict"] == "warn"      # no units, optional outputs absent
    for cid in ("filter.consistency", "robust.noise_step", "robust.outage"):
        assert "run failed" not in checks[cid]["measured"], checks[cid]
    nees = checks["filter.consistency"]["details"]
    assert math.isfinite(nees["nees_position"]) and "nees_attitude" not in nees
    text = (out / "verify.md").read_text()
    assert "| filter.consistency |" in text
    assert junit.read_text().count("<testcase") == len(checks)


def test_crashing_fmu_crashes_its_checks_and_the_report_is_written(broken, navfmu_cli,
                                                                   tmp_path):
    out = tmp_path / "report"
    status, stdout, err = navfmu_cli("verify", broken / "CrashingKf.fmu", "--runs", 1,
                                     "--out", out)
    assert status == 1
    checks = {c["id"]: c for c in json.loads((out / "verify.json").read_text())["checks"]}
    # a probe or run whose host dies (twice: retried once) is a crash, not a fail on merits
    for cid in ("fmi.state", "fmi.variable_step", "filter.closure", "filter.consistency",
                "robust.outage"):
        assert checks[cid]["verdict"] == "crash", checks[cid]
        assert "SIGABRT" in checks[cid]["reason"] and "retried once" in checks[cid]["reason"]
    assert checks["filter.closure"]["details"]["failure"]["crashed"]
    assert "crash" in stdout.splitlines()[-1]
    assert (out / "verify.md").is_file()


@pytest.mark.slow
@pytest.mark.parametrize("name,meant,also", [
    ("OverconfidentKf", "filter.consistency", set()),
    # an unmodelled 2 |omega_ie x v| ~ 0.015 m/s^2 is a real fault everywhere the INS counts:
    # its velocity and attitude NEES leave the band and it drifts through the outage too
    ("WrongCoriolisKf", "filter.closure", {"filter.consistency", "robust.outage"}),
    ("IgnoresValidKf", "robust.outage", set()),
    ("InexactRestoreKf", "fmi.state", set())])
def test_broken_filter_fails_its_check_in_a_full_verification(broken, navfmu_cli, tmp_path,
                                                              name, meant, also):
    out = tmp_path / name
    status, _, _ = navfmu_cli("verify", broken / f"{name}.fmu", "--runs", 3, "--out", out)
    checks = json.loads((out / "verify.json").read_text())["checks"]
    assert status == 1
    assert {c["id"] for c in checks if c["verdict"] == "fail"} == {meant} | also



CHILD = """
import json, os, sys
if json.load(open(sys.argv[1]))["write"]:
    print(json.dumps({"rms_m": 1.5}), flush=True)
os.abort()
"""


def test_a_crash_at_exit_after_the_result_is_a_warning_not_a_failed_run(tmp_path, monkeypatch):
    """A child that wrote its result and then died (a pythonfmu binary without the exit hook
    corrupting the heap at exit) gives its result and a warning naming the signal; one that
    died before writing it is a crashed run."""
    from orchestrator.errors import NavfmuWarning
    from orchestrator.verification.verdicts import run_child

    (tmp_path / "aborting_child.py").write_text(CHILD)
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    with pytest.warns(NavfmuWarning, match=r"Filter\.fmu: the host process ended with "
                                           r"SIGABRT at exit, after the run had written"):
        assert run_child("aborting_child", {"fmu": "/x/Filter.fmu", "write": True}) == {
            "rms_m": 1.5}
    result = run_child("aborting_child", {"fmu": "/x/Filter.fmu", "write": False})
    assert result["crashed"] and "SIGABRT" in result["error"]
