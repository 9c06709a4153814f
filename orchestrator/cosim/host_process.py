"""Child processes that load FMUs for the master, so that an FMU which crashes or hangs ends
that child, not navfmu: the environment they run in, how one ended in words, and one-shot jobs.

Two kinds use it: the FMU host of a foreign FMU (:mod:`orchestrator.cosim.fmu_host`, a
process that lives as long as the instance and answers one request per FMI call or step) and
``navfmu verify``'s probes and scenario runs (:mod:`orchestrator.verification`), one job
each: ``python -m MODULE JOB.json``, whose answer is the last line it prints (JSON).
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any, Dict

from ..building.build import ROOT
from ..errors import NavfmuWarning

#: longest a one-shot child may take before it counts as hung [s]
CHILD_TIMEOUT_S = 900.0


def child_environment() -> Dict[str, str]:
    """This process's environment with this installation's ``orchestrator`` (and the FMU
    sources' folder) first on ``PYTHONPATH``: the child runs the same navfmu as its parent."""
    env = dict(os.environ)
    paths = [str(ROOT), str(ROOT / "fmus")]
    env["PYTHONPATH"] = os.pathsep.join(paths + [p for p in env.get("PYTHONPATH", "")
                                                 .split(os.pathsep) if p])
    return env


def ending(returncode: int) -> str:
    """How a child ended, from its return code: ``SIGSEGV`` (killed by that signal) or
    ``exit status 3``."""
    if returncode < 0:
        try:
            return signal.Signals(-returncode).name
        except ValueError:
            return f"signal {-returncode}"
    return f"exit status {returncode}"


def run_child(module: str, job: Dict[str, Any], timeout: float = CHILD_TIMEOUT_S
              ) -> Dict[str, Any]:
    """Run ``python -m module JOB.json`` and return the JSON of its last stdout line; when
    the child dies first (an FMU that crashes its host) or hangs, ``{"error": ...}`` says how
    it ended, with the last line it wrote to stderr.  The child's temporary files (the FMUs
    it extracts) go into the job's folder, removed however the child ended."""
    with tempfile.TemporaryDirectory(prefix="navfmu_child_") as tmp:
        job_file = Path(tmp) / "job.json"
        job_file.write_text(json.dumps(job), encoding="utf-8")
        try:
            proc = subprocess.run([sys.executable, "-m", module, str(job_file)], cwd=tmp,
                                  capture_output=True, text=True, timeout=timeout,
                                  env=dict(child_environment(), TMPDIR=tmp))
        except subprocess.TimeoutExpired:
            return {"error": f"the host process did not finish within {timeout:.0f} s"}
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    last = (proc.stderr.strip().splitlines() or ["no message"])[-1]
    result = _result(lines[-1]) if lines else None
    if result is not None and proc.returncode != 0:
        _warn_crash_at_exit(job, proc.returncode, last)
    if result is not None:
        return result
    return {"error": f"the host process ended with {ending(proc.returncode)} "
                     f"({last[:300]})", "crashed": True}


def _result(line: str):
    try:
        return json.loads(line)
    except json.JSONDecodeError:
        return None


def _warn_crash_at_exit(job: Dict[str, Any], returncode: int, last: str) -> None:
    """The child wrote its result (its last act) and then died: a crash in the process's
    exit, not in the run it reports (e.g. a pythonfmu binary without navfmu's exit hook
    resetting its freed interpreter owner, docs/guide/reliability.md).  The result counts;
    the warning says what happened."""
    warnings.warn(f"{Path(str(job.get('fmu', '?'))).name}: the host process ended with "
                  f"{ending(returncode)} at exit, after the run had written its result "
                  f"({last[:200]}); the result counts, the crash is of the process's exit",
                  NavfmuWarning, stacklevel=3)


__all__ = ["CHILD_TIMEOUT_S", "child_environment", "ending", "run_child"]
