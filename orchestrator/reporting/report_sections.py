"""The Markdown of a scenario's section of ``navfmu report`` (:mod:`orchestrator.reporting.report`):
the paper's table against ours, the orderings the paired intervals support, a guided vehicle's
mission metrics, the improvement of one filter over another, the time per filter cycle and the
outlier detection, each as a list of lines; and the cells every section shares (an interval,
the runs' provenance, a per-run quantity's interval).
"""
from __future__ import annotations

import math
from typing import Dict, List, Optional

from ..campaigns import statistics as st
from ..campaigns.campaign_summary import AXES, per_run_values
from ..results import mission_metrics
from ..results.metric_comparisons import improvement_percent, per_axis, rms_3d, rms_ratio


def ci(s, digits=3):
    if s is None:
        return "-"
    if isinstance(s, float):
        return f"{s:.{digits}f}" if math.isfinite(s) else "-"
    if not math.isfinite(s["half_width"]):
        return f"{s['mean']:.{digits}f}"
    return f"{s['mean']:.{digits}f} [{s['low']:.{digits}f}, {s['high']:.{digits}f}]"


def provenance_line(plan) -> str:
    p = plan["summary"]["provenance"]
    return (f"scenario `{p['scenario']}`, {plan['summary']['runs']} runs ({p['seeds']}), "
            f"backend {p['backend']}, samples {p['samples']}, window "
            f"{p['window'] or 'whole run'}, stop time "
            f"{str(p['stop_time']) + ' s' if p['stop_time'] else 'of the SSD'}, commit "
            f"`{str(p['commit'])[:12]}`")


def per_run_interval(plan, f, fn) -> Optional[Dict[str, float]]:
    values = [fn(r["metrics"]) for r in plan["records"][f] if r["metrics"]]
    interval = st.positive_interval(values) if values else None
    return interval if interval and interval["n"] else None


def paper_table(plan) -> List[str]:
    summary, ref = plan["summary"], plan["reference"]
    if not ref.get("table"):
        return ([f"({ref.get('note') or 'The paper gives no table.'})", ""] + _orderings(plan)
                + _improvement(plan) + _time_per_cycle(plan) + _detection(plan))
    lines = [f"**Table: RMS errors** ({ref.get('source', '')}). Ours: mean [95 % CI] over the "
             f"runs, {summary['method']}; {provenance_line(plan)}.", ""]
    keys = list(summary["axes"])  # the axes the filters have (attitude-only: attitude)
    lines.append("| filter | | " + " | ".join(f"{summary['axes'][k]['label']} "
                                               f"[{summary['axes'][k]['unit']}]" for k in keys)
                 + " |")
    lines.append("|---|---|" + "---|" * len(keys))
    for row in ref.get("table", ()):
        f = row.get("filter")
        if f not in summary["filters"]:
            continue
        ours = [ci(summary["axes"][k]["filters"][f], 3 if summary["axes"][k]["unit"] == "m"
                    else 4) for k in keys]
        theirs = [ci(summary["axes"][k]["filters"][f]["paper"]) for k in keys]
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


def mission_table(plan) -> List[str]:
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
        lines.append(f"| {f} | " + " | ".join(ci(st.t_interval(values[k][f]), 2)
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
            lines.append(f"| {group} 3-D RMS reduction [%] | {ci(st.t_interval(v), 1)} | "
                         f"{imp[group]} |")
        for suffix, fn, what, interval in (
                ("_ned", improvement_percent, "reduction [%]", st.t_interval),
                ("_ratio_ned", rms_ratio, "ratio base/filter", st.log_interval)):
            if group + suffix not in imp:
                continue
            for i, axis in enumerate("NED"):
                v = [fn(per_axis(b["metrics"], group)[i],
                        per_axis(f["metrics"], group)[i]) for b, f in pairs]
                lines.append(f"| {group} {axis} {what} | {ci(interval(v), 2)} | "
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
    base_ms = per_run_interval(plan, base, lambda m: m.get("time_per_step_ms")) \
        if base in plan["records"] else None
    for f in plan["summary"]["filters"]:
        ms = per_run_interval(plan, f, lambda m: m.get("time_per_step_ms"))
        if ms is None or f not in times:
            continue
        ratio = ms["mean"] / base_ms["mean"] if base_ms else float("nan")
        lines.append(f"| {f} | {ci(ms, 4)} | {ratio:.2f} | {times[f]} | "
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
