"""What every PNG figure of navfmu shares: matplotlib without a display, the atomic write of
a figure (temp file + rename) that also closes it, the legend outside the frame, and the
titles that say whose figure it is, read from the run itself.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .run_results import atomic_write  # noqa: E402


def save_png(fig, path):
    """Write ``fig`` to ``path`` as a PNG atomically, close it, return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        return atomic_write(path, lambda f: fig.savefig(f, format="png", dpi=110), binary=True)
    finally:
        plt.close(fig)



def legend_outside(ax, **kwargs):
    """The legend of ``ax`` right of its frame, so it never hides a point of the data."""
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                     **{"fontsize": 8, **kwargs})


def run_title(results, title="", truth_name=None):
    """``title`` with what the run was: its model and, for the truth, the motion profile and
    the time span actually simulated (from ``results.metadata``), so a figure of another
    profile or stop time never carries the name of the model's default one."""
    meta = results.metadata or {}
    params = (meta.get("parameters") or {}).get(truth_name) or {}
    parts = [p for p in (title or meta.get("model"),
                         f"profile '{params['profile']}'" if "profile" in params else "")
             if p]
    t = np.asarray(results.time, dtype=float)
    if t.size:
        parts.append(f"{t[0]:g}-{t[-1]:g} s")
    return ", ".join(parts)


def figure_title(entries):
    """Whose figure it is, from the run itself: the model's name, the filters' labels of
    ``entries`` and, for the truth, its motion profile and the time span simulated
    (:func:`run_title`), e.g. ``aircraft_500s: Kf, Iakf, profile 'climb', 0-500 s``."""
    results = entries[0][1]
    labels = ", ".join(dict.fromkeys(entry[0] for entry in entries))
    model = (results.metadata or {}).get("model") or ""
    truth = next((c for c in results.components if "truth_time" in results.columns[c]), None)
    return run_title(results, f"{model}: {labels}" if model else labels, truth)


def save_time_figure(fig, ax, ylabel: str, what: str, title: str, path):
    """The common end of a one-axes figure over time: labels, grid, the legend outside, the
    title (:func:`titled`), then :func:`save_png`."""
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    ax.set_title(titled(what, title))
    fig.tight_layout()
    return save_png(fig, path)


def titled(what: str, title: str) -> str:
    """A figure's title: what it shows, then whose it is (``title``, when given)."""
    return f"{what}\n{title}" if title else what
