"""GnssReceiver's batch (navcore.components.gnss_receiver_batch) against each receiver stepped
alone on the same inputs, bit for bit: per-run parameters (seeds, intervals, an output
delay, a lever arm, outages and outliers), communication steps finer and coarser than the
fixes, a refused input failing its run alone with its own error, and a receiver class with
its own step.  The receivers inside whole simulations in batches are in
tests/test_batch_simulation.py.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.components.gnss_receiver_batch import GnssReceiverBatch
from navcore.components.sensor_components import GnssReceiver
from navcore.core.batch import BatchInputs
from navcore.errors import InputError

NAMES = tuple(p.name for p in GnssReceiver.inputs)
LAT, LON = 0.6, 0.2

RUNS = [
    {"seed": 3, "pos_sigma_n": 2.0, "pos_sigma_e": 2.0, "pos_sigma_d": 4.0},
    {"seed": 4, "pos_sigma_n": 1.0, "vel_sigma_n": 0.1, "fix_interval": 0.5,
     "outages": "3,5", "outlier_period": 2.0, "outlier_multiple": 5.0},
    {"seed": 5, "pos_sigma_n": 2.0, "output_delay": 0.35},
    {"seed": 6, "pos_sigma_e": 1.5, "lever_arm_x": 1.2, "lever_arm_z": -0.4},
    {"seed": 7, "pos_sigma_n": 3.0, "fix_interval": 0.2,
     "noise_steps": "2,4,pos,9,9,9", "outlier_patches": "5,6,pos,ne,30"},
]


def _truth(t):
    """A turning, climbing vehicle's truth at time t (every input of the receiver)."""
    yaw = 0.3 * t
    return {"truth_time": t, "truth_lat": LAT + 1e-6 * t, "truth_lon": LON + 2e-6 * t,
            "truth_h": 100.0 + 0.5 * t, "truth_vn": 6.0 * math.cos(yaw),
            "truth_ve": 6.0 * math.sin(yaw), "truth_vd": -0.5, "truth_roll": 0.1,
            "truth_pitch": 0.05, "truth_yaw": yaw}


def _inputs(rows):
    real = np.array([[row[n] for n in NAMES] for row in rows])
    return BatchInputs({n: real[:, j] for j, n in enumerate(NAMES)}, real, NAMES)


def _run_both(runs, steps, h, cls=GnssReceiver, meddle=None):
    """The batch and each receiver alone over ``steps`` steps of ``h`` on the truth (run b's
    input row changed by ``meddle(k, b, row)``).  Returns the batch's outputs, the singles'
    (None from a run's error on), the singles' errors and the batch."""
    batch = GnssReceiverBatch(cls, len(runs))
    batch.set_parameters(runs)
    singles = [cls(**p) for p in runs]
    outs = [batch.start(0.0)]
    alone = [[[s.start(0.0)[n] for n in batch.columns]] for s in singles]
    errors = [None] * len(runs)
    for k in range(steps):
        t = k * h
        rows = [_truth(t + h) for _ in runs]
        if meddle is not None:
            for b, row in enumerate(rows):
                meddle(k, b, row)
        outs.append(batch.advance(t, h, _inputs(rows)).copy())
        for b, single in enumerate(singles):
            if errors[b] is None:
                try:
                    out = single.advance(t, h, rows[b])
                    alone[b].append([out[n] for n in batch.columns])
                    continue
                except InputError as exc:
                    errors[b] = exc
            alone[b].append(None)
    return np.array(outs), alone, errors, batch


@pytest.mark.parametrize("h", [0.01, 0.1, 0.35, 1.3])
def test_every_receiver_of_a_batch_gives_the_outputs_of_its_receiver_alone(h):
    steps = int(round(8.0 / h))
    outs, alone, errors, batch = _run_both(RUNS, steps, h)
    assert errors == [None] * len(RUNS)
    assert batch.take_failures() == {}
    for b in range(len(RUNS)):
        np.testing.assert_array_equal(outs[:, b], np.array(alone[b]))
    epoch = batch.columns["gnss_epoch"]
    # the runs took their own fixes: at their own intervals and with their own errors
    assert len({outs[-1, b, epoch] for b in range(len(RUNS))}) > 1
    lat = batch.columns["gnss_lat"]
    assert len({outs[-1, b, lat] for b in range(len(RUNS))}) == len(RUNS)


def test_a_receiver_whose_input_is_refused_fails_alone_with_its_own_error():
    def meddle(k, b, row):
        if b == 1 and k >= 250:
            row["truth_h"] = math.nan
    outs, alone, errors, batch = _run_both(RUNS, 400, 0.01, meddle=meddle)
    failures = batch.take_failures()
    assert list(failures) == [1]
    assert isinstance(failures[1], InputError)
    assert str(failures[1]) == str(errors[1])
    assert "truth_h" in str(failures[1])
    for b in (0, 2, 3, 4):
        np.testing.assert_array_equal(outs[:, b], np.array(alone[b]))


class _EveryStepReceiver(GnssReceiver):
    """A receiver whose step counts its calls (its own code at every step)."""

    calls = 0

    def step(self, t, h, inputs):
        type(self).calls += 1
        return super().step(t, h, inputs)


def test_a_receiver_class_with_its_own_step_steps_by_it_every_time():
    _EveryStepReceiver.calls = 0
    outs, alone, errors, batch = _run_both(RUNS[:2], 50, 0.01, cls=_EveryStepReceiver)
    assert _EveryStepReceiver.calls == 2 * 50 * 2        # the batch's and the singles'
    for b in range(2):
        np.testing.assert_array_equal(outs[:, b], np.array(alone[b]))


def test_between_fixes_the_batch_calls_no_receiver():
    """The batch's point: the steps between fixes (here 99 of 100) cost no receiver call.
    A run with an output delay steps by its own code while a fix waits; one with a lever
    arm at every step (its attitude)."""
    calls = []

    class Counting(GnssReceiver):
        pass

    runs = [RUNS[0], RUNS[2], RUNS[3]]
    batch = GnssReceiverBatch(Counting, len(runs))
    batch.set_parameters(runs)
    batch.start(0.0)
    for b, member in enumerate(batch.members):
        step = member.step
        member.step = lambda t, h, inputs, b=b, step=step: calls.append(b) or step(t, h, inputs)
    for k in range(500):
        batch.advance(k * 0.01, 0.01, _inputs([_truth((k + 1) * 0.01)] * len(runs)))
    assert calls.count(0) == 5            # one call per fix of its 1 s interval
    # fixes at 1, 2, 3, 4 s: the step taking each and the 35 until it is out 0.35 s later;
    # the fix at 5 s: the last step takes it
    assert calls.count(1) == 4 * 36 + 1
    assert calls.count(2) == 500
