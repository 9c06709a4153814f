"""Matplotlib PNG plots of a run: errors with +-3 sigma, NIS, adaptive factors.

The comparison plots take ``entries``: a list of ``(label, results, component, errors)`` with
``errors`` from ``metrics.navigation_errors`` (one entry per filter, each possibly from its own
run).  Every function writes one PNG atomically (temp file + rename) and returns its path.
"""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from .results import atomic_write  # noqa: E402

_GROUPS = (
    ("position", "pos_", ("n", "e", "d"), "std_p", 1.0, "m"),
    ("velocity", "vel_", ("n", "e", "d"), "std_v", 1.0, "m/s"),
    ("attitude", "phi_", ("n", "e", "d"), "std_att_", math.degrees(1.0), "deg"),
)


def _save(fig, path):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        return atomic_write(path, lambda f: fig.savefig(f, format="png", dpi=110), binary=True)
    finally:
        plt.close(fig)


def plot_errors(entries, path, title=""):
    """Position, velocity and attitude errors (rows) per NED axis (columns) of every filter,
    with the +-3 sigma envelope of the filter's own covariance (dashed, same colour)."""
    fig, axes = plt.subplots(3, 3, figsize=(14, 9), sharex=True)
    for f_i, (label, results, name, e) in enumerate(entries):
        colour = f"C{f_i}"
        t = e["time"]
        for row, (group, err, axes_names, std, scale, unit) in enumerate(_GROUPS):
            for col, a in enumerate(axes_names):
                ax = axes[row, col]
                ax.plot(t, e[err + a] * scale, color=colour, lw=0.8, label=label)
                if results.has(name, std + a):
                    s3 = 3.0 * results.column(name, std + a) * scale
                    ax.plot(t, s3, color=colour, lw=0.6, ls="--")
                    ax.plot(t, -s3, color=colour, lw=0.6, ls="--")
                ax.set_title(f"{group} error {a.upper()}", fontsize=9)
                ax.set_ylabel(unit)
                ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    axes[0, 0].legend(fontsize=8, loc="upper left")
    fig.suptitle(title or "errors (solid) and +-3 sigma from the filter (dashed)")
    fig.tight_layout()
    return _save(fig, path)


def plot_nis(entries, path, title=""):
    """NIS at the update epochs with the two-sided 95 % chi-square band of one epoch."""
    fig, ax = plt.subplots(figsize=(12, 4))
    dofs = set()
    for f_i, (label, results, name, _) in enumerate(entries):
        if not (results.has(name, "nis") and results.has(name, "updated")):
            continue
        upd = results.column(name, "updated") > 0.5
        if not upd.any():
            continue
        t = results.column(name, "nav_time")[upd]
        ax.semilogy(t, np.maximum(results.column(name, "nis")[upd], 1e-3), ".", ms=3,
                    color=f"C{f_i}", label=label)
        dofs.update(int(d) for d in np.unique(results.column(name, "nis_dof")[upd]))
    for dof in sorted(dofs):
        lo, hi = stats.chi2.ppf([0.025, 0.975], dof)
        ax.axhline(hi, color="k", lw=0.8, ls="--")
        ax.axhline(lo, color="k", lw=0.8, ls=":")
        ax.text(ax.get_xlim()[0], hi, f" chi2({dof}) 97.5 %", va="bottom", fontsize=8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("NIS")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or "normalized innovation squared")
    fig.tight_layout()
    return _save(fig, path)


def plot_series(entries, variables, path, title=""):
    """Diagnostic outputs (adaptive scales, fading factor, model probabilities...) over time:
    one panel per variable, one line per filter that has it.  Returns None if none has any."""
    present = [v for v in variables if any(r.has(c, v) for _, r, c, _ in entries)]
    if not present:
        return None
    fig, axes = plt.subplots(len(present), 1, figsize=(12, 2.4 * len(present)), sharex=True,
                             squeeze=False)
    for ax, var in zip(axes[:, 0], present):
        for f_i, (label, results, name, _) in enumerate(entries):
            if results.has(name, var):
                ax.plot(results.time, results.column(name, var), color=f"C{f_i}", lw=0.8,
                        label=label)
        ax.set_ylabel(var)
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)


def plot_trajectory(results, truth_name, path, title=""):
    """Ground track, height, speed and attitude of the truth."""
    col = results.column
    t = col(truth_name, "truth_time")
    lat, lon, h = col(truth_name, "truth_lat"), col(truth_name, "truth_lon"), col(truth_name, "truth_h")
    north = (lat - lat[0]) * 6378137.0
    east = (lon - lon[0]) * 6378137.0 * np.cos(lat[0])
    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    axes[0, 0].plot(east / 1e3, north / 1e3)
    axes[0, 0].set_xlabel("east [km]")
    axes[0, 0].set_ylabel("north [km]")
    axes[0, 0].set_aspect("equal", adjustable="datalim")
    axes[0, 1].plot(t, h)
    axes[0, 1].set_ylabel("height [m]")
    speed = np.sqrt(sum(col(truth_name, f"truth_v{a}") ** 2 for a in "ned"))
    axes[1, 0].plot(t, speed)
    axes[1, 0].set_ylabel("speed [m/s]")
    for a in ("roll", "pitch", "yaw"):
        axes[1, 1].plot(t, np.degrees(col(truth_name, "truth_" + a)), label=a, lw=0.8)
    axes[1, 1].set_ylabel("attitude [deg]")
    axes[1, 1].legend(fontsize=8)
    for ax in axes.flat[1:]:
        ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
    axes[0, 0].grid(True, alpha=0.3)
    fig.suptitle(title or "truth trajectory")
    fig.tight_layout()
    return _save(fig, path)
