"""Benchmark of the campaign executors: the same small campaign serially, on a local process
pool and on a Dask LocalCluster, in one invocation (ratios, never absolute bounds).

* speed-up: wall time of the serial campaign / wall time on ``workers`` pool processes
  (workers started and warmed before the clock starts, as in a long campaign);
* per-run overhead: the same campaign with runs of one base step, so the wall time per run
  is almost only dispatch, result transfer and the run file; Dask's minus the pool's is
  what Dask adds per run.
"""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, Optional, Sequence

from .campaign import Campaign, CampaignSpec
from .executor import Executor, Task
from .defaults import BENCH_RUNS, BENCH_WORKERS


def _warm(seconds: float) -> int:
    """Import what a run needs and hold the worker a moment (so every worker gets one)."""
    from ..cosim import master  # noqa: F401
    from ..running import scenarios  # noqa: F401

    scenarios.registry()
    time.sleep(seconds)
    return os.getpid()


def _timed_campaign(spec: CampaignSpec, options: Dict[str, Any]) -> float:
    with tempfile.TemporaryDirectory(prefix="navfmu-bench-") as folder:
        campaign = Campaign(spec, Path(folder), log=lambda m: None)
        campaign.prepare()
        with Executor(**options) as ex:
            n = max(1, options.get("workers", 1))
            list(ex.run([Task(("warm", i), _warm, (0.3,)) for i in range(2 * n)]))
            t0 = time.perf_counter()
            campaign.run(ex)
            return time.perf_counter() - t0


def bench_executors(scenario: str, filters: Sequence[str] = ("Kf",), runs: int = BENCH_RUNS,
                    stop_time: Optional[float] = 50.0, workers: int = BENCH_WORKERS,
                    dask: bool = True,
                    log=print) -> Dict[str, Any]:
    """Wall times of one campaign per executor mode and the derived ratios (JSON-ready)."""
    Executor(workers=workers)      # --workers checked before the serial leg runs
    modes = {"serial": {"workers": 1}, "pool": {"workers": workers}}
    if dask:
        modes["dask"] = {"workers": workers, "local_cluster": True}
    spec = CampaignSpec(scenario=scenario, filters=tuple(filters), runs=runs,
                        stop_time=stop_time)
    walls = {}
    for mode, options in modes.items():
        log(f"campaign of {runs * len(filters)} runs, {mode}")
        walls[mode] = _timed_campaign(spec, options)
    from ..running.scenarios import load_scenario

    tiny = CampaignSpec(scenario=scenario, filters=tuple(filters), runs=runs,
                        stop_time=load_scenario(scenario).base_step)
    overhead = {}
    for mode in ("pool", "dask") if dask else ("pool",):
        log(f"campaign of {runs * len(filters)} one-step runs, {mode}")
        overhead[mode] = _timed_campaign(tiny, modes[mode]) / (runs * len(filters))
    out = {"scenario": scenario, "filters": list(filters), "runs": runs,
           "stop_time": stop_time, "workers": workers, "wall_s": walls,
           "speedup_pool_over_serial": walls["serial"] / walls["pool"],
           "one_step_run_s": overhead, "load_average": list(os.getloadavg()),
           "cores": os.cpu_count()}
    if dask:
        out["dask_overhead_per_run_s"] = overhead["dask"] - overhead["pool"]
    return out


def format_bench(out: Dict[str, Any]) -> str:
    """The text ``navfmu bench --executors`` prints."""
    w = out["wall_s"]
    lines = [f"{out['scenario']}: {out['runs'] * len(out['filters'])} runs of "
             f"{out['stop_time']:g} s ({', '.join(out['filters'])}), workers started before "
             "the clock; load average " + "/".join(f"{x:.1f}" for x in out["load_average"])
             + f" on {out['cores']} cores",
             "  wall time: " + ", ".join(f"{m} {t:.2f} s" for m, t in w.items()),
             f"  speed-up of {out['workers']} pool workers over serial: "
             f"{out['speedup_pool_over_serial']:.2f}",
             "  one-step runs, wall time per run: " + ", ".join(
                 f"{m} {1e3 * t:.1f} ms" for m, t in out["one_step_run_s"].items())]
    if "dask_overhead_per_run_s" in out:
        lines.append(f"  Dask's overhead per run over the pool: "
                     f"{1e3 * out['dask_overhead_per_run_s']:.1f} ms")
    return "\n".join(lines)


__all__ = ["bench_executors", "format_bench"]
