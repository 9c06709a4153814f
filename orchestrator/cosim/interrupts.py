"""Ctrl-C (SIGINT) during a command: deferred to the master's safe points.

A KeyboardInterrupt raised by Python's default SIGINT handler lands in whatever bytecode runs
at that moment, and during a co-simulation that is mostly the Python code *inside* an FMU
(pythonfmu runs the slave in this interpreter): the FMU turns it into fmi2Fatal and the run
is reported as a component fault.  Within :func:`deferred`, SIGINT only sets a flag;
:func:`check` raises :class:`Interrupted` at points where stopping is safe: between macro
steps (the command line's progress callback, called about every 1 % of a run), between the
output files being written, and when the block ends.  An FMU never sees the interrupt, the
run's instances are terminated by the master's ``finally``, and the output folder is
discarded or complete (:mod:`orchestrator.results.outputs`).  A second Ctrl-C while one is pending
does not force anything: the command still ends at the next safe point.
"""
from __future__ import annotations

import contextlib
import signal
import threading

_pending = {"flag": False}


class Interrupted(KeyboardInterrupt):
    """The user interrupted the command (raised at a safe point, never inside an FMU)."""


def _handler(signum, frame):
    _pending["flag"] = True


def check() -> None:
    """Raise :class:`Interrupted` if a SIGINT is pending (a no-op outside :func:`deferred`)."""
    if _pending["flag"]:
        _pending["flag"] = False
        raise Interrupted()


@contextlib.contextmanager
def deferred():
    """Within the block, SIGINT sets a flag instead of raising; the block ends with
    :class:`Interrupted` if one arrived, whatever else it raised (the user asked to stop)."""
    if threading.current_thread() is not threading.main_thread():
        yield  # signal handlers can only be installed from the main thread
        return
    _pending["flag"] = False
    previous = signal.signal(signal.SIGINT, _handler)
    try:
        yield
    except Interrupted:
        raise
    except BaseException:
        if _pending["flag"]:
            _pending["flag"] = False
            raise Interrupted() from None
        raise
    finally:
        signal.signal(signal.SIGINT, previous)
    check()


__all__ = ["Interrupted", "deferred", "check"]
