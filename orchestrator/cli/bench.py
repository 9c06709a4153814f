"""``navfmu bench``: the FMU path against navcore directly, or several filters against each
other, timed in one process with the runs alternating; the measurements and their text."""
from __future__ import annotations

import contextlib
import os
import time
from typing import Any, Dict, List, Optional, Sequence

from navcore.ins import ideal_track

from ..campaigns.defaults import BENCH_RUNS, BENCH_WORKERS
from ..running import prechecks
from .cli_options import filter_names
from ..running.comparison_text import _num
from ..errors import NavfmuError
from ..cosim.master import Simulation
from .progress import progress_bars
from ..running.scenarios import FILTER_COMPONENT, ensure_fmus, registry, swap_filter
from ..model.ssp import SystemModel


@contextlib.contextmanager
def single_run_costs():
    """Within: no trajectory reads the ideal samples of an earlier run of this process
    (:mod:`navcore.ins.ideal_track`), so whichever path or filter runs first, every run costs what
    a single run costs."""
    before = os.environ.get(ideal_track.SWITCH)
    os.environ[ideal_track.SWITCH] = "0"
    try:
        yield
    finally:
        if before is None:
            del os.environ[ideal_track.SWITCH]
        else:
            os.environ[ideal_track.SWITCH] = before


#: the most alternating runs per path or filter a benchmark takes (the fastest of a few is
#: the measurement; more only lengthen it)
MAX_REPEAT = 100


def check_bench_options(filters=None, against_libcosim=False, executors=False, runs=None,
                        workers=None) -> None:
    """The option combinations of ``navfmu bench`` that mean something: one measurement
    (``--libcosim`` and ``--executors`` exclude each other) and ``--runs``/``--workers`` only
    with ``--executors``, which they are for; refused before anything runs."""
    if against_libcosim and executors:
        raise NavfmuError("--libcosim and --executors are two measurements; give one")
    if against_libcosim and filters is not None:
        raise NavfmuError("--libcosim times the scenario's own filter; leave out --filters")
    for name, value in (("--runs", runs), ("--workers", workers)):
        if value is not None and not executors:
            raise NavfmuError(f"{name} applies to --executors only (the campaign it times)")


def _check_repeat(repeat) -> int:
    """The checked ``repeat`` count of a benchmark: 1 to :data:`MAX_REPEAT` runs."""
    if int(repeat) != repeat or repeat < 1:
        raise NavfmuError(f"--repeat: the number of runs per path must be a positive integer, "
                          f"got {repeat}")
    if repeat > MAX_REPEAT:
        raise NavfmuError(f"--repeat: at most {MAX_REPEAT} alternating runs per path, got "
                          f"{repeat}")
    return int(repeat)


def _check_bench_run(model: SystemModel, stop_time, repeat) -> int:
    """The checked ``repeat`` count of a benchmark and its stop time."""
    repeat = _check_repeat(repeat)
    prechecks.check_stop_time(stop_time, model.start_time)
    return repeat


def _timed_run(sim: Simulation, stop_time, progress):
    t0 = time.perf_counter()
    res = sim.run(stop_time=stop_time, progress=progress)
    return time.perf_counter() - t0, res


@single_run_costs()
def bench(model: SystemModel, stop_time: Optional[float] = None, repeat: int = 2,
          progress_factory=None, log=print) -> Dict[str, Any]:
    """Run the same system through the navcore objects directly and through the FMUs, in one
    process, alternating ``repeat`` times; keep each path's fastest run (the machine is shared,
    the minimum is the least disturbed) and return wall times, their ratio and the
    per-component costs of those runs."""
    repeat = _check_bench_run(model, stop_time, repeat)
    ensure_fmus(model, log=log)
    out: Dict[str, Any] = {}
    best: Dict[str, Any] = {}
    for _ in range(repeat):
        for backend in ("direct", "fmu"):
            sim = Simulation(model, backend=backend,
                             registry=registry() if backend == "direct" else None)
            wall, res = _timed_run(sim, stop_time,
                                   progress_factory(backend) if progress_factory else None)
            if backend not in best or wall < best[backend][0]:
                best[backend] = (wall, res)
    for backend, (wall, res) in best.items():
        out[backend] = _path_costs(wall, res)
    out["repeat"] = repeat
    out["ratio"] = out["fmu"]["wall_s"] / out["direct"]["wall_s"]
    a, b = best["fmu"][1], best["direct"][1]
    out["identical"] = all(
        a.columns[c] == b.columns[c] and (a.data[c] == b.data[c]).all() for c in a.components)
    return out


def _path_costs(wall: float, res) -> Dict[str, Any]:
    """Costs of one benchmark run: wall time, simulated seconds per wall second, and per
    component the mean time per call and per base step (calls x mean / base steps) of its
    do_step and of its whole exchange (set inputs, do_step, get outputs)."""
    steps = len(res.time) - 1
    calls = res.metadata.get("step_calls", {})
    per_step = {c: 1e6 * v * calls.get(c, 0) / max(steps, 1)
                for c, v in res.exchange_step_time_s.items()}
    return {"wall_s": wall, "steps": steps,
            "simulated_s_per_wall_s": (float(res.time[-1]) - float(res.time[0])) / wall,
            "do_step_us": {c: 1e6 * v for c, v in res.step_time_s.items()},
            "exchange_us": {c: 1e6 * v for c, v in res.exchange_step_time_s.items()},
            "exchange_us_per_step": per_step,
            "master_overhead_us": 1e6 * res.metadata.get("master_overhead_s_per_step",
                                                         float("nan")),
            "wall_us_per_step": 1e6 * wall / max(steps, 1)}


def _fastest_filter_runs(models, filters, stop_time, repeat, progress_factory):
    """Filter -> the measurements of its run with the smallest mean filter do_step time."""
    best: Dict[str, Dict[str, Any]] = {}
    for _ in range(repeat):
        for f in filters:
            wall, res = _timed_run(Simulation(models[f], backend="fmu"), stop_time,
                                   progress_factory(f) if progress_factory else None)
            step = float(res.step_time_s[FILTER_COMPONENT])
            if f not in best or step < best[f]["do_step_s"]:
                best[f] = {"do_step_s": step, "wall_s": wall,
                           "calls": int(res.metadata["step_calls"][FILTER_COMPONENT]),
                           "steps": int(res.metadata["n_steps"]),
                           "stop_time": float(res.metadata["stop_time"]),
                           "cycle_s": float(res.metadata["base_step"])
                           * int(res.metadata["decimation"][FILTER_COMPONENT])}
    return best


@single_run_costs()
def bench_filters(model: SystemModel, filters: Sequence[str], stop_time: Optional[float] = None,
                  repeat: int = 3, progress_factory=None, reference=None,
                  log=print) -> Dict[str, Any]:
    """Run ``model`` through the FMUs once per filter of ``filters`` (swapped into the
    ``filter`` component), alternating the filters ``repeat`` times in this process, and keep
    each filter's fastest run (smallest mean do_step time of the filter: the machine is
    shared, the minimum is the least disturbed).  Returns per filter the filter's mean FMU
    do_step time per call (one filter cycle) in ms, the run's wall time, and the ratios to the
    first filter, next to the paper's ``time_per_cycle_ms`` (``reference``, paper.json) when it
    lists the filter; JSON-ready."""
    filters = list(filters)
    if not filters:
        raise NavfmuError("--filters: give at least one filter")
    if len(set(filters)) != len(filters):
        raise NavfmuError(f"--filters: a filter is listed twice: {', '.join(filters)}")
    repeat = _check_bench_run(model, stop_time, repeat)
    models = {f: swap_filter(model, f) for f in filters}
    for m in models.values():
        ensure_fmus(m, log=log)
    best = _fastest_filter_runs(models, filters, stop_time, repeat, progress_factory)
    paper = (reference or {}).get("time_per_cycle_ms") or {}
    base, paper_base = filters[0], paper.get(filters[0])
    rows = {}
    for f in filters:
        b = best[f]
        ms = 1e3 * b["do_step_s"]
        paper_ms = paper.get(f)
        rows[f] = {"time_per_cycle_ms": ms, "ratio": ms / (1e3 * best[base]["do_step_s"]),
                   "wall_s": b["wall_s"], "filter_calls": b["calls"], "base_steps": b["steps"],
                   "cycle_s": b["cycle_s"], "paper_time_per_cycle_ms": paper_ms,
                   "paper_ratio": (paper_ms / paper_base
                                   if paper_ms is not None and paper_base else None)}
    return {"model": model.name, "backend": "fmu", "stop_time": best[base]["stop_time"],
            "repeat": repeat,
            "baseline": base, "filters": rows}


def format_bench(model_name: str, out: Dict[str, Any]) -> str:
    """Text of :func:`bench`."""
    lines = [f"{model_name}, {out['fmu']['steps']} steps of the base step, one process, "
             f"fastest of {out['repeat']} alternating runs per path:",
             f"  wall time direct {out['direct']['wall_s']:.2f} s, co-simulation "
             f"{out['fmu']['wall_s']:.2f} s, ratio {out['ratio']:.3f}",
             f"  simulated seconds per wall second: direct "
             f"{out['direct']['simulated_s_per_wall_s']:.1f}, co-simulation "
             f"{out['fmu']['simulated_s_per_wall_s']:.1f}",
             f"  identical results through both paths: {out['identical']}",
             f"  {'component':14s} {'direct step':>12s} {'FMU step':>10s} "
             f"{'FMU set+step+get':>17s}   [us per call]   {'direct':>8s} {'FMU':>8s}"
             "   [us per base step]"]
    d, f = out["direct"], out["fmu"]
    for c in f["do_step_us"]:
        lines.append(f"  {c:14s} {d['do_step_us'][c]:12.1f} {f['do_step_us'][c]:10.1f} "
                     f"{f['exchange_us'][c]:17.1f}                   "
                     f"{d['exchange_us_per_step'][c]:8.1f} {f['exchange_us_per_step'][c]:8.1f}")
    lines.append(f"  master overhead per base step: direct {d['master_overhead_us']:.1f} us, "
                 f"FMU {f['master_overhead_us']:.1f} us; wall time per base step: direct "
                 f"{d['wall_us_per_step']:.1f} us, FMU {f['wall_us_per_step']:.1f} us")
    return "\n".join(lines)


def format_filter_bench(out: Dict[str, Any]) -> str:
    """Text of :func:`bench_filters`."""
    rows = out["filters"]
    first = rows[out["baseline"]]
    lines: List[str] = [
        f"{out['model']}: {out['stop_time']:g} s through the FMUs per filter "
        f"({first['base_steps']} base steps), one process, fastest of {out['repeat']} "
        "alternating runs per filter:",
        f"  {'filter':14s} {'ms per cycle':>12s} {'ratio':>7s} {'paper [ms]':>11s} "
        f"{'paper ratio':>12s} {'wall [s]':>9s}"]

    for name, r in rows.items():
        lines.append(f"  {name:14s} {r['time_per_cycle_ms']:12.4f} {r['ratio']:7.2f} "
                     f"{_num(r['paper_time_per_cycle_ms'], '11.3f')} "
                     f"{_num(r['paper_ratio'], '12.2f')} {r['wall_s']:9.2f}")
    lines.append(f"  one cycle = one do_step of the filter FMU ({first['cycle_s']:g} s); ratios "
                 f"to {out['baseline']}, the first filter")
    return "\n".join(lines)


def _libcosim_text(model_name, stop, out) -> str:
    return (f"{model_name}, {stop:g} s, fastest of {out['repeat']} alternating runs: ours "
            f"(jacobi) {out['ours_s']:.2f} s, libcosim recording every output "
            f"{out['libcosim_recorded_s']:.2f} s (ratio {out['ratio_recorded']:.2f}), "
            f"libcosim alone {out['libcosim_unrecorded_s']:.2f} s (ratio "
            f"{out['ratio_unrecorded']:.2f})")


def bench_command(scenario=None, stop=100.0, repeat=3, filters=None, against_libcosim=False,
                  executors=False, runs=BENCH_RUNS, workers=BENCH_WORKERS, as_json=False,
                  log=print) -> str:
    """``navfmu bench``: the measurement its options choose (FMU path against direct, the
    ``filters`` against each other, our master against libcosim, or the executors), as text
    or JSON.  ``scenario`` defaults to navfmu's own models/aircraft_500s.  Every run is
    measured as a single run (:func:`single_run_costs`)."""
    import json

    from ..building import build as fmu_build
    from ..results.jsonsafe import jsonable
    from ..running.scenarios import load_scenario, paper_reference

    scenario = scenario or fmu_build.ROOT / "models" / "aircraft_500s"
    check_bench_options(filters, against_libcosim, executors)
    repeat = _check_repeat(repeat)
    if executors:
        from ..campaigns.campaign_bench import bench_executors, format_bench as format_executors

        names = filter_names(filters or "Kf")
        with single_run_costs():
            out = bench_executors(str(scenario), names, runs=runs, stop_time=stop,
                                  workers=workers, log=log)
        return json.dumps(out, indent=2) if as_json else format_executors(out)
    model = load_scenario(scenario)
    if against_libcosim:
        from ..cosim.libcosim_run import bench_against_libcosim

        ensure_fmus(model, log=log)
        with single_run_costs():
            out = bench_against_libcosim(scenario, stop, repeat)
        return json.dumps(out, indent=2) if as_json else _libcosim_text(model.name, stop, out)
    if filters is not None:
        with progress_bars() as progress_bar:
            out = bench_filters(model, filter_names(filters), stop_time=stop, repeat=repeat,
                                progress_factory=progress_bar, reference=paper_reference(model),
                                log=log)
        return json.dumps(jsonable(out), indent=2) if as_json else format_filter_bench(out)
    with progress_bars() as progress_bar:
        out = bench(model, stop_time=stop, repeat=repeat, progress_factory=progress_bar, log=log)
    return json.dumps(out, indent=2) if as_json else format_bench(model.name, out)


__all__ = ["bench", "bench_filters", "bench_command", "check_bench_options", "format_bench",
           "format_filter_bench", "MAX_REPEAT"]
