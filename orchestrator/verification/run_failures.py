"""Why a run of a verification failed, where, and what to try: the simulated time, the FMI
call, the FMU's own logged message and the Python exception it raised (pythonfmu logs it as
``Fatal py exception encountered: [doStep] ...`` with the exception's repr on the next line),
or how its host process ended.

:func:`failure_of` turns the error of a run (:class:`~orchestrator.errors.SimulationError`
and its kin) into a plain dict, which travels in the run's summary as ``failure``;
:func:`one_line` is the summary's line of it, :func:`full_text` the whole of it for
``verify.json`` and JUnit.  A *crash* (the host process died: a signal, an abort) is told
apart from a refused step or an exception: the judges give it its own verdict.
"""
from __future__ import annotations

import re
from typing import Any, Dict, Optional

#: log lines of the failing component kept in a failure
LOG_LINES_KEPT = 20
_CALL = re.compile(r"\((fmi2\w+[^)]*?) failed(?: with status (\w+))?")
_PY_EXCEPTION = "py exception encountered"


def _exception_text(log) -> Optional[str]:
    """The Python exception of a pythonfmu slave from its log (its repr), or a traceback's
    last line."""
    for line in log:
        if _PY_EXCEPTION in line:
            rest = line.split("\n", 1)[1:]
            if rest and rest[0].strip():
                return rest[0].strip()
        if "Traceback (most recent call last)" in line:
            tail = [ln.strip() for ln in line.splitlines() if ln.strip()]
            return tail[-1] if tail else None
    return None


def hint(failure: Dict[str, Any]) -> str:
    """What to try next for ``failure``."""
    where = f" --stop {failure['time'] + 1:g}" if failure.get("time") is not None else ""
    if failure.get("crashed"):
        return ("the host process died (retried once): a fault in the FMU's binary or in a "
                "library it loads; run the scenario with this FMU as the filter "
                f"(navfmu run SCENARIO --filter FMU{where}) under a debugger or with "
                "PYTHONFAULTHANDLER=1")
    if failure.get("exception"):
        return ("the FMU's code raised it: run the scenario with this FMU as the filter "
                f"(navfmu run SCENARIO --filter FMU{where}) and read the FMU's log, or call "
                "the slave class's do_step in Python with the inputs of that time")
    if failure.get("nonfinite"):
        return ("an output became NaN or inf: look for a division, square root or matrix "
                "inverse on a value that a gap, a first fix or a zero step makes singular")
    return ("the FMU refused a call: its logged message says why; the filter contract is in "
            "docs/guide/filters.md")


def failure_of(exc: BaseException) -> Dict[str, Any]:
    """The failure of a run that raised ``exc`` (module docstring)."""
    lines = str(exc).splitlines() or [type(exc).__name__]
    log = tuple(getattr(exc, "log", ()) or ())
    call = status = None
    for line in lines[1:]:
        m = _CALL.search(line)
        if m:
            call, status = m.group(1), m.group(2)
            break
    failure = {"error": lines[0], "component": getattr(exc, "component", "") or None,
               "time": getattr(exc, "time", None), "call": call, "status": status,
               "exception": _exception_text(log), "log": list(log[-LOG_LINES_KEPT:])}
    failure["hint"] = hint(failure)
    return failure


def crash_failure(error: str) -> Dict[str, Any]:
    """The failure of a run whose host process died (``error`` says how it ended)."""
    failure = {"error": error, "crashed": True, "time": None, "call": None, "exception": None,
               "log": []}
    failure["hint"] = hint(failure)
    return failure


def one_line(failure: Dict[str, Any]) -> str:
    """``t = 5 s, fmi2DoStep ...: LinAlgError(...) (the FMU's message); try: ...``."""
    parts = []
    if failure.get("time") is not None:
        parts.append(f"t = {failure['time']:g} s")
    if failure.get("call"):
        parts.append(failure["call"] + (f" -> {failure['status']}" if failure.get("status")
                                        else ""))
    what = failure.get("exception") or failure["error"]
    if failure.get("exception"):
        what += f" (FMU log: {failure['error']})"
    head = ", ".join(parts)
    return (f"{head}: " if head else "") + f"{what}; try: {failure['hint']}"


def full_text(failure: Dict[str, Any]) -> str:
    """Every field of ``failure``, the FMU's log last."""
    rows = [f"{k}: {failure[k]}" for k in ("error", "component", "time", "call", "status",
                                           "exception", "hint") if failure.get(k) is not None]
    if failure.get("log"):
        rows.append("FMU log:\n  " + "\n  ".join(failure["log"]))
    return "\n".join(rows)


__all__ = ["failure_of", "crash_failure", "one_line", "full_text", "hint"]
