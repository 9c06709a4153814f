"""The filters of a comparison on one replayed log, stepped by one replay.

``navfmu compare --replay LOG`` runs one scenario per filter on the same log.  The replay
component has no inputs and draws nothing, and on a replay nothing but the filter differs
between the runs: so one system whose replay drives every filter (one component per filter,
each wired to the replay as the scenario wires its ``filter``) gives every filter the inputs
its own run gives it, while the replay, the master's loop and the replay's exchange run once
instead of once per filter.  The batch engine (:mod:`orchestrator.cosim.batch`) cannot do it:
a batch holds one model whose runs differ in parameters, and a filter's class is its
component, not a parameter.

The shared run is split into one :class:`~orchestrator.running.scenarios.Run` per filter
whose results hold what its single run records (the replay's columns and the filter's under
the name ``filter``, the metadata of its components, its warnings), so its metrics, tables
and files are those of its single run.  It applies when nothing reads the filter's outputs
(every other component then steps as in each single run) and the rows stay in memory (not
``--format parquet``, whose runs stream to their own files); otherwise, and when the shared
run fails (the failure is then the first failing filter's own, named as in its single run),
the filters run one by one.
"""
from __future__ import annotations

import dataclasses
import re
import warnings
from typing import Callable, Dict, List, Optional, Sequence

from ..building.build import ensure_fmus
from ..cosim.master import Simulation
from ..errors import SkippedParametersWarning
from ..model.ssp import Connection, SystemModel
from ..results.run_results import Results
from . import prechecks, replay as log_replay
from .scenarios import (FILTER_COMPONENT, Run, filter_label, measured_run, registry,
                        report_inconsistency, report_warnings, swap_filter)

#: metadata entries keyed by component name
_PER_COMPONENT = ("decimation", "sources", "model_names", "replaced_sources", "parameters",
                  "step_calls", "builds")


def shareable(model: SystemModel, filters: Sequence[Optional[str]], replay, fmt: str) -> bool:
    """Whether the runs of ``filters`` on ``replay`` can share one replay (module
    docstring)."""
    names = [c.name for c in model.components]
    return (replay is not None and len(filters) > 1 and all(filters) and fmt != "parquet"
            and FILTER_COMPONENT in names
            and not any(c.start_component == FILTER_COMPONENT for c in model.connections)
            and len({filter_label(model, f) for f in filters}) == len(filters))


def _component_name(label: str, taken: Sequence[str]) -> str:
    name, k = f"{FILTER_COMPONENT}_{label}", 1
    while name in taken:
        k += 1
        name = f"{FILTER_COMPONENT}_{label}_{k}"
    return name


def _joint_model(singles: Dict[str, SystemModel], names: Dict[str, str]) -> SystemModel:
    """One model: the components of the first single model, its ``filter`` replaced by one
    component per filter (``names``: label -> component name) wired as ``filter`` is."""
    first = next(iter(singles.values()))
    components, connections = [], []
    for c in first.components:
        if c.name != FILTER_COMPONENT:
            components.append(c)
            continue
        components += [dataclasses.replace(singles[label].component(FILTER_COMPONENT),
                                           name=name) for label, name in names.items()]
    for c in first.connections:
        if c.end_component != FILTER_COMPONENT:
            connections.append(c)
            continue
        connections += [dataclasses.replace(c, end_component=name) for name in names.values()]
    replaced = {k: v for k, v in first.replaced_sources.items() if k != FILTER_COMPONENT}
    for name in names.values():
        replaced[name] = first.replaced_sources.get(FILTER_COMPONENT,
                                                    first.component(FILTER_COMPONENT).source)
    return dataclasses.replace(first, components=components, connections=connections,
                               replaced_sources=replaced)


def _joint_parameters(parameters: Dict[str, object], names: Sequence[str]) -> Dict[str, object]:
    prefix = FILTER_COMPONENT + "."
    joint = {k: v for k, v in parameters.items() if not k.startswith(prefix)}
    for k, v in parameters.items():
        if k.startswith(prefix):
            joint.update({name + k[len(FILTER_COMPONENT):]: v for name in names})
    return joint


def _renamer(name: str) -> Callable[[str], str]:
    """Text naming component ``name`` as the single run names it (``filter``)."""
    pattern = re.compile(rf"(?<![\w.]){re.escape(name)}(?=[.:' ]|$)")
    return lambda text: pattern.sub(FILTER_COMPONENT, text)


def _mentions(text: str, names: Sequence[str]) -> bool:
    return any(_renamer(n)(text) != text for n in names)


def _split(results: Results, order: Sequence[str], name: str, others: Sequence[str]) -> Results:
    """The results of the filter component ``name`` as its single run records them:
    ``order`` the single model's components (``filter`` for ``name``), ``others`` the
    other filters' components."""
    def of(component):
        return name if component == FILTER_COMPONENT else component

    rename = _renamer(name)
    meta = dict(results.metadata)
    for key in _PER_COMPONENT:
        if isinstance(meta.get(key), dict):
            meta[key] = {c: meta[key][of(c)] for c in order if of(c) in meta[key]}
    for key in ("order", "hosted", "warnings", "skipped_parameters", "delayed_connections"):
        if isinstance(meta.get(key), list):
            meta[key] = [rename(v) for v in meta[key] if not _mentions(v, others)]
    meta["shared_replay_filters"] = len(others) + 1
    recorded = [c for c in order if of(c) in results.data]
    return Results(results.time, {c: results.data[of(c)] for c in recorded},
                   {c: results.columns[of(c)] for c in recorded},
                   {c: results.units[of(c)] for c in recorded},
                   {c: results.step_time_s[of(c)] for c in recorded
                    if of(c) in results.step_time_s},
                   {c: results.exchange_step_time_s[of(c)] for c in recorded
                    if of(c) in results.exchange_step_time_s}, meta)


def _single_warning(caught, name: str, others: Sequence[str]) -> Optional[Warning]:
    """A warning of the shared run's master as the single run of ``name`` gives it (None
    when it is about another filter only)."""
    text = str(caught.message)
    if issubclass(caught.category, SkippedParametersWarning):
        head, _, items = text.partition(": ")
        kept = [i for i in items.split(", ") if not _mentions(i, others)]
        if not kept:
            return None
        text = f"{head}: {', '.join(kept)}"
    elif _mentions(text, others):
        return None
    return caught.category(_renamer(name)(text))


def simulate_filters(model: SystemModel, filters: Sequence[str], backend: str, stop_time,
                     parameters, window, progress, algorithm, log, replay,
                     replay_options=None, isolation=None) -> List[Run]:
    """The runs of ``filters`` on the log ``replay``, stepped by one replay (module
    docstring); each as :func:`~orchestrator.running.scenarios.simulate_scenario` returns
    it for its filter alone."""
    singles, notes = {}, None
    for f in filters:
        single, notes = log_replay.replay_model(swap_filter(model, f), replay,
                                                stop_time=stop_time, **(replay_options or {}))
        singles[filter_label(model, f)] = single
    names: Dict[str, str] = {}
    for label in singles:
        names[label] = _component_name(label, [c.name for c in model.components]
                                       + list(names.values()))
    joint = _joint_model(singles, names)
    overrides = {**log_replay.parameter_overrides(next(iter(singles.values())), notes),
                 **(parameters or {})}
    if backend == "fmu":
        ensure_fmus(joint, log=log)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sim = Simulation(joint, backend=backend,
                         registry=registry() if backend == "direct" else None,
                         parameters=_joint_parameters(overrides, list(names.values())),
                         record=log_replay.recorded_signals(joint, notes),
                         algorithm=algorithm, isolation=isolation)
        prechecks.check_simulation(sim, None)
        results = sim.run(stop_time=None, progress=progress)
    runs = []
    for label, name in names.items():
        others = [n for n in names.values() if n != name]
        for w in caught:          # the master's warnings, as each single run gives them
            single = _single_warning(w, name, others)
            if single is not None:
                warnings.warn(single, stacklevel=2)
        order = [c.name for c in singles[label].components]
        split = _split(results, order, name, others)
        report_warnings(split)
        runs.append(report_inconsistency(measured_run(label, singles[label], split, window,
                                                      time_origin=notes["time_origin"])))
    return runs


__all__ = ["shareable", "simulate_filters"]
