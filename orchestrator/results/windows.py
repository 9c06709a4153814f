"""Metrics over the named time windows of a scenario's paper.json, next to the paper's claims.

A paper may judge its filters before and after an event (paper 003: ideal conditions for
0-100 s, vibration from 121 s) instead of over the whole run.  ``paper.json`` then has::

    "windows": {"before": {"t0": 0, "t1": 100, "label": "..."}, ...},
    "claims": [{"window": "after", "kind": "at_most" | "about" | "similar",
                "filter": "F" (or "filters": [...]), "angle": "pitch",
                "value_deg": 0.5, "text": "..."}, ...]

:func:`window_comparison` computes every filter's RMS errors (``metrics.filter_metrics``) in
each window and lists the claims with our value beside them; :func:`format_windows` prints
it.  What a claim means is the paper's text: ``at_most`` and ``about`` carry the paper's
number, ``similar`` compares the named filters with each other (our ratio of the larger to
the smaller RMS is shown).
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Sequence

from . import metrics as nav_metrics
from ..errors import NavfmuError

#: the metric groups reported per window: (metrics key, label, unit)
_GROUPS = (("attitude_rms_deg", "attitude", "deg"), ("position_rms_m", "position", "m"),
           ("velocity_rms_mps", "velocity", "m/s"))


def window_bounds(w, where: str):
    """``(t0, t1)`` [s] of a paper.json window ``w`` (a dict with numbers ``t0`` < ``t1``,
    both finite), or a NavfmuError naming it ``where``: the one check of every paper.json
    window (the named windows here, the phase windows of :mod:`orchestrator.results.phases`)."""
    try:
        t0, t1 = float(w["t0"]), float(w["t1"])
    except (KeyError, TypeError, ValueError):
        raise NavfmuError(f"paper.json: {where} must have numbers 't0' and 't1' (s), got "
                          f"{w!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise NavfmuError(f"paper.json: {where}: need finite t0 < t1, got {t0}, {t1}")
    return t0, t1


def paper_windows(reference) -> Dict[str, Dict[str, Any]]:
    """The named windows of a paper.json (``{}`` without any), each checked."""
    windows = (reference or {}).get("windows") or {}
    for name, w in windows.items():
        window_bounds(w, f"window '{name}'")
    return windows


def window_comparison(runs: Sequence[Any], component: str, reference=None) -> Dict[str, Any]:
    """Per window: ``{label, t0, t1, filters: {run label: metrics}}`` and the claims with
    ``ours``; empty when paper.json has no windows.  ``component`` is the filter component
    of each run; a run streamed to a file brings its windows' metrics computed while it ran
    (``run.window_metrics``)."""
    windows = paper_windows(reference)
    if not windows:
        return {}
    out: Dict[str, Any] = {"windows": {}, "claims": []}
    for name, w in windows.items():
        per_filter = {}
        for run in runs:
            if component not in run.metrics:
                continue
            if getattr(run, "series_file", None) is not None:  # streamed: what it reached
                if name in run.window_metrics:
                    per_filter[run.label] = run.window_metrics[name][component]
            else:
                per_filter[run.label] = nav_metrics.filter_metrics(
                    run.results, component, window=(float(w["t0"]), float(w["t1"])))
        out["windows"][name] = {"label": w.get("label", name), "t0": w["t0"], "t1": w["t1"],
                                "filters": per_filter}
    for claim in (reference or {}).get("claims", ()):
        out["claims"].append(_judge(claim, out["windows"]))
    return out


def _judge(claim: Dict[str, Any], windows: Dict[str, Any]) -> Dict[str, Any]:
    row = dict(claim)
    window = windows.get(claim.get("window"), {"filters": {}})
    angle = claim.get("angle", "pitch")
    names = claim.get("filters") or [claim.get("filter")]
    values = [window["filters"].get(n, {}).get("attitude_rms_deg", {}).get(angle) for n in names]
    if any(v is None for v in values):
        row["missing"] = [n for n, v in zip(names, values) if v is None]
        return row
    if claim.get("kind") == "similar":
        row["ours"] = dict(zip(names, values))
        row["ours_ratio"] = max(values) / min(values) if min(values) > 0 else float("inf")
    else:
        row["ours"] = values[0]
    return row


def format_windows(comparison: Dict[str, Any]) -> str:
    """Text of :func:`window_comparison` (empty if it has nothing)."""
    if not comparison:
        return ""
    lines: List[str] = []
    for name, w in comparison["windows"].items():
        lines.append(f"\n{name}: {w['label']} ([{w['t0']:g}, {w['t1']:g}] s), RMS error")
        for label, m in w["filters"].items():
            parts = []
            for key, group, unit in _GROUPS:
                if key in m:
                    parts.append(f"{group} " + "/".join(f"{v:.4f}" for v in m[key].values())
                                 + f" {unit}")
            lines.append(f"  {label:14s} " + "; ".join(parts)
                         + "   (attitude roll/pitch/yaw)")
    if comparison["claims"]:
        lines.append("\npaper's claims and ours:")
    for c in comparison["claims"]:
        head = f"  [{c.get('window')}] {c.get('text', '')}"
        if "missing" in c:
            lines.append(f"{head}: not compared, add {', '.join(c['missing'])} to --filters")
        elif c.get("kind") == "similar":
            ours = ", ".join(f"{k} {v:.4f}" for k, v in c["ours"].items())
            lines.append(f"{head}: ours {c.get('angle')} {ours} deg (ratio "
                         f"{c['ours_ratio']:.2f})")
        else:
            lines.append(f"{head}: paper {c.get('value_deg')} deg, ours {c.get('angle')} "
                         f"{c['ours']:.4f} deg")
    return "\n".join(lines)
