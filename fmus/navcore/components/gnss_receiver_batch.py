"""GnssReceiver's batch (:mod:`navcore.core.batch`): B receivers, each run's own code whenever
it has something to do.

A receiver steps far more often than it takes a fix (at every communication step of its
component, 10 or 100 times per fix), and between fixes its step only checks its inputs and
compares the truth's time with its next epoch.  The batch does those two things for all runs
at once: a run whose inputs are all accepted (:meth:`~navcore.core.batch.ComponentBatch.
accepted_rows`, the ranges its ``check_inputs`` enforces), whose next epoch is not near, that
holds no fix for later (``output_delay``) and needs no attitude (lever arm) keeps its outputs,
as its own step would.  Every other run steps by its own component (:meth:`GnssReceiver.step
<navcore.components.sensor_components.GnssReceiver.step>`), which decides exactly: a fix, a
refused input, a queued fix published.  So each run's fixes are its receiver's, draw for draw.

"Near" is generous (twice the time tolerance of :meth:`GnssReceiver.step`): a run the batch
lets step that has no fix due does what the batch would have done.  A receiver class that
steps otherwise (a subclass's own ``step`` or ``check_inputs``) runs its own code always.
"""
from __future__ import annotations

from typing import List

import numpy as np

from ..core.batch import ComponentBatch
from ..core.timing import time_tolerance_rows

#: the inputs every step of a receiver checks (GnssReceiver.step)
CHECKED_INPUTS = ("truth_time", "truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve",
                  "truth_vd")


class GnssReceiverBatch(ComponentBatch):
    """B runs of :class:`~navcore.components.sensor_components.GnssReceiver` (module
    docstring)."""

    def _started(self, start_time: float) -> np.ndarray:
        runs = self.runs
        self.out = np.zeros((runs, len(self.columns)))
        self.next_fix = np.full(runs, -np.inf)    # a failed run's row: never quiet
        self.interval = np.ones(runs)
        self.busy = np.ones(runs, dtype=bool)     # queued fixes, or its own code always
        shell = next(c for c in self.component_class.__mro__
                     if c.__dict__.get("batch_class") is type(self))
        self._own_class = [type(m).step is not shell.step
                           or type(m).check_inputs is not shell.check_inputs
                           for m in self.members]
        for b in range(runs):
            if b not in self._failures:
                self._adopt(b)
        return self.out.copy()

    def _adopt(self, b: int) -> None:
        member = self.members[b]
        self.out[b] = self._outputs_of(member)
        self.next_fix[b] = member.next_fix
        self.interval[b] = member.interval
        self.busy[b] = self._own_class[b] or member.lever is not None or bool(member.queue)

    def _kept(self, rows: List[int]) -> None:
        if not hasattr(self, "out"):
            return
        for name in ("out", "next_fix", "interval", "busy"):
            setattr(self, name, getattr(self, name)[rows])
        self._own_class = [self._own_class[i] for i in rows]

    def advance(self, t, h, inputs) -> np.ndarray:
        truth = inputs.real_columns(CHECKED_INPUTS)
        t_truth = truth[:, 0]
        # near: within twice GnssReceiver.step's tolerance of the next epoch
        own = t_truth + 2.0 * time_tolerance_rows(self.interval, t_truth) >= self.next_fix
        own |= self.busy
        own |= ~self.accepted_rows(truth, CHECKED_INPUTS)
        if own.any():
            failures = self._failures
            runs = np.flatnonzero(own).tolist()
            for b, values in zip(runs, self._inputs_of_runs(runs, inputs)):
                if b not in failures:
                    self._by_itself(b, lambda m, values=values: m.step(t, h, values))
        return self.out


__all__ = ["CHECKED_INPUTS", "GnssReceiverBatch"]
