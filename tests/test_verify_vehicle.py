"""``navfmu verify`` on vehicles written without navfmu: the kinematic aircraft of
tests/verify_fmus/KinematicAircraft.py (plain pythonfmu, no numpy) passes the vehicle checks
and flies through ImuSensor -> GnssReceiver -> Kf, and each variant, carrying one realistic
bug, fails the check meant to catch it (recordings of 30 s, ``quick``; each test < 15 s)."""
from __future__ import annotations

import zipfile

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.campaigns.executor import Executor, Task
from orchestrator.verification import roles, vehicle_checks
from orchestrator.verification.fmi_checks import check_validate, run_fmi_checks
from orchestrator.verification.scenario_run import run_job
from orchestrator.verification.setting import make_setting

from verify_helpers import build_variants, variant_name

#: bug -> the check that must fail (the vehicle checks, or the FMI probes for fmi.*)
CATALOGUE = {
    "ne_swap": "vehicle.velocity",
    "rate_sign": "vehicle.body_rates",
    "no_gravity": "vehicle.specific_force",
    "nan_until_step": "vehicle.initial_outputs",
    "euler_step": "vehicle.step_size",
    "restore_forgets": "fmi.state",
    "project_module": "fmi.state",
}
KINEMATIC = ("vehicle.initial_outputs", "vehicle.velocity", "vehicle.body_rates",
             "vehicle.specific_force", "vehicle.step_size")


@pytest.fixture(scope="session")
def aircraft(tmp_path_factory):
    return build_variants(tmp_path_factory.mktemp("aircraft"), "KinematicAircraft",
                          ["", *CATALOGUE],
                          {"project_module": ["kinematic_aircraft_routes.py"]})


@pytest.fixture(scope="session")
def dist():
    fmu_build.build(log=None)
    return fmu_build.DIST


def _setting(path):
    facts = roles.read_fmu(path)
    return make_setting(facts, roles.detect_role(facts))


def _vehicle_checks(path, fly=False):
    """The vehicle checks of ``path`` on a quick recording; the flight only when ``fly``."""
    setting = _setting(path)
    planned = vehicle_checks.plan(setting, 1, quick=True)
    with Executor() as ex:
        results = dict(ex.run([Task(k, run_job, (job, iso)) for k, job, iso in planned.jobs]))
        follow = vehicle_checks.next_jobs(setting, planned, results)
        if fly:
            results.update(ex.run([Task(k, run_job, (job, iso)) for k, job, iso in follow]))
        else:
            results[follow[0][0]] = {"error": "not flown"}
    checks, _ = vehicle_checks.judge_plan(setting, planned, results, None)
    return {c.id: c for c in checks}


def test_the_role_is_vehicle(aircraft):
    assert roles.detect_role(roles.read_fmu(aircraft / "KinematicAircraft.fmu")) == "vehicle"


def test_good_aircraft_passes_and_flies(aircraft):
    checks = _vehicle_checks(aircraft / "KinematicAircraft.fmu", fly=True)
    bad = {cid: (c.verdict, c.measured, c.reason) for cid, c in checks.items()
           if c.verdict != "pass"}
    assert not bad
    assert checks["vehicle.step_size"].details["largest"]["position"] < 1e-6
    # the rates integrated over 30 s stay on the reported attitude (0.0003 deg measured)
    assert checks["vehicle.body_rates"].details["integrated_attitude_error_deg"] < 0.01
    rms = checks["vehicle.flight"].details["rms"]      # Kf on uav_mission's MEMS IMU: ~1 m
    assert 0.2 < rms["position"] < 3.0 and rms["velocity"] < 0.3


def test_guided_uav_passes_the_vehicle_checks(dist):
    """Our own vehicle (guided on its truth for the recording, turbulence on)."""
    checks = _vehicle_checks(dist / "GuidedUav.fmu")
    assert {cid: checks[cid].verdict for cid in KINEMATIC} == {cid: "pass" for cid in KINEMATIC}
    assert checks["vehicle.body_rates"].details["integrated_attitude_error_deg"] < 0.01


def test_good_aircraft_passes_the_fmi_checks(aircraft):
    checks = {c.id: c for c in run_fmi_checks(_setting(aircraft / "KinematicAircraft.fmu"))}
    for cid in ("fmi.validate", "fmi.ports", "fmi.state", "fmi.variable_step"):
        assert checks[cid].verdict == "pass", (cid, checks[cid].reason)


@pytest.mark.parametrize("bug", sorted(CATALOGUE))
def test_broken_aircraft_fails_its_check(aircraft, bug):
    meant = CATALOGUE[bug]
    path = aircraft / f"{variant_name('KinematicAircraft', bug)}.fmu"
    if meant.startswith("fmi."):
        checks = {c.id: c for c in run_fmi_checks(_setting(path))}
    else:
        checks = _vehicle_checks(path)
    check = checks[meant]
    assert check.verdict == "fail", (check.measured, check.reason)
    if meant.startswith("vehicle."):      # the kinematics fail only where the bug is
        others = {cid: checks[cid].verdict for cid in KINEMATIC if cid != meant}
        expected = {"vehicle.specific_force": "fail"} if bug == "ne_swap" else {}
        assert {k: v for k, v in others.items() if v != "pass"} == expected
    if bug == "rate_sign":
        assert checks[meant].details["integrated_attitude_error_deg"] > 90
    if bug == "no_gravity":                # the whole of gravity is missing
        assert 9.7 < checks[meant].details["max_mismatch"] < 9.9
    if bug == "euler_step":                # and 5 steps are not one of 5 periods
        assert checks[meant].details["largest"]["position"] > 0.1
        fmi = {c.id: c for c in run_fmi_checks(_setting(path))}
        assert fmi["fmi.variable_step"].verdict == "fail"
    if bug == "project_module":            # one line naming the cause and the remedy
        assert "second instance" in check.reason and "sys.modules" in check.reason
        assert "authoring_fmus.md" in check.reason and "\n" not in check.reason


def test_validate_fails_without_initial_unknowns(aircraft, tmp_path):
    """The aircraft's model description without the InitialUnknowns it adds (pythonfmu 0.7
    writes none): fmi.validate fails, as docs/guide/authoring_fmus.md says."""
    good = aircraft / "KinematicAircraft.fmu"
    bare = tmp_path / "KinematicAircraft.fmu"
    with zipfile.ZipFile(good) as src, zipfile.ZipFile(bare, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                start, end = text.index("<InitialUnknowns>"), text.index("</InitialUnknowns>")
                data = (text[:start] + text[end + len("</InitialUnknowns>"):]).encode()
            dst.writestr(item, data)
    assert check_validate(_setting(good)).verdict == "pass"
    check = check_validate(_setting(bare))
    assert check.verdict == "fail" and "InitialUnknowns" in check.reason
