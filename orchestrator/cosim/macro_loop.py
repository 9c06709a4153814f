"""The macro-step loop of a run and its early end (rules 1, 6 and 9 of
:mod:`orchestrator.cosim.master`).

:class:`MacroLoop` is the part of :class:`~orchestrator.cosim.master.Simulation` that counts the
macro steps of a run, steps them, records each row when due, reports progress, and ends the run
cleanly when a component asks to terminate it.
"""
from __future__ import annotations

import time as _time
import warnings

from navcore.core.timing import TIME_TOLERANCE

from ..errors import NavfmuError, NavfmuWarning, SimulationTerminated


class MacroLoop:
    """The loop, as methods of the simulation that runs it: they read its ``base_step`` and
    ``record_every``."""

    def _n_steps(self, start: float, stop: float) -> int:
        if not stop > start:
            raise NavfmuError(f"the stop time {stop} must be greater than the start time {start}")
        ratio = (stop - start) / self.base_step
        n = int(round(ratio))
        if n < 1 or abs(ratio - n) > TIME_TOLERANCE * max(ratio, 1.0):
            raise NavfmuError(f"the run from {start} s to {stop} s is not an integer number of "
                              f"base steps of {self.base_step} s")
        return n

    def _loop(self, step, record, recording, n_steps: int, progress):
        """The macro steps 0 .. n_steps-1, each row recorded when due; returns the loop's
        wall time [ns], the macro steps done and the :class:`SimulationTerminated` that
        ended it early (or None).  ``progress`` is called about every 1 % and at the end."""
        record_every = self.record_every
        progress_every = max(1, n_steps // 100)
        next_progress = progress_every if progress is not None else n_steps + 1
        ended = None
        loop_start = _time.perf_counter_ns()
        for k in range(n_steps):
            try:
                step(k)
            except SimulationTerminated as exc:
                ended, n_steps = exc, k
                break
            kp1 = k + 1
            if kp1 % record_every == 0:
                record(recording.slot(kp1 // record_every))
            if kp1 == next_progress:
                progress(kp1, n_steps)
                next_progress = kp1 + progress_every
        loop_ns = _time.perf_counter_ns() - loop_start
        if progress is not None and n_steps % progress_every:
            progress(n_steps, n_steps)
        return loop_ns, n_steps, ended

    def _ended(self, ended: SimulationTerminated, start: float, done: int, recording):
        """A component ended the simulation in macro step ``done`` (rule 9): the run ends at
        its last recorded row before it, which every component reached; returns that stop
        time and its macro steps.  With no row past the initial one, the run fails."""
        rows = done // self.record_every
        if rows == 0:
            raise ended
        recording.end_at(rows + 1)
        n_steps = rows * self.record_every
        stop = start + n_steps * self.base_step
        warnings.warn(f"{ended}; the results end at t = {stop:.9g} s, the last recorded "
                      f"communication point every component reached", NavfmuWarning,
                      stacklevel=3)
        return stop, n_steps
