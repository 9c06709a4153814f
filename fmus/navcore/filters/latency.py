"""Time of validity of GNSS fixes: the history a filter needs to apply a late fix exactly.

A fix reaches a filter some time after it was taken: the receiver's own latency, or a master
that passes outputs one communication step late (Jacobi exchange, as libcosim does: the fix
taken at ``gnss_time = 1.0`` by a 1 Hz receiver reaches the filter at t = 2.0).  The filters
of :mod:`navcore.components.filter_component` apply every fix at the IMU epoch nearest its
``gnss_time`` (within half an IMU interval; the INS solution is carried to ``gnss_time`` by its
velocity over that fraction, see :meth:`navcore.filters.ins_gnss_kf.KfEngine.measurement`):

* a fix taken at the current epoch is applied at once (the same arithmetic as a filter
  without history);
* a fix from the past is applied by **rollback and re-propagation**: the filter goes back
  to its latest checkpoint at or before the fix's epoch, re-propagates the stored IMU
  increments up to that epoch, applies the fix there and re-propagates the rest up to now.
  This is the exact "recalculation" remedy for a measurement lag (Groves, *Principles of
  GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., 2013, sec. 3.3
  on time synchronization); unlike carrying the correction forward with the accumulated
  transition matrix (Larsen et al., "Incorporation of time delayed measurements in a
  discrete-time Kalman filter", CDC 1998), which is exact only for a linear filter, it holds
  for every engine -- the adaptive and robust KFs, the UKFs, the IMM bank -- because the
  engine itself is replayed: after the replay the filter's state is bit for bit the state
  of a run in which the fix arrived on time;
* a fix from the future (``gnss_time`` more than half an IMU interval after the filter's
  time, e.g. a receiver stepped before the IMU) waits until the INS reaches its epoch.

A fix whose ``gnss_time`` is more than the latency bound ``max_fix_age`` away from the
filter's time, or before the epoch of a fix already applied, is not applied; the filter
counts it.  A checkpoint is the engine's declared state as plain data (:mod:`navcore.core.state`),
so the history is part of the FMU state like everything else; a rollback restores it into an
engine built afresh from the parameters, exactly as an FMU state is restored.  Cost: a
checkpoint (about one propagation's cost) after
every update, and once late fixes have been seen also every :data:`CHECKPOINT_INTERVAL`
seconds, so that a fix ``d`` seconds late re-propagates at most ``d + CHECKPOINT_INTERVAL``
seconds of IMU data.  A run whose fixes all arrive on time pays one copy per update (and,
without fixes, one per latency bound: the history never holds more than about twice the
bound).
"""
from __future__ import annotations

from typing import List, Tuple

import numpy as np

from ..core import state as _state
from ..core.timing import time_tolerance

#: seconds of IMU data between two checkpoints of the filter state
CHECKPOINT_INTERVAL = 0.1

#: one stored IMU interval: (imu_time, dtheta (3,), dvel (3,), imu_dt)
Increment = Tuple[float, object, object, float]


def checkpoint_spacing(keep, dense):
    """Seconds between two checkpoints: :data:`CHECKPOINT_INTERVAL` if ``dense`` (late
    fixes were seen), else ``keep``; numpy arrays give it for every run of a batch."""
    if isinstance(dense, np.ndarray):
        return np.where(dense, CHECKPOINT_INTERVAL, keep)
    return CHECKPOINT_INTERVAL if dense else keep


def checkpoint_due(time, last, dt, keep, dense):
    """Whether an interval of ``dt`` ending at ``time`` is checkpointed after the checkpoint
    at ``last`` (:func:`checkpoint_spacing` apart); numpy arrays of ``last``, ``keep``,
    ``dense`` give it for every run of a batch."""
    return time - last >= checkpoint_spacing(keep, dense) - time_tolerance(dt, time)


class SolutionHistory:
    """Checkpoints of a filter engine and the IMU increments integrated since the oldest.

    ``checkpoints`` is a list of ``(time, engine state tree)``, oldest first, all at IMU
    epochs and none before the epoch of the latest applied fix; ``increments`` holds every
    interval integrated after the oldest checkpoint.
    """

    state_fields = ("checkpoints", "increments")

    def __init__(self, time: float, engine) -> None:
        self.checkpoints: List[Tuple[float, object]] = []
        self.increments: List[Increment] = []
        self.restart(time, engine)

    def restart(self, time: float, engine) -> None:
        """Forget everything before ``time`` (a fix was applied there) and checkpoint it."""
        self.checkpoints = [(time, _state.capture(engine, "checkpoint"))]
        self.increments = []

    def record(self, increment: Increment, engine, keep: float, dense: bool) -> None:
        """Store an interval just integrated; checkpoint ``engine`` when one is due (every
        :data:`CHECKPOINT_INTERVAL` if ``dense``, else every ``keep`` seconds); drop what no
        fix within ``keep`` seconds of the new time can need."""
        time = increment[0]
        self.increments.append(increment)
        if checkpoint_due(time, self.checkpoints[-1][0], increment[3], keep, dense):
            self.checkpoints.append((time, _state.capture(engine, "checkpoint")))
        self._forget_before(time - keep)

    def extend(self, increments: List[Increment], keep: float) -> None:
        """Store intervals integrated one after the other, none of which is due for a
        checkpoint: the history :meth:`record` leaves after each of them (what is
        forgotten depends only on the latest time, as the horizon only advances)."""
        self.increments.extend(increments)
        if increments:
            self._forget_before(increments[-1][0] - keep)

    def _forget_before(self, horizon: float) -> None:
        """Forget what no fix after ``horizon`` can need: every checkpoint but the latest
        one at or before it, and the increments up to that checkpoint."""
        cps = self.checkpoints
        if len(cps) > 1 and cps[1][0] <= horizon:
            while len(cps) > 1 and cps[1][0] <= horizon:
                cps.pop(0)
            oldest = cps[0][0]
            incs = self.increments
            n = 0
            while n < len(incs) and incs[n][0] <= oldest:
                n += 1
            del incs[:n]

    def oldest_time(self) -> float:
        return self.checkpoints[0][0]

    def rollback(self, latest: float):
        """``(time, engine state tree, increments)``: the latest checkpoint at or before
        ``latest`` and the increments after it; the later checkpoints and those increments
        leave the history (the caller restores the tree into a fresh engine and
        re-propagates the increments through :meth:`record`)."""
        cps = self.checkpoints
        k = len(cps) - 1
        while k > 0 and cps[k][0] > latest:
            k -= 1
        del cps[k + 1:]
        time, engine = cps[k]
        incs = self.increments
        n = 0
        while n < len(incs) and incs[n][0] <= time:
            n += 1
        replay = incs[n:]
        del incs[n:]
        return time, engine, replay
