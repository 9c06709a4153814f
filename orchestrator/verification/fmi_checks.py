"""The FMI checks every role gets: ``fmpy validate``, the contract's ports, the declared
state and variable-step capabilities, and hostile host calls.

The checks that load the FMU run in a child process (:mod:`.fmi_probe`), so an FMU that
crashes its host gets the verdict ``crash`` on them (retried once; for ``fmi.hostile``,
whose criterion is that the host lives on, it fails) and the verification goes on.
"""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import List

import numpy as np

from ..cosim import interrupts
from .roles import ROLE_TITLES, contract
from .setting import Setting, input_table
from .run_failures import crash_failure
from .verdicts import Check, run_child

PROBE_MODULE = "orchestrator.verification.fmi_probe"
#: communication steps merged into one by the variable-step check
VARIABLE_STEP_FACTOR = 5


def check_validate(setting: Setting) -> Check:
    from fmpy.validation import validate_fmu

    try:
        problems = [str(p) for p in validate_fmu(str(setting.facts.path))]
    except Exception as exc:  # fmpy raises plain exceptions for broken archives
        problems = [f"fmpy cannot validate the FMU: {exc}"]
    return Check("fmi.validate", "fmpy validate", "fmpy.validation reports no problem",
                 f"{len(problems)} problem(s)", "fail" if problems else "pass",
                 "; ".join(problems[:5]) + (" ..." if len(problems) > 5 else ""),
                 {"problems": problems})


def check_ports(setting: Setting) -> Check:
    facts, role = setting.facts, setting.role
    wrong, missing_required, missing_optional, no_unit = [], [], [], []
    for port in contract(role):
        var = facts.variables.get(port.name)
        if var is None:
            (missing_required if port.required else missing_optional).append(port.name)
            continue
        if var.causality != port.causality or var.type != port.type:
            wrong.append(f"{port.name} is a {var.causality} {var.type}, the contract asks "
                         f"for a {port.causality} {port.type}")
        elif port.type == "Real" and port.unit and not var.unit:
            no_unit.append(port.name)
        elif port.type == "Real" and var.unit != port.unit:
            wrong.append(f"{port.name} has unit '{var.unit}', the contract's is "
                         f"'{port.unit}'")
    details = {"missing_required": missing_required, "missing_optional": missing_optional,
               "wrong": wrong, "no_unit": no_unit}
    measured = (f"{len(missing_required)} required missing, {len(wrong)} wrong, "
                f"{len(no_unit)} without unit, {len(missing_optional)} optional missing")
    reasons = []
    if missing_required:
        reasons.append("missing: " + ", ".join(missing_required))
    reasons += wrong
    if no_unit:
        reasons.append(f"{len(no_unit)} Reals declare no unit (the contract's are SI), e.g. "
                       + ", ".join(no_unit[:4]))
    if missing_optional:
        reasons.append("optional outputs absent (checks needing them are skipped): "
                       + ", ".join(missing_optional))
    verdict = ("fail" if missing_required or wrong
               else ("warn" if missing_optional or no_unit else "pass"))
    return Check("fmi.ports", f"contract ports of an {ROLE_TITLES[role]}",
                 "every required port with the contract's causality, type and SI unit",
                 measured, verdict, "; ".join(reasons), details)


def _probe(setting: Setting, probe: str, table_file: Path, h: float, **extra):
    job = {"fmu": str(setting.facts.path), "probe": probe, "table": str(table_file), "h": h,
           "parameters": setting.parameters, **extra}
    interrupts.safe_point("verify-probe")   # a Ctrl-C stops between the probes
    result = run_child(PROBE_MODULE, job)
    if result.get("crashed") and probe != "hostile":    # a crash is retried once
        result = run_child(PROBE_MODULE, job)
        if result.get("crashed"):
            result["error"] += " (twice: retried once)"
    return result


def _probe_failed(cid: str, title: str, criterion: str, result) -> Check:
    """The check of a probe that did not finish: ``crash`` when its host died (twice), not a
    judgement of the criterion; ``fail`` when the FMU refused or raised."""
    if result.get("crashed"):
        failure = crash_failure(result["error"])
        return Check(cid, title, criterion, "host crashed", "crash",
                     f"{result['error']}; try: {failure['hint']}", result)
    return Check(cid, title, criterion, "probe failed", "fail", result["error"], result)


def _state_check(setting: Setting, result) -> Check:
    facts = setting.facts
    criterion = ("after fmi2SetFMUstate, and after fmi2DeSerializeFMUstate into a new instance, "
                 "the outputs continue bit-identical")
    if not facts.can_get_set_state:
        return Check("fmi.state", "FMU state restore", criterion, "not declared", "skip",
                     "canGetAndSetFMUstate is false: nothing to check")
    if "error" in result:
        return _probe_failed("fmi.state", "FMU state restore", criterion, result)
    bad = [f"{what}: {result[what]['what']}" for what in ("set_state", "deserialize")
           if result.get(what)]
    measured = ("bit-identical" if not bad else "differs") + (
        f" over {result['steps'] - result['steps'] // 2} steps after t = "
        f"{result['restored_at_s']:g} s")
    reason = "; ".join(bad)
    if not facts.can_serialize_state:
        reason = (reason + "; " if reason else "") + "canSerializeFMUstate false: not checked"
    return Check("fmi.state", "FMU state restore", criterion, measured,
                 "fail" if bad else "pass", reason, result)


def _variable_step_check(setting: Setting, result) -> Check:
    k = VARIABLE_STEP_FACTOR
    criterion = (f"{k} steps of one period equal one step of {k} periods (all outputs bit "
                 "for bit at the common instants)")
    if not setting.facts.can_variable_step:
        return Check("fmi.variable_step", "variable communication step", criterion,
                     "not declared", "skip", "canHandleVariableCommunicationStepSize is false")
    if "error" in result:
        return _probe_failed("fmi.variable_step", "variable communication step", criterion,
                             result)
    diff = result["difference"]
    return Check("fmi.variable_step", "variable communication step", criterion,
                 "equal" if diff is None else "differs", "pass" if diff is None else "fail",
                 "" if diff is None else diff["what"], result)


def _hostile_check(result) -> Check:
    criterion = ("an unknown value reference, a set of an output and a step back in time each "
                 "return fmi2Discard or worse; the host process lives on")
    if "error" in result:      # the host died, or the probe could not make its instances
        return Check("fmi.hostile", "hostile host calls", criterion,
                     "host ended" if result.get("crashed") else "probe failed", "fail",
                     result["error"], result)
    statuses = result["statuses"]
    accepted = [name for name, status in statuses.items()
                if status < result["error_status_from"]]
    measured = ", ".join(f"{name}: status {status}" for name, status in statuses.items())
    return Check("fmi.hostile", "hostile host calls", criterion, measured,
                 "fail" if accepted else "pass",
                 ("accepted without an error status: " + ", ".join(accepted)) if accepted
                 else "", result)


def run_fmi_checks(setting: Setting) -> List[Check]:
    """All FMI checks of ``setting`` (the probes in child processes, one after the other)."""
    checks = [check_validate(setting), check_ports(setting)]
    table, h = input_table(setting)
    with tempfile.TemporaryDirectory(prefix="navfmu_verify_table_") as tmp:
        table_file = Path(tmp) / "inputs.npz"
        np.savez(table_file, **table)
        state = (_probe(setting, "state", table_file, h)
                 if setting.facts.can_get_set_state else {})
        checks.append(_state_check(setting, state))
        variable = (_probe(setting, "variable_step", table_file, h, k=VARIABLE_STEP_FACTOR)
                    if setting.facts.can_variable_step else {})
        checks.append(_variable_step_check(setting, variable))
        checks.append(_hostile_check(_probe(setting, "hostile", table_file, h)))
    return checks


__all__ = ["run_fmi_checks", "check_validate", "check_ports"]
