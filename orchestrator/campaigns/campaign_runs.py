"""One run of a campaign, executed by a worker: the run of a (filter, run index) job, or of a
batch of one filter's jobs, streamed into its metrics, mission metrics and series file; and
the run files (``runs/<filter>/run-<iiii>.json``, ``series/<filter>/run-<iiii>.<fmt>``) it
writes and the driver reads back (:mod:`orchestrator.campaigns.campaign`).
"""
from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any, Dict, List, Optional

from ..cosim import interrupts
from ..cosim.isolation import Isolation
from ..errors import NavfmuError
from ..results import mission_metrics
from ..results import recorder
from ..results.jsonsafe import jsonable
from ..results.run_results import atomic_write


def run_path(out: Path, filter_name: str, index: int) -> Path:
    return Path(out) / "runs" / filter_name / f"run-{index:04d}.json"


def series_path(out: Path, filter_name: str, index: int, fmt: str) -> Path:
    return Path(out) / "series" / filter_name / f"run-{index:04d}.{fmt}"


def _job_parameters(job: Dict[str, Any]) -> Dict[str, Any]:
    parameters = dict(job["parameters"])
    parameters.update({f"{c}.seed": s for c, s in job["seeds"].items()})
    return parameters


class _RunSinks:
    """Where one run's rows go: its metrics, its mission metrics and (when asked and the
    folder is visible here) its series file."""

    def __init__(self, job: Dict[str, Any], overlap: int):
        self.job = job
        self.metrics = recorder.MetricsSink(window=job["window"], samples=job["samples"],
                                            overlap=overlap)
        out = Path(job["out"])
        self.visible = out.is_dir()
        series = None
        if job["series"] and self.visible:
            path = series_path(out, job["filter"], job["index"], job["series"])
            path.parent.mkdir(parents=True, exist_ok=True)
            series = (recorder.ParquetSink(path) if job["series"] == "parquet"
                      else recorder.CsvSink(path))
        self.mission = mission_metrics.MissionSink(window=job["window"])
        self.tee = recorder.Tee([self.metrics, series, self.mission])

    def record(self, header, wall_time_s: float) -> Dict[str, Any]:
        """The run's record (written to its run file when the folder is visible here)."""
        from ..running.scenarios import FILTER_COMPONENT

        job = self.job
        metrics = dict(self.metrics.metrics.get(FILTER_COMPONENT, {}))
        if FILTER_COMPONENT in self.mission.metrics:
            metrics["mission"] = self.mission.metrics[FILTER_COMPONENT]
        record = {"filter": job["filter"], "index": job["index"], "seeds": job["seeds"],
                  "metrics": metrics, "stop_time": header.metadata["stop_time"],
                  "wall_time_s": wall_time_s, "pid": os.getpid(),
                  "commit": job.get("commit", "")}
        if self.visible:
            write_run(Path(job["out"]), record)
        return record


def run_one(job: Dict[str, Any]) -> Dict[str, Any]:
    """Run one (filter, index) of a campaign; write its run file when the folder is visible
    here; return the record.  ``job`` is plain data (picklable for any executor)."""
    from ..cosim.master import Simulation
    from ..running.scenarios import load_scenario, registry, swap_filter

    interrupts.safe_point(f"campaign-run-{job['filter']}-{job['index']}")   # test hook
    t0 = time.perf_counter()
    model = swap_filter(load_scenario(job["ssd"]), job["filter"])
    sim = Simulation(model, backend=job["backend"],
                     registry=registry() if job["backend"] == "direct" else None,
                     parameters=_job_parameters(job),
                     isolation=Isolation(**job.get("isolation", {})))
    sinks = _RunSinks(job, overlap=max(sim.decimation.values()) + 1)
    header = sim.run(stop_time=job["stop_time"], sink=sinks.tee)
    return sinks.record(header, time.perf_counter() - t0)


def run_batch(jobs: List[Dict[str, Any]]) -> List[Dict[str, Any]]:
    """Run the jobs of one filter (other indices) as one batch on the direct backend
    (:mod:`orchestrator.cosim.batch`): the records of :func:`run_one`, each run's file
    written as soon as the batch ends.  A run that fails fails alone: the others' files are
    written, then its error is raised, naming it (the first, when several failed)."""
    from ..cosim.batch import BatchSimulation
    from ..running.scenarios import load_scenario, registry, swap_filter

    first = jobs[0]
    for job in jobs:
        interrupts.safe_point(f"campaign-run-{job['filter']}-{job['index']}")   # test hook
    t0 = time.perf_counter()
    model = swap_filter(load_scenario(first["ssd"]), first["filter"])
    sim = BatchSimulation(model, registry(), [_job_parameters(job) for job in jobs])
    overlap = max(sim.decimation.values()) + 1
    sinks = [_RunSinks(job, overlap) for job in jobs]
    outcomes = sim.run(stop_time=first["stop_time"], sinks=[s.tee for s in sinks])
    wall = (time.perf_counter() - t0) / len(jobs)    # the batch's time, shared
    records, failed = [], []
    for job, run_sinks, outcome in zip(jobs, sinks, outcomes):
        if isinstance(outcome, NavfmuError):
            failed.append((job, outcome))
        else:
            records.append(run_sinks.record(outcome, wall))
    if failed:
        job, error = failed[0]
        raise NavfmuError(f"run {job['index']} of {job['filter']}: {error}") from error
    return records


def write_run(out: Path, record: Dict[str, Any]) -> Path:
    path = run_path(out, record["filter"], record["index"])
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(path, lambda f: f.write(json.dumps(jsonable(record), indent=1)))


def read_run(out: Path, filter_name: str, index: int) -> Optional[Dict[str, Any]]:
    """The record of a finished run, or None (missing; an unreadable file counts as missing
    and is run again)."""
    path = run_path(out, filter_name, index)
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return None
    if record.get("filter") != filter_name or record.get("index") != index:
        return None
    return record
