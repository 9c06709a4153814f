"""Replaying sensor logs: record a run's sensor signals as a log, and swap a scenario's sensor
components for one ImuGnssReplay FMU playing a log.

Recording (:func:`sensor_log_from_results`): the component recording ``imu_time``/``imu_dt``
gives ``imu.csv`` (one line per new ``imu_time``), the one recording ``gnss_epoch`` gives
``gnss.csv`` (one line per change of the epoch counter; every fix must have been recorded),
the one recording ``truth_time`` gives ``truth.csv`` (one line per new truth time).  The
values are written with 17 significant digits, so a replay feeds a filter the very numbers
the recorded run fed it.

The swap (:func:`replace_components`) is generic: a set of components is replaced by one new
component; connections leaving a replaced component now leave the new one (same connector
names), connections into a replaced component are dropped.  :func:`replay_model` applies it
with the ImuGnssReplay FMU: every component whose connected outputs the replay FMU also has
is replaced, the run's time span becomes the log's, and the base step its IMU period.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from navcore.sensors.log_cache import shared_log
from navcore.sensors.log_time import (DEFAULT_MAX_DT_JITTER, absolute_text,
                                     check_max_dt_jitter, steps_to_reach)
from navcore.sensors.sensorlog import LogError, SensorLog, write_log

from ..building import build as fmu_build
from ..errors import NavfmuError
from ..results.metrics import find_component
from ..results.run_results import Results, check_commit
from ..model.ssp import ComponentSpec, Connection, SystemModel

REPLAY_MODEL = "ImuGnssReplay"
#: name of the component that replaces the sensor components
REPLAY_COMPONENT = "replay"

_IMU = ("time", "dt", "dtheta_x", "dtheta_y", "dtheta_z", "dvel_x", "dvel_y", "dvel_z")
_GNSS = ("time", "lat", "lon", "h", "vn", "ve", "vd")
_TRUTH = ("time", "lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw")


# -- recording ---------------------------------------------------------------------------
def _first_of_each(t: np.ndarray, start: int = 0) -> np.ndarray:
    """Rows where ``t`` takes a new value (held outputs repeat), from row ``start``."""
    rows = np.arange(start, len(t))
    keep = np.concatenate([[True], np.diff(t[start:]) != 0]) if len(rows) else rows
    return rows[keep]


def sensor_log_from_results(results: Results) -> SensorLog:
    """The sensor log of a recorded run (module docstring)."""
    col = results.column
    imu_c = find_component(results, "imu_", _IMU)
    gnss_c = find_component(results, "gnss_", _GNSS[:4] + ("valid", "epoch"))
    t_imu = col(imu_c, "imu_time")
    rows = _first_of_each(t_imu, 1)
    rows = rows[col(imu_c, "imu_dt")[rows] > 0]
    imu = {k: col(imu_c, "imu_" + k)[rows].copy() for k in _IMU}
    epoch = col(gnss_c, "gnss_epoch")
    change = np.flatnonzero(np.diff(epoch) != 0) + 1
    if len(change) and (np.diff(epoch[np.concatenate([[0], change])]) != 1).any():
        raise NavfmuError(f"component '{gnss_c}': its gnss_epoch jumps between recorded rows, "
                          "so fixes were not recorded; record every step to write a sensor log")
    gnss = {k: col(gnss_c, "gnss_" + k)[change].copy() for k in _GNSS
            if results.has(gnss_c, "gnss_" + k)}
    gnss["valid"] = col(gnss_c, "gnss_valid")[change].copy()
    if results.has(gnss_c, "gnss_outlier"):
        gnss["outlier"] = col(gnss_c, "gnss_outlier")[change].copy()
    truth = None
    try:
        truth_c = find_component(results, "truth_", _TRUTH)
    except NavfmuError:
        truth_c = None
    if truth_c is not None:
        rows = _first_of_each(col(truth_c, "truth_time"))
        truth = {k: col(truth_c, "truth_" + k)[rows].copy() for k in _TRUTH}
    return SensorLog(imu, gnss, truth)


def write_sensor_log(results: Results, folder) -> Path:
    """Write the sensor log of ``results`` to ``folder`` (atomically, see
    :func:`navcore.sensors.sensorlog.write_log`)."""
    try:
        return write_log(folder, sensor_log_from_results(results), before_commit=check_commit)
    except LogError as exc:
        raise NavfmuError(str(exc)) from None


# -- the swap ----------------------------------------------------------------------------
def replace_components(model: SystemModel, names: Sequence[str], new: ComponentSpec,
                       **changes) -> SystemModel:
    """``model`` with the components ``names`` replaced by ``new`` (module docstring).
    ``changes`` set other fields of the model (``start_time``, ``stop_time``, ``base_step``)."""
    names = list(names)
    for n in names:
        model.component(n)  # raises naming the model file if unknown
    if new.name in [c.name for c in model.components if c.name not in names]:
        raise NavfmuError(f"{model.path}: a component named '{new.name}' exists already")
    connections: List[Connection] = []
    connectors = dict(new.connectors)
    for c in model.connections:
        if c.end_component in names:
            continue
        if c.start_component in names:
            old = model.component(c.start_component)
            connectors[c.start_connector] = old.connectors.get(c.start_connector,
                                                                ("output", "Real"))
            if c.start_connector in old.units:
                new.units.setdefault(c.start_connector, old.units[c.start_connector])
            c = dataclasses.replace(c, start_component=new.name)
        connections.append(c)
    new = dataclasses.replace(new, connectors=connectors)
    first = min(i for i, c in enumerate(model.components) if c.name in names)
    kept = [c for c in model.components if c.name not in names]
    components = kept[:first] + [new] + kept[first:]
    replaced = dict(model.replaced_sources)
    replaced[new.name] = new.source
    return dataclasses.replace(model, components=components, connections=connections,
                               replaced_sources=replaced, **changes)


def _replay_outputs() -> set:
    from navcore.components.replay import ImuGnssReplay

    return {p.name for p in ImuGnssReplay.outputs}


def replaceable_components(model: SystemModel) -> List[str]:
    """The components every connected output of which the replay FMU has too."""
    outputs = _replay_outputs()
    used: Dict[str, set] = {}
    for c in model.connections:
        used.setdefault(c.start_component, set()).add(c.start_connector)
    return [c.name for c in model.components
            if c.name in used and used[c.name] <= outputs]


def _log_span(log: SensorLog, folder, start_time, stop_time) -> Tuple[float, float]:
    """The run's span in the log's relative time: from the first interval starting at or
    after ``start_time`` to ``stop_time`` (both in the log's time, origin included)."""
    origin = log.time_origin
    begins = log.imu["time"] - log.imu["dt"]
    start = log.start_time
    if start_time is not None:
        k = int(np.searchsorted(begins, float(start_time) - origin - 1e-9 * log.imu_period))
        if k >= len(begins):
            raise NavfmuError(f"--start {start_time}: after the last IMU interval of the log "
                              f"{folder}, which ends at "
                              f"{absolute_text(log.stop_time, origin)} s")
        start = float(begins[k])
    if stop_time is not None and float(stop_time) - origin > log.stop_time:
        raise NavfmuError(f"--stop {stop_time:g}: after the end of the log {folder} "
                          f"({absolute_text(log.stop_time, origin)} s); give a stop time up "
                          "to it, or no --stop to replay to the log's end")
    end = log.stop_time if stop_time is None else float(stop_time) - origin
    return start, end


def replay_model(model: SystemModel, log_dir, source: Optional[Path] = None,
                 stop_time: Optional[float] = None, start_time: Optional[float] = None,
                 max_dt_jitter: Optional[float] = None,
                 ) -> Tuple[SystemModel, Dict[str, object]]:
    """``model`` with its sensor components replaced by ImuGnssReplay playing ``log_dir``;
    returns the new model and notes (``replaced``, ``log``, ``has_truth``,
    ``has_gnss_velocity``, ``time_origin``, ``start_time``, ``stop_time``, ``base_step``).
    The run spans the log's IMU intervals (from the first one starting at or after
    ``start_time``, up to ``stop_time``, both in the log's time), stepped at the log's replay
    step (:func:`navcore.sensors.log_time.replay_step`); the run's times are the log's minus its
    ``time_origin``.  ``max_dt_jitter``: the bound on the IMU intervals (default the
    format's)."""
    folder = Path(log_dir).expanduser().resolve()
    jitter = DEFAULT_MAX_DT_JITTER if max_dt_jitter is None else max_dt_jitter
    try:
        jitter = check_max_dt_jitter(jitter, "--max-dt-jitter")
        log = shared_log(folder, jitter)
    except LogError as exc:
        raise NavfmuError(f"--replay: {exc}") from None
    names = replaceable_components(model)
    if not names:
        raise NavfmuError(f"{model.path}: no component whose outputs the replay provides "
                          "(a trajectory/IMU or GNSS receiver component)")
    source = Path(source) if source else fmu_build.fmu_path(REPLAY_MODEL)
    parameters = {"log": ("String", str(folder))}
    if jitter != DEFAULT_MAX_DT_JITTER:
        parameters["max_dt_jitter"] = ("Real", jitter)
    new = ComponentSpec(name=REPLAY_COMPONENT, source=source, parameters=parameters)
    step = log.replay_step
    start, end = _log_span(log, folder, start_time, stop_time)
    n = steps_to_reach(start, end, step)
    if n < 1:
        raise NavfmuError(f"--replay: the log {folder} holds less than one IMU interval "
                          f"between {absolute_text(start, log.time_origin)} s and the stop "
                          f"time {absolute_text(end, log.time_origin)} s")
    changes = {"start_time": start, "stop_time": start + n * step, "base_step": step}
    for c in model.components:
        if c.name not in names and c.step_hint is not None:
            ratio = c.step_hint / step
            if abs(ratio - round(ratio)) > 1e-9 * ratio:
                raise NavfmuError(f"--replay: component '{c.name}' steps every {c.step_hint} s, "
                                  f"not a multiple of the log's replay step {step} s")
    new_model = replace_components(model, names, new, **changes)
    if "std_n" in log.gnss:
        new_model = connect_receiver_sigmas(new_model)
    notes = {"replaced": names, "log": str(folder), "has_truth": log.truth is not None,
             "has_gnss_velocity": log.has_gnss_velocity, "time_origin": log.time_origin,
             **changes}
    return new_model, notes


def connect_receiver_sigmas(model: SystemModel) -> SystemModel:
    """The replay's ``gnss_std_*`` connected to every component fed its ``gnss_lat`` whose
    model (one of ours, by the FMU's name) has the inputs ``gnss_std_*``; a foreign FMU is
    left as it is (it may not have them)."""
    from navcore.components.registry import REGISTRY
    from navcore.core.signals import GNSS_STD

    names = [p.name for p in GNSS_STD]
    fed = {c.end_component for c in model.connections
           if c.start_component == REPLAY_COMPONENT and c.start_connector == "gnss_lat"}
    components, connections = [], list(model.connections)
    for c in model.components:
        cls = REGISTRY.get(Path(c.source).stem)
        has = cls is not None and all(n in {p.name for p in cls.inputs} for n in names)
        if c.name in fed and has and not any(n in c.connectors for n in names):
            c = dataclasses.replace(c, connectors={**c.connectors,
                                                   **{n: ("input", "Real") for n in names}},
                                    units={**c.units, **{n: "m" for n in names}})
            connections += [Connection(REPLAY_COMPONENT, n, c.name, n) for n in names]
        elif c.name == REPLAY_COMPONENT:
            c = dataclasses.replace(c, connectors={**c.connectors,
                                                   **{n: ("output", "Real") for n in names}},
                                    units={**c.units, **{n: "m" for n in names}})
        components.append(c)
    return dataclasses.replace(model, components=components, connections=connections)


def resolve_log_parameters(model: SystemModel) -> SystemModel:
    """A relative ``log`` parameter of a replay component in an SSD is relative to the .ssd
    file (as the component's ``source``); make it absolute."""
    components = []
    for c in model.components:
        value = c.parameters.get("log")
        if value is not None and value[0] == "String" and not Path(value[1]).is_absolute() \
                and Path(c.source).stem == REPLAY_MODEL:
            path = (Path(model.path).parent / value[1]).resolve()
            c = dataclasses.replace(c, parameters={**c.parameters, "log": ("String", str(path))})
        components.append(c)
    return dataclasses.replace(model, components=components)


def parameter_overrides(model: SystemModel, notes: Mapping[str, object]) -> Dict[str, object]:
    """Parameters a replay needs set: a log without GNSS velocity makes every component with a
    ``measurement`` parameter use positions only."""
    if notes.get("has_gnss_velocity", True):
        return {}
    return {f"{c.name}.measurement": "position" for c in model.components
            if "measurement" in c.parameters}


def recorded_signals(model: SystemModel, notes: Mapping[str, object]) -> Optional[List[str]]:
    """What a replay run records: everything (None), except the replay's truth outputs when
    the log has no truth (so no metric or plot mistakes them for a reference)."""
    if notes.get("has_truth", True):
        return None
    from navcore.components.replay import ImuGnssReplay

    keep = [f"{REPLAY_COMPONENT}.{p.name}" for p in ImuGnssReplay.outputs
            if not p.name.startswith("truth_") and p.type != "String"]
    return [c.name for c in model.components if c.name != REPLAY_COMPONENT] + keep
