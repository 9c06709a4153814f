"""``navfmu tune``: the genetic algorithm (orchestrator.campaigns.genetic) over parameters of a
model.

Each cost evaluation is one co-simulation of the system model per training seed with the
candidate's values set on the named component; the cost is the attitude fitness of paper 003
eq. 20 (``metrics.attitude_fitness``: RMS of the attitude error over the samples of the
fitness window and the three Euler angles, deg) of the model's ``filter`` component, averaged
over the training seeds.  A training seed ``s`` is given to every component parameter named
``seed``, so the tuner sees other sensor noise than the model's own runs if asked to.

Evaluations run through :class:`orchestrator.campaigns.executor.Executor` (serial, local process
pool, Dask), one task per candidate, or on the direct backend one task per batch of candidates
(all their training runs stepped together, :mod:`orchestrator.cosim.batch`: the numbers of the
single runs); results depend only on the candidates, so the same ``--seed`` gives the same
tuned values with any number of workers and any batch size.

Parameter ranges: a ``--range name=lo:hi`` option, else the parameter's declared limits
(``Port.limits`` of our components, when both ends are finite), else, for another FMU, the
``min``/``max`` of its model description.

The first population holds the model's current values (its bindings or the declared
defaults) besides random individuals, so the tuned set is never worse than them on the
training runs.

Outputs (in ``out``): ``<component>_tuned.ssv`` (an SSP parameter set: the component's
other parameters as the model binds them, then the best values; the model binds it with one
line in place of the component's bindings,
``<ssd:ParameterBinding source="<component>_tuned.ssv"/>``), ``tune.json`` (settings, per
generation best/mean cost, the best values) and ``fitness.png`` (paper 003's Fig. 1).
"""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..results import metrics as nav_metrics
from ..model.ssv_writer import ssv_text
from ..errors import NavfmuError
from . import batching
from .executor import Executor, Task
from .genetic import GeneticAlgorithm, decode
from ..results.run_results import atomic_write
from ..running.scenarios import FILTER_COMPONENT, ensure_fmus, load_scenario, registry
from ..running.ssv_bindings import bind_overrides
from ..cosim.master import Simulation
from ..model.ssp import SystemModel
from .defaults import DEFAULT_SEED, DEFAULT_WORKERS


@dataclass(frozen=True)
class TuneSpec:
    """What one evaluation needs (picklable, for the executor's workers)."""

    ssd: str
    component: str
    names: Tuple[str, ...]
    train_seeds: Tuple[Optional[int], ...]
    backend: str
    stop_time: Optional[float]
    window: Optional[Tuple[float, float]]
    seed_parameters: Tuple[str, ...]
    #: fixed overrides of every run (``--ssv``), under the candidate's values and the seeds
    parameters: Tuple[Tuple[str, Any], ...] = ()
    #: the sensor log every run replays (``--replay``; ``stop_time`` then in the log's time)
    replay: Optional[str] = None


def spec_model(spec: TuneSpec) -> Tuple[SystemModel, Dict[str, Any], Optional[float]]:
    """The model one evaluation runs, the overrides its log adds to every run and the stop
    time of :meth:`Simulation.run`: the scenario, or with ``spec.replay`` the scenario
    replaying that log (:func:`~orchestrator.running.replay.replay_model`; the log is parsed
    once per process, :mod:`navcore.sensors.log_cache`)."""
    model = load_scenario(spec.ssd)
    if spec.replay is None:
        return model, {}, spec.stop_time
    from ..running import replay as log_replay

    model, notes = log_replay.replay_model(model, spec.replay, stop_time=spec.stop_time)
    return model, log_replay.parameter_overrides(model, notes), None


def parse_ranges(items: Sequence[str]) -> Dict[str, Tuple[float, float]]:
    """``["a=lo:hi", ...]`` -> ``{a: (lo, hi)}``."""
    out = {}
    for item in items:
        name, sep, rng = item.partition("=")
        try:
            lo, hi = (float(x) for x in rng.split(":"))
        except ValueError:
            lo = hi = math.nan
        if not sep or not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
            raise NavfmuError(f"--range: expected name=lo:hi with lo < hi, got {item!r}")
        out[name.strip()] = (lo, hi)
    return out


def _declared_ranges(model: SystemModel, component: str, backend: str):
    """name -> (type, min, max, start) of the component's numeric parameters."""
    spec = model.component(component)
    source = Path(spec.source)
    out = {}
    if source.stem in registry():
        for p in registry()[source.stem].parameters:
            if p.type in ("Real", "Integer"):
                lim = p.limits
                lo = math.nextafter(lim.low, math.inf) if lim.low_open else lim.low
                hi = math.nextafter(lim.high, -math.inf) if lim.high_open else lim.high
                out[p.name] = (p.type, lo if math.isfinite(lo) else None,
                               hi if math.isfinite(hi) else None, float(p.start))
        return out
    if source.is_file():
        from fmpy import read_model_description

        for v in read_model_description(str(source)).modelVariables:
            if v.causality == "parameter" and v.type in ("Real", "Integer"):
                lo = None if v.min is None else float(v.min)
                hi = None if v.max is None else float(v.max)
                out[v.name] = (v.type, lo, hi, float(v.start))
        return out
    raise NavfmuError(f"component '{component}': FMU not found ({source}); build it first")


def resolve_parameters(model: SystemModel, component: str, names: Sequence[str],
                       ranges: Dict[str, Tuple[float, float]], backend: str):
    """``(lo, hi, types, current)`` for ``names`` (see the module docstring); ``current``
    holds the values the model runs with now (its bindings, else the declared start)."""
    if not names:
        raise NavfmuError("--params: give at least one parameter to tune")
    if len(set(names)) != len(names):
        raise NavfmuError(f"--params: a parameter is listed twice: {', '.join(names)}")
    declared = _declared_ranges(model, component, backend)
    for name in ranges:
        if name not in names:
            raise NavfmuError(f"--range {name}: not one of --params")
    lo, hi, types, current = [], [], [], []
    bound = model.component(component).parameters
    for name in names:
        if name == "seed":
            raise NavfmuError(f"--params seed: component '{component}''s random seed is not "
                              "a tuning parameter (the cost would fit one noise draw); give "
                              "the seeds to train on with --train-seeds")
        if name not in declared:
            raise NavfmuError(f"--params: component '{component}' has no numeric parameter "
                              f"'{name}'")
        typ, dlo, dhi, start = declared[name]
        current.append(float(bound[name][1]) if name in bound else start)
        a, b = ranges.get(name, (dlo, dhi))
        if a is None or b is None:
            raise NavfmuError(f"--params {name}: the parameter declares no range; give "
                              f"--range {name}=lo:hi")
        lo.append(a)
        hi.append(b)
        types.append(typ)
    return np.array(lo, float), np.array(hi, float), tuple(types), np.array(current)


def _values(spec: TuneSpec, types, x) -> Dict[str, Any]:
    return {n: (int(round(v)) if t == "Integer" else float(v))
            for n, t, v in zip(spec.names, types, x)}


def _run_parameters(spec: TuneSpec, values: Dict[str, Any], seed,
                    log_overrides=None) -> Dict[str, Any]:
    parameters = {**(log_overrides or {}), **dict(spec.parameters)}
    parameters.update({f"{spec.component}.{k}": v for k, v in values.items()})
    if seed is not None:
        parameters.update({p: seed for p in spec.seed_parameters})
    return parameters


def _fitness(spec: TuneSpec, results) -> float:
    """The attitude fitness of one run's results (paper 003 eq. 20)."""
    names = nav_metrics.filters_of(results)
    target = FILTER_COMPONENT if FILTER_COMPONENT in names else (names or [None])[0]
    if target is None:
        raise NavfmuError(f"{spec.ssd}: no filter component to measure the fitness of")
    errors = nav_metrics.navigation_errors(results, target)
    return nav_metrics.attitude_fitness(errors, nav_metrics.window_mask(errors, spec.window))


def evaluate(spec: TuneSpec, values: Dict[str, Any]) -> float:
    """Cost of one candidate: mean attitude fitness over the training seeds (a task)."""
    model, log_overrides, stop = spec_model(spec)
    costs = []
    for seed in spec.train_seeds:
        sim = Simulation(model, backend=spec.backend,
                         registry=registry() if spec.backend == "direct" else None,
                         parameters=_run_parameters(spec, values, seed, log_overrides))
        costs.append(_fitness(spec, sim.run(stop_time=stop)))
    return float(np.mean(costs))


def evaluate_batch(spec: TuneSpec, candidates: List[Dict[str, Any]]) -> List[float]:
    """:func:`evaluate` of several candidates (a task): every (candidate, training seed) run
    in one batch on the direct backend (:mod:`orchestrator.cosim.batch`, the numbers of the
    single runs); a run that fails raises its own error after the batch."""
    from ..cosim.batch import BatchSimulation

    model, log_overrides, stop = spec_model(spec)
    sets = [_run_parameters(spec, values, seed, log_overrides) for values in candidates
            for seed in spec.train_seeds]
    outcomes = BatchSimulation(model, registry(), sets).run(stop_time=stop)
    for outcome in outcomes:
        if isinstance(outcome, NavfmuError):
            raise outcome
    seeds = len(spec.train_seeds)
    return [float(np.mean([_fitness(spec, r) for r in outcomes[i * seeds:(i + 1) * seeds]]))
            for i in range(len(candidates))]


def _seed_parameters(model: SystemModel, backend: str) -> Tuple[str, ...]:
    found = []
    for c in model.components:
        try:
            declared = _declared_ranges(model, c.name, backend)
        except NavfmuError:
            continue
        if "seed" in declared:
            found.append(f"{c.name}.seed")
    return tuple(found)


def _costs(ex: Executor, spec: TuneSpec, candidates, batch: Optional[int],
           workers: int) -> List[float]:
    """The cost of every candidate of a generation: one task per candidate, or per batch of
    candidates on the direct backend (:mod:`.batching`)."""
    size = batching.batch_size(batch, spec.backend, len(candidates), workers)
    if size == 1:
        costs = ex.map([Task(i, evaluate, (spec, c)) for i, c in enumerate(candidates)])
        return [costs[i] for i in range(len(candidates))]
    groups = [candidates[i:i + size] for i in range(0, len(candidates), size)]
    costs = ex.map([Task(i, evaluate_batch, (spec, g)) for i, g in enumerate(groups)])
    return [c for i in range(len(groups)) for c in costs[i]]


def run_tune(scenario, component: str, names: Sequence[str], generations: int = 5,
             population: int = 10, workers: int = DEFAULT_WORKERS,
             seed: int = DEFAULT_SEED,
             ranges: Optional[Dict[str, Tuple[float, float]]] = None,
             train_seeds: Sequence[int] = (), backend: str = "direct",
             stop_time: Optional[float] = None, window=None, scheduler=None,
             crossover_probability: float = 0.8, mutation_probability: float = 0.2,
             progress=None, log=print, batch: Optional[int] = None,
             parameters: Optional[Dict[str, Any]] = None,
             replay: Optional[str] = None) -> Dict[str, Any]:
    """Run the GA (see the module docstring); returns the JSON-ready summary.  ``batch``:
    candidates per batch on the direct backend (None: chosen, :mod:`.batching`).
    ``parameters``: overrides of every run (``{"component.parameter": value}``, ``--ssv``);
    the tuned component's are its current values and go into the tuned set.  ``replay``:
    a sensor log every run replays in place of the scenario's sensors (``stop_time`` in the
    log's time), the runs of a batch sharing one replay (:mod:`navcore.components.
    replay_batch`)."""
    batching.check_batch(batch, backend)
    batch_size = batch
    model, spec, (lo, hi, types, current) = _tuning_spec(
        scenario, component, names, ranges, train_seeds, backend, stop_time, window,
        parameters, replay, log)
    ga = GeneticAlgorithm(len(names), population, generations, crossover_probability,
                          mutation_probability, seed)
    # progress in individuals of the generations (an individual met before is not re-run)
    total = population * generations
    with Executor(workers=workers, scheduler=scheduler) as ex:
        def batch(rows):
            candidates = [_values(spec, types, decode(r, lo, hi)) for r in rows]
            return _costs(ex, spec, candidates, batch_size, workers)

        def generation_done(g, _result):
            if progress is not None:
                progress((g + 1) * population, total)
            log(f"generation {g + 1}/{generations}: best cost {_result.best_so_far[-1]:.5f}, "
                f"generation mean {_result.generation_mean[-1]:.5f}")

        result = ga.run(batch, generation_done, initial=[(current - lo) / (hi - lo)])
    best = _values(spec, types, decode(result.best_genes, lo, hi))
    return {"model": model.name, "ssd": str(model.path), "component": component,
            "parameters": list(names), "ranges": {n: [float(a), float(b)]
                                                  for n, a, b in zip(names, lo, hi)},
            "population": population, "generations": generations, "seed": seed,
            "workers": workers, "backend": backend, "train_seeds": list(train_seeds),
            "replay": spec.replay,
            "window": list(window) if window else None,
            "cost": "attitude RMS over the window and roll/pitch/yaw [deg] (paper 003 eq. 20)",
            "best_values": best, "best_cost": result.best_cost,
            "bound_parameters": {k: [t, v] for k, (t, v) in
                                 model.component(component).parameters.items() if k not in best},
            "best_so_far": result.best_so_far, "generation_best": result.generation_best,
            "generation_mean": result.generation_mean, "evaluations": result.evaluations}


def _tuning_spec(scenario, component, names, ranges, train_seeds, backend, stop_time, window,
                 parameters, replay, log):
    """The model (overrides bound), the :class:`TuneSpec` every evaluation runs, and the tuned
    parameters' ranges, types and current values; a bad component, parameter, range or
    sensor log is refused here, before any evaluation."""
    model = load_scenario(scenario)
    if component not in [c.name for c in model.components]:
        raise NavfmuError(f"--component: {model.path} has no component '{component}'")
    if backend == "fmu":
        ensure_fmus(model, log=log)
    model = bind_overrides(model, parameters or {})
    resolved = resolve_parameters(model, component, list(names), ranges or {}, backend)
    spec = TuneSpec(str(model.path), component, tuple(names),
                    tuple(int(s) for s in train_seeds) or (None,), backend, stop_time,
                    window, _seed_parameters(model, backend) if train_seeds else (),
                    tuple((parameters or {}).items()),
                    None if replay is None else str(Path(replay).expanduser().resolve()))
    if replay is not None:      # a bad log or span: its error now, before any evaluation
        replayed = spec_model(spec)[0]
        if backend == "fmu":
            ensure_fmus(replayed, log=log)
        spec = dataclasses.replace(spec, seed_parameters=(
            _seed_parameters(replayed, backend) if train_seeds else ()))
    return model, spec, resolved


def write_tune_outputs(summary: Dict[str, Any], out: Path) -> List[Path]:
    """``<component>_tuned.ssv``, ``tune.json`` and ``fitness.png``, all in ``out`` (never in
    the model's folder); none of them if one cannot be written."""
    from ..results import filter_plots  # not imported by the executor's workers

    out = Path(out)
    made = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise NavfmuError(f"--out {out}: cannot make the folder: {exc.strerror or exc}"
                          ) from None
    name = f"{summary['component']}_tuned"
    ssv = out / f"{name}.ssv"
    text = ssv_text(name, summary["best_values"], summary.get("bound_parameters"))
    writers = [lambda: atomic_write(ssv, lambda f: f.write(text)),
               lambda: atomic_write(out / "tune.json",
                                    lambda f: f.write(json.dumps(summary, indent=2))),
               lambda: filter_plots.plot_fitness(summary, out / "fitness.png")]
    written: List[Path] = []
    try:
        for write in writers:
            written.append(write())
    except BaseException:
        for path in written:       # all three or none: no tuned set without its record
            path.unlink(missing_ok=True)
        if made:
            shutil.rmtree(out, ignore_errors=True)
        raise
    return written
