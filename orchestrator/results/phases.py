"""Per-phase statistics of recorded filter outputs over the phase windows a scenario declares.

A scenario's ``paper.json`` may carry a ``phases`` block (scenario data; the master knows
nothing of manoeuvres)::

    "phases": {"windows": [{"label": "strong", "t0": 0, "t1": 600}, ...],
               "variables": ["nis", "q_scale", "model_prob_2"]}

:func:`phase_statistics` gives, for every filter of every run and every listed variable the
filter records and that changes during the run, the mean over the filter's update epochs
(``updated`` rows, by ``nav_time``) whose time lies in the windows of each label (windows of one
label pooled, clipped to the run), and the ratio of the first label's mean to the second's.
"""
from __future__ import annotations

from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from ..errors import NavfmuError
from .windows import window_bounds


def phase_windows(reference: Optional[Dict[str, Any]]) -> List[Dict[str, Any]]:
    """The validated ``phases.windows`` of a paper.json (``[]`` when it has none)."""
    block = (reference or {}).get("phases")
    if not block:
        return []
    windows = block.get("windows") if isinstance(block, dict) else None
    if not isinstance(windows, list):
        raise NavfmuError("paper.json: 'phases' must have a list 'windows' of "
                          "{label, t0, t1}")
    out = []
    for i, w in enumerate(windows):
        where = f"phases.windows[{i}]"
        if not isinstance(w, dict) or "label" not in w:
            raise NavfmuError(f"paper.json: {where} must have 'label', 't0' and 't1' (s), "
                              f"got {w!r}")
        t0, t1 = window_bounds(w, where)
        out.append({"label": str(w["label"]), "t0": t0, "t1": t1})
    return out


def _labels(windows: Sequence[Dict[str, Any]]) -> List[str]:
    labels: List[str] = []
    for w in windows:
        if w["label"] not in labels:
            labels.append(w["label"])
    return labels


def phase_statistics(runs: Sequence[Any], reference: Optional[Dict[str, Any]],
                     filters_in) -> Optional[Dict[str, Any]]:
    """Means per phase label (module docstring); None when the scenario declares no phases.

    ``runs`` have ``label`` and ``results``; ``filters_in(results)`` names the filter
    components of a run."""
    windows = phase_windows(reference)
    if not windows:
        return None
    variables = list((reference.get("phases") or {}).get("variables") or ())
    labels = _labels(windows)
    rows = []
    for run in runs:
        res = run.results
        for comp in filters_in(res):
            if not (res.has(comp, "updated") and res.has(comp, "nav_time")):
                continue
            upd = res.column(comp, "updated") > 0.5
            t = res.column(comp, "nav_time")[upd]
            masks = {}
            for label in labels:
                m = np.zeros(t.shape, dtype=bool)
                for w in windows:
                    if w["label"] == label:
                        m |= (t >= w["t0"]) & (t < w["t1"])
                masks[label] = m
            name = run.label if comp == "filter" else f"{run.label}:{comp}"
            for var in variables:
                if not res.has(comp, var):
                    continue
                values = res.column(comp, var)[upd]
                if values.size == 0 or np.all(values == values[0]):
                    continue
                means = {label: (float(values[m].mean()) if m.any() else None)
                         for label, m in masks.items()}
                a, b = (means[labels[0]], means[labels[1]]) if len(labels) > 1 else (None, None)
                rows.append({"filter": name, "variable": var, "means": means,
                             "epochs": {label: int(m.sum()) for label, m in masks.items()},
                             "ratio": (a / b if a is not None and b not in (None, 0.0)
                                       else None)})
    return {"windows": windows, "labels": labels, "rows": rows}


def format_phase_statistics(stats: Optional[Dict[str, Any]]) -> str:
    """Text of :func:`phase_statistics` ('' when there is nothing to print)."""
    if not stats or not stats["rows"]:
        return ""
    labels = stats["labels"]
    spans = "; ".join(
        f"{label} " + ", ".join(f"{w['t0']:g}-{w['t1']:g}" for w in stats["windows"]
                                if w["label"] == label) + " s" for label in labels)
    lines = [f"\nmeans per phase at the update epochs (phases from paper.json: {spans}):"]
    head = f"  {'filter':10s} {'variable':14s}" + "".join(f" {label:>10s}" for label in labels)
    if len(labels) > 1:
        head += f" {labels[0] + '/' + labels[1]:>14s}"
    lines.append(head)
    for r in stats["rows"]:
        cells = "".join(f" {'-':>10s}" if r["means"][lb] is None else f" {r['means'][lb]:10.3f}"
                        for lb in labels)
        if len(labels) > 1:
            cells += f" {'-':>14s}" if r["ratio"] is None else f" {r['ratio']:14.2f}"
        lines.append(f"  {r['filter']:10s} {r['variable']:14s}{cells}")
    return "\n".join(lines)


def shade_phases(ax, windows: Sequence[Dict[str, Any]]) -> None:
    """Shade the windows of the first phase label on a matplotlib axis (time in s)."""
    labels = _labels(windows)
    if not labels:
        return
    lim = ax.get_xlim()
    first = True
    for w in windows:
        if w["label"] == labels[0]:
            ax.axvspan(w["t0"], w["t1"], color="0.85", alpha=0.5, lw=0, zorder=0,
                       label=f"{labels[0]} phase" if first else None)
            first = False
    ax.set_xlim(lim)
