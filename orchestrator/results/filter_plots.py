"""Matplotlib PNG plots of what a filter says about itself: NIS with its chi-square band,
diagnostic outputs over time (adaptive scales, fading factor, model probabilities...), the
estimated measurement noise R, chi-square statistics with their gates, outlier detection, and
the GA tuner's cost per generation.

They take ``entries`` as :mod:`orchestrator.results.plots` does; each writes one PNG
atomically and returns its path, or None when no entry has the outputs it draws.
"""
from __future__ import annotations

import numpy as np
from matplotlib.ticker import MaxNLocator
from navcore.filters.innovation_stats import chi2_lower_quantile

from . import metrics as nav_metrics
from .phases import shade_phases
from .plot_style import legend_outside, plt, save_png, save_time_figure, titled


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
    return save_png(fig, path)


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
    return save_time_figure(fig, ax, "NIS", "normalized innovation squared", title, path)


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
    return save_png(fig, path)


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
    return save_png(fig, path)


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
    return save_time_figure(fig, ax, "chi-square statistic",
                            "chi-square statistic of the innovations", title, path)


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
    return save_png(fig, path)
