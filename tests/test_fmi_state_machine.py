"""FMI 2.0's call sequence guarded in the patched library: calls out of sequence, on a freed
instance or with a freed FMU state return fmi2Error with one logged line, never crash the host;
a wrong GUID creates no instance; a refused input is fmi2Error naming the input and the time.

Each FMU runs tests/fmi_state_probe.py in a process of its own (a double free or a use after
free kills that process, and the test names the case it died in).  A sensor, a Kf-family and a
UKF filter, and the replay (which has no Real input: its NaN case is skipped).
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from orchestrator.building import build as fmu_build
from test_native_library import require_patched

OK, DISCARD, ERROR = 0, 2, 3
FMUS = ["GnssReceiver", "Kf", "Ukf", "ImuGnssReplay"]


@pytest.fixture(scope="module", params=FMUS)
def probe(request, tmp_path_factory):
    name = request.param
    fmu_build.build([name], log=None)
    require_patched(fmu_build.fmu_path(name))
    out = tmp_path_factory.mktemp("state_probe") / f"{name}.jsonl"
    proc = subprocess.run([sys.executable, str(Path(__file__).with_name("fmi_state_probe.py")),
                           str(fmu_build.fmu_path(name)), str(out)],
                          capture_output=True, text=True, timeout=300)
    cases, started = {}, None
    for line in out.read_text().splitlines() if out.exists() else []:
        record = json.loads(line)
        if record.get("started"):
            started = record["case"]
        else:
            cases[record["case"]], started = record, None
    return name, cases, proc, started


def _case(probe, case):
    name, cases, proc, started = probe
    if case not in cases:
        pytest.fail(f"{name}: the host process died in case {started!r} (return code "
                    f"{proc.returncode}): {proc.stderr[-2000:]}")
    return cases[case]


def _one_error_line(result, *words):
    """Exactly one message of status Error on one line, holding ``words``."""
    errors = [m for s, m in result["logs"] if s == ERROR]
    assert len(errors) == 1, result["logs"]
    assert "\n" not in errors[0].strip() and all(w in errors[0] for w in words), errors[0]


def test_free_instance_twice_is_harmless(probe):
    result = _case(probe, "free_instance_twice")
    assert result["after"]["get_after"] == ERROR       # the freed instance is refused
    assert result["logs"] == []                        # nothing logged through a freed instance


def test_get_real_after_free_instance_is_error(probe):
    result = _case(probe, "get_real_after_free_instance")
    assert result["status"] == ERROR and result["logs"] == []


def test_freed_fmu_state_is_refused_everywhere(probe):
    result = _case(probe, "set_state_after_free_state")
    assert result["status"] == ERROR
    assert result["after"]["serialize_size"] == ERROR and result["after"]["free_again"] == ERROR
    assert result["after"]["step_after"] == OK        # the instance kept its state and steps
    assert [s for s, _ in result["logs"]] == [ERROR] * 3
    assert "fmi2SetFMUstate" in result["logs"][0][1] and "freed" in result["logs"][0][1]


def test_state_of_a_freed_instance_is_refused(probe):
    result = _case(probe, "state_of_a_freed_instance")
    assert result["status"] == ERROR and result["after"]["step_after"] == OK
    _one_error_line(result, "fmi2SetFMUstate", "unknown or was freed")


@pytest.mark.parametrize("case, call, state, after", [
    ("do_step_before_exit_initialization", "fmi2DoStep", "initializationMode",
     {"exit_after": OK}),
    ("do_step_after_terminate", "fmi2DoStep", "terminated", {"get_after": OK}),
    ("enter_initialization_twice", "fmi2EnterInitializationMode", "initializationMode",
     {"exit_after": OK, "step_after": OK}),
    ("setup_experiment_after_initialization", "fmi2SetupExperiment", "stepComplete",
     {"step_after": OK}),
    ("get_real_when_instantiated", "fmi2GetReal", "instantiated", {}),
    ("set_real_after_terminate", "fmi2SetReal", "terminated", {}),
    ("terminate_twice", "fmi2Terminate", "terminated", {}),
])
def test_call_out_of_sequence_is_error_naming_call_and_state(probe, case, call, state, after):
    """fmi2Error and one line naming the call and the state; the state stays, so the legal
    call after it works."""
    result = _case(probe, case)
    assert result["status"] == ERROR
    _one_error_line(result, f"{call} is not allowed in state {state}")
    assert result["after"] == after


def test_reset_returns_to_instantiated(probe):
    result = _case(probe, "reset_returns_to_instantiated")
    assert result["status"] == OK
    assert result["after"] == {"step_early": ERROR, "setup": OK, "enter": OK, "exit": OK,
                               "step_after": OK}
    _one_error_line(result, "fmi2DoStep is not allowed in state instantiated")


def test_wrong_guid_creates_no_instance(probe):
    result = _case(probe, "wrong_guid")
    assert result["after"]["instantiated"] is False
    _one_error_line(result, "GUID '{00000000-0000-0000-0000-000000000000}'", "not this FMU's")


def test_nan_input_is_error_naming_the_input_and_time(probe):
    name = probe[0]
    result = _case(probe, "nan_input")
    if result["after"].get("skipped"):
        pytest.skip(f"{name} has no Real input")
    assert result["status"] == ERROR
    first = result["logs"][0]
    assert first[0] == ERROR and "= nan" in first[1] and "(at t = 0 s)" in first[1], first
    assert "'imu_dvel_z'" in first[1] or "'truth_lat'" in first[1]
    assert "\n" not in first[1].strip()
    after = result["after"]
    # the instance is in the error state: a step is refused naming that error, a get and a
    # reset work
    assert after["step_again"] == ERROR and after["get_after"] == OK and after["reset"] == OK
    (again,) = after["again_logs"]
    assert "fmi2DoStep is not allowed in state error" in again[1] and "= nan" in again[1]
