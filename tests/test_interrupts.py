"""Ctrl-C during `navfmu run`: always `navfmu: interrupted`, exit 130, never an FMU fault and
never a partial output folder.

Real processes get a SIGINT: half at a random time after the three FMUs were extracted (into
the process's own TMPDIR: the run is instantiating and stepping them; pythonfmu runs the slaves
in the process's interpreter, so an undeferred KeyboardInterrupt would land inside an FMU),
half at a random time after the staging folder of the outputs appeared (the files are being
written).  Afterwards the output folder is absent or complete (every file its marker lists,
nothing else) and no staging folder is left.  The default run interrupts 2 processes, the
slow test 20.
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.results.outputs import MARKER

MODEL = fmu_build.ROOT / "models" / "aircraft_500s"
PARALLEL = 4


@pytest.fixture(scope="module", autouse=True)
def _fmus():
    fmu_build.build(log=None)


def _env(tmp):
    env = dict(os.environ)
    env["TMPDIR"] = str(tmp)
    env["PYTHONPATH"] = os.pathsep.join([str(fmu_build.FMU_SOURCES), str(fmu_build.ROOT),
                                         env.get("PYTHONPATH", "")])
    return env


def _start(out, tmp):
    return subprocess.Popen([sys.executable, "-m", "orchestrator.cli", "run", str(MODEL),
                             "--stop", "30", "--out", str(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env=_env(tmp))


def _staging(folder, name):
    return [p for p in folder.iterdir() if p.name.startswith(f".{name}.")]


def _wait_for(proc, ready):
    deadline = time.monotonic() + 120
    while not ready():
        if proc.poll() is not None or time.monotonic() > deadline:
            return False
        time.sleep(0.005)
    return True


def _interrupt(proc, out, tmp, phase, rng):
    """Send SIGINT in ``phase`` ('stepping': a random time after the FMUs were extracted;
    'writing': a random time after the staging folder appeared); False if the process ended
    first."""
    if phase == "stepping":
        ready = _wait_for(proc, lambda: len(list(tmp.iterdir())) >= 3)
        delay = rng.uniform(0.0, 1.5)
    else:
        ready = _wait_for(proc, lambda: _staging(out.parent, out.name))
        delay = rng.uniform(0.0, 0.4)
    if not ready:
        return False
    time.sleep(delay)
    if proc.poll() is not None:
        return False
    proc.send_signal(signal.SIGINT)
    return True


def _check(proc, out):
    err = proc.stderr.read()
    code = proc.wait(timeout=120)
    assert code == 130, err
    assert err.strip().splitlines()[-1] == "navfmu: interrupted", err
    assert "Traceback" not in err and "Fatal" not in err and "navfmu: error" not in err, err
    if out.exists():  # interrupted after the move: complete
        listed = set((out / MARKER).read_text().split())
        assert {p.name for p in out.iterdir()} == listed | {MARKER}
    assert not _staging(out.parent, out.name)


def _one_run(tmp_path, i, phase, delay_seed):
    """Start run ``i``, interrupt it in ``phase``, check the outcome; returns whether the
    interrupt was sent before the run ended."""
    folder, tmp = tmp_path / f"run{i}", tmp_path / f"tmp{i}"
    folder.mkdir()
    tmp.mkdir()
    out = folder / "out"
    proc = _start(out, tmp)
    if not _interrupt(proc, out, tmp, phase, random.Random(delay_seed)):
        proc.wait(timeout=120)
        return False
    _check(proc, out)
    return True


def _interrupt_runs(tmp_path, runs_per_phase, seed):
    """``runs_per_phase`` runs interrupted while stepping and as many while writing, PARALLEL
    at a time (one thread watches each process)."""
    phases = ["stepping", "writing"] * runs_per_phase
    with ThreadPoolExecutor(PARALLEL) as pool:
        done = list(pool.map(lambda ip: _one_run(tmp_path, ip[0], ip[1], seed * 1000 + ip[0]),
                             enumerate(phases)))
    interrupted = {p: sum(d for d, q in zip(done, phases) if q == p) for p in set(phases)}
    assert interrupted == {"stepping": runs_per_phase, "writing": runs_per_phase}


def test_sigint_while_stepping_and_while_writing(tmp_path):
    _interrupt_runs(tmp_path, 1, seed=13)


@pytest.mark.slow
def test_sigint_twenty_times(tmp_path):
    _interrupt_runs(tmp_path, 10, seed=20)
