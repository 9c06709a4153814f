"""Ctrl-C during `navfmu run`: always `navfmu: interrupted`, exit 130, never an FMU fault and
never a partial output folder.

Real processes get a SIGINT at a chosen point, sent by the test hook
(:data:`~orchestrator.cosim.interrupts.SIGNAL_AT_ENV`; the process signals itself when it
passes that safe point): while the three FMUs step (the progress update at half the run's
steps; pythonfmu runs the slaves in the process's interpreter, so the signal must wait for the
master's safe point) and while the outputs are written (after the first file is in the staging
folder).  Afterwards no output folder exists (the signal came before the staging folder was
moved into place) and no staging folder is left.  The default run interrupts 2 processes; the
slow test the other points of stepping and of writing.  The hook signals at a safe point, so
that a signal arriving anywhere else (inside an FMU) waits for the next one is checked in the
process itself, by signals sent in the middle of a deferred block.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.cosim import interrupts
from orchestrator.cosim.interrupts import SIGNAL_AT_ENV

MODEL = fmu_build.ROOT / "models" / "aircraft_500s"
PARALLEL = 2


@pytest.fixture(scope="module", autouse=True)
def _fmus():
    fmu_build.build(log=None)


class _SignalNotDeferred(Exception):
    """Raised by the test's own handler, which the deferred block must replace."""


def _not_deferred(signum, frame):
    raise _SignalNotDeferred(signal.Signals(signum).name)


def _deferred_ending(body):
    """The exception that ends ``with deferred(): body()`` (caught here: an Interrupted
    escaping a test would stop pytest itself, as a KeyboardInterrupt does)."""
    try:
        with interrupts.deferred():
            body()
    except BaseException as ending:
        return ending
    return None


def test_a_signal_between_safe_points_waits_for_the_next():
    """SIGINT in the middle of a deferred block (where FMU code would run) only sets the
    flag: the code after it runs, the next safe point raises Interrupted; a SIGINT after a
    pending SIGTERM does not replace it: the block ends as Terminated.  Outside the block this
    test's handler would raise at once."""
    previous = {s: signal.signal(s, _not_deferred) for s in (signal.SIGINT, signal.SIGTERM)}
    reached = []

    def interrupted_between_safe_points():
        os.kill(os.getpid(), signal.SIGINT)
        reached.append(("after the signal", interrupts.pending()))
        interrupts.check()
        reached.append("after the safe point")

    def terminated_then_interrupted():
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGINT)
        reached.append("after both")

    try:
        ending = _deferred_ending(interrupted_between_safe_points)
        assert type(ending) is interrupts.Interrupted, repr(ending)
        assert reached == [("after the signal", True)]
        ending = _deferred_ending(terminated_then_interrupted)
        assert type(ending) is interrupts.Terminated, repr(ending)
        assert reached[-1] == "after both" and not interrupts.pending()
        assert signal.getsignal(signal.SIGINT) is _not_deferred  # restored
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def _env(point):
    env = dict(os.environ)
    env[SIGNAL_AT_ENV] = f"{point}:INT"
    env["PYTHONPATH"] = os.pathsep.join([str(fmu_build.FMU_SOURCES), str(fmu_build.ROOT),
                                         env.get("PYTHONPATH", "")])
    return env


def _staging(folder, name):
    return [p for p in folder.iterdir() if p.name.startswith(f".{name}.")]


def _interrupted_run(tmp_path, point):
    """`navfmu run` of 10 s with SIGINT at safe point ``point``: the outcome checked."""
    folder = tmp_path / point.replace("%", "")
    folder.mkdir()
    out = folder / "out"
    done = subprocess.run([sys.executable, "-m", "orchestrator.cli", "run", str(MODEL),
                           "--stop", "10", "--out", str(out)], env=_env(point),
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          timeout=300)
    err = done.stderr
    assert done.returncode == 130, (point, err)
    assert err.strip().splitlines()[-1] == "navfmu: interrupted", (point, err)
    assert "Traceback" not in err and "Fatal" not in err and "navfmu: error" not in err, err
    assert not out.exists(), point
    assert not _staging(folder, "out"), point


def _interrupt_runs(tmp_path, points):
    with ThreadPoolExecutor(PARALLEL) as pool:
        list(pool.map(lambda point: _interrupted_run(tmp_path, point), points))


def test_sigint_while_stepping_and_while_writing(tmp_path):
    _interrupt_runs(tmp_path, ["step-50%", "writing"])


@pytest.mark.slow
def test_sigint_at_every_tenth_of_the_steps_and_every_part_written(tmp_path):
    """Three parts are written (results.csv, metrics.json, the plots): updates at 0, 33, 66
    and 100 % of them."""
    _interrupt_runs(tmp_path, [f"step-{p}%" for p in (1, *range(10, 101, 10))]
                    + ["part-0%", "part-33%", "part-66%", "part-100%"])
