"""The figures of a scenario's section of ``navfmu report`` (:mod:`orchestrator.reporting.report`):
the RMS intervals of every filter, and the errors with their sigma and the NIS over time of
run 0 of the paper's filters, simulated again and streamed to Parquet unless a finished run
with the same seeds and stop time is already there.
"""
from __future__ import annotations

from pathlib import Path
from typing import Dict

from ..campaigns.seeds import run_seeds
from ..errors import NavfmuError
from ..results import metrics as nav_metrics
from ..results import filter_plots, plots
from ..results import recorder


def scenario_figures(plan, out: Path, log, run: bool = True) -> Dict[str, Path]:
    """RMS intervals of every filter; errors and NIS over time of run 0 of the paper's
    filters (all filters when there is no paper)."""
    from ..running.scenarios import simulate_scenario

    name = plan["model"].name
    (out / "figures").mkdir(parents=True, exist_ok=True)
    figures = {"rms": plots.plot_rms_intervals(
        plan["summary"], out / "figures" / f"{name}_rms.png",
        f"{name}: RMS per run, mean and 95 % interval over {plan['summary']['runs']} runs "
        "(x: paper)")}
    paper = [r.get("filter") for r in (plan["reference"] or {}).get("table", ())]
    shown = [f for f in plan["filters"] if f in paper] or plan["filters"][:3]
    seeds = run_seeds(plan["spec"], plan["offsets"], 0)
    entries = []
    (out / "series").mkdir(parents=True, exist_ok=True)
    for f in shown:
        path = out / "series" / f"{name}_{f}_run0.parquet"
        if not _same_run(path, seeds, plan["spec"].stop_time or plan["model"].stop_time):
            if not run:
                continue
            log(f"{name}: run 0 of {f} for the figures")
            simulate_scenario(plan["model"], filter=f, backend="direct",
                              stop_time=plan["spec"].stop_time,
                              parameters={f"{c}.seed": s for c, s in seeds.items()},
                              stream_to=path, log=log)
        view = recorder.plot_view(path, max_rows=6000)
        entries.append((f, view, "filter", nav_metrics.navigation_errors(view, "filter")))
    if not entries:
        return figures
    title = f"{name}, run 0 ({', '.join(f'{c}.seed {s}' for c, s in seeds.items())})"
    if all("pos_n" in e for *_, e in entries):
        plan["errors_caption"] = plots.errors_caption(entries)
        figures["errors"] = plots.plot_errors(entries, out / "figures" / f"{name}_errors.png",
                                              title)
    else:  # attitude-only filters
        plan["errors_caption"] = plots.ATTITUDE_ERRORS_CAPTION
        figures["errors"] = plots.plot_attitude_errors(
            entries, out / "figures" / f"{name}_errors.png", title)
    figures["nis"] = filter_plots.plot_nis(entries, out / "figures" / f"{name}_nis.png", title)
    return figures


def _same_run(path: Path, seeds: Dict[str, int], stop_time: float) -> bool:
    """True if ``path`` holds a finished run with these seeds and stop time (a resumed
    report reuses it)."""
    if not path.is_file():
        return False
    try:
        meta = recorder.read_parquet(path, columns=[]).metadata
    except NavfmuError:
        return False
    params = meta.get("parameters", {})
    return (abs(float(meta.get("stop_time", -1.0)) - float(stop_time)) < 1e-9 and all(
        params.get(c, {}).get("seed") == s for c, s in seeds.items()))
