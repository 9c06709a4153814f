"""ImuGnssReplay's batch (:mod:`navcore.core.batch`): B runs replaying their logs, one step per
log instead of one per run.

A replay's outputs depend on its parameters (``log``, ``max_dt_jitter``) and the time alone:
it has no inputs and draws nothing.  So the runs of a batch that replay the same log (the
same folder and bound; the content is one per process, :mod:`navcore.sensors.log_cache`)
output the same values at every step, and the batch steps one of them, the group's first
run, by its own component's code (:meth:`ImuGnssReplay.step
<navcore.components.replay.ImuGnssReplay.step>`) and writes its outputs into every row of
the group with one assignment.  Each run therefore gets, bit for bit, the outputs its single
run computes; a step past the end of the log fails every run of the group with the error
its single run raises.  Runs replaying other logs (another folder in a sweep) form their own
groups.  Every run is started by its own component (its parameters checked there, a missing
log failing that run alone); the parsed log and the replay's tables are shared, so a batch
of 64 runs holds one copy of them.
"""
from __future__ import annotations

from typing import Dict, List, Tuple

import numpy as np

from ..core.batch import ComponentBatch


class ImuGnssReplayBatch(ComponentBatch):
    """B runs of :class:`~navcore.components.replay.ImuGnssReplay` (module docstring)."""

    def _started(self, start_time: float) -> np.ndarray:
        self.out = np.zeros((self.runs, len(self.columns)))
        by_log: Dict[Tuple[str, float], List[int]] = {}
        for b, member in enumerate(self.members):
            if b not in self._failures:
                key = (member.log_folder, member.params["max_dt_jitter"])
                by_log.setdefault(key, []).append(b)
        self._set_groups(list(by_log.values()))
        for leader, rows in self.groups:
            self.out[rows] = self._outputs_of(self.members[leader])
        return self.out.copy()

    def _set_groups(self, groups: List[List[int]]) -> None:
        """``groups``: the batch rows of each log, the first one the run that steps; one
        group of every row writes by a slice (no gather)."""
        every = len(groups) == 1 and groups[0] == list(range(self.runs))
        self.groups = [(rows[0], slice(None) if every else np.array(rows, dtype=np.intp))
                       for rows in groups]
        self._group_rows = groups

    def _kept(self, rows: List[int]) -> None:
        if not hasattr(self, "groups"):
            return
        position = {old: new for new, old in enumerate(rows)}
        self._set_groups([[position[b] for b in group if b in position]
                          for group in self._group_rows if any(b in position for b in group)])
        self.out = self.out[rows]

    def advance(self, t, h, inputs) -> np.ndarray:
        out, members = self.out, self.members
        for leader, rows in self.groups:
            try:
                members[leader].step(t, h, {})
            except Exception as exc:          # the log's end: every run of the log fails
                for b in self._group_list(rows):
                    self.fail(b, exc)
                continue
            out[rows] = self._outputs_of(members[leader])
        return out

    def _group_list(self, rows) -> List[int]:
        return list(range(self.runs)) if isinstance(rows, slice) else rows.tolist()


__all__ = ["ImuGnssReplayBatch"]
