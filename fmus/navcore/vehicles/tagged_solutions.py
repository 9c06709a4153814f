"""The navigation solution a sample flies on: chosen by its time tag, never by call order.

A guided vehicle receives a time-tagged navigation solution at every communication step, but
when it arrives depends on the master: under a Jacobi exchange (libcosim) a step from t sees
the filter's output at t, under Gauss-Seidel with the filter stepped first its output at the
step's end, and a master may step with any size, so one step may cover many of the vehicle's
samples.  For the flight to be the same under all of them, the sample at ``t`` flies on the
newest solution tagged at or before ``t`` (:meth:`TaggedSolutions.due`); a solution tagged
later waits, pending, until the samples reach its tag.  Both the solution in use and the
pending ones are state (saved and restored with the vehicle).

Until a first solution is due (the run's start, when the filter's first output already
carries the first step's end), the earliest one received stands in, extrapolated back to the
sample by its user: nothing earlier exists.
"""
from __future__ import annotations

import bisect
from typing import List, Optional, Tuple

from ..core.timing import time_tolerance

#: a solution: (time tag [s], values)
Solution = Tuple[float, Tuple[float, ...]]


class TaggedSolutions:
    """The solutions received so far that a sample may still need: the newest one due (tagged
    at or before the latest sample asked for) and the pending ones (tagged after it), oldest
    first."""

    state_fields = ("current", "pending")

    def __init__(self):
        self.current: Optional[Solution] = None
        self.pending: List[Solution] = []

    def receive(self, tag: float, values: Tuple[float, ...]) -> None:
        """Keep the solution ``values`` of time ``tag``.  One older than the solution in use
        is dropped (it can never be the newest due); one of a tag already held replaces it
        (a solution delivered again over several steps)."""
        solution = (tag, values)
        current, pending = self.current, self.pending
        if current is not None and tag <= current[0]:
            if tag == current[0]:
                self.current = solution
            return
        if not pending or tag > pending[-1][0]:    # the usual order
            pending.append(solution)
            return
        i = bisect.bisect_left([s[0] for s in pending], tag)
        if pending[i][0] == tag:
            pending[i] = solution
        else:
            pending.insert(i, solution)

    def due(self, t: float, period: float) -> Optional[Solution]:
        """The newest solution tagged at or before ``t`` (within the time tolerance of a grid
        of ``period``, :func:`navcore.core.timing.time_tolerance`), the pending ones it passes
        dropped; before any is due the earliest pending one (module docstring); None when
        nothing was received."""
        pending = self.pending
        if pending:
            latest = t + time_tolerance(period, t)
            n = 0
            while n < len(pending) and pending[n][0] <= latest:
                n += 1
            if n:
                self.current = pending[n - 1]
                del pending[:n]
        if self.current is not None:
            return self.current
        return pending[0] if pending else None
