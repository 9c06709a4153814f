"""A campaign's numbers: per filter and axis the RMS mean with its interval, paired
differences between filters, the orderings they support, next to the paper's ordering.

Input: ``records`` (filter -> per-run records of :mod:`orchestrator.campaigns.campaign`, the same
run indices for every filter).  Output: a JSON-ready dict (:func:`summarize`) and its text
(:func:`format_summary`).  Statistics are those of :mod:`orchestrator.campaigns.statistics`; the
per-run RMS and the pooled RMS those of :mod:`orchestrator.results.metrics`.
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Sequence

from ..results import metric_comparisons
from ..results import metrics as nav_metrics
from ..results import mission_metrics
from . import statistics as st

#: (key, metrics group, metrics axis, label, unit), in the tables' order (north, east, down)
AXES = tuple(
    [(f"pos_{a}", "position_rms_m", a, f"pos {a.upper()}", "m")
     for a in nav_metrics.AXES]
    + [(f"vel_{a}", "velocity_rms_mps", a, f"vel {a.upper()}", "m/s")
       for a in nav_metrics.AXES]
    + [(f"att_{a}", "attitude_rms_deg", a, a, "deg") for a in nav_metrics.ATTITUDE]
    # the mission metrics of a guided vehicle (orchestrator.results.mission_metrics), when
    # the runs have them
    + [(key, "mission", key, label, "m") for key, label in mission_metrics.SHORT_LABELS.items()])
_PAPER_KEYS = {"position_rms_m": "position_ned_m", "velocity_rms_mps": "velocity_ned_mps",
               "attitude_rms_deg": "attitude_deg"}


def recorded_axes(records: Mapping[str, Sequence[Mapping[str, Any]]]) -> List[tuple]:
    """The :data:`AXES` every run of every filter has (an attitude-only filter: attitude)."""
    runs = [r["metrics"] for rows in records.values() for r in rows]
    return [ax for ax in AXES if all(ax[1] in m for m in runs)]


def per_run_values(records: Sequence[Mapping[str, Any]], group: str, axis: str) -> List[float]:
    """One value per run (a metric a run could not measure, stored as null: NaN)."""
    values = [r["metrics"][group][axis] for r in records]
    return [math.nan if v is None else float(v) for v in values]


def paper_values(reference: Optional[Mapping[str, Any]]) -> Dict[str, Dict[str, float]]:
    """filter -> axis key -> the paper's number (from paper.json's ``table``)."""
    out: Dict[str, Dict[str, float]] = {}
    for row in (reference or {}).get("table", ()):
        name = row.get("filter")
        for key, group, axis, _, _ in AXES:
            if group not in _PAPER_KEYS:
                continue
            values = row.get(_PAPER_KEYS[group])
            if name and values is not None:
                i = (nav_metrics.ATTITUDE if group == "attitude_rms_deg"
                     else nav_metrics.AXES).index(axis)
                if values[i] is not None:
                    out.setdefault(name, {})[key] = float(values[i])
    return out


def summarize(records: Mapping[str, Sequence[Mapping[str, Any]]],
              reference: Optional[Mapping[str, Any]] = None,
              provenance: Optional[Mapping[str, Any]] = None) -> Dict[str, Any]:
    """Statistics of a campaign (see the module docstring)."""
    filters = list(records)
    paper = paper_values(reference)
    axes: Dict[str, Any] = {}
    for key, group, axis, label, unit in recorded_axes(records):
        values = {f: per_run_values(records[f], group, axis) for f in filters}
        entry = {"label": label, "unit": unit,
                 "filters": {f: {**st.positive_interval(v),
                                 "pooled_rms": metric_comparisons.pooled_rms(v),
                                 "paper": paper.get(f, {}).get(key)}
                             for f, v in values.items()}}
        if len(filters) > 1:
            entry["orderings"] = st.supported_orderings(values)
            ranked = [f for f in filters if f in paper and key in paper[f]]
            if len(ranked) > 1:
                ranked.sort(key=lambda f: paper[f][key])
                entry["paper_ordering"] = ranked
                entry["paper_ordering_supported"] = st.ordering_holds(values, ranked)
        axes[key] = entry
    n_runs = len(next(iter(records.values()))) if records else 0
    return {"runs": n_runs, "filters": filters, "level": st.LEVEL, "method": st.METHOD,
            "paired_method": st.PAIRED_METHOD, "axes": axes,
            "provenance": dict(provenance or {})}


def _ci(s: Mapping[str, float], digits: int) -> str:
    if not math.isfinite(s["half_width"]):      # one run: no interval
        return f"{s['mean']:.{digits}f} (n = {s['n']})"
    return f"{s['mean']:.{digits}f} [{s['low']:.{digits}f}, {s['high']:.{digits}f}]"


def _digits(unit: str) -> int:
    return 3 if unit == "m" else 4


def format_summary(summary: Mapping[str, Any]) -> str:
    """The tables ``navfmu montecarlo`` prints."""
    filters = summary["filters"]
    axes = summary["axes"]
    p = summary.get("provenance", {})
    lines = [f"{p.get('scenario', '')}: {summary['runs']} runs x {len(filters)} filters "
             f"({p.get('seeds', '')}; backend {p.get('backend', '')}; commit "
             f"{str(p.get('commit', ''))[:12]})",
             f"RMS per run: mean [{100 * summary['level']:.0f} % CI], {summary['method']}"]
    w = 26
    lines.append(f"{'axis':12s}" + "".join(f"{f:>{w}s}" for f in filters))
    for key, entry in axes.items():
        d = _digits(entry["unit"])
        lines.append(f"{entry['label'] + ' [' + entry['unit'] + ']':12s}"
                     + "".join(f"{_ci(entry['filters'][f], d):>{w}s}" for f in filters))
    if len(filters) > 1:
        pairs = [(pp["a"], pp["b"]) for pp in next(iter(axes.values()))["orderings"]["pairs"]]
        lines.append(f"\npaired difference a - b: mean [{100 * summary['level']:.0f} % CI], "
                     f"{summary['paired_method']}; '<' / '>' when the interval excludes 0")
        lines.append(f"{'axis':12s}" + "".join(f"{a + ' - ' + b:>{w + 2}s}" for a, b in pairs))
        for key, entry in axes.items():
            d = _digits(entry["unit"])
            cells = [f"{_ci(pp['difference'], d)} {pp['verdict']}"
                     for pp in entry["orderings"]["pairs"]]
            lines.append(f"{entry['label']:12s}" + "".join(f"{c:>{w + 2}s}" for c in cells))
        lines.append("\norderings the campaign supports ('<': paired interval below 0, "
                     "'~': not resolved), and the paper's:")
        for key, entry in axes.items():
            text = f"  {entry['label']:8s} {entry['orderings']['chain']}"
            if "paper_ordering" in entry:
                text += (f"   paper {' < '.join(entry['paper_ordering'])}: "
                         + ("supported" if entry["paper_ordering_supported"] else
                            "not supported"))
            lines.append(text)
    return "\n".join(lines)


__all__ = ["AXES", "recorded_axes", "summarize", "format_summary", "paper_values", "per_run_values"]
