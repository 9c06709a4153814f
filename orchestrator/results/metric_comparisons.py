"""Numbers made of the metrics of several filters or runs (the per-filter metrics are
:mod:`orchestrator.results.metrics`): the RMS table of the papers' shape, a paper's row in the
metrics' shape, the 3-D RMS of a group, the pooled RMS over runs, the improvement of a filter
over a baseline and their RMS ratio.

Definitions: 3-D RMS of a group: root of the sum of the per-axis mean squares; improvement of
a filter over a baseline in percent: 100 (1 - RMS_filter / RMS_baseline); RMS ratio:
RMS_baseline / RMS_filter (paper 001's "6 times"); pooled RMS: root of the mean of the
per-run mean squares.
"""
from __future__ import annotations

import math

import numpy as np

from .metrics import ATTITUDE, AXES


def reference_metrics(position_ned=None, velocity_ned=None, attitude_deg=None):
    """A paper's row (lists in the tables' order: N/E/D, roll/pitch/yaw; None where the paper
    gives no number) in the shape of :func:`orchestrator.results.metrics.filter_metrics`' RMS
    groups, for
    :func:`rms_table`."""
    def group(values, keys):
        if values is None:
            return None
        return {k: (None if v is None else float(v)) for k, v in zip(keys, values)}

    return {"position_rms_m": group(position_ned, AXES),
            "velocity_rms_mps": group(velocity_ned, AXES),
            "attitude_rms_deg": group(attitude_deg, ATTITUDE)}


def _cell(group, key, width, decimals):
    value = (group or {}).get(key)
    if value is None or not math.isfinite(value):
        return f"{'-':>{width}s}"
    return f"{value:{width}.{decimals}f}"


def rms_table(rows, reference=None):
    """Text table of the position and velocity RMS per axis north, east, down (paper 001's
    Table 1 rearranged from its east, north, up) plus attitude RMS (paper 000's Table 4).

    ``rows``: list of (label, metrics dict) in the given order, metrics from
    :func:`orchestrator.results.metrics.filter_metrics` or :func:`reference_metrics` (a missing
    group or None value prints '-'); ``reference``: list of (label, pos_ned, vel_ned[, att_deg])
    from a paper, printed under the rows.
    """
    rows = list(rows)
    for ref in reference or ():
        label, pos, vel = ref[:3]
        rows.append((label, reference_metrics(pos, vel, ref[3] if len(ref) > 3 else None)))
    w = max([len("RMS error")] + [len(label) for label, _ in rows])
    head = (f"{'RMS error':{w}s} {'pos N':>10s} {'pos E':>10s} {'pos D':>10s} "
            f"{'vel N':>8s} {'vel E':>8s} {'vel D':>8s} {'roll':>7s} {'pitch':>7s} {'yaw':>7s}")
    units = (f"{'':{w}s} {'[m]':>10s} {'[m]':>10s} {'[m]':>10s} {'[m/s]':>8s} {'[m/s]':>8s} "
             f"{'[m/s]':>8s} {'[deg]':>7s} {'[deg]':>7s} {'[deg]':>7s}")
    lines = [head, units]
    for label, m in rows:
        p, v, a = (m.get("position_rms_m"), m.get("velocity_rms_mps"),
                   m.get("attitude_rms_deg"))
        lines.append(" ".join([f"{label:{w}s}"] + [_cell(p, k, 10, 4) for k in AXES]
                              + [_cell(v, k, 8, 4) for k in AXES]
                              + [_cell(a, k, 7, 4) for k in ATTITUDE]))
    return "\n".join(lines)


#: the metrics key of each 3-D RMS group
GROUP_KEYS = {"position": "position_rms_m", "velocity": "velocity_rms_mps",
              "attitude": "attitude_rms_deg"}


def rms_3d(metrics, group):
    """3-D RMS of ``group`` (position/velocity/attitude): the root of the sum of the per-axis
    mean squares."""
    values = metrics[GROUP_KEYS[group]].values()
    return float(math.sqrt(sum(v * v for v in values)))


def pooled_rms(per_run_rms):
    """RMS over several runs of equal length: the root of the mean of the per-run mean
    squares (the README's and the slow tests' "RMS over the Monte Carlo runs")."""
    x = np.asarray(per_run_rms, dtype=float)
    return float(np.sqrt(np.mean(x * x)))


def improvement_percent(baseline, value):
    """Reduction of ``value`` against ``baseline`` in percent of the baseline (nan if the
    baseline is 0)."""
    baseline, value = float(baseline), float(value)
    return 100.0 * (1.0 - value / baseline) if baseline != 0.0 else float("nan")


def rms_ratio(baseline, value):
    """baseline / value (nan if value is 0): "improved n times"."""
    baseline, value = float(baseline), float(value)
    return baseline / value if value != 0.0 else float("nan")


def per_axis(metrics, group):
    """RMS of ``group`` in the tables' order N, E, D (position, velocity) or roll, pitch, yaw."""
    keys = ATTITUDE if group == "attitude" else AXES
    return [float(metrics[GROUP_KEYS[group]][k]) for k in keys]


__all__ = ["reference_metrics", "rms_table", "GROUP_KEYS", "rms_3d", "pooled_rms",
           "improvement_percent", "rms_ratio", "per_axis"]
