"""``navfmu verify`` on a catalogue of broken filters written without navfmu: the
independent reference EKF of tests/verify_fmus/RefEkf.py (plain pythonfmu and numpy) passes
every check its variants are meant to fail, and each variant, carrying one realistic bug,
fails the check meant to catch it (one seed; each FMU runs only the cases that decide)."""
from __future__ import annotations

import pytest

from orchestrator.campaigns.executor import Executor, Task
from orchestrator.verification import filter_checks, roles
from orchestrator.verification.fmi_checks import run_fmi_checks
from orchestrator.verification.scenario_run import run_job
from orchestrator.verification.setting import make_setting

from verify_helpers import build_reference_filters, reference_name

#: bug -> (the check that must fail, the cases whose runs decide it; None: the FMI probes)
CATALOGUE = {
    "lever_sign": ("filter.lever_arm", {"lever_arm", "consistency"}),
    "no_bias_feedback": ("robust.mems_imu", {"mems_imu"}),
    "ne_swap": ("filter.closure", {"closure"}),
    "time_tag": ("robust.late_fixes", {"late_fixes"}),
    "overconfident": ("filter.consistency", {"consistency"}),
    "underconfident": ("filter.consistency", {"consistency"}),
    "forgets_covariance": ("fmi.state", None),
    "nan_after_gap": ("robust.outage", {"outage"}),
    "crash": ("filter.closure", {"closure"}),
}


@pytest.fixture(scope="session")
def catalogue(tmp_path_factory):
    return build_reference_filters(tmp_path_factory.mktemp("ref_ekf"), ["", *CATALOGUE])


def _checks(path, names):
    """The verdicts of the FMU ``path`` on the filter cases ``names`` (one seed) or, for
    None, on the FMI probes."""
    facts = roles.read_fmu(path)
    setting = make_setting(facts, roles.detect_role(facts))
    if names is None:
        return {c.id: c for c in run_fmi_checks(setting)}
    planned = filter_checks.plan(setting, 1)
    cases = [c for c in planned.cases if c.name in names]
    jobs = [j for j in planned.jobs if j[0][0] in names]
    with Executor() as ex:
        results = dict(ex.run([Task(k, run_job, (job, iso)) for k, job, iso in jobs]))
    return {c.id: c for c in filter_checks.judge(cases, results) if c.id != "filter.timing"}


#: the reference filter's runs, grouped as its variants need them (a test each, < 20 s)
REFERENCE_GROUPS = {"fmi": None, **{bug: cases for bug, (_, cases) in CATALOGUE.items()
                                    if cases and bug not in ("underconfident", "crash")}}


@pytest.mark.parametrize("group", sorted(REFERENCE_GROUPS))
def test_reference_filter_passes(catalogue, group):
    """The good filter passes every check its variants fail (on the same cases)."""
    checks = _checks(catalogue / "RefEkf.fmu", REFERENCE_GROUPS[group])
    meant = [m for m, cases in CATALOGUE.values() if cases == REFERENCE_GROUPS[group]]
    assert set(meant) <= set(checks)
    bad = {cid: (c.verdict, c.measured, c.reason) for cid, c in checks.items()
           if c.verdict not in ("pass", "warn") and cid != "fmi.hostile"}
    assert not bad
    if group == "lever_sign":   # the lever arm handled: the errors of an antenna at the IMU
        assert checks["filter.lever_arm"].details["ratio"] < 1.1
    if group == "fmi":          # plain pythonfmu accepts a set of an output
        assert checks["fmi.hostile"].verdict == "fail"
        assert checks["fmi.validate"].verdict == checks["fmi.state"].verdict == "pass"


@pytest.mark.parametrize("bug", sorted(CATALOGUE))
def test_broken_reference_filter_fails_its_check(catalogue, bug):
    meant, names = CATALOGUE[bug]
    checks = _checks(catalogue / f"{reference_name(bug)}.fmu", names)
    check = checks[meant]
    assert check.verdict == "fail", (check.measured, check.reason)
    if bug == "lever_sign":        # the arm's sign flipped: 2 |l| = 9.2 m of error
        assert check.details["ratio"] > 3.0
    if bug in ("overconfident", "underconfident"):
        nees = check.details["nees_position"]
        assert nees > 6.75 if bug == "overconfident" else nees < 0.75
    if bug == "crash":             # where, why and what to try, from the FMU's log
        failure = check.details["failure"]
        assert failure["time"] == pytest.approx(5.0)
        assert "fmi2DoStep" in failure["call"]
        assert "LinAlgError('Matrix is not positive definite')" == failure["exception"]
        assert "t = 5 s" in check.reason and "try:" in check.reason
    if bug == "nan_after_gap":
        # the first fix after the 30 s outage (140-170 s)
        assert "non-finite" in check.reason
        assert 170.0 <= check.details["failure"]["time"] <= 171.0
