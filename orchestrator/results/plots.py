"""Matplotlib PNG plots of a run: errors with +-3 sigma (or, for several filters, sliding-window
RMS), NIS, adaptive factors, estimated R, chi-square statistics with their gates, outlier
detection, the truth trajectory.

The comparison plots take ``entries``: a list of ``(label, results, component, errors)`` with
``errors`` from ``metrics.navigation_errors`` (one entry per filter, each possibly from its own
run).  Every function writes one PNG atomically (temp file + rename) and returns its path; the
optional plots return None when no entry has the outputs they draw.
"""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from navcore.filters.innovation_stats import chi2_lower_quantile  # noqa: E402
from navcore.ins import earth  # noqa: E402

from . import metrics as nav_metrics  # noqa: E402
from .phases import shade_phases  # noqa: E402
from .run_results import atomic_write  # noqa: E402

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


def _save(fig, path):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        return atomic_write(path, lambda f: fig.savefig(f, format="png", dpi=110), binary=True)
    finally:
        plt.close(fig)


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


def legend_outside(ax, **kwargs):
    """The legend of ``ax`` right of its frame, so it never hides a point of the data."""
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                     **{"fontsize": 8, **kwargs})


#: what :func:`plot_attitude_errors` draws, in words
ATTITUDE_ERRORS_CAPTION = "attitude errors (solid) with the filters' own +-3 sigma (dashed)"


def errors_caption(entries):
    """What :func:`plot_errors` draws for ``entries``, in words for a report's text (one
    definition, so the text and the figure agree on the sigma)."""
    if len(entries) > 1:
        return ("RMS of the errors over a sliding window (solid) and of the filters' own "
                "1 sigma (dashed)")
    return "errors (solid) with the filter's own +-3 sigma (dashed)"


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


def titled(what: str, title: str) -> str:
    """A figure's title: what it shows, then whose it is (``title``, when given)."""
    return f"{what}\n{title}" if title else what


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
    return _save(fig, path)


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
    return _save(fig, path)


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
    return _save(fig, path)


def plot_fitness(summary, path):
    """Paper 003's Fig. 1: the GA's best cost so far and the generation mean per generation
    (``summary`` from ``orchestrator.campaigns.tune.run_tune``)."""
    fig, ax = plt.subplots(figsize=(8, 4))
    g = np.arange(1, len(summary["best_so_far"]) + 1)
    ax.plot(g, summary["best_so_far"], "o-", ms=3, label="best so far")
    ax.plot(g, summary["generation_mean"], "s--", ms=3, alpha=0.7, label="generation mean")
    ax.set_xlabel("generation")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))   # generations are whole
    ax.set_ylabel("cost: attitude RMS [deg] (eq. 20)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title(f"{summary['model']}: GA over {len(summary['parameters'])} parameters of "
                 f"'{summary['component']}', population {summary['population']} "
                 "(paper 003 Fig. 1)", fontsize=9)
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
        lo, hi = chi2_lower_quantile(np.array([0.025, 0.975]), dof)
        ax.axhline(hi, color="k", lw=0.8, ls="--", label=f"chi2({dof}) 97.5 %")
        ax.axhline(lo, color="k", lw=0.8, ls=":", label=f"chi2({dof}) 2.5 %")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("NIS")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    ax.set_title(titled("normalized innovation squared", title))
    fig.tight_layout()
    return _save(fig, path)


def _constant(values):
    values = np.asarray(values, dtype=float)
    return values.size == 0 or bool(np.all(values == values[0]))


def plot_series(entries, variables, path, title="", log_variables=(), phases=()):
    """Diagnostic outputs (adaptive scales, fading factor, model probabilities...) over time:
    one panel per variable, one line per filter that has it.  A variable that stays at one
    value in every filter that has it gets no panel but a line in the footnote.  Returns None
    (no plot) if no filter has any of ``variables`` or none of them changes.  ``phases``
    (windows of :mod:`orchestrator.results.phases`) are shaded."""
    present = [v for v in variables if any(r.has(c, v) for _, r, c, _ in entries)]
    if not present:
        return None
    constant = {}
    for var in present:
        values = [r.column(c, var) for _, r, c, _ in entries if r.has(c, var)]
        first = [float(v[0]) for v in values if v.size]
        if all(_constant(v) for v in values) and len(set(first)) <= 1:
            holders = [label for label, r, c, _ in entries if r.has(c, var)]
            constant[var] = (first[0] if first else float("nan"), holders)
    panels = [v for v in present if v not in constant]
    if not panels:
        return None
    fig, axes = plt.subplots(len(panels), 1, figsize=(12, 2.4 * len(panels) + 0.4),
                             sharex=True, squeeze=False)
    for ax, var in zip(axes[:, 0], panels):
        for f_i, (label, results, name, _) in enumerate(entries):
            if results.has(name, var):
                ax.plot(results.time, results.column(name, var), color=f"C{f_i}", lw=0.8,
                        label=label)
        if var in log_variables:
            ax.set_yscale("log")
        ax.set_ylabel(var)
        ax.grid(True, alpha=0.3)
        shade_phases(ax, phases)
    axes[0, 0].legend(fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    if constant:
        note = "constant over the run: " + "; ".join(
            f"{var} = {value:g} ({', '.join(holders)})"
            for var, (value, holders) in constant.items())
        fig.text(0.01, 0.005, note, fontsize=8, va="bottom", wrap=True)
        fig.tight_layout(rect=(0, 0.03, 1, 1))
    else:
        fig.tight_layout()
    return _save(fig, path)


_R_AXES = (("n", "-"), ("e", "--"), ("d", ":"))


def plot_r_estimate(entries, path, title=""):
    """The measurement noise the adaptive filters estimate (``r_est_p*`` [m], ``r_est_v*``
    [m/s], 1 sigma): a position and a velocity panel, one colour per filter, line style per
    NED axis.  Returns None if no entry has these outputs."""
    groups = (("position", "r_est_p", "m"), ("velocity", "r_est_v", "m/s"))
    have = [(f_i, e) for f_i, e in enumerate(entries)
            if any(e[1].has(e[2], prefix + a) for _, prefix, _ in groups for a, _ in _R_AXES)]
    if not have:
        return None
    fig, axes = plt.subplots(2, 1, figsize=(12, 6.5), sharex=True)
    for ax, (group, prefix, unit) in zip(axes, groups):
        for f_i, (label, results, name, _) in have:
            for a, style in _R_AXES:
                if results.has(name, prefix + a):
                    ax.plot(results.time, results.column(name, prefix + a), color=f"C{f_i}",
                            ls=style, lw=0.9, label=f"{label} {a.upper()}")
        ax.set_ylabel(f"{group} R [{unit}, 1 sigma]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=3, loc="best")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(titled("estimated GNSS measurement noise (diagonal of R, as 1 sigma)", title))
    fig.tight_layout()
    return _save(fig, path)


def _gate_label(gate):
    return f"{gate['name']} = {gate['value']:g} ({gate['source']})"


def plot_chi2(entries, path, title="", phases=()):
    """Chi-square statistic of every update: ``chi2`` of a filter that outputs it (CTFA-UKF,
    eq. 24), ``nis`` of the others (the same statistic of a plain filter), log scale, with
    the chi-square gates of the filters that output ``chi2`` (ctfa_t1/t2, value from the
    run's parameters or the default, as the legend says); ``phases`` (windows of
    :mod:`orchestrator.results.phases`) are shaded.  Returns None unless an entry has a ``chi2``
    output."""
    if not any(r.has(c, "chi2") for _, r, c, _ in entries):
        return None
    fig, ax = plt.subplots(figsize=(12, 4.5))
    gates = {}
    for f_i, (label, results, name, _) in enumerate(entries):
        ep = nav_metrics.update_epochs(results, name)
        if ep is None or not ep["time"].size:
            continue
        var = "chi2" if "chi2" in ep else "nis" if "nis" in ep else None
        if var is None:
            continue
        ax.semilogy(ep["time"], np.maximum(ep[var], 1e-3), ".-", ms=3, lw=0.5,
                    color=f"C{f_i}", label=f"{label}: {var}")
        for g in nav_metrics.chi2_thresholds(results, name):
            if g["statistic"] == "chi2":
                gates.setdefault((g["name"], g["value"]), g)
    for i, g in enumerate(sorted(gates.values(), key=lambda g: g["value"])):
        ax.axhline(g["value"], color="k", lw=0.9, ls=("--", ":", "-.")[i % 3],
                   label=_gate_label(g))
    shade_phases(ax, phases)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("chi-square statistic")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    ax.set_title(titled("chi-square statistic of the innovations", title))
    fig.tight_layout()
    return _save(fig, path)


def plot_outliers(entries, path, title=""):
    """Outlier gate of the robust filters (those with ``chi2_max``): top, the largest
    per-observation chi-square statistic of every update (log scale) with the gate
    ``chi2_threshold`` (from the run's parameters or the default, as the legend says), the
    epochs of injected outliers circled; bottom, one row of markers for the epochs where the
    receiver injected an outlier (``gnss_outlier`` at the filter's update epochs) and one per
    filter for the epochs where it rejected observations (``n_rejected`` > 0).  Returns None
    unless an entry has ``chi2_max``."""
    robust = [(f_i, e) for f_i, e in enumerate(entries) if e[1].has(e[2], "chi2_max")]
    if not robust:
        return None
    fig, (ax, ax_ev) = plt.subplots(2, 1, figsize=(12, 6.5), sharex=True,
                                    gridspec_kw={"height_ratios": [3, 1.4]})
    gates = {}
    rows = []
    injected_drawn = False
    for f_i, (label, results, name, _) in robust:
        ep = nav_metrics.update_epochs(results, name)
        if ep is None or not ep["time"].size:
            continue
        t = ep["time"]
        ax.semilogy(t, np.maximum(ep["chi2_max"], 1e-3), ".", ms=3, color=f"C{f_i}",
                    label=f"{label}: chi2_max")
        if "injected" in ep and ep["injected"].any():
            inj = ep["injected"]
            ax.semilogy(t[inj], np.maximum(ep["chi2_max"][inj], 1e-3), "o", mfc="none",
                        ms=7, color="r", label=None if injected_drawn else "injected outlier")
            if not injected_drawn:
                rows.append(("injected (receiver)", t[inj], "r", "x"))
                injected_drawn = True
        for g in nav_metrics.chi2_thresholds(results, name):
            if g["statistic"] == "chi2_max":
                gates.setdefault((g["name"], g["value"]), g)
        if "n_rejected" in ep:
            rows.append((f"detected: {label}", t[ep["n_rejected"] > 0], f"C{f_i}", "|"))
    for i, g in enumerate(sorted(gates.values(), key=lambda g: g["value"])):
        ax.axhline(g["value"], color="k", lw=0.9, ls=("--", ":", "-.")[i % 3],
                   label=_gate_label(g))
    ax.set_ylabel("largest v_i^2 / S_ii")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    for y, (name, times, colour, marker) in enumerate(rows):
        ax_ev.plot(times, np.full(times.shape, -y), marker, color=colour, ms=8, mew=1.5)
    ax_ev.set_yticks([-y for y in range(len(rows))])
    ax_ev.set_yticklabels([r[0] for r in rows], fontsize=8)
    ax_ev.set_ylim(-len(rows) + 0.5, 0.5)
    ax_ev.grid(True, axis="x", alpha=0.3)
    ax_ev.set_xlabel("time [s]")
    ax.set_title(titled("per-observation chi-square test and outlier epochs", title))
    fig.tight_layout()
    return _save(fig, path)


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
    return _save(fig, path)


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
    return _save(fig, path)
