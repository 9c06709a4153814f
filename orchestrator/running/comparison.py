"""Our numbers next to the paper's: the RMS table with the paper's rows and the comparison
blocks of paper.json (improvement over a baseline, time per filter cycle, phases, outlier
detection, the paper's windows), as a JSON-ready dict.  Its text:
:mod:`orchestrator.running.comparison_text`."""
from __future__ import annotations

from typing import Any, Dict, Sequence

from ..results import metrics as nav_metrics
from ..results import phases as scenario_phases
from ..results import windows as paper_windows
from ..results.metric_comparisons import (improvement_percent, per_axis, reference_metrics,
    rms_3d, rms_ratio, rms_table)
from .scenarios import FILTER_COMPONENT, Run


def _row_label(run: Run, component: str) -> str:
    return run.label if component == FILTER_COMPONENT else f"{run.label}:{component}"


def report_table(runs: Sequence[Run], reference=None) -> str:
    """RMS table of every filter of ``runs``, each followed by the row of the paper's
    ``table`` (paper.json) whose ``filter`` it is, then the paper's rows of filters not run.
    Missing numbers of the paper (null) print '-'."""
    ref_rows = []
    for r in (reference or {}).get("table", ()):
        values = (r.get("position_ned_m"), r.get("velocity_ned_mps"), r.get("attitude_deg"))
        if all(v is None for v in values):
            continue  # the paper gives no number for this row (e.g. only in a figure)
        ref_rows.append((r.get("filter"), f"paper: {r['label']}",
                         reference_metrics(*values)))
    used = set()
    rows = []
    for run in runs:
        for f, m in run.metrics.items():
            rows.append((_row_label(run, f), m))
            if f != FILTER_COMPONENT:
                continue
            for i, (name, label, ref) in enumerate(ref_rows):
                if name == run.label and i not in used:
                    rows.append((label, ref))
                    used.add(i)
    rows += [(label, ref) for i, (_, label, ref) in enumerate(ref_rows) if i not in used]
    return rms_table(rows)


def _by_filter(runs: Sequence[Run]) -> Dict[str, Dict[str, Any]]:
    """Filter label (the FMU's name) -> metrics of the swapped ``filter`` component."""
    return {run.label: run.metrics[FILTER_COMPONENT] for run in runs
            if FILTER_COMPONENT in run.metrics}


def _improvement_items(imp, b, f):
    """The per-group entries of the improvement block: 3-D percentages, per-axis percentages
    and per-axis RMS ratios, for the keys paper.json's ``improvement_percent`` has."""
    items = []
    for group in ("position", "velocity", "attitude"):
        if group in imp:
            b3, f3 = rms_3d(b, group), rms_3d(f, group)
            items.append({"key": group, "kind": "percent_3d", "baseline_rms": b3,
                          "filter_rms": f3, "ours": improvement_percent(b3, f3),
                          "paper": imp[group]})
        for suffix, kind in (("_ned", "percent_axes"), ("_ratio_ned", "ratio_axes")):
            key = group + suffix
            if key not in imp:
                continue
            bs, fs = per_axis(b, group), per_axis(f, group)
            fn = (improvement_percent if kind == "percent_axes"
                  else rms_ratio)
            items.append({"key": key, "kind": kind, "baseline_rms": bs, "filter_rms": fs,
                          "ours": [fn(x, y) for x, y in zip(bs, fs)], "paper": imp[key]})
    return items


def _improvement_block(imp, ours):
    base, filt = imp["baseline"], imp["filter"]
    block: Dict[str, Any] = {"baseline": base, "filter": filt, "note": imp.get("note", "")}
    missing = [f for f in (base, filt) if f not in ours]
    if missing:
        block["missing"] = missing
    else:
        block["items"] = _improvement_items(imp, ours[base], ours[filt])
    return block


def _time_per_cycle_block(times, ours, runs):
    base = next(iter(times))
    rows = []
    base_ms = ours.get(base, {}).get("time_per_step_ms")
    for name, m in ours.items():
        ms = m.get("time_per_step_ms")
        if ms is None:
            continue
        paper_ms = times.get(name)
        rows.append({"filter": name, "ours_ms": ms,
                     "ours_ratio": ms / base_ms if base_ms else None,
                     "paper_ms": paper_ms,
                     "paper_ratio": paper_ms / times[base] if paper_ms is not None else None})
    run0 = runs[0].results.metadata if runs else {}
    return {"baseline": base, "rows": rows,
            "filter_step_s": (run0.get("base_step", float("nan"))
                              * (run0.get("decimation") or {}).get(FILTER_COMPONENT, 1)),
            "missing": [f for f in times if f not in ours]}


def paper_comparison(runs: Sequence[Run], reference=None) -> Dict[str, Any]:
    """Our numbers next to the paper's, for the blocks ``reference`` (paper.json) has:

    * ``improvement_percent`` (baseline and filter names): per-axis entries (``position_ned``,
      ``velocity_ned`` [%], ``position_ratio_ned``, ``velocity_ratio_ned`` [baseline RMS /
      filter RMS], north/east/down) and 3-D entries (``position``, ``velocity`` [%], of the 3-D
      RMS, see :func:`orchestrator.results.metric_comparisons.rms_3d`);
    * ``time_per_cycle_ms`` (filter -> ms; the first listed is the baseline of the ratios):
      our filter's mean do_step time per call next to it;

    and, from the filters' outputs alone, the outlier detection of every filter that reports
    it (the ``outlier_detection`` entry of its metrics).  A block whose filters were not run says
    which are missing.  JSON-ready dict;
    :func:`orchestrator.running.comparison_text.format_comparison`
    prints it."""
    reference = reference or {}
    ours = _by_filter(runs)
    out: Dict[str, Any] = {}
    imp = reference.get("improvement_percent")
    if isinstance(imp, dict) and imp.get("baseline") and imp.get("filter"):
        out["improvement"] = _improvement_block(imp, ours)
    times = reference.get("time_per_cycle_ms")
    if isinstance(times, dict) and times:
        out["time_per_cycle"] = _time_per_cycle_block(times, ours, runs)
    phase_stats = scenario_phases.phase_statistics(runs, reference, nav_metrics.filters_of)
    if phase_stats and phase_stats["rows"]:
        out["phases"] = phase_stats
    detection = {name: m["outlier_detection"] for name, m in ours.items()
                 if "outlier_detection" in m}
    if detection:
        out["outlier_detection"] = detection
    windowed = paper_windows.window_comparison(runs, FILTER_COMPONENT, reference)
    if windowed:
        out["windows"] = windowed
    return out


__all__ = ["report_table", "paper_comparison"]
