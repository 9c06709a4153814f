"""Streamed recording: the Parquet and CSV files and the chunked metrics equal the in-memory
run; memory stays flat in the flight length (slow)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from orchestrator.results import metrics as nav_metrics
from orchestrator.results import recorder
from orchestrator.running import scenarios
from orchestrator.cosim.master import Simulation

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "models" / "aircraft_outliers"


@pytest.fixture(scope="module")
def model():
    return scenarios.swap_filter(scenarios.load_scenario(SCENARIO), "NewtonRobustKf")


@pytest.fixture(scope="module")
def in_memory(model):
    sim = Simulation(model, backend="direct", registry=scenarios.registry())
    return sim.run(stop_time=20.0)


@pytest.fixture(scope="module")
def streamed(model, tmp_path_factory):
    """The same run streamed in chunks of 250 rows (the receiver is decimated 100:1, so the
    chunks cut through its held outputs); returns the folder, header and metrics."""
    folder = tmp_path_factory.mktemp("streamed")
    header, metrics = _streamed(model, folder, 250)
    return folder, header, metrics


def _streamed(model, tmp_path, chunk_rows, overlap=101):
    """The run streamed in chunks of ``chunk_rows`` rows to a Parquet file, a CSV file and
    the metric accumulators."""
    sinks = [recorder.ParquetSink(tmp_path / "run.parquet"), recorder.CsvSink(tmp_path / "run.csv"),
             recorder.MetricsSink(overlap=overlap)]
    tee = recorder.Tee(sinks)
    tee.chunk_rows = chunk_rows
    sim = Simulation(model, backend="direct", registry=scenarios.registry())
    header = sim.run(stop_time=20.0, sink=tee)
    return header, sinks[2].metrics


def _flat(d, prefix=""):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            yield f"{prefix}{k}", v


def test_streamed_files_and_metrics_equal_the_in_memory_run(in_memory, streamed):
    tmp_path, header, streamed = streamed
    assert len(header.time) == 0 and header.metadata["n_steps"] == 2000
    back = recorder.read_parquet(tmp_path / "run.parquet")
    np.testing.assert_array_equal(back.time, in_memory.time)
    for comp in in_memory.components:
        assert back.columns[comp] == in_memory.columns[comp]
        assert back.units[comp] == in_memory.units[comp]
        np.testing.assert_array_equal(back.data[comp], in_memory.data[comp])
    frame = pd.read_parquet(tmp_path / "run.parquet")         # one call, CSV's titles
    assert list(frame.columns) == in_memory.header()
    in_memory.to_csv(tmp_path / "memory.csv")
    assert (tmp_path / "run.csv").read_bytes() == (tmp_path / "memory.csv").read_bytes()
    (tmp_path / "memory.csv").unlink()
    # metrics from chunks against the whole-array definition (sums in another order)
    expected = dict(_flat(nav_metrics.filter_metrics(in_memory, "filter")))
    got = dict(_flat(streamed["filter"]))
    assert set(got) == set(expected)
    for key, value in expected.items():
        if key == "time_per_step_ms":
            continue
        assert got[key] == pytest.approx(value, rel=1e-12, abs=1e-15), key
    assert expected["outlier_detection.injected_epochs"] == 2


def test_plot_view_keeps_every_update_and_every_kth_row(in_memory, streamed):
    view = recorder.plot_view(streamed[0] / "run.parquet", max_rows=300)
    stride = view.metadata["plot_stride"]
    assert stride == 7                      # ceil(2001 / 300)
    updated = in_memory.column("filter", "updated") > 0.5
    rows = (np.arange(len(in_memory.time)) % stride == 0) | updated
    np.testing.assert_array_equal(view.time, in_memory.time[rows])
    np.testing.assert_array_equal(view.data["filter"], in_memory.data["filter"][rows])


def test_failed_run_leaves_no_file(model, tmp_path):
    sink = recorder.ParquetSink(tmp_path / "run.parquet")
    sim = Simulation(model, backend="direct", registry=scenarios.registry(),
                     parameters={"filter.init_h": float("nan")})
    with pytest.raises(Exception):
        sim.run(stop_time=5.0, sink=sink)
    assert list(tmp_path.iterdir()) == []


def test_not_a_results_file(tmp_path):
    from orchestrator.errors import NavfmuError

    (tmp_path / "x.parquet").write_bytes(b"not parquet")
    with pytest.raises(NavfmuError, match="not a readable Parquet file"):
        recorder.read_parquet(tmp_path / "x.parquet")


# ------------------------------------------------------------------------------------------
# memory and size of a long run (slow)
# ------------------------------------------------------------------------------------------
def _peak_rss_mb(out, stop):
    """Peak resident memory [MB] of `navfmu compare uav_maneuver --format parquet` in a child
    process (ru_maxrss of the waited-for children; one child per call)."""
    script = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True); "
              "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "fmus"), str(ROOT),
                                                       os.environ.get("PYTHONPATH", "")]))
    command = [sys.executable, "-c", script, sys.executable, "-m", "orchestrator.cli",
               "compare", str(ROOT / "models" / "uav_maneuver"), "--filters",
               "Ukf,ImmUkf,CtfaUkf", "--format", "parquet", "--out", str(out)]
    if stop is not None:
        command += ["--stop", str(stop)]
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    return int(done.stdout.strip().splitlines()[-1]) / 1024.0


@pytest.mark.slow
def test_uav_60_min_three_filters_memory_flat_and_files_small(tmp_path):
    short = _peak_rss_mb(tmp_path / "10min", 600.0)
    full = _peak_rss_mb(tmp_path / "60min", None)
    written = sum(p.stat().st_size for p in (tmp_path / "60min").iterdir()) / 1e6
    metrics = json.loads((tmp_path / "60min" / "metrics.json").read_text())
    print(f"peak RSS 10 min {short:.0f} MB, 60 min {full:.0f} MB; 60 min wrote {written:.0f} MB")
    assert metrics["Ukf"]["metrics"]["filter"]["window_s"] == [0.0, 3600.0]
    assert full < 400.0
    assert written < 250.0
    assert abs(full - short) < 0.2 * short


def test_compare_streams_parquet_into_the_output_folder(tmp_path, capsys):
    from orchestrator.cli.commands import main

    out = tmp_path / "cmp"
    with pytest.raises(SystemExit) as exc:
        main(["compare", str(SCENARIO), "--filters", "Kf,NewtonRobustKf", "--stop", "5",
              "--backend", "direct", "--format", "parquet", "--out", str(out)])
    assert exc.value.code == 0, capsys.readouterr().err
    frame = pd.read_parquet(out / "results_NewtonRobustKf.parquet")
    assert len(frame) == 501
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["Kf"]["metrics"]["filter"]["samples"] == 501
    assert (out / "errors.png").is_file()
    assert [p.name for p in tmp_path.iterdir()] == ["cmp"]      # no stream folder left
