"""A batch of runs (orchestrator.cosim.batch) against the same runs one at a time.

Each run of a batch must record exactly the arrays its single run records (bit for bit),
under both algorithms, with the natively batched TrajectoryImu (one trajectory, B IMU error
models in one kernel call) and the components stepped one per run; a run that fails inside a
batch fails alone with the error of its single run; a campaign run in batches writes the run
files of the campaign run one at a time.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from navcore.components import sensor_components
from navcore.components.kf_components import Kf
from navcore.errors import DivergenceError
from orchestrator.campaigns import batching, campaign, campaign_runs
from orchestrator.campaigns.executor import Executor
from orchestrator.cosim.batch import BatchSimulation
from orchestrator.cosim.master import Simulation
from orchestrator.errors import NavfmuError, SimulationError
from orchestrator.results import recorder
from orchestrator.running.scenarios import load_scenario, registry, swap_filter

from campaign_helpers import MODELS


def _seed_sets(model, runs, first=10):
    random = [c.name for c in model.components if c.name != "filter"]
    return [{f"{c}.seed": first + 7 * i + j for j, c in enumerate(random)}
            for i in range(runs)]


def _single(model, parameters, stop, algorithm="gauss-seidel", reg=None):
    return Simulation(model, backend="direct", registry=reg or registry(),
                      parameters=parameters, algorithm=algorithm).run(stop_time=stop)


def _assert_same_run(single, batched):
    assert batched.columns == single.columns
    np.testing.assert_array_equal(batched.time, single.time)
    for comp in single.data:
        assert np.array_equal(batched.data[comp], single.data[comp], equal_nan=True), comp
    assert batched.metadata["warnings"] == single.metadata["warnings"]


@pytest.mark.parametrize("scenario, filter_name, stop, algorithm", [
    ("aircraft_500s", "Kf", 30.0, "gauss-seidel"),
    ("aircraft_500s", "Iakf", 30.0, "jacobi"),
    ("aircraft_500s", "InsOnly", 10.0, "gauss-seidel"),
    ("aircraft_outliers", "NewtonRobustKf", 30.0, "gauss-seidel"),
    ("aircraft_outliers", "Igg3RobustKf", 30.0, "jacobi"),
    ("mems_outages", "SageHusaFading", 60.0, "gauss-seidel"),
    ("uav_maneuver", "ImmUkf", 10.0, "jacobi"),
    ("uav_maneuver", "Ukf", 20.0, "gauss-seidel"),
    ("uav_maneuver_mems", "CtfaUkf", 10.0, "gauss-seidel"),
    ("ahrs_turntable", "FuzzyUkfAhrs", 20.0, "gauss-seidel"),
    ("ahrs_turntable", "UkfAhrs", 20.0, "jacobi"),
    ("uav_mission", "Kf", 10.0, "gauss-seidel"),
])
def test_every_run_of_a_batch_records_the_arrays_of_its_single_run(
        scenario, filter_name, stop, algorithm):
    model = swap_filter(load_scenario(MODELS / scenario), filter_name)
    sets = _seed_sets(model, 3)
    outcomes = BatchSimulation(model, registry(), sets, algorithm=algorithm).run(stop_time=stop)
    assert len(outcomes) == 3
    for parameters, batched in zip(sets, outcomes):
        _assert_same_run(_single(model, parameters, stop, algorithm), batched)
        assert batched.metadata["batch_runs"] == 3
    # the seeds do make the runs differ (the comparison above is not of equal runs)
    assert not np.array_equal(outcomes[0].data["filter"], outcomes[1].data["filter"])


@pytest.mark.parametrize("scenario, filter_name", [
    ("aircraft_500s", "Kf"), ("aircraft_500s", "Ukf"), ("ahrs_turntable", "FuzzyUkfAhrs")])
def test_the_sensors_and_the_filter_of_a_batch_are_stepped_natively(scenario, filter_name):
    assert sensor_components.TrajectoryImu.batch_class is not None
    assert sensor_components.GnssReceiver.batch_class is not None
    model = swap_filter(load_scenario(MODELS / scenario), filter_name)
    sim = BatchSimulation(model, registry(), _seed_sets(model, 4))
    kinds = {d.spec.name: type(sim._batch_instance(d, 4, {})).__name__
             for d in sim.components}
    gnss = {"gnss": "NativeBatchInstance"} if "gnss" in kinds else {}
    assert kinds == {"trajectory": "NativeBatchInstance", "filter": "NativeBatchInstance",
                     **gnss}


def test_streamed_runs_of_a_batch_give_the_chunks_of_their_single_runs(tmp_path):
    model = load_scenario(MODELS / "aircraft_500s")
    sets = _seed_sets(model, 2)
    single_paths = [tmp_path / f"single-{b}.parquet" for b in range(2)]
    batch_paths = [tmp_path / f"batch-{b}.parquet" for b in range(2)]
    for parameters, path in zip(sets, single_paths):
        sink = recorder.ParquetSink(path)
        sink.chunk_rows = 700          # several chunks, the last one short
        Simulation(model, backend="direct", registry=registry(),
                   parameters=parameters).run(stop_time=20.0, sink=sink)
    sinks = [recorder.ParquetSink(p) for p in batch_paths]
    for sink in sinks:
        sink.chunk_rows = 700
    BatchSimulation(model, registry(), sets).run(stop_time=20.0, sinks=sinks)
    for a, b in zip(single_paths, batch_paths):
        left, right = recorder.read_parquet(a), recorder.read_parquet(b)
        for comp in left.data:
            np.testing.assert_array_equal(right.data[comp], left.data[comp])


class _DivergingKf(Kf):
    """Kf that diverges at t = 5 s when its p0_pos is 7 m (one run of a batch)."""

    def step(self, t, h, inputs):
        if self.params["p0_pos"] == 7.0 and t >= 5.0:
            raise DivergenceError(f"{self.model_name}: output 'nav_lat' became non-finite at "
                                  f"t = {t} s (the filter diverged)")
        return super().step(t, h, inputs)


def test_a_run_failing_inside_a_batch_fails_alone_with_its_own_error(tmp_path):
    reg = dict(registry(), Kf=_DivergingKf)
    model = load_scenario(MODELS / "aircraft_500s")
    sets = _seed_sets(model, 4)
    sets[1]["filter.p0_pos"] = 7.0            # diverges at 5 s
    sets[2]["filter.p0_pos"] = -1.0           # refused before the start
    for b in (0, 3):
        sets[b]["filter.p0_pos"] = 5.0
    paths = [tmp_path / f"run-{b}.csv" for b in range(4)]
    outcomes = BatchSimulation(model, reg, sets).run(
        stop_time=10.0, sinks=[recorder.CsvSink(p) for p in paths])
    with pytest.raises(SimulationError) as diverged:
        _single(model, sets[1], 10.0, reg=reg)
    assert isinstance(outcomes[1], SimulationError)
    assert str(outcomes[1]) == str(diverged.value)
    with pytest.raises(NavfmuError) as refused:
        _single(model, sets[2], 10.0, reg=reg)
    assert isinstance(outcomes[2], NavfmuError) and str(outcomes[2]) == str(refused.value)
    assert "p0_pos" in str(outcomes[2])
    assert sorted(q.name for q in tmp_path.iterdir()) == ["run-0.csv", "run-3.csv"]
    for b in (0, 3):
        alone = tmp_path / "alone" / f"run-{b}.csv"
        alone.parent.mkdir(exist_ok=True)
        Simulation(model, backend="direct", registry=reg, parameters=sets[b]).run(
            stop_time=10.0, sink=recorder.CsvSink(alone))
        assert paths[b].read_bytes() == alone.read_bytes()


def test_parameter_values_are_converted_and_refused_per_run_as_alone():
    """A natively batched component converts each run's values as a single run does (a
    whole float seed is an Integer) and refuses one that does not convert for that run only,
    with the single run's message; an input's value set with the parameters holds there."""
    model = load_scenario(MODELS / "aircraft_500s")
    sets = _seed_sets(model, 3)
    sets[0]["trajectory.seed"] = 12.0
    sets[1]["trajectory.seed"] = 1.5
    for p in sets:
        p["filter.gnss_std_n"] = 2.5               # an input, unconnected here
    outcomes = BatchSimulation(model, registry(), sets).run(stop_time=2.0)
    with pytest.raises(NavfmuError) as alone:
        _single(model, sets[1], 2.0)
    assert isinstance(outcomes[1], NavfmuError) and str(outcomes[1]) == str(alone.value)
    for b in (0, 2):
        _assert_same_run(_single(model, sets[b], 2.0), outcomes[b])


def test_a_batch_whose_runs_all_fail_returns_every_error():
    model = load_scenario(MODELS / "aircraft_500s")
    sets = [dict(p, **{"filter.p0_pos": -1.0}) for p in _seed_sets(model, 2)]
    outcomes = BatchSimulation(model, registry(), sets).run(stop_time=1.0)
    assert all(isinstance(o, NavfmuError) and "p0_pos" in str(o) for o in outcomes)


def test_runs_of_a_batch_must_fly_one_trajectory():
    model = load_scenario(MODELS / "aircraft_500s")
    sets = _seed_sets(model, 2)
    for b, period in enumerate((0.01, 0.02)):
        sets[b]["trajectory.imu_period"] = period
    outcomes = BatchSimulation(model, registry(), sets).run(stop_time=1.0)
    assert isinstance(outcomes[0], type(outcomes[0])) and not isinstance(outcomes[0],
                                                                         Exception)
    assert isinstance(outcomes[1], NavfmuError)
    assert "imu_period" in str(outcomes[1]) and "one trajectory" in str(outcomes[1])


def test_a_campaign_in_batches_writes_the_run_files_of_single_runs(tmp_path):
    def run(batch, folder, runs, ran):
        spec = campaign.CampaignSpec(scenario=str(MODELS / "aircraft_500s"),
                                     filters=("Kf", "SageHusaFading"), runs=runs,
                                     stop_time=20.0, batch=batch)
        camp = campaign.Campaign(spec, folder, log=lambda m: None)
        camp.prepare()
        with Executor() as ex:
            counts = camp.run(ex)
        assert counts["ran"] == ran
        return camp

    single = run(1, tmp_path / "single", 5, 10)
    run(3, tmp_path / "batched", 2, 4)          # a campaign resumed with another batch size
    batched = run(3, tmp_path / "batched", 5, 6)
    tasks = batched.tasks([("Kf", i) for i in range(5)], workers=1)
    assert [t.key for t in tasks] == [("Kf", 0, 2), ("Kf", 3, 4)]
    for f in ("Kf", "SageHusaFading"):
        for i in range(5):
            a = json.loads(campaign_runs.run_path(single.out, f, i).read_text())
            b = json.loads(campaign_runs.run_path(batched.out, f, i).read_text())
            for record in (a, b):
                for key in ("wall_time_s", "pid"):
                    record.pop(key)
                record["metrics"].pop("time_per_step_ms")
            assert a == b


def test_the_batch_size_follows_the_option_the_backend_and_the_workers(monkeypatch):
    monkeypatch.setattr(batching, "available_memory", lambda: None)
    assert batching.batch_size(None, "direct", 20, 1, filters=3) == 20    # one per filter
    assert batching.batch_size(None, "direct", 20, 2, filters=3) == 10    # 6 tasks, 2 workers
    assert batching.batch_size(None, "direct", 3, 2, filters=4) == 3      # the report's
    assert batching.batch_size(None, "direct", 20, 2) == 5
    assert batching.batch_size(None, "direct", 500, 1) == batching.MAX_BATCH
    assert batching.batch_size(None, "fmu", 20, 1) == 1
    assert batching.batch_size(4, "direct", 20, 1) == 4
    monkeypatch.setattr(batching, "available_memory", lambda: 8 * batching.RUN_MEMORY_BYTES)
    assert batching.batch_size(None, "direct", 20, 1) == 2
    with pytest.raises(NavfmuError, match="--batch"):
        batching.check_batch(4, "fmu")
    with pytest.raises(NavfmuError, match="--batch"):
        batching.check_batch(0, "direct")
