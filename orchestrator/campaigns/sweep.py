"""Parameter-scale sweep: one scenario run per (level, filter, seed) with chosen parameters scaled.

A small campaign for sensitivity studies: every level ``k`` multiplies the scenario's values of
the named parameters (``"component.parameter"``) by ``k``; each (level, filter, seed) is one
task of :mod:`orchestrator.campaigns.executor` running the scenario on the direct backend (identical
to the FMU path), and its result is the 3-D RMS of the position, velocity and attitude errors
(``metric_comparisons.rms_3d``) plus the per-phase means of :mod:`orchestrator.results.phases` when
the scenario declares phases.  :func:`sweep_table` turns the results into a Markdown table
(mean over the seeds, each filter's RMS relative to the first filter's, the baseline) and
:func:`plot_sweep` into a PNG.  Nothing here knows what the parameters mean.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..results import metric_comparisons
from ..results import metrics as nav_metrics
from . import batching
from .executor import Executor, Task
from ..results.phases import phase_statistics
from .defaults import DEFAULT_WORKERS

GROUPS = ("position", "velocity", "attitude")


def base_values(model, names: Sequence[str]) -> Dict[str, float]:
    """The scenario's values of ``"component.parameter"`` names (from its SSV bindings)."""
    from orchestrator.cosim.master import Simulation
    from orchestrator.running.scenarios import registry

    values = Simulation(model, backend="direct", registry=registry()).parameter_values
    flat = {}
    for comp, params in values.items():
        for pname, value in params.items():
            flat[f"{comp}.{pname}"] = value
    missing = [n for n in names if n not in flat]
    if missing:
        from ..errors import NavfmuError
        raise NavfmuError(f"{model.path}: no parameter {', '.join(missing)} to sweep")
    return {n: float(flat[n]) for n in names}


def run_point(scenario: str, filter: str, level: float, scaled: Dict[str, float],
              fixed: Dict[str, Any], stop_time: Optional[float]) -> Dict[str, Any]:
    """One sweep task (module docstring): scenario path, filter, level, base values of the
    scaled parameters, other parameter overrides (e.g. seeds)."""
    import warnings

    from orchestrator.running import scenarios

    model = scenarios.load_scenario(scenario)
    parameters = _point_parameters(level, scaled, fixed)
    with warnings.catch_warnings():       # the baseline skips the adaptive filters' settings
        warnings.simplefilter("ignore", UserWarning)
        run = scenarios.simulate_scenario(model, filter=filter, backend="direct",
                                          stop_time=stop_time, parameters=parameters,
                                          build=False, log=lambda m: None)
    return _point(run, model)


def _point_parameters(level: float, scaled: Dict[str, float],
                      fixed: Dict[str, Any]) -> Dict[str, Any]:
    """The overrides of one point: the fixed ones, and the scaled ones at ``level``."""
    parameters = dict(fixed)
    parameters.update({name: level * value for name, value in scaled.items()})
    return parameters


def _point(run, model) -> Dict[str, Any]:
    """A sweep point's result from its run (module docstring)."""
    from orchestrator.running import scenarios

    metrics = run.metrics[scenarios.FILTER_COMPONENT]
    out = {"rms_3d": {g: metric_comparisons.rms_3d(metrics, g) for g in GROUPS}, "phases": {}}
    stats = phase_statistics([run], scenarios.paper_reference(model), nav_metrics.filters_of)
    for row in (stats or {}).get("rows", ()):
        out["phases"][row["variable"]] = row["means"]
    return out


def run_points(scenario: str, filter: str, points: Sequence[Tuple[float, Dict[str, Any]]],
               scaled: Dict[str, float], stop_time: Optional[float]) -> List[Dict[str, Any]]:
    """:func:`run_point` of several ``(level, fixed)`` points of one filter, run as one batch
    (:mod:`orchestrator.cosim.batch`: the numbers of the single runs); a run that fails
    raises its own error after the batch."""
    import warnings

    from orchestrator.cosim.batch import BatchSimulation
    from orchestrator.running import scenarios

    model = scenarios.swap_filter(scenarios.load_scenario(scenario), filter)
    sets = [_point_parameters(level, scaled, fixed) for level, fixed in points]
    with warnings.catch_warnings():       # the baseline skips the adaptive filters' settings
        warnings.simplefilter("ignore", UserWarning)
        outcomes = BatchSimulation(model, scenarios.registry(), sets).run(stop_time=stop_time)
    label = scenarios.filter_label(model)
    points_out = []
    for outcome in outcomes:
        if isinstance(outcome, Exception):
            raise outcome
        points_out.append(_point(scenarios.measured_run(label, model, outcome), model))
    return points_out


def sweep(scenario: str, filters: Sequence[str], levels: Sequence[float],
          scaled_names: Sequence[str], seeds: Sequence[Dict[str, Any]] = ({},),
          stop_time: Optional[float] = None, workers: int = DEFAULT_WORKERS, progress=None,
          batch: Optional[int] = None):
    """Results keyed ``(level, filter, seed index)`` (module docstring).  ``batch``: points
    of a filter per batch (None: chosen, :mod:`.batching`; 1: one task per point)."""
    from orchestrator.running import scenarios

    base = base_values(scenarios.load_scenario(scenario), scaled_names)
    keys = [(float(k), f, i) for k in levels for f in filters for i in range(len(seeds))]
    tasks = []      # a filter's points in batches, as a campaign's runs
    for f, indices in batching.batches([(key[1], j) for j, key in enumerate(keys)], batch,
                                       "direct", workers):
        group = tuple(keys[j] for j in indices)
        if len(group) == 1:
            (k, _, i), = group
            tasks.append(Task(group[0], run_point, (str(scenario), f, k, base,
                                                    dict(seeds[i]), stop_time)))
        else:
            tasks.append(Task(group, run_points, (
                str(scenario), f, [(k, dict(seeds[i])) for k, _, i in group], base,
                stop_time)))
    results = {}
    with Executor(workers=workers) as ex:
        for key, value in ex.run(tasks, progress=progress):
            results.update(zip(key, value) if isinstance(value, list) else [(key, value)])
    return {key: results[key] for key in keys}


def _mean_over_seeds(results, level, filt, get):
    values = [get(v) for (k, f, _), v in results.items() if k == level and f == filt]
    values = [x for x in values if x is not None]
    return float(np.mean(values)) if values else float("nan")


def sweep_table(results, filters: Sequence[str], phase_variables: Sequence[str] = ()) -> str:
    """Markdown table: per level, each filter's 3-D RMS (position m, velocity m/s, attitude
    deg), its ratio to the first filter's, and the per-phase means of ``phase_variables``."""
    levels = sorted({k for k, _, _ in results})
    base = filters[0]
    head = ["level", "filter", "pos 3-D [m]", "vel 3-D [m/s]", "att 3-D [deg]",
            f"pos / {base}", f"vel / {base}", f"att / {base}"]
    phase_labels: List[str] = []            # in the scenario's window order
    for v in results.values():
        for means in v["phases"].values():
            phase_labels += [lb for lb in means if lb not in phase_labels]
    for var in phase_variables:
        head += [f"{var} {lb}" for lb in phase_labels]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for k in levels:
        ref = {g: _mean_over_seeds(results, k, base, lambda v, g=g: v["rms_3d"][g])
               for g in GROUPS}
        for f in filters:
            rms = {g: _mean_over_seeds(results, k, f, lambda v, g=g: v["rms_3d"][g])
                   for g in GROUPS}
            cells = [f"{k:g}", f, f"{rms['position']:.3f}", f"{rms['velocity']:.4f}",
                     f"{rms['attitude']:.4f}"]
            cells += [f"{rms[g] / ref[g]:.2f}" for g in GROUPS]
            for var in phase_variables:
                for lb in phase_labels:
                    x = _mean_over_seeds(results, k, f,
                                         lambda v, lb=lb, var=var: v["phases"].get(var, {}).get(lb))
                    cells.append("-" if x != x else f"{x:.3g}")
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot_sweep(results, filters: Sequence[str], path, title="", xlabel="level") -> Path:
    """RMS ratio to the first filter (position, velocity, attitude panels) over the level."""
    from ..results.plot_style import plt, save_png

    levels = sorted({k for k, _, _ in results})
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), sharex=True)
    base = filters[0]
    for ax, g in zip(axes, GROUPS):
        ref = np.array([_mean_over_seeds(results, k, base, lambda v: v["rms_3d"][g])
                        for k in levels])
        for i, f in enumerate(filters):
            y = np.array([_mean_over_seeds(results, k, f, lambda v: v["rms_3d"][g])
                          for k in levels])
            ax.plot(levels, y / ref, "o-", color=f"C{i}", label=f)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_title(f"{g} 3-D RMS / {base}", fontsize=9)
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return save_png(fig, path)
