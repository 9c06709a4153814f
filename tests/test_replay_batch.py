"""ImuGnssReplay's batch (navcore.components.replay_batch) against each replay stepped alone,
bit for bit: runs on two logs (and two jitter bounds) in one batch, communication steps finer
and coarser than the log's interval, a run whose log is missing failing alone at the start,
the runs of a log failing together with their single run's error past the log's end, and
dropped runs."""
from __future__ import annotations

import shutil

import numpy as np
import pytest

from navcore.components.replay import ImuGnssReplay
from navcore.components.replay_batch import ImuGnssReplayBatch
from navcore.core.batch import BatchInputs
from navcore.errors import NavcoreError
from navcore.sensors import log_cache
from orchestrator.building import build as fmu_build

LOG = fmu_build.ROOT / "models" / "replay_gnss_ins_sim" / "log"


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """The scenario's log and a copy of it cut after 3 s of IMU lines (another log)."""
    folder = tmp_path_factory.mktemp("logs")
    short = folder / "short"
    shutil.copytree(LOG, short)
    lines = (short / "imu.csv").read_text().splitlines()
    (short / "imu.csv").write_text("\n".join(lines[:301]) + "\n")
    return str(LOG), str(short)


def _empty_inputs(runs):
    return BatchInputs({}, np.zeros((runs, 0)), ())


def _run_both(runs, steps, h):
    batch = ImuGnssReplayBatch(ImuGnssReplay, len(runs))
    batch.set_parameters(runs)
    singles, errors, alone = [], [], []
    outs = [batch.start(0.0)]
    for p in runs:
        s = ImuGnssReplay()
        try:
            for k, v in p.items():
                s.set_parameter(k, v)
            first = s.start(0.0)
        except NavcoreError as exc:
            singles.append(None), errors.append(exc), alone.append([None])
            continue
        singles.append(s), errors.append(None)
        alone.append([[float(first[n]) for n in batch.columns]])
    for k in range(steps):
        t = k * h
        outs.append(batch.advance(t, h, _empty_inputs(batch.runs)).copy())
        for b, s in enumerate(singles):
            if errors[b] is None:
                try:
                    out = s.advance(t, h, {})
                    alone[b].append([float(out[n]) for n in batch.columns])
                    continue
                except NavcoreError as exc:
                    errors[b] = exc
            alone[b].append(None)
    return np.array(outs), alone, errors, batch


@pytest.mark.parametrize("h", [0.005, 0.01, 0.03])
def test_every_run_gives_the_outputs_of_its_replay_alone(logs, h):
    full, short = logs
    runs = [{"log": full}, {"log": short}, {"log": full, "max_dt_jitter": 0.2},
            {"log": full}, {"log": str(LOG.parent / "no-such-log")}]
    steps = int(round(4.0 / h))
    outs, alone, errors, batch = _run_both(runs, steps, h)
    failures = batch.take_failures()
    # the missing log fails its run alone, at the start, with its single run's error
    assert str(failures[4]) == str(errors[4]) and "no-such-log" in str(errors[4])
    # the short log ends at 3 s: its run fails there with its single run's error
    assert str(failures[1]) == str(errors[1]) and "ends at" in str(errors[1])
    assert set(failures) == {1, 4}
    for b in (0, 2, 3):
        assert errors[b] is None
        np.testing.assert_array_equal(outs[:, b], np.array(alone[b]))
    k_end = next(k for k, row in enumerate(alone[1]) if row is None)
    np.testing.assert_array_equal(outs[:k_end, 1], np.array(alone[1][:k_end]))
    # the runs do move: the IMU outputs change from step to step
    assert len(np.unique(outs[:, 0, batch.columns["imu_dtheta_x"]])) > steps // 2


def test_one_step_per_log_and_dropped_runs(logs, monkeypatch):
    full, short = logs
    runs = [{"log": full}, {"log": short}, {"log": full}, {"log": short}]
    batch = ImuGnssReplayBatch(ImuGnssReplay, 4)
    batch.set_parameters(runs)
    log_cache.clear()
    before = log_cache.parses
    batch.start(0.0)
    assert log_cache.parses - before == 2          # one parse per log
    calls = []
    step = ImuGnssReplay.step
    monkeypatch.setattr(ImuGnssReplay, "step",
                        lambda self, t, h, i: calls.append(self) or step(self, t, h, i))
    batch.advance(0.0, 0.01, _empty_inputs(4))
    assert len(calls) == 2                         # one step per log, not per run
    batch.keep([3, 0])
    out = batch.advance(0.01, 0.01, _empty_inputs(2)).copy()
    single = ImuGnssReplay()
    single.set_parameter("log", short)
    single.start(0.0)
    single.advance(0.0, 0.01, {})
    expected = single.advance(0.01, 0.01, {})
    assert out[0].tolist() == [float(expected[n]) for n in batch.columns]
    assert out[0].tolist() == out[1].tolist()      # same log, same time
