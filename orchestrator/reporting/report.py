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

This module discovers the scenarios and runs their campaigns; the figures are
:mod:`.report_figures`, a scenario's tables :mod:`.report_sections`, the document
:mod:`.report_markdown`.
"""
from __future__ import annotations

import dataclasses
import time
import warnings
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from ..building import build as fmu_build
from ..campaigns import campaign as camp
from ..campaigns import campaign_runs as camp_runs
from ..campaigns import seeds as camp_seeds
from ..campaigns.batching import check_batch
from ..campaigns.executor import Executor
from ..model.suggestions import did_you_mean
from ..errors import NavfmuError, SkippedParametersWarning, WiringError
from ..results.run_results import atomic_write
from ..running.prechecks import check_stop_time
from ..campaigns.defaults import DEFAULT_RUNS, DEFAULT_WORKERS
from .report_figures import scenario_figures
from .report_markdown import markdown

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
            random = camp_seeds.random_components(swap_filter(model, ordered[0]), "direct")
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
        plan["figures"] = scenario_figures(plan, out, log, run=not only_finished)
        sections.append(plan)
    if not sections:
        raise NavfmuError(f"{out}: no scenario to report")
    command = (f"navfmu report --runs {runs}" + "".join(f" --scenario {n}" for n in scenarios)
               + (" --only-finished" if only_finished else ""))
    text = markdown(sections, command, time.perf_counter() - t0, workers, scheduler,
                     local_cluster)
    return atomic_write(out / "report.md", lambda f: f.write(text))


def _finished(spec, folder: Path):
    """``spec`` with ``runs`` = the number of leading runs every filter has, or None."""
    n = 0
    while n < spec.runs and all(camp_runs.read_run(folder, f, n) for f in spec.filters):
        n += 1
    return dataclasses.replace(spec, runs=n) if n else None


def _summary(campaign, records, plan):
    from ..campaigns.campaign_summary import summarize

    return summarize(records, plan["reference"], camp.provenance(campaign, records))


__all__ = ["build_report", "discover", "fitting_filters", "DEFAULT_RUNS"]
