"""A check's verdict and the child processes the checks that load the FMU run in.

Verdicts: ``pass``, ``fail``, ``warn`` (worth a look, does not fail the verification) and
``skip`` (the FMU lacks what the check needs, e.g. an optional output; never a fail).
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Dict, Optional

from ..building.build import ROOT
from ..errors import NavfmuWarning

VERDICTS = ("pass", "fail", "warn", "skip")
#: longest a child process may take before it counts as hung [s]
CHILD_TIMEOUT_S = 900.0


@dataclass
class Check:
    """One check: what it measures, its criterion, what it measured and the verdict with the
    reason (every fail, warn and skip says why)."""

    id: str
    title: str
    criterion: str
    measured: str
    verdict: str
    reason: str = ""
    details: Dict[str, Any] = field(default_factory=dict)
    figure: Optional[str] = None

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict {self.verdict!r} is not one of {VERDICTS}")

    def as_dict(self):
        return asdict(self)


def _ending(returncode: int) -> str:
    if returncode < 0:
        try:
            return f"signal {signal.Signals(-returncode).name}"
        except ValueError:
            return f"signal {-returncode}"
    return f"exit status {returncode}"


def run_child(module: str, job: Dict[str, Any], timeout: float = CHILD_TIMEOUT_S
              ) -> Dict[str, Any]:
    """Run ``python -m module JOB.json`` and return the JSON of its last stdout line; when
    the child dies first (an FMU that crashes its host) or hangs, ``{"error": ...}`` says how
    it ended, with the last line it wrote to stderr."""
    with tempfile.TemporaryDirectory(prefix="navfmu_verify_") as tmp:
        job_file = Path(tmp) / "job.json"
        job_file.write_text(json.dumps(job), encoding="utf-8")
        env = dict(os.environ)
        paths = [str(ROOT), str(ROOT / "fmus")]
        env["PYTHONPATH"] = os.pathsep.join(paths + [p for p in env.get("PYTHONPATH", "")
                                                     .split(os.pathsep) if p])
        try:
            proc = subprocess.run([sys.executable, "-m", module, str(job_file)], cwd=tmp,
                                  capture_output=True, text=True, timeout=timeout, env=env)
        except subprocess.TimeoutExpired:
            return {"error": f"the host process did not finish within {timeout:.0f} s"}
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    last = (proc.stderr.strip().splitlines() or ["no message"])[-1]
    result = _result(lines[-1]) if lines else None
    if result is not None and proc.returncode != 0:
        _warn_crash_at_exit(job, proc.returncode, last)
    if result is not None:
        return result
    return {"error": f"the host process ended with {_ending(proc.returncode)} "
                     f"({last[:300]})", "crashed": True}


def _result(line: str) -> Optional[Dict[str, Any]]:
    try:
        return json.loads(line)
    except json.JSONDecodeError:
        return None


def _warn_crash_at_exit(job: Dict[str, Any], returncode: int, last: str) -> None:
    """The child wrote its result (its last act) and then died: a crash in the process's
    exit, not in the run the check judges (e.g. a pythonfmu binary without navfmu's exit
    hook resetting its freed interpreter owner, docs/guide/reliability.md).  The result
    counts; the warning says what happened."""
    warnings.warn(f"verify: {Path(str(job.get('fmu', '?'))).name}: the host process ended with "
                  f"{_ending(returncode)} at exit, after the run had written its result "
                  f"({last[:200]}); the result counts, the crash is of the process's exit",
                  NavfmuWarning, stacklevel=3)


__all__ = ["Check", "VERDICTS", "run_child"]
