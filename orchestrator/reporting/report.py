"""``navfmu report``: one Markdown report with PNG figures that reproduces the papers' tables
from Monte Carlo campaigns, with NEES/NIS consistency and a cross matrix of filters and
scenarios.

Discovery is generic: every folder of ``models/`` with a ``SystemStructure.ssd`` is a
scenario (its ``paper.json``, when present, gives the paper's tables); every filter FMU
script whose navcore component has every variable the scenario's ``filter`` component is
connected with fits that scenario (INS/GNSS filters on the INS/GNSS scenarios, attitude
filters on an attitude scenario).  Each scenario gets one campaign
(:mod:`orchestrator.campaigns.campaign`, folder ``campaigns/<scenario>/``) of every fitting filter,
so re-running the report only runs what is missing.  Figures of the papers' kind (errors with
their sigma, as the text under them says, and NIS over time) come from run 0 of the paper's
filters, streamed to Parquet.
"""
from __future__ import annotations

import dataclasses
import datetime
import math
import os
import platform
import time
import warnings
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from ..building import build as fmu_build
from ..campaigns import campaign as camp
from ..results import metrics as nav_metrics
from ..results import plots
from ..results import recorder
from ..campaigns import statistics as st
from ..campaigns.campaign_summary import AXES, per_run_values
from ..campaigns.batching import check_batch
from ..campaigns.executor import Executor
from ..model.suggestions import did_you_mean
from ..errors import NavfmuError, SkippedParametersWarning, WiringError
from ..results import mission_metrics
from ..results.metric_comparisons import (GROUP_KEYS, improvement_percent, per_axis, rms_3d,
    rms_ratio)
from ..results.run_results import atomic_write
from ..running.prechecks import check_stop_time
from ..campaigns.defaults import DEFAULT_RUNS, DEFAULT_WORKERS

MODELS = fmu_build.ROOT / "models"


def fitting_filters(model) -> List[str]:
    """The filter FMUs (fmus/<Name>.py with a navcore component) that fit ``model``'s
    ``filter`` component (:class:`~orchestrator.cosim.master.Simulation` accepts the swap)."""
    from ..cosim.master import Simulation
    from ..running.scenarios import FILTER_COMPONENT, registry, swap_filter

    if FILTER_COMPONENT not in [c.name for c in model.components]:
        return []
    names = []
    for script in fmu_build.slave_scripts():
        if script.stem not in registry():
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")      # the scenario's parameters it lacks
                sim = Simulation(swap_filter(model, script.stem), backend="direct",
                                 registry=registry())
        except (WiringError, NavfmuError):
            continue
        if sim.components[sim.names.index(FILTER_COMPONENT)].variables.get("nav_time"):
            names.append(script.stem)
    return names


def scenario_folders(models: Path = MODELS, names: Sequence[str] = ()) -> List[Path]:
    """The scenario folders of ``models`` (sorted by name), or those ``names`` chooses (in
    their order, each once): a scenario name of ``models`` or the path of a scenario folder.
    An unknown name is refused before anything runs, with the names close to it."""
    found = sorted(p for p in Path(models).iterdir() if (p / "SystemStructure.ssd").is_file())
    if not names:
        return found
    by_name = {p.name: p for p in found}
    chosen: List[Path] = []
    for name in names:
        folder = by_name.get(name) or Path(name)
        if not (folder / "SystemStructure.ssd").is_file():
            raise NavfmuError(f"--scenario {name}: no scenario of that name in {models} and "
                              "no scenario folder at that path (scenarios: "
                              f"{', '.join(by_name)}){did_you_mean(name, by_name)}")
        if folder.resolve() not in [c.resolve() for c in chosen]:
            chosen.append(folder)
    return chosen


def discover(models: Path = MODELS, names: Sequence[str] = ()) -> List[Dict[str, Any]]:
    """Scenarios of ``models/`` (sorted by name; or those of ``names``,
    :func:`scenario_folders`): dict ``path``, ``model``, ``reference`` (paper.json or None),
    ``filters`` (fitting, the paper's first, in its table's order), ``random`` (its components
    with a ``seed``)."""
    from ..running.scenarios import load_scenario, paper_reference, swap_filter

    plans = []
    for folder in scenario_folders(models, names):
        model = load_scenario(folder)
        reference = paper_reference(model)
        fitting = fitting_filters(model)
        paper = [r.get("filter") for r in (reference or {}).get("table", ())]
        ordered = [f for f in paper if f in fitting] + [f for f in fitting if f not in paper]
        if ordered:
            random = camp.random_components(swap_filter(model, ordered[0]), "direct")
            plans.append({"path": folder, "model": model, "reference": reference,
                          "filters": ordered, "random": random})
    if not plans:
        raise NavfmuError(f"{models}: no scenario with a filter the FMU scripts provide")
    return plans


def build_report(out, runs: int = DEFAULT_RUNS, workers: int = DEFAULT_WORKERS,
                 scheduler=None, local_cluster=False, stop_time: Optional[float] = None,
                 models: Path = MODELS, progress_factory=None, log=print,
                 only_finished: bool = False, batch: Optional[int] = None,
                 scenarios: Sequence[str] = ()) -> Path:
    """Run (or resume) the campaigns and write ``out/report.md`` with ``out/figures/``.

    ``only_finished``: run nothing; report, per scenario, the first runs every filter of its
    campaign in ``out`` has finished (a campaign cut short or still running), and the
    figures whose run-0 series exist.  ``scenarios``: report only these (names of ``models``
    or scenario folders, :func:`scenario_folders`; default: every scenario of ``models``)."""
    out = Path(out)
    if not str(out).strip():
        raise NavfmuError("--out: empty path; give a folder")
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise NavfmuError(f"--runs: expected a whole number >= 1, got {runs!r}")
    Executor(workers=workers, scheduler=scheduler, local_cluster=local_cluster)  # checks them
    check_stop_time(stop_time, 0.0)
    check_batch(batch, "direct")
    if only_finished and not list((out / "campaigns").glob(f"*/{camp.MANIFEST}")):
        raise NavfmuError(f"--only-finished: {out / 'campaigns'} holds no campaign to report "
                          "(run the report without --only-finished first)")
    with warnings.catch_warnings():
        # every filter is swapped into every scenario here: skipped parameters are expected
        warnings.simplefilter("ignore", SkippedParametersWarning)
        plans = discover(models, scenarios)     # an unknown scenario is refused before any run
        return _build_report(out, runs, workers, scheduler, local_cluster, stop_time, plans,
                             progress_factory, log, only_finished, batch, scenarios)


def _build_report(out, runs, workers, scheduler, local_cluster, stop_time, plans,
                  progress_factory, log, only_finished, batch, scenarios=()) -> Path:
    t0 = time.perf_counter()
    sections = []
    for plan in plans:
        name = plan["model"].name
        # a scenario without a random source (a replayed log) gives the same run every time
        spec = camp.CampaignSpec(scenario=str(plan["path"]), filters=tuple(plan["filters"]),
                                 runs=runs if plan["random"] else 1, stop_time=stop_time,
                                 batch=batch)
        folder = out / "campaigns" / name
        if only_finished:
            spec = _finished(spec, folder)
            if spec is None:
                log(f"{name}: no finished run of every filter in {folder}: left out")
                continue
        else:
            log(f"{name}: {spec.runs} runs x {len(spec.filters)} filters "
                f"({', '.join(spec.filters)})")
            camp.run_campaign(spec, folder, workers=workers, scheduler=scheduler,
                              local_cluster=local_cluster,
                              progress=progress_factory(name) if progress_factory else None,
                              log=log)
        campaign = camp.Campaign(spec, folder, log=log)
        campaign.check()
        if only_finished:
            campaign.runs = spec.runs   # the leading runs every filter has finished
        records = campaign.records()
        plan.update(summary=_summary(campaign, records, plan), records=records,
                    offsets=campaign.offsets, spec=spec)
        plan["figures"] = _figures(plan, out, log, run=not only_finished)
        sections.append(plan)
    if not sections:
        raise NavfmuError(f"{out}: no scenario to report")
    command = (f"navfmu report --runs {runs}" + "".join(f" --scenario {n}" for n in scenarios)
               + (" --only-finished" if only_finished else ""))
    text = _markdown(sections, command, time.perf_counter() - t0, workers, scheduler,
                     local_cluster)
    return atomic_write(out / "report.md", lambda f: f.write(text))


def _finished(spec, folder: Path):
    """``spec`` with ``runs`` = the number of leading runs every filter has, or None."""
    n = 0
    while n < spec.runs and all(camp.read_run(folder, f, n) for f in spec.filters):
        n += 1
    return dataclasses.replace(spec, runs=n) if n else None


def _summary(campaign, records, plan):
    from ..campaigns.campaign_summary import summarize

    return summarize(records, plan["reference"], camp.provenance(campaign, records))


def _figures(plan, out: Path, log, run: bool = True) -> Dict[str, Path]:
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
    seeds = camp.run_seeds(plan["spec"], plan["offsets"], 0)
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
    figures["nis"] = plots.plot_nis(entries, out / "figures" / f"{name}_nis.png", title)
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


# ----------------------------------------------------------------------------------------
# Markdown
# ----------------------------------------------------------------------------------------
def _ci(s, digits=3):
    if s is None:
        return "-"
    if isinstance(s, float):
        return f"{s:.{digits}f}" if math.isfinite(s) else "-"
    if not math.isfinite(s["half_width"]):
        return f"{s['mean']:.{digits}f}"
    return f"{s['mean']:.{digits}f} [{s['low']:.{digits}f}, {s['high']:.{digits}f}]"


def _provenance(plan) -> str:
    p = plan["summary"]["provenance"]
    return (f"scenario `{p['scenario']}`, {plan['summary']['runs']} runs ({p['seeds']}), "
            f"backend {p['backend']}, samples {p['samples']}, window "
            f"{p['window'] or 'whole run'}, stop time "
            f"{str(p['stop_time']) + ' s' if p['stop_time'] else 'of the SSD'}, commit "
            f"`{str(p['commit'])[:12]}`")


def _per_run(plan, f, fn) -> Optional[Dict[str, float]]:
    values = [fn(r["metrics"]) for r in plan["records"][f] if r["metrics"]]
    interval = st.positive_interval(values) if values else None
    return interval if interval and interval["n"] else None


def _paper_table(plan) -> List[str]:
    summary, ref = plan["summary"], plan["reference"]
    if not ref.get("table"):
        return ([f"({ref.get('note') or 'The paper gives no table.'})", ""] + _orderings(plan)
                + _improvement(plan) + _time_per_cycle(plan) + _detection(plan))
    lines = [f"**Table: RMS errors** ({ref.get('source', '')}). Ours: mean [95 % CI] over the "
             f"runs, {summary['method']}; {_provenance(plan)}.", ""]
    keys = list(summary["axes"])  # the axes the filters have (attitude-only: attitude)
    lines.append("| filter | | " + " | ".join(f"{summary['axes'][k]['label']} "
                                               f"[{summary['axes'][k]['unit']}]" for k in keys)
                 + " |")
    lines.append("|---|---|" + "---|" * len(keys))
    for row in ref.get("table", ()):
        f = row.get("filter")
        if f not in summary["filters"]:
            continue
        ours = [_ci(summary["axes"][k]["filters"][f], 3 if summary["axes"][k]["unit"] == "m"
                    else 4) for k in keys]
        theirs = [_ci(summary["axes"][k]["filters"][f]["paper"]) for k in keys]
        lines.append(f"| {f} | ours | " + " | ".join(ours) + " |")
        lines.append(f"| {row.get('label', '')} | paper | " + " | ".join(theirs) + " |")
    lines.append("")
    lines += _orderings(plan)
    lines += _improvement(plan)
    lines += _time_per_cycle(plan)
    lines += _detection(plan)
    return lines


def _orderings(plan) -> List[str]:
    summary = plan["summary"]
    if len(summary["filters"]) < 2:
        return []
    paper = [e for e in summary["axes"].values() if "paper_ordering" in e]
    lines = ["**Orderings** of the paper's filters (paired t intervals of the per-run "
             "differences; `<`: the interval lies below 0, `~`: not resolved):", ""]
    names = [r.get("filter") for r in plan["reference"].get("table", ())
             if r.get("filter") in plan["records"]] or list(plan["records"])
    where = {key: (group, axis) for key, group, axis, *_ in AXES}
    for key, entry in summary["axes"].items():
        group, axis = where[key]
        values = {f: [r["metrics"][group][axis] for r in plan["records"][f]] for f in names}
        chain = st.supported_orderings(values)["chain"] if len(values) > 1 else "-"
        text = f"- {entry['label']}: {chain}"
        if "paper_ordering" in entry:
            text += (f"; paper {' < '.join(entry['paper_ordering'])}: "
                     + ("**supported**" if entry["paper_ordering_supported"]
                        else "not supported"))
        lines.append(text)
    if not paper:
        lines.append("- (the paper gives no per-axis numbers to order)")
    return lines + [""]


#: the mission metrics of the report, the first one ordering the filters
_MISSION_KEYS = ("cross_track_rms_m", "outage_cross_track_max_m", "outage_position_error_max_m",
                 "cross_track_max_m", "waypoint_miss_max_m")


def _mission(plan) -> List[str]:
    """A guided vehicle's mission metrics (orchestrator.results.mission_metrics): the filters
    ordered by their mean cross-track error, each metric with its interval, and the orderings
    the paired intervals support."""
    records = plan["records"]
    if not records or not all("mission" in r["metrics"] for rows in records.values()
                              for r in rows):
        return []
    values = {k: {f: per_run_values(rows, "mission", k) for f, rows in records.items()}
              for k in _MISSION_KEYS}
    order = sorted(records, key=lambda f: st.t_interval(values[_MISSION_KEYS[0]][f])["mean"])
    labels = mission_metrics.SHORT_LABELS
    lines = ["**Mission**: the true path against the route, per filter ordered by its mean "
             "cross-track RMS (mean [95 % CI] over the runs; `out`: during the GNSS outage; "
             "`orchestrator/results/mission_metrics.py`).", "",
             "| filter | " + " | ".join(f"{labels[k]} [m]" for k in _MISSION_KEYS) + " |",
             "|---|" + "---|" * len(_MISSION_KEYS)]
    for f in order:
        lines.append(f"| {f} | " + " | ".join(_ci(st.t_interval(values[k][f]), 2)
                                             for k in _MISSION_KEYS) + " |")
    if len(records) > 1:
        lines += ["", "Orderings the paired intervals support:", ""]
        lines += [f"- {labels[k]}: {st.supported_orderings(values[k])['chain']}"
                  for k in _MISSION_KEYS[:3]]
    return lines + [""]


def _improvement(plan) -> List[str]:
    imp = (plan["reference"] or {}).get("improvement_percent")
    if not isinstance(imp, dict) or imp.get("baseline") not in plan["records"] or \
            imp.get("filter") not in plan["records"]:
        return []
    base, filt = imp["baseline"], imp["filter"]
    pairs = list(zip(plan["records"][base], plan["records"][filt]))
    lines = [f"**Improvement of {filt} over {base}** (per run, then mean [95 % CI]; "
             f"ratios: geometric mean with the {st.LOG_METHOD}; {imp.get('note', '')}):", "",
             "| quantity | ours | paper |", "|---|---|---|"]
    for group in ("position", "velocity", "attitude"):
        if group in imp:
            v = [improvement_percent(rms_3d(b["metrics"], group), rms_3d(f["metrics"], group))
                 for b, f in pairs]
            lines.append(f"| {group} 3-D RMS reduction [%] | {_ci(st.t_interval(v), 1)} | "
                         f"{imp[group]} |")
        for suffix, fn, what, interval in (
                ("_ned", improvement_percent, "reduction [%]", st.t_interval),
                ("_ratio_ned", rms_ratio, "ratio base/filter", st.log_interval)):
            if group + suffix not in imp:
                continue
            for i, axis in enumerate("NED"):
                v = [fn(per_axis(b["metrics"], group)[i],
                        per_axis(f["metrics"], group)[i]) for b, f in pairs]
                lines.append(f"| {group} {axis} {what} | {_ci(interval(v), 2)} | "
                             f"{imp[group + suffix][i]} |")
    return lines + [""]


def _time_per_cycle(plan) -> List[str]:
    times = (plan["reference"] or {}).get("time_per_cycle_ms")
    if not isinstance(times, dict):
        return []
    base = next(iter(times))
    lines = ["**Time per filter cycle** (navcore step on the direct backend, mean over the "
             "runs' per-run means, on a shared machine; `navfmu bench --filters` measures "
             "the FMUs alternating in one process):", "",
             "| filter | ours [ms] | ours / " + base + " | paper [ms] | paper / " + base + " |",
             "|---|---|---|---|---|"]
    base_ms = _per_run(plan, base, lambda m: m.get("time_per_step_ms")) \
        if base in plan["records"] else None
    for f in plan["summary"]["filters"]:
        ms = _per_run(plan, f, lambda m: m.get("time_per_step_ms"))
        if ms is None or f not in times:
            continue
        ratio = ms["mean"] / base_ms["mean"] if base_ms else float("nan")
        lines.append(f"| {f} | {_ci(ms, 4)} | {ratio:.2f} | {times[f]} | "
                     f"{times[f] / times[base]:.2f} |")
    return lines + [""]


def _detection(plan) -> List[str]:
    lines = []
    for f, rows in plan["records"].items():
        dets = [r["metrics"].get("outlier_detection") for r in rows]
        if not all(dets) or not sum(d["injected_epochs"] for d in dets):
            continue
        total = {k: sum(d[k] for d in dets) for k in (
            "injected_epochs", "detected_epochs", "clean_observations",
            "false_alarm_observations")}
        rate = total["detected_epochs"] / total["injected_epochs"] if total[
            "injected_epochs"] else float("nan")
        fa = total["false_alarm_observations"] / total["clean_observations"] if total[
            "clean_observations"] else float("nan")
        lines.append(f"- {f}: detected {total['detected_epochs']}/{total['injected_epochs']} "
                     f"injected epochs ({100 * rate:.1f} %), false alarms on "
                     f"{100 * fa:.2f} % of the clean observations (all runs pooled)")
    return (["**Outlier detection**:", ""] + lines + [""]) if lines else []


def _mean_inside(metrics, group):
    """Mean over the axes of a group's percentage inside +-3 sigma (None without sigmas)."""
    per_axis = (metrics.get("inside_3sigma_pct") or {}).get(group)
    return sum(per_axis.values()) / len(per_axis) if per_axis else None


def _consistency(sections) -> List[str]:
    lines = ["## Consistency: NEES and NIS", "",
             "Mean NEES per group (expected 3 for a consistent filter) and mean NIS at the "
             "updates (expected: its dof; 95 % band of one run's mean in brackets), each "
             "mean [95 % CI] over the runs; NEES uses the diagonal of the covariance.  Inside "
             "+-3 sigma: percentage of the samples with |error| <= 3 sigma, mean of the three "
             "axes of the group (99.7 % for a consistent filter), mean [95 % CI] over the runs.",
             "",
             "| scenario | filter | NEES position | NEES velocity | NEES attitude | mean NIS | "
             "dof | one run's band | inside 3 sigma pos/vel/att [%] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for plan in sections:
        for f, rows in plan["records"].items():
            nees = [_per_run(plan, f, lambda m, g=g: (m.get("nees") or {}).get(g))
                    for g in ("position", "velocity", "attitude")]
            nis = _per_run(plan, f, lambda m: (m.get("nis") or {}).get("mean"))
            first = rows[0]["metrics"].get("nis") or {}
            band = first.get("band95")
            inside = [_per_run(plan, f, lambda m, g=g: _mean_inside(m, g))
                      for g in ("position", "velocity", "attitude")]
            lines.append(f"| {plan['model'].name} | {f} | " + " | ".join(_ci(n, 2) for n in nees)
                         + f" | {_ci(nis, 2)} | {first.get('dof', '-')} | "
                         + (f"{band[0]:.2f}-{band[1]:.2f}" if band else "-") + " | "
                         + " / ".join(_ci(v, 1) for v in inside) + " |")
    return lines + [""] + _inconsistent(sections)


def _inconsistent(sections) -> List[str]:
    """One line per scenario and filter with runs whose position errors are mostly outside
    +-3 sigma (:func:`orchestrator.results.metrics.inconsistency_warning` of its first such
    run, and how many runs are)."""
    lines = []
    for plan in sections:
        for f, rows in plan["records"].items():
            found = [w for w in (nav_metrics.inconsistency_warning(f, row["metrics"])
                                 for row in rows) if w]
            if found:
                lines.append(f"- {plan['model'].name}: warning: {found[0]} (in {len(found)} of "
                             f"{len(rows)} runs)")
    return lines + [""] if lines else []


def _cross_matrix(sections) -> List[str]:
    filters = []
    for plan in sections:
        filters += [f for f in plan["filters"] if f not in filters]
    lines = ["## Cross matrix", "",
             "3-D RMS (root of the sum of the per-axis mean squares) per run, mean [95 % CI]: "
             "position [m] / velocity [m/s] / attitude [deg]; every filter that fits each "
             "scenario.", "",
             "| filter | " + " | ".join(p["model"].name for p in sections) + " |",
             "|---|" + "---|" * len(sections)]
    for f in filters:
        cells = []
        for plan in sections:
            if f not in plan["records"]:
                cells.append("-")
                continue
            group_rms = lambda m, g: (rms_3d(m, g)  # noqa: E731
                                      if GROUP_KEYS[g] in m else None)
            cells.append(" / ".join(_ci(_per_run(plan, f, lambda m, g=g: group_rms(m, g)),
                                        3 if g == "position" else 4)
                                    for g in ("position", "velocity", "attitude")))
        lines.append(f"| {f} | " + " | ".join(cells) + " |")
    lines += ["", "Runs per scenario: " + "; ".join(f"{_provenance(p)}" for p in sections), ""]
    return lines


def _markdown(sections, command, seconds, workers, scheduler, local_cluster) -> str:
    commit = camp.code_commit()
    where = (f"Dask scheduler {scheduler}" if scheduler else
             f"Dask LocalCluster of {workers}" if local_cluster else
             f"{workers} local worker process(es)")
    lines = ["# navfmu: the papers' tables from Monte Carlo campaigns", "",
             f"Generated {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC by "
             f"`{command}` at commit `{commit}` in {seconds / 60:.1f} min on "
             f"{where} ({platform.machine()}, {os.cpu_count()} cores, load average "
             f"{os.getloadavg()[0]:.1f}).", "",
             "Every run of a scenario uses the seeds of its run index (same seeds for every "
             "filter, so the filters' numbers are paired); RMS per axis over every recorded "
             "row of the run (`orchestrator/results/metrics.py`), on the direct backend "
             "(the navcore objects behind the FMUs, identical numbers: "
             "`tests/test_campaign.py`).  Means "
             f"with {st.METHOD}; differences with {st.PAIRED_METHOD}.  The per-run files are "
             "in `campaigns/<scenario>/runs/`.", ""]
    for plan in sections:
        ref = plan["reference"]
        lines += [f"## {plan['model'].name}" + (f": paper {ref['paper'].split(':')[0]}"
                                                 if ref else ""), ""]
        if ref:
            lines += [ref.get("paper", ""), ""] + _paper_table(plan)
        lines += _mission(plan)
        figs = plan["figures"]
        lines += [f"![RMS of every filter on {plan['model'].name}](figures/{figs['rms'].name})",
                  ""]
        if "errors" in figs:
            lines += [f"{plan['errors_caption'][:1].upper()}{plan['errors_caption'][1:]} "
                      f"and NIS of run 0 "
                      f"({_provenance(plan).split(', backend')[0]}):", "",
                      f"![errors](figures/{figs['errors'].name})", "",
                      f"![NIS](figures/{figs['nis'].name})", ""]
    lines += _consistency(sections) + _cross_matrix(sections)
    return "\n".join(lines) + "\n"


__all__ = ["build_report", "discover", "fitting_filters", "DEFAULT_RUNS"]
