"""The Markdown document of ``navfmu report`` (:mod:`orchestrator.reporting.report`): its header
(command, commit, machine, method), every scenario's section (:mod:`.report_sections`, the
figures of :mod:`.report_figures`), the NEES/NIS consistency table with its warnings, and the
cross matrix of filters and scenarios.
"""
from __future__ import annotations

import datetime
import os
import platform
from typing import List

from ..campaigns import campaign as camp
from ..campaigns import statistics as st
from ..results import metrics as nav_metrics
from ..results.metric_comparisons import GROUP_KEYS, rms_3d
from .report_sections import ci, mission_table, paper_table, per_run_interval, provenance_line


def _mean_inside(metrics, group):
    """Mean over the axes of a group's percentage inside +-3 sigma (None without sigmas)."""
    per_axis = (metrics.get("inside_3sigma_pct") or {}).get(group)
    return sum(per_axis.values()) / len(per_axis) if per_axis else None


def consistency_table(sections) -> List[str]:
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
            nees = [per_run_interval(plan, f, lambda m, g=g: (m.get("nees") or {}).get(g))
                    for g in ("position", "velocity", "attitude")]
            nis = per_run_interval(plan, f, lambda m: (m.get("nis") or {}).get("mean"))
            first = rows[0]["metrics"].get("nis") or {}
            band = first.get("band95")
            inside = [per_run_interval(plan, f, lambda m, g=g: _mean_inside(m, g))
                      for g in ("position", "velocity", "attitude")]
            lines.append(f"| {plan['model'].name} | {f} | " + " | ".join(ci(n, 2) for n in nees)
                         + f" | {ci(nis, 2)} | {first.get('dof', '-')} | "
                         + (f"{band[0]:.2f}-{band[1]:.2f}" if band else "-") + " | "
                         + " / ".join(ci(v, 1) for v in inside) + " |")
    return lines + [""] + inconsistent_lines(sections)


def inconsistent_lines(sections) -> List[str]:
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


def cross_matrix(sections) -> List[str]:
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
            cells.append(" / ".join(ci(per_run_interval(plan, f, lambda m, g=g: group_rms(m, g)),
                                        3 if g == "position" else 4)
                                    for g in ("position", "velocity", "attitude")))
        lines.append(f"| {f} | " + " | ".join(cells) + " |")
    lines += ["", "Runs per scenario: " + "; ".join(f"{provenance_line(p)}" for p in sections), ""]
    return lines


def markdown(sections, command, seconds, workers, scheduler, local_cluster) -> str:
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
            lines += [ref.get("paper", ""), ""] + paper_table(plan)
        lines += mission_table(plan)
        figs = plan["figures"]
        lines += [f"![RMS of every filter on {plan['model'].name}](figures/{figs['rms'].name})",
                  ""]
        if "errors" in figs:
            lines += [f"{plan['errors_caption'][:1].upper()}{plan['errors_caption'][1:]} "
                      f"and NIS of run 0 "
                      f"({provenance_line(plan).split(', backend')[0]}):", "",
                      f"![errors](figures/{figs['errors'].name})", "",
                      f"![NIS](figures/{figs['nis'].name})", ""]
    lines += consistency_table(sections) + cross_matrix(sections)
    return "\n".join(lines) + "\n"
