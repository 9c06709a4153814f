"""Ctrl-C (SIGINT) and SIGTERM during a command: deferred to the master's safe points.

A KeyboardInterrupt raised by Python's default SIGINT handler lands in whatever bytecode runs
at that moment, and during a co-simulation that is mostly the Python code *inside* an FMU
(pythonfmu runs the slave in this interpreter): the FMU turns it into fmi2Fatal and the run
is reported as a component fault.  Within :func:`deferred`, SIGINT and SIGTERM only set a
flag; :func:`check` raises :class:`Interrupted` (or :class:`Terminated`) at points where
stopping is safe: between macro steps (the command line's progress callback, called about
every 1 % of a run), between the output files being written, while a campaign waits for its
workers, and when the block ends.  An FMU never sees the signal, the run's instances are
terminated by the master's ``finally``, and the output folder is discarded or complete
(:mod:`orchestrator.results.outputs`).  A second signal while one is pending does not force
anything: the command still ends at the next safe point (SIGTERM wins over SIGINT: the
command then ends as terminated).

Tests reach a chosen safe point deterministically through the environment variable
:data:`SIGNAL_AT_ENV` (``POINT:SIGNAL``, e.g. ``writing:TERM``): the process sends itself
that signal when it passes :func:`safe_point` ``POINT`` the first time.  The points:
``writing`` (after each output file), ``campaign-started`` (the manifest written),
``campaign-run-FILTER-INDEX`` (that campaign run starting, in the process that runs it),
``campaign-ran-N`` (the driver has the N-th result of this invocation), ``pool-waiting`` (the
driver waiting for its process pool, from the pool's start), ``commit`` (a written file or
sensor log about to be moved into place: a signal pending there commits nothing, so a command
ends with its output complete and status 0, or with nothing of it written and the status of
the signal), ``verify-probe`` (before each FMI probe of ``verify``) and the command line's
progress
updates ``UNIT-P%`` (``step-50%``: half the steps of a run done; ``part-0%``: the output
writing begun).  ``KILL`` (SIGKILL) stands for a crash.
"""
from __future__ import annotations

import contextlib
import os
import signal
import threading

from ..results import run_results

#: ``POINT:SIGNAL``: send SIGNAL (INT or TERM) to this process at safe point POINT (tests)
SIGNAL_AT_ENV = "NAVFMU_TEST_SIGNAL_AT"
_HANDLED = (signal.SIGINT, signal.SIGTERM)
_pending = {"signal": None, "fired": set()}


class Interrupted(KeyboardInterrupt):
    """The user interrupted the command (raised at a safe point, never inside an FMU)."""

    signum = signal.SIGINT


class Terminated(Interrupted):
    """The command was asked to end by SIGTERM (raised at a safe point)."""

    signum = signal.SIGTERM


def _handler(signum, frame):
    if _pending["signal"] != signal.SIGTERM:
        _pending["signal"] = signum


def pending() -> bool:
    """Whether a signal waits for the next safe point."""
    return _pending["signal"] is not None


def check() -> None:
    """Raise :class:`Interrupted` / :class:`Terminated` if a signal is pending (a no-op
    outside :func:`deferred`)."""
    signum = _pending["signal"]
    if signum is not None:
        _pending["signal"] = None
        raise Terminated() if signum == signal.SIGTERM else Interrupted()


def safe_point(name: str) -> None:
    """A named safe point: the test hook :data:`SIGNAL_AT_ENV` may fire here, then
    :func:`check`."""
    point, _, sig = os.environ.get(SIGNAL_AT_ENV, "").partition(":")
    if point == name and name not in _pending["fired"]:
        _pending["fired"].add(name)
        os.kill(os.getpid(), getattr(signal, f"SIG{sig or 'INT'}"))
    check()


@contextlib.contextmanager
def ignored():
    """SIGINT ignored within the block: processes started meanwhile inherit that (Python
    installs its KeyboardInterrupt handler only where SIGINT is not ignored), so helper
    processes in the terminal's process group leave Ctrl-C to this one."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _commit_point() -> None:
    safe_point("commit")


@contextlib.contextmanager
def deferred():
    """Within the block, SIGINT and SIGTERM set a flag instead of raising; the block ends with
    :class:`Interrupted` / :class:`Terminated` if one arrived, whatever else it raised (the
    user asked to stop)."""
    if threading.current_thread() is not threading.main_thread():
        yield  # signal handlers can only be installed from the main thread
        return
    _pending["signal"] = None
    previous = {s: signal.signal(s, _handler) for s in _HANDLED}
    run_results.COMMIT_CHECKS.append(_commit_point)
    try:
        yield
    except Interrupted:
        if _pending["signal"] is not None:
            check()     # a SIGTERM arrived on top of the SIGINT being handled
        raise
    except BaseException:
        if _pending["signal"] is not None:
            try:
                check()
            except Interrupted as stop:
                raise stop from None
        raise
    finally:
        run_results.COMMIT_CHECKS.remove(_commit_point)
        for s, handler in previous.items():
            signal.signal(s, handler)
    check()


__all__ = ["Interrupted", "Terminated", "deferred", "check", "pending", "safe_point",
           "ignored", "SIGNAL_AT_ENV"]
