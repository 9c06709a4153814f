"""Matplotlib PNG plots of a run's navigation errors: errors with +-3 sigma (or, for several
filters, sliding-window RMS), attitude errors, the RMS intervals of a campaign, and the truth
trajectory.  What a filter says about itself (NIS, adaptive factors, estimated R, chi-square
statistics, outlier detection) is :mod:`.filter_plots`; what every figure shares,
:mod:`.plot_style`.

The comparison plots take ``entries``: a list of ``(label, results, component, errors)`` with
``errors`` from ``metrics.navigation_errors`` (one entry per filter, each possibly from its own
run).  Every function writes one PNG atomically (temp file + rename) and returns its path; the
optional plots return None when no entry has the outputs they draw.
"""
from __future__ import annotations

import math

import numpy as np
from navcore.ins import earth

from . import metrics as nav_metrics
from .plot_style import legend_outside, plt, run_title, save_png, titled

#: the panels of the error plots, named as in the RMS tables: (group, unit, scale to the
#: unit, [(axis label, error key, sigma keys)]).  Position and velocity N/E/D;
#: attitude as the Euler-angle errors roll/pitch/yaw of the tables, whose sigmas come from
#: the filter's N/E/D tilt sigmas (see :func:`_attitude_sigmas`).
_PANELS = (
    ("position", "m", 1.0, [(a.upper(), f"pos_{a}", f"std_p{a}") for a in nav_metrics.AXES]),
    ("velocity", "m/s", 1.0, [(a.upper(), f"vel_{a}", f"std_v{a}") for a in nav_metrics.AXES]),
    ("attitude", "deg", math.degrees(1.0), [(a, f"att_{a}", a) for a in nav_metrics.ATTITUDE]),
)
ATTITUDE_NOTE = ("attitude: Euler-angle errors roll/pitch/yaw as in the tables; their sigmas "
                 "come from the filter's tilt sigmas about N/E/D, turned by the heading psi: "
                 "s_roll^2 = cos^2(psi) s_N^2 + sin^2(psi) s_E^2, s_pitch^2 = sin^2(psi) s_N^2 "
                 "+ cos^2(psi) s_E^2, s_yaw = s_D (small angles, near-level attitude, N-E "
                 "correlation neglected)")
#: error plots of several filters show the RMS over a sliding window of this many seconds,
#: or of this fraction of the run when that is longer
RMS_WINDOW_S = 10.0
RMS_WINDOW_FRACTION = 1.0 / 60.0


def _attitude_sigmas(results, name):
    """1-sigma of the roll/pitch/yaw errors from the tilt sigmas ``std_att_n/e/d`` (see
    :data:`ATTITUDE_NOTE`); None when the filter has no attitude sigmas."""
    if not all(results.has(name, f"std_att_{a}") for a in "ned"):
        return None
    sn, se, sd = (results.column(name, f"std_att_{a}") for a in "ned")
    c, s = np.cos(results.column(name, "nav_yaw")), np.sin(results.column(name, "nav_yaw"))
    return {"roll": np.sqrt((c * sn) ** 2 + (s * se) ** 2),
            "pitch": np.sqrt((s * sn) ** 2 + (c * se) ** 2), "yaw": sd}


def _sigma(results, name, key, attitude):
    if attitude is not None and key in attitude:
        return attitude[key]
    return results.column(name, key) if results.has(name, key) else None


#: what :func:`plot_attitude_errors` draws, in words
ATTITUDE_ERRORS_CAPTION = "attitude errors (solid) with the filters' own +-3 sigma (dashed)"


def errors_caption(entries):
    """What :func:`plot_errors` draws for ``entries``, in words for a report's text (one
    definition, so the text and the figure agree on the sigma)."""
    if len(entries) > 1:
        return ("RMS of the errors over a sliding window (solid) and of the filters' own "
                "1 sigma (dashed)")
    return "errors (solid) with the filter's own +-3 sigma (dashed)"


def _error_limit(values, valid):
    """Half-height of a panel: from the errors (their 99.9 % |error| quantile, plus 30 %),
    never from a sigma, so a diverging filter's envelope cannot flatten the others."""
    finite = [np.abs(v[valid & np.isfinite(v)]) for v in values]
    finite = [v for v in finite if v.size]
    if not finite:
        return None
    peak = max(float(np.quantile(v, 0.999)) for v in finite)
    return 1.3 * peak if peak > 0 else None


def plot_errors(entries, path, title=""):
    """Errors of one filter (one ``entries`` item) with its +-3 sigma (dashed), or, for several
    filters, the RMS of each error over a sliding window (:func:`plot_error_rms`).  Rows
    position/velocity/attitude, columns the axes of the RMS tables; each panel's scale comes
    from the errors (a sigma beyond it is cut off at the frame)."""
    if len(entries) > 1:
        return plot_error_rms(entries, path, title)
    label, results, name, e = entries[0]
    attitude = _attitude_sigmas(results, name)
    invalid = ~np.asarray(e["valid"], dtype=bool)   # no estimate yet: nothing drawn
    fig, axes = plt.subplots(3, 3, figsize=(14, 9.5), sharex=True)
    t = e["time"]
    for row, (group, unit, scale, axes_spec) in enumerate(_PANELS):
        for col, (axis, key, std) in enumerate(axes_spec):
            ax = axes[row, col]
            err = np.where(invalid, np.nan, e[key] * scale)
            ax.plot(t, err, color="C0", lw=0.8, label=f"{label} error")
            limit = _error_limit([err], e["valid"])
            sigma = _sigma(results, name, std, attitude)
            if sigma is not None:
                s3 = np.where(invalid, np.nan, 3.0 * sigma * scale)
                off = limit is not None and bool(np.all(s3[e["valid"]] > limit))
                ax.plot(t, s3, color="C1", lw=0.8, ls="--",
                        label=f"{label} +-3 sigma" + (" (beyond the frame)" if off else ""))
                ax.plot(t, -s3, color="C1", lw=0.8, ls="--")
            if limit:
                ax.set_ylim(-limit, limit)
            ax.set_title(f"{group} error {axis}", fontsize=9)
            ax.set_ylabel(unit)
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    for ax in axes.flat:  # the first panel, and every panel whose sigma is off its scale
        if ax is axes[0, 0] or any("beyond" in t for t in ax.get_legend_handles_labels()[1]):
            ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(titled(errors_caption(entries), title))
    fig.text(0.01, 0.005, ATTITUDE_NOTE, fontsize=7, va="bottom", wrap=True)
    fig.tight_layout(rect=(0, 0.035, 1, 1))
    return save_png(fig, path)


def _moving_rms(t, x, valid, window_s):
    """RMS of ``x`` over a centred window of ``window_s`` seconds, on ``t``'s samples (NaN
    where the window holds no valid sample)."""
    sq = np.where(valid & np.isfinite(x), x * x, 0.0)
    n = (valid & np.isfinite(x)).astype(float)
    cs, cn = np.concatenate([[0.0], np.cumsum(sq)]), np.concatenate([[0.0], np.cumsum(n)])
    lo = np.searchsorted(t, t - window_s / 2, side="left")
    hi = np.searchsorted(t, t + window_s / 2, side="right")
    count = cn[hi] - cn[lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, np.sqrt((cs[hi] - cs[lo]) / count), np.nan)


def plot_error_rms(entries, path, title=""):
    """Several filters: the RMS of every error over a sliding window (solid, one colour per
    filter) and the RMS of the filter's own 1 sigma over the same window (dashed: what the
    filter claims), log scale, so long runs and filters far apart stay readable.  Lines are
    drawn widest first (the first filter), so a filter whose curve lies on another's shows
    as a narrower line inside it; 1 sigma curves that agree within 1 % are drawn once, with
    the names of all of them; the legend sits below the panels, off the data."""
    fig, axes = plt.subplots(3, 3, figsize=(14, 10.5), sharex=True)
    span = max(float(e["time"][-1] - e["time"][0]) for _, _, _, e in entries if e["time"].size)
    window = max(RMS_WINDOW_S, RMS_WINDOW_FRACTION * span)
    widths = np.linspace(2.4, 0.9, len(entries))
    for row, (group, unit, scale, axes_spec) in enumerate(_PANELS):
        for col, (axis, key, std) in enumerate(axes_spec):
            ax = axes[row, col]
            sigmas = []
            for f_i, (label, results, name, e) in enumerate(entries):
                t, valid = e["time"], e["valid"]
                step = max(1, t.size // 3000)  # a smooth curve needs no more points
                rms = _moving_rms(t, e[key] * scale, valid, window)
                ax.semilogy(t[::step], rms[::step], color=f"C{f_i}", lw=widths[f_i],
                            alpha=0.85, label=label, zorder=2 + f_i)
                sigma = _sigma(results, name, std, _attitude_sigmas(results, name))
                if sigma is not None:
                    srms = _moving_rms(t, sigma * scale, valid, window)
                    sigmas.append((f_i, label, t[::step], srms[::step]))
            for members, (t, srms) in _coinciding(sigmas):
                ax.semilogy(t, srms, color=f"C{members[0][0]}" if len(members) == 1 else "k",
                            lw=0.8, ls="--", zorder=10,
                            label=f"{', '.join(m[1] for m in members)}: 1 sigma (own)")
            ax.set_title(f"{group} error {axis}: RMS over {window:g} s", fontsize=9)
            ax.set_ylabel(unit)
            ax.grid(True, which="both", alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    handles, labels = _legend_entries(axes.flat)
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)), fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 0.03))
    fig.suptitle(titled(f"RMS errors over a sliding {window:g} s window", title))
    fig.text(0.01, 0.005, ATTITUDE_NOTE, fontsize=7, va="bottom", wrap=True)
    rows = 1 + (len(labels) - 1) // 4
    fig.tight_layout(rect=(0, 0.05 + 0.025 * rows, 1, 1))
    return save_png(fig, path)


def _coinciding(curves, tolerance=0.01):
    """Group ``(index, label, t, values)`` curves whose values agree within ``tolerance``
    (relative) wherever both are finite; yields ``(members, (t, values))`` per group."""
    groups = []
    for curve in curves:
        for members, (t, ref) in groups:
            both = np.isfinite(ref) & np.isfinite(curve[3]) if ref.shape == curve[3].shape \
                else None
            if both is not None and both.any() and np.all(
                    np.abs(curve[3][both] - ref[both]) <= tolerance * np.abs(ref[both])):
                members.append(curve)
                break
        else:
            groups.append(([curve], (curve[2], curve[3])))
    return groups


def _legend_entries(axes):
    """Every distinct legend label of ``axes`` once, in the order first drawn."""
    seen = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(label, handle)
    return list(seen.values()), list(seen)


def plot_attitude_errors(entries, path, title="", angles=nav_metrics.ATTITUDE):
    """Euler angle errors (one panel per angle of ``angles``) of every filter, with the
    +-3 sigma of the filter's ``std_<angle>`` output when it has one (dashed); paper 003's
    Fig. 3 is ``angles=("pitch",)``."""
    fig, axes = plt.subplots(len(angles), 1, figsize=(12, 2.6 * len(angles) + 0.6),
                             sharex=True, squeeze=False)
    for f_i, (label, results, name, e) in enumerate(entries):
        ok = e["valid"]
        t = e["time"][ok]
        for ax, a in zip(axes[:, 0], angles):
            ax.plot(t, np.degrees(e["att_" + a][ok]), color=f"C{f_i}", lw=0.7, label=label)
            if results.has(name, "std_" + a):
                s3 = 3.0 * np.degrees(results.column(name, "std_" + a)[ok])
                ax.plot(t, s3, color=f"C{f_i}", lw=0.6, ls="--")
                ax.plot(t, -s3, color=f"C{f_i}", lw=0.6, ls="--")
            ax.set_ylabel(f"{a} error [deg]")
            ax.grid(True, alpha=0.3)
    legend_outside(axes[0, 0])
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(titled(ATTITUDE_ERRORS_CAPTION, title))
    fig.tight_layout()
    return save_png(fig, path)


def plot_trajectory(results, truth_name, path, title=""):
    """The truth: ground track, height, velocity north/east/down, speed, roll and pitch, yaw;
    the title names the run's profile and span (:func:`run_title`)."""
    col = results.column
    t = col(truth_name, "truth_time")
    lat, lon = col(truth_name, "truth_lat"), col(truth_name, "truth_lon")
    h = col(truth_name, "truth_h")
    rn, re = earth.radii(lat[0])  # the ground track in metres about the start (WGS-84 radii)
    north = (lat - lat[0]) * (rn + h[0])
    east = (lon - lon[0]) * (re + h[0]) * np.cos(lat[0])
    fig, axes = plt.subplots(3, 2, figsize=(12, 11))
    axes[0, 0].plot(east / 1e3, north / 1e3)
    axes[0, 0].plot(east[:1] / 1e3, north[:1] / 1e3, "o", color="C2", label="start")
    axes[0, 0].set_xlabel("east [km]")
    axes[0, 0].set_ylabel("north [km]")
    axes[0, 0].set_aspect("equal", adjustable="datalim")
    axes[0, 0].legend(fontsize=8)
    axes[0, 1].plot(t, h)
    axes[0, 1].set_ylabel("height [m]")
    v = {a: col(truth_name, f"truth_v{a}") for a in "ned"}
    for name, values in (("north", v["n"]), ("east", v["e"]), ("down", v["d"])):
        axes[1, 0].plot(t, values, lw=0.8, label=name)
    axes[1, 0].set_ylabel("velocity [m/s]")
    axes[1, 0].legend(fontsize=8)
    axes[1, 1].plot(t, np.sqrt(sum(x ** 2 for x in v.values())))
    axes[1, 1].set_ylabel("speed [m/s]")
    for a in ("roll", "pitch"):
        axes[2, 0].plot(t, np.degrees(col(truth_name, "truth_" + a)), label=a, lw=0.8)
    axes[2, 0].set_ylabel("attitude [deg]")
    axes[2, 0].legend(fontsize=8)
    axes[2, 1].plot(t, np.degrees(col(truth_name, "truth_yaw")), lw=0.8, color="C2")
    axes[2, 1].set_ylabel("yaw [deg]")
    for ax in axes.flat[1:]:
        ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
    axes[0, 0].grid(True, alpha=0.3)
    fig.suptitle(f"truth trajectory: {run_title(results, title, truth_name)}")
    fig.tight_layout()
    return save_png(fig, path)


def plot_rms_intervals(summary, path, title=""):
    """A campaign's RMS per axis (panels, the papers' table order, log scale): per filter the
    mean over the runs with its confidence interval (bar), and the paper's number (cross)
    when it has one; ``summary`` from :func:`orchestrator.campaigns.campaign_summary.summarize`."""
    axes_items = list(summary["axes"].items())
    filters = summary["filters"]
    rows = max(1, -(-len(axes_items) // 3))  # an attitude-only campaign: one row
    fig, axes = plt.subplots(rows, 3, figsize=(max(9.0, 1.1 * len(filters) + 6), 3 * rows),
                             squeeze=False)
    x = np.arange(len(filters))
    for ax, (key, entry) in zip(axes.flat, axes_items):
        stats_ = [entry["filters"][f] for f in filters]
        mean = np.array([s["mean"] for s in stats_])
        # log scale (RMS spans decades between filters): a lower bound <= 0 is drawn at mean/100
        low = np.array([s["low"] if s["low"] > 0 else s["mean"] / 100 for s in stats_])
        err = np.array([mean - low, [s["high"] - s["mean"] for s in stats_]])
        ax.bar(x, mean, color=[f"C{i}" for i in range(len(filters))], alpha=0.6)
        ax.errorbar(x, mean, yerr=np.nan_to_num(err), fmt="none", ecolor="k", capsize=3, lw=1)
        ax.set_yscale("log")
        paper = [entry["filters"][f].get("paper") for f in filters]
        if any(p is not None for p in paper):
            ax.plot(x, [np.nan if p is None else p for p in paper], "kx", ms=8,
                    label="paper")
            ax.legend(fontsize=7)
        ax.set_xticks(x)
        ax.set_xticklabels(filters, rotation=45, ha="right", fontsize=7)
        ax.set_title(f"{entry['label']} RMS [{entry['unit']}]", fontsize=9)
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(title or f"RMS per run: mean and {100 * summary['level']:.0f} % interval over "
                 f"{summary['runs']} runs")
    fig.tight_layout()
    return save_png(fig, path)
