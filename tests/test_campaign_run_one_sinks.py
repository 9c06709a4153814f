"""What ``campaign_runs.run_one`` hands the master, with stand-ins for the simulation and the
sinks (no run, no file library): the metrics sink's overlap of one slowest period plus one
step, the series sink only when a series is asked for and the folder is visible (Parquet or
CSV at the run's series path), the mission sink's window, and the record's metrics with and
without a filter's metrics and a mission."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from orchestrator.cosim.isolation import Isolation

from orchestrator.campaigns import campaign_runs
from orchestrator.cosim import master
from orchestrator.results import mission_metrics, recorder
from orchestrator.running import scenarios

FILTER = scenarios.FILTER_COMPONENT


class _Sink:
    """A stand-in sink: keeps its constructor's arguments."""

    made = []

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs, self.metrics = args, kwargs, {}
        _Sink.made.append(self)


class _Metrics(_Sink):
    pass


class _Mission(_Sink):
    pass


class _Parquet(_Sink):
    pass


class _Csv(_Sink):
    pass


class _Simulation:
    """A stand-in master: components decimated 1, 4 and 2; ``run`` keeps its sink."""

    last = None

    def __init__(self, model, backend, registry, parameters, isolation):
        self.decimation = {"trajectory": 1, "gnss": 4, "filter": 2}
        self.parameters = parameters
        self.isolation = isolation
        _Simulation.last = self

    def run(self, stop_time, sink):
        self.sink = sink
        return SimpleNamespace(metadata={"stop_time": stop_time})


@pytest.fixture
def stand_ins(monkeypatch):
    _Sink.made = []
    monkeypatch.setattr(master, "Simulation", _Simulation)
    monkeypatch.setattr(scenarios, "load_scenario", lambda ssd: "model")
    monkeypatch.setattr(scenarios, "swap_filter", lambda model, name: model)
    monkeypatch.setattr(recorder, "MetricsSink", _Metrics)
    monkeypatch.setattr(recorder, "ParquetSink", _Parquet)
    monkeypatch.setattr(recorder, "CsvSink", _Csv)
    monkeypatch.setattr(mission_metrics, "MissionSink", _Mission)


def _job(out, **kw):
    return {"ssd": "model.ssd", "filter": "Kf", "index": 3, "seeds": {"gnss": 7},
            "parameters": [], "backend": "direct", "stop_time": 4.0, "window": (1.0, 3.0),
            "samples": "all", "series": None, "out": str(out), "commit": "abc", **kw}


def _made(kind):
    return [s for s in _Sink.made if type(s) is kind]


def test_the_sinks_of_a_run_without_a_series(tmp_path, stand_ins):
    record = campaign_runs.run_one(_job(tmp_path))
    (metrics,), (mission,) = _made(_Metrics), _made(_Mission)
    # the slowest component steps every 4 base steps: an overlap of 4 + 1 rows
    assert metrics.kwargs == {"window": (1.0, 3.0), "samples": "all", "overlap": 5}
    assert mission.kwargs == {"window": (1.0, 3.0)}
    assert _made(_Parquet) == [] and _made(_Csv) == []
    assert _Simulation.last.sink.sinks == [metrics, mission]
    assert _Simulation.last.parameters == {"gnss.seed": 7}
    assert _Simulation.last.isolation == Isolation()      # a job that does not say: foreign
    assert record["metrics"] == {} and record["stop_time"] == 4.0 and record["index"] == 3


@pytest.mark.parametrize("fmt, kind", [("parquet", _Parquet), ("csv", _Csv)])
def test_a_series_is_written_in_the_format_asked_at_the_runs_path(tmp_path, stand_ins, fmt,
                                                                  kind):
    campaign_runs.run_one(_job(tmp_path, series=fmt))
    (sink,) = _made(kind)
    assert sink.args == (tmp_path / "series" / "Kf" / f"run-0003.{fmt}",)
    assert sink.args[0].parent.is_dir()
    assert len(_made(_Parquet)) + len(_made(_Csv)) == 1
    assert sink in _Simulation.last.sink.sinks


def test_no_series_where_the_folder_is_not_visible(tmp_path, stand_ins):
    campaign_runs.run_one(_job(tmp_path / "elsewhere", series="csv"))
    assert _made(_Parquet) == [] and _made(_Csv) == []


def test_the_record_takes_the_filters_metrics_and_its_mission(tmp_path, stand_ins,
                                                              monkeypatch):
    class Metrics(_Metrics):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.metrics = {FILTER: {"rms": 1.5}, "other": {"rms": 9.0}}

    class Mission(_Mission):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.metrics = {FILTER: {"xtrack_rms": 4.2}}

    monkeypatch.setattr(recorder, "MetricsSink", Metrics)
    monkeypatch.setattr(mission_metrics, "MissionSink", Mission)
    record = campaign_runs.run_one(_job(tmp_path))
    assert record["metrics"] == {"rms": 1.5, "mission": {"xtrack_rms": 4.2}}
