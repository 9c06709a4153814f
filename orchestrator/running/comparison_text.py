"""The text of a paper comparison (:func:`orchestrator.running.comparison.paper_comparison`): the
paper's windows, the improvement over the baseline, the time per filter cycle, the phases
and the outlier detection, as ``navfmu run`` and ``compare`` print them."""
from __future__ import annotations

from typing import Any, Dict, List

from ..results import phases as scenario_phases
from ..results import windows as paper_windows

_UNITS = {"position": "m", "velocity": "m/s", "attitude": "deg"}


def _num(value, fmt="8.3f"):
    if value is None or (isinstance(value, float) and value != value):
        return f"{'-':>{len(format(0.0, fmt))}s}"
    return format(value, fmt)


def _pct(value):
    return "-" if value != value else f"{100 * value:.1f} %"


def _improvement_lines(imp) -> List[str]:
    base, filt = imp["baseline"], imp["filter"]
    lines = [f"\npaper's improvement of {filt} over {base}:"]
    if "missing" in imp:
        lines.append(f"  not compared: add {', '.join(imp['missing'])} to --filters")
    for item in imp.get("items", ()):
        key = item["key"]
        if item["kind"] == "percent_3d":
            unit = _UNITS.get(key, "")
            lines.append(f"  {key} 3-D RMS: {base} {item['baseline_rms']:.4f} {unit}, {filt} "
                         f"{item['filter_rms']:.4f} {unit}: ours "
                         f"{_num(item['ours'], '.1f').strip()} % lower, paper "
                         f"{_num(item['paper'], '.1f').strip()} %")
            continue
        what = (f"{key.split('_')[0]} RMS ratio {base}/{filt}" if item["kind"] == "ratio_axes"
                else f"{key.split('_')[0]} RMS reduction [%]")
        lines.append(f"  {what:40s} {'N':>8s} {'E':>8s} {'D':>8s}")
        fmt = "8.2f" if item["kind"] == "ratio_axes" else "8.1f"
        lines.append(f"  {'    ours':40s} " + " ".join(_num(v, fmt) for v in item["ours"]))
        lines.append(f"  {'    paper':40s} " + " ".join(_num(v, fmt) for v in item["paper"]))
    if imp.get("items") and any(i["kind"] == "percent_3d" for i in imp["items"]):
        lines.append("  (3-D RMS: root of the sum of the per-axis mean squares)")
    return lines


def _time_per_cycle_lines(tpc, bench_command: str, show_missing: bool) -> List[str]:
    base = tpc["baseline"]
    lines = [f"\nmean time per filter cycle (the filter's do_step, one cycle = "
             f"{tpc['filter_step_s']:g} s), ratios to {base}:",
             f"  {'filter':14s} {'ours [ms]':>10s} {'ours ratio':>11s} "
             f"{'paper [ms]':>11s} {'paper ratio':>12s}"]
    for r in tpc["rows"]:
        lines.append(f"  {r['filter']:14s} {_num(r['ours_ms'], '10.4f')} "
                     f"{_num(r['ours_ratio'], '11.2f')} {_num(r['paper_ms'], '11.3f')} "
                     f"{_num(r['paper_ratio'], '12.2f')}")
    if tpc["missing"] and show_missing:
        lines.append(f"  (paper lists {', '.join(tpc['missing'])}: not run here)")
    lines.append("  ours: separate runs one after the other on a shared machine; for the "
                 "ratios measured in one process, alternating the filters, run "
                 + (bench_command or "`navfmu bench SCENARIO --filters A,B,C`"))
    return lines


def _detection_lines(det) -> List[str]:
    lines = ["\noutlier detection at the update epochs (injected = the receiver's "
             "gnss_outlier of the fix used):"]
    for name, d in det.items():
        gate = d.get("chi2_threshold")
        gate_text = (f"; gate {gate['value']:g} ({gate['source']}), expected "
                     f"{100 * d['expected_false_alarm_rate_chi2_1']:.1f} % per clean "
                     "observation" if gate else "")
        lines.append(f"  {name}: detected {d['detected_epochs']}/{d['injected_epochs']} "
                     f"injected epochs ({_pct(d['detection_rate'])}); false alarms on "
                     f"{d['false_alarm_epochs']}/{d['clean_epochs']} clean epochs "
                     f"({_pct(d['false_alarm_rate'])}), "
                     f"{d['false_alarm_observations']}/{d['clean_observations']} clean "
                     f"observations ({_pct(d['false_alarm_rate_per_observation'])})"
                     + gate_text)
    return lines


def format_comparison(comparison: Dict[str, Any], bench_command: str = "",
                      show_missing: bool = True) -> str:
    """Text of a paper comparison (empty if it has nothing); ``show_missing=False`` leaves
    out the blocks that lack a filter (a single-filter ``navfmu run``)."""
    lines = [paper_windows.format_windows(comparison.get("windows") or {})]
    imp = comparison.get("improvement")
    if imp and ("missing" not in imp or show_missing):
        lines += _improvement_lines(imp)
    tpc = comparison.get("time_per_cycle")
    if tpc:
        lines += _time_per_cycle_lines(tpc, bench_command, show_missing)
    phase_text = scenario_phases.format_phase_statistics(comparison.get("phases"))
    if phase_text:
        lines.append(phase_text)
    det = comparison.get("outlier_detection")
    if det:
        lines += _detection_lines(det)
    return "\n".join(line for line in lines if line)


__all__ = ["format_comparison"]
