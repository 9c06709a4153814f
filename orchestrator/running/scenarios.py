"""The scenario facade: load a scenario, swap its filter, run it and compute its metrics.

A *scenario* is a folder of ``models/`` with a ``SystemStructure.ssd`` (and optional
``paper.json`` with the paper's reference numbers).  Filters are found in the results by the
signal contract: every recorded component with a ``nav_time`` output is a filter, the one with
``truth_time`` is the truth source.  What is made of runs lives beside it: the paper
comparison (:mod:`orchestrator.running.comparison`, :mod:`orchestrator.running.comparison_text`),
the output files (:mod:`orchestrator.running.run_outputs`) and the benchmarks
(:mod:`orchestrator.cli.bench`).
"""
from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional

from ..building import build as fmu_build
from ..building.build import ensure_fmus
from ..results import metrics as nav_metrics
from ..results import mission_metrics
from . import prechecks
from .paper_shape import check_reference
from ..results import recorder
from ..results import windows as paper_windows
from ..errors import NavfmuError, NavfmuWarning
from ..cosim.master import Simulation
from ..results.run_results import Results
from ..model.ssp import SystemModel
from ..model.ssp_archive import load_model
from ..model.suggestions import did_you_mean

#: name of the component a ``--filter`` swap replaces
FILTER_COMPONENT = "filter"


def registry():
    """Model name -> navcore component class, for the direct backend."""
    from navcore.components.registry import REGISTRY

    return REGISTRY


def resolve_filter(name_or_path: str) -> Path:
    """``Kf`` -> ``fmus/dist/Kf.fmu``; a path to an ``.fmu`` is taken as it is."""
    p = Path(name_or_path)
    if p.suffix == ".fmu" or "/" in name_or_path:
        if not p.is_file():
            raise NavfmuError(f"filter FMU file not found: {p}")
        return p.resolve()
    if not (fmu_build.FMU_SOURCES / f"{name_or_path}.py").is_file():
        ours = filter_fmus()
        raise NavfmuError(f"unknown filter '{name_or_path}' (our filters: {', '.join(ours)}; "
                          f"or give the path of an .fmu file){did_you_mean(name_or_path, ours)}")
    return fmu_build.fmu_path(name_or_path)


def filter_fmus() -> List[str]:
    """Our FMUs that are navigation filters (their component outputs ``nav_time``), not the
    sensors or the replay."""
    known = registry()
    return [s.stem for s in fmu_build.slave_scripts() if s.stem in known
            and any(port.name == "nav_time" for port in known[s.stem].outputs)]


def swap_filter(model: SystemModel, filter: str) -> SystemModel:
    """``model`` with its ``filter`` component's FMU replaced (see :func:`resolve_filter`)."""
    if FILTER_COMPONENT not in [c.name for c in model.components]:
        raise NavfmuError(f"{model.path}: no component named '{FILTER_COMPONENT}' to swap")
    return model.replace_source(FILTER_COMPONENT, resolve_filter(filter))


def load_scenario(path) -> SystemModel:
    from .replay import resolve_log_parameters

    return resolve_log_parameters(load_model(Path(path)))


def paper_reference(model: SystemModel) -> Optional[Dict[str, Any]]:
    ref = Path(model.path).parent / "paper.json"
    if not ref.is_file():
        return None
    try:
        data = json.loads(ref.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise NavfmuError(f"{ref}: cannot read the paper's reference numbers: {exc}") from None
    return check_reference(data, ref)


def mission_baseline(model: SystemModel) -> Optional[Dict[str, Any]]:
    """The baseline run a mission scenario declares in its ``mission.json``: ``{"label": ...,
    "parameters": {"component.parameter": value}}`` (e.g. the vehicle guided on its truth),
    or None."""
    ref = Path(model.path).parent / "mission.json"
    if not ref.is_file():
        return None
    try:
        baseline = json.loads(ref.read_text(encoding="utf-8"))["baseline"]
        label, parameters = str(baseline["label"]), dict(baseline["parameters"])
    except (OSError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        raise NavfmuError(f"{ref}: cannot read the mission baseline ('baseline' with 'label' "
                          f"and 'parameters'): {exc!r}") from None
    return {"label": label, "parameters": parameters}


def has_truth(results: Results) -> bool:
    return any(results.has(c, "truth_time") for c in results.components)


@dataclass
class Run:
    """One co-simulation and its metrics."""

    label: str
    model: SystemModel
    results: Results
    metrics: Dict[str, Dict[str, Any]] = field(default_factory=dict)
    #: the Parquet file the run was streamed to (then ``results`` has no rows)
    series_file: Optional[Path] = None
    #: of a streamed run: paper.json window name -> filter component -> metrics
    window_metrics: Dict[str, Dict[str, Dict[str, Any]]] = field(default_factory=dict)
    #: of a replay: the log's time of the run's time 0 [s] (its time origin)
    time_origin: float = 0.0


def filter_label(model: SystemModel, filter: Optional[str] = None) -> str:
    """The name a run of ``model`` (with ``filter`` swapped in) is reported under: the
    filter FMU's name, or the model's name when it has no ``filter`` component."""
    if FILTER_COMPONENT not in [c.name for c in model.components]:
        return model.name
    return Path(resolve_filter(filter) if filter
                else model.component(FILTER_COMPONENT).source).stem


def simulate_scenario(model: SystemModel, filter: Optional[str] = None, backend: str = "fmu",
                      stop_time: Optional[float] = None, parameters=None, window=None,
                      progress=None, build=True, log=print, replay=None,
                      algorithm="gauss-seidel", stream_to=None, replay_options=None,
                      isolation=None, components=None) -> Run:
    """Run one scenario (optionally with the filter component swapped, and with its sensor
    components replaced by a replay of the sensor log in folder ``replay``, see
    :func:`orchestrator.running.replay.replay_model`, with its keyword arguments
    ``replay_options``: ``start_time``, ``max_dt_jitter``) and compute metrics (not without a
    truth).

    ``stream_to``: a ``.parquet`` path; the rows then go to that file and to the metrics in
    chunks (memory flat in the flight length) instead of staying in ``results``.
    ``isolation``: which FMUs run in a host process of their own
    (:class:`~orchestrator.cosim.isolation.Isolation`; default: the foreign ones).
    ``components``: model name -> component class over the registry's (direct backend)."""
    label = filter_label(model, filter)
    if filter:
        model = swap_filter(model, filter)
    record = None
    origin = 0.0
    if replay is not None:
        from . import replay as log_replay

        model, notes = log_replay.replay_model(model, replay, stop_time=stop_time,
                                               **(replay_options or {}))
        stop_time = None
        parameters = {**log_replay.parameter_overrides(model, notes), **(parameters or {})}
        record = log_replay.recorded_signals(model, notes)
        origin = notes["time_origin"]
    if backend == "fmu" and build:
        ensure_fmus(model, log=log)
    known = {**registry(), **(components or {})} if backend == "direct" else None
    sim = Simulation(model, backend=backend, registry=known,
                     parameters=parameters, record=record, algorithm=algorithm,
                     isolation=isolation)
    prechecks.check_simulation(sim, stop_time)
    if stream_to is not None:
        run = _streamed_run(label, model, sim, stop_time, progress, window, stream_to)
        report_warnings(run.results)
        run.time_origin = origin
        return report_inconsistency(run)
    results = sim.run(stop_time=stop_time, progress=progress)
    report_warnings(results)
    return report_inconsistency(measured_run(label, model, results, window,
                                             time_origin=origin))


def report_inconsistency(run: Run) -> Run:
    """Each filter of ``run`` whose position errors are mostly outside +-3 sigma
    (:func:`orchestrator.results.metrics.inconsistency_warning`): the warning kept in its
    metrics (``inconsistent``, so in metrics.json) and raised as a :class:`NavfmuWarning`."""
    for metrics in run.metrics.values():
        warning = nav_metrics.inconsistency_warning(run.label, metrics)
        if warning:
            metrics["inconsistent"] = warning
            warnings.warn(warning, NavfmuWarning, stacklevel=3)
    return run


def measured_run(label: str, model: SystemModel, results: Results, window=None,
                 time_origin: float = 0.0) -> Run:
    """The :class:`Run` of ``results`` with the metrics of every filter (none without a
    truth): what :func:`simulate_scenario` returns for rows kept in memory."""
    run = Run(label, model, results, time_origin=time_origin)
    if not has_truth(results):
        return run
    vehicle = mission_metrics.find_vehicle(results)
    for f in nav_metrics.filters_of(results):
        run.metrics[f] = nav_metrics.filter_metrics(results, f, window=window)
        if vehicle is not None:
            run.metrics[f]["mission"] = mission_metrics.mission_metrics(results, f, window,
                                                                        vehicle)
    return run


def report_warnings(results) -> None:
    """Each warning a component reported during the run (kept in
    ``results.metadata["warnings"]``) raised as a :class:`NavfmuWarning`: the command line
    prints it once as ``navfmu: warning: ...``."""
    for warning in results.metadata.get("warnings", ()):
        warnings.warn(warning, NavfmuWarning, stacklevel=3)


def _streamed_run(label, model, sim, stop_time, progress, window, stream_to) -> Run:
    """Run ``sim`` streaming its rows to the Parquet file ``stream_to`` and to the metrics of
    ``window`` and of every paper window the run reaches (a shorter run leaves the others out)."""
    overlap = max(sim.decimation.values()) + 1
    sink = recorder.MetricsSink(window=window, overlap=overlap)
    end = model.stop_time if stop_time is None else stop_time
    windowed = {name: recorder.MetricsSink(window=(float(w["t0"]), float(w["t1"])),
                                           overlap=overlap)
                for name, w in paper_windows.paper_windows(paper_reference(model)).items()
                if end is None or float(w["t0"]) < end}
    header = sim.run(stop_time=stop_time, progress=progress, sink=recorder.Tee(
        [sink, *windowed.values(), recorder.ParquetSink(stream_to)]))
    return Run(label, model, header, dict(sink.metrics), Path(stream_to),
               {name: dict(s.metrics) for name, s in windowed.items()})
