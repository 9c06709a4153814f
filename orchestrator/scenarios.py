"""One facade function per task: run a scenario, compare filters, benchmark the paths.

A *scenario* is a folder of ``models/`` with a ``SystemStructure.ssd`` (and optional
``paper.json`` with the paper's reference numbers).  Filters are found in the results by the
signal contract: every recorded component with a ``nav_time`` output is a filter, the one with
``truth_time`` is the truth source.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from . import build as fmu_build
from . import metrics as nav_metrics
from . import plots
from .errors import NavfmuError
from .master import Simulation
from .results import Results, atomic_write
from .ssp import SystemModel, load_ssd

#: name of the component a ``--filter`` swap replaces
FILTER_COMPONENT = "filter"
#: adaptive diagnostics plotted when a filter has them
ADAPTIVE_OUTPUTS = ("q_scale", "r_scale", "fading_factor", "outlier", "chi2", "model_prob_1",
                    "model_prob_2", "model_prob_3")


def registry():
    """Model name -> navcore component class, for the direct backend."""
    from navcore.components import REGISTRY

    return REGISTRY


def _fmu_sources(model: SystemModel) -> List[Path]:
    return [c.source for c in model.components]


def ensure_fmus(model: SystemModel, log=print) -> None:
    """Build the FMUs the model uses that come from ``fmus/dist`` and are missing or stale."""
    names = []
    for src in _fmu_sources(model):
        src = Path(src).resolve()
        if src.parent == fmu_build.DIST.resolve():
            if (fmu_build.FMU_SOURCES / f"{src.stem}.py").is_file():
                names.append(src.stem)
    scripts = [fmu_build.FMU_SOURCES / f"{n}.py" for n in names]
    stale = [s.stem for s in scripts if fmu_build.is_stale(s)]
    if stale:
        fmu_build.build(stale, log=log)


def resolve_filter(name_or_path: str) -> Path:
    """``Kf`` -> ``fmus/dist/Kf.fmu``; a path to an ``.fmu`` is taken as it is."""
    p = Path(name_or_path)
    if p.suffix == ".fmu" or "/" in name_or_path:
        if not p.is_file():
            raise NavfmuError(f"--filter: FMU file not found: {p}")
        return p.resolve()
    if not (fmu_build.FMU_SOURCES / f"{name_or_path}.py").is_file():
        known = ", ".join(s.stem for s in fmu_build.slave_scripts())
        raise NavfmuError(f"--filter: unknown filter '{name_or_path}' (known FMUs: {known}; or "
                          "give the path of an .fmu file)")
    return fmu_build.fmu_path(name_or_path)


def load_scenario(path) -> SystemModel:
    path = Path(path)
    return load_ssd(path)


def paper_reference(model: SystemModel) -> Optional[Dict[str, Any]]:
    ref = Path(model.path).parent / "paper.json"
    if not ref.is_file():
        return None
    try:
        return json.loads(ref.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise NavfmuError(f"{ref}: cannot read the paper's reference numbers: {exc}") from None


def filters_in(results: Results) -> List[str]:
    return [c for c in results.components if results.has(c, "nav_time")]


@dataclass
class Run:
    """One co-simulation and its metrics."""

    label: str
    model: SystemModel
    results: Results
    metrics: Dict[str, Dict[str, Any]] = field(default_factory=dict)


def simulate_scenario(model: SystemModel, filter: Optional[str] = None, backend: str = "fmu",
                      stop_time: Optional[float] = None, parameters=None, window=None,
                      progress=None, build=True, log=print) -> Run:
    """Run one scenario (optionally with the filter component swapped) and compute metrics."""
    names = [c.name for c in model.components]
    if filter:
        if FILTER_COMPONENT not in names:
            raise NavfmuError(f"{model.path}: no component named '{FILTER_COMPONENT}' to swap")
        model = model.replace_source(FILTER_COMPONENT, resolve_filter(filter))
    label = (Path(model.component(FILTER_COMPONENT).source).stem
             if FILTER_COMPONENT in names else model.name)
    if backend == "fmu" and build:
        ensure_fmus(model, log=log)
    sim = Simulation(model, backend=backend, registry=registry() if backend == "direct" else None,
                     parameters=parameters)
    results = sim.run(stop_time=stop_time, progress=progress)
    run = Run(label, model, results)
    for f in filters_in(results):
        run.metrics[f] = nav_metrics.filter_metrics(results, f, window=window)
    return run


def report_table(runs: Sequence[Run], reference=None) -> str:
    rows = []
    for run in runs:
        for f, m in run.metrics.items():
            rows.append((f"{run.label}" if f == FILTER_COMPONENT else f"{run.label}:{f}", m))
    ref_rows = []
    if reference:
        for r in reference.get("table", ()):
            ref_rows.append((f"paper: {r['label']}", r["position_enu_m"], r["velocity_enu_mps"]))
    return nav_metrics.rms_table(rows, ref_rows)


def write_outputs(runs: Sequence[Run], out: Path, fmt="csv", plots_on=True, title="") -> List[Path]:
    """Results (one file per run), metrics.json and plots; every file written atomically."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for run in runs:
        stem = "results" if len(runs) == 1 else f"results_{run.label}"
        if fmt == "npz":
            written.append(run.results.to_npz(out / f"{stem}.npz"))
        else:
            written.append(run.results.to_csv(out / f"{stem}.csv"))
    summary = {run.label: {"metrics": run.metrics,
                           "step_time_s": run.results.step_time_s,
                           "exchange_step_time_s": run.results.exchange_step_time_s,
                           "metadata": _jsonable(run.results.metadata)} for run in runs}
    written.append(atomic_write(out / "metrics.json",
                                lambda f: f.write(json.dumps(summary, indent=2, sort_keys=True))))
    if plots_on:
        entries = []
        for run in runs:
            for f in filters_in(run.results):
                label = run.label if f == FILTER_COMPONENT else f"{run.label}:{f}"
                entries.append((label, run.results, f,
                                nav_metrics.navigation_errors(run.results, f)))
        if entries:
            written.append(plots.plot_errors(entries, out / "errors.png", title))
            written.append(plots.plot_nis(entries, out / "nis.png", title))
            p = plots.plot_series(entries, ADAPTIVE_OUTPUTS, out / "adaptive.png", title)
            if p:
                written.append(p)
        truth = nav_metrics.find_component(runs[0].results, "truth_", ("time", "lat", "lon", "h"))
        written.append(plots.plot_trajectory(runs[0].results, truth, out / "trajectory.png", title))
    return written


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


def bench(model: SystemModel, stop_time: Optional[float] = None, repeat: int = 2,
          progress_factory=None, log=print) -> Dict[str, Any]:
    """Run the same system through the navcore objects directly and through the FMUs, in one
    process, alternating ``repeat`` times; keep each path's fastest run (the machine is shared,
    the minimum is the least disturbed) and return wall times, their ratio and the
    per-component costs of those runs."""
    ensure_fmus(model, log=log)
    out: Dict[str, Any] = {}
    best: Dict[str, Any] = {}
    for _ in range(max(1, int(repeat))):
        for backend in ("direct", "fmu"):
            sim = Simulation(model, backend=backend,
                             registry=registry() if backend == "direct" else None)
            progress = progress_factory(backend) if progress_factory else None
            t0 = time.perf_counter()
            res = sim.run(stop_time=stop_time, progress=progress)
            wall = time.perf_counter() - t0
            if backend not in best or wall < best[backend][0]:
                best[backend] = (wall, res)
    for backend, (wall, res) in best.items():
        out[backend] = {"wall_s": wall, "steps": len(res.time) - 1,
                        "do_step_us": {c: 1e6 * v for c, v in res.step_time_s.items()},
                        "exchange_us": {c: 1e6 * v for c, v in res.exchange_step_time_s.items()},
                        "master_overhead_us": 1e6 * res.metadata.get("master_overhead_s_per_step",
                                                                     float("nan"))}
    out["repeat"] = max(1, int(repeat))
    out["ratio"] = out["fmu"]["wall_s"] / out["direct"]["wall_s"]
    a, b = best["fmu"][1], best["direct"][1]
    out["identical"] = all(
        a.columns[c] == b.columns[c] and (a.data[c] == b.data[c]).all() for c in a.components)
    return out
