"""The rollback history of the late-fix path (navcore.filters.latency.SolutionHistory) on a toy
engine, against checkpoint and increment times worked out by hand from the documented rules:
a checkpoint every CHECKPOINT_INTERVAL (dense) or every ``keep`` seconds, nothing kept that no
fix within ``keep`` seconds can need, a rollback to the latest checkpoint at or before a time.
"""
from __future__ import annotations

import numpy as np
import pytest

from navcore.core.timing import time_tolerance
from navcore.errors import StateError
from navcore.filters.latency import CHECKPOINT_INTERVAL, SolutionHistory

DT = 0.01   # IMU interval of the toy runs


class Counter:
    """A declared engine whose state is the time it was propagated to."""

    state_fields = ("t",)

    def __init__(self, t: float) -> None:
        self.t = t


def _history_after(n_intervals: int, keep: float, dense: bool) -> SolutionHistory:
    engine = Counter(0.0)
    history = SolutionHistory(0.0, engine)
    for k in range(1, n_intervals + 1):
        engine.t = k * DT
        history.record((k * DT, None, None, DT), engine, keep, dense)
    return history


def _checkpoint_times(history):
    return [round(t, 9) for t, _ in history.checkpoints]


def _increment_times(history):
    return [round(inc[0], 9) for inc in history.increments]


def test_dense_checkpoints_every_interval_and_sparse_ones_every_keep():
    assert CHECKPOINT_INTERVAL == pytest.approx(0.1)
    dense = _history_after(30, keep=10.0, dense=True)
    assert _checkpoint_times(dense) == [0.0, 0.1, 0.2, 0.3]
    # each checkpoint holds the engine's state at its own time
    assert [tree["t"] for _, tree in dense.checkpoints] == pytest.approx([0.0, 0.1, 0.2, 0.3])
    assert len(dense.increments) == 30
    sparse = _history_after(30, keep=0.25, dense=False)
    # a checkpoint once 0.25 s have passed since the last: at 0.25; the one at 0.0 is kept
    # while a fix 0.25 s old (at 0.05 when t = 0.3) may still need it
    assert _checkpoint_times(sparse) == [0.0, 0.25]


def test_what_no_fix_within_keep_can_need_is_dropped():
    history = _history_after(30, keep=0.15, dense=True)
    # at t = 0.3 a fix may be from 0.15 s back: the latest checkpoint at or before 0.15 is 0.1
    assert _checkpoint_times(history) == [0.1, 0.2, 0.3]
    assert history.oldest_time() == pytest.approx(0.1)
    # the increments integrated after the oldest checkpoint, and only those
    assert _increment_times(history) == [round(k * DT, 9) for k in range(11, 31)]


def test_a_checkpoint_exactly_at_the_horizon_replaces_the_older_ones():
    # times exact in binary: IMU interval 1/8 s (each interval is a dense checkpoint)
    engine = Counter(0.0)
    history = SolutionHistory(0.0, engine)
    for k in range(1, 5):
        history.record((k / 8, None, None, 1 / 8), engine, 0.25, True)
    # horizon 0.5 - 0.25 = 0.25: a fix at 0.25 starts from the checkpoint at 0.25
    assert _checkpoint_times(history) == [0.25, 0.375, 0.5]
    assert _increment_times(history) == [0.375, 0.5]


@pytest.mark.parametrize("latest, start", [(0.2, 0.2), (0.25, 0.2), (0.15, 0.1), (0.05, 0.0),
                                           (-1.0, 0.0), (0.3, 0.3)])
def test_rollback_starts_from_the_latest_checkpoint_at_or_before(latest, start):
    history = _history_after(30, keep=10.0, dense=True)
    time, tree, replay = history.rollback(latest)
    assert time == pytest.approx(start)
    assert tree["t"] == pytest.approx(start)
    # the increments after the start are handed back for re-propagation and leave the history
    assert [round(inc[0], 9) for inc in replay] == [
        round(k * DT, 9) for k in range(round(start / DT) + 1, 31)]
    assert _increment_times(history) == [round(k * DT, 9) for k in range(1, round(start / DT) + 1)]
    assert _checkpoint_times(history) == [round(0.1 * k, 9) for k in range(round(start / 0.1) + 1)]


def test_restart_forgets_the_history():
    history = _history_after(30, keep=10.0, dense=True)
    history.restart(0.3, Counter(0.3))
    assert _checkpoint_times(history) == [0.3] and history.increments == []


def test_a_checkpoint_is_due_at_the_edge_of_the_time_tolerance():
    # an interval end at spacing - tolerance is the same instant as the due time (0.25 s)
    engine = Counter(0.0)
    history = SolutionHistory(0.0, engine)
    t = 0.25
    for _ in range(5):             # t = 0.25 - time_tolerance(dt, t), solved by iteration
        t = 0.25 - time_tolerance(0.125, t)
    assert t < 0.25
    history.record((t, None, None, 0.125), engine, 0.25, False)
    assert len(history.checkpoints) == 2
    history = SolutionHistory(0.0, engine)
    history.record((np.nextafter(t, 0.0), None, None, 0.125), engine, 0.25, False)
    assert len(history.checkpoints) == 1


def test_rollback_hands_back_every_increment_after_its_checkpoint():
    # intervals of 1/8 s, each a checkpoint: rolling back to 0.375 keeps 3 increments (an odd
    # number) and hands back those at 0.5 and 0.625
    engine = Counter(0.0)
    history = SolutionHistory(0.0, engine)
    for k in range(1, 6):
        history.record((k / 8, None, None, 1 / 8), engine, 10.0, True)
    time, _, replay = history.rollback(0.4)
    assert time == 0.375
    assert [inc[0] for inc in replay] == [0.5, 0.625]
    assert _increment_times(history) == [0.125, 0.25, 0.375]


def test_a_checkpoint_names_itself_in_a_state_error():
    engine = Counter(0.0)
    engine.extra = 1.0                         # not declared
    with pytest.raises(StateError, match=r"^checkpoint: attribute\(s\) extra of Counter"):
        SolutionHistory(0.0, engine)
    engine = Counter(0.0)
    history = SolutionHistory(0.0, engine)
    engine.extra = 1.0
    with pytest.raises(StateError, match=r"^checkpoint: attribute\(s\) extra of Counter"):
        history.record((0.125, None, None, 0.125), engine, 10.0, True)


@pytest.mark.parametrize("dt, keep, dense", [(1 / 16, 1 / 16, True), (1 / 32, 3 / 32, True),
                                             (1 / 8, 3 / 8, False), (1 / 100, 0.15, True),
                                             (1 / 64, 0.25, False)])
def test_the_history_keeps_exactly_what_a_fix_within_keep_can_need(dt, keep, dense):
    """After every interval: the oldest checkpoint is the latest one at or before time - keep
    (or the first of the run), and the increments are exactly those after it."""
    engine = Counter(0.0)
    history = SolutionHistory(0.0, engine)
    recorded = []
    for k in range(1, 60):
        increment = (k * dt, None, None, dt)
        recorded.append(increment)
        history.record(increment, engine, keep, dense)
        times = [t for t, _ in history.checkpoints]
        horizon = k * dt - keep
        assert times == sorted(times) and times[-1] <= k * dt
        assert times[0] <= horizon or times[0] == 0.0, (k, times)
        assert len(times) == 1 or times[1] > horizon, (k, times)
        assert history.increments == [inc for inc in recorded if inc[0] > times[0]], k
