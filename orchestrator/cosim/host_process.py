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
from pathlib import Path
from typing import Any, Dict

from ..building.build import ROOT

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
    if proc.returncode == 0 and lines:
        try:
            return json.loads(lines[-1])
        except json.JSONDecodeError:
            pass
    last = (proc.stderr.strip().splitlines() or ["no message"])[-1]
    return {"error": f"the host process ended with {ending(proc.returncode)} "
                     f"({last[:300]})", "crashed": True}


__all__ = ["CHILD_TIMEOUT_S", "child_environment", "ending", "run_child"]
