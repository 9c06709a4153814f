"""The plots read at a glance: scales from the errors, +-3 sigma in the legend, the tables'
axis names, sliding-window RMS for several filters, no flat adaptive panels."""
from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from orchestrator.results import plots
from orchestrator.results.run_results import Results

N = 2001
T = np.linspace(0.0, 200.0, N)
STD = ([f"std_p{a}" for a in "ned"] + [f"std_v{a}" for a in "ned"]
       + [f"std_att_{a}" for a in "ned"])


def _entry(label, error, sigma, yaw=0.0, extra=None):
    """A filter whose every error is ``error`` (array) and every sigma ``sigma``."""
    columns = STD + ["nav_yaw"] + list(extra or {})
    data = np.column_stack([np.full(N, sigma)] * len(STD) + [np.full(N, yaw)]
                           + [np.asarray(v, float) for v in (extra or {}).values()])
    res = Results(time=T, data={"filter": data}, columns={"filter": columns},
                  units={"filter": [""] * len(columns)})
    keys = ([f"pos_{a}" for a in "ned"] + [f"vel_{a}" for a in "ned"]
            + [f"att_{a}" for a in ("roll", "pitch", "yaw")])
    e = {k: np.asarray(error, float) for k in keys}
    e.update(time=T, valid=np.ones(N, bool))
    return (label, res, "filter", e)


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions draw, kept open for inspection."""
    kept = []

    def save(fig, path):
        kept.append(fig)
        return path

    monkeypatch.setattr(plots, "_save", save)
    yield kept
    for fig in kept:
        plt.close(fig)


def test_single_filter_scale_from_errors_sigma_in_legend(figures, tmp_path):
    err = np.sin(T)  # |error| <= 1
    plots.plot_errors([_entry("InsOnly", err, 2e4)], tmp_path / "e.png")
    fig = figures[0]
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["position error E", "position error N", "position error U",
                      "velocity error E", "velocity error N", "velocity error U",
                      "attitude error roll", "attitude error pitch", "attitude error yaw"]
    pos_e = fig.axes[0]
    assert pos_e.get_ylim() == pytest.approx((-1.3, 1.3), rel=1e-3)  # not +-6e4
    labels = pos_e.get_legend_handles_labels()[1]
    assert labels == ["InsOnly error", "InsOnly +-3 sigma (beyond the frame)"]
    assert any("Euler-angle errors roll/pitch/yaw as in the tables" in t.get_text()
               for t in fig.texts)


def test_attitude_sigmas_turn_with_the_heading():
    for yaw, roll_from in ((0.0, "n"), (math.pi / 2, "e")):
        sig = {"n": 1.0, "e": 2.0, "d": 3.0}
        extra = {f"std_att_{a}": np.full(N, s) for a, s in sig.items()}
        label, res, name, _ = _entry("f", np.zeros(N), 0.0, yaw=yaw)
        res.data[name][:, [res.columns[name].index(k) for k in extra]] = np.column_stack(
            list(extra.values()))
        out = plots._attitude_sigmas(res, name)
        assert out["roll"] == pytest.approx(np.full(N, sig[roll_from]))
        assert out["yaw"] == pytest.approx(np.full(N, 3.0))


def test_moving_rms_against_closed_forms():
    valid = np.ones(N, bool)
    const = plots._moving_rms(T, np.full(N, -2.0), valid, 10.0)
    assert const == pytest.approx(np.full(N, 2.0))
    x = 3.0 * np.sin(2 * np.pi * T)
    sine = plots._moving_rms(T, x, valid, 10.0)
    # 10 periods of 10 samples plus the closing sample (a zero): 3 sqrt(50 / 101)
    assert sine[N // 2] == pytest.approx(3.0 * math.sqrt(50.0 / 101.0))
    assert sine[N // 2] == pytest.approx(3.0 / math.sqrt(2.0), rel=0.01)
    # near the start the window is cut: the samples from t = 0 to t = 1 + 5 s
    assert sine[10] == pytest.approx(math.sqrt(np.mean(x[:61] ** 2)))
    valid[: N // 2] = False  # invalid samples do not count
    half = plots._moving_rms(T, np.where(valid, 1.0, 1e9), valid, 10.0)
    assert np.isnan(half[0]) and half[-1] == 1.0


def test_several_filters_get_sliding_rms_on_a_log_scale(figures, tmp_path):
    entries = [_entry("Kf", 0.5 * np.ones(N), 1.0), _entry("InsOnly", 50.0 * np.ones(N), 2e4)]
    plots.plot_errors(entries, tmp_path / "e.png")
    ax = figures[0].axes[0]
    assert ax.get_yscale() == "log" and ax.get_title() == "position error E: RMS over 10 s"
    labels = ax.get_legend_handles_labels()[1]
    assert labels == ["Kf", "InsOnly", "Kf: 1 sigma (own)", "InsOnly: 1 sigma (own)"]
    kf_line = ax.get_lines()[0].get_ydata()
    assert kf_line == pytest.approx(np.full(kf_line.shape, 0.5))


def test_several_filters_legend_off_the_panels_and_equal_sigmas_drawn_once(figures, tmp_path):
    """Three filters claiming the same sigma: one dashed line named after all three (not
    three on top of each other); the legend is the figure's, below the panels, not inside
    one; equal error curves stay visible as nested lines (the first drawn widest)."""
    entries = [_entry(n, 0.5 * np.ones(N), 1.0) for n in ("Kf", "SageHusaFading", "Iakf")]
    plots.plot_errors(entries, tmp_path / "e.png")
    fig = figures[0]
    ax = fig.axes[0]
    assert ax.get_legend() is None and len(fig.legends) == 1
    assert [t.get_text() for t in fig.legends[0].get_texts()] == [
        "Kf", "SageHusaFading", "Iakf", "Kf, SageHusaFading, Iakf: 1 sigma (own)"]
    legend_top = fig.legends[0].get_window_extent().y1
    assert all(a.get_window_extent().y0 > legend_top for a in fig.axes)
    widths = [line.get_linewidth() for line in ax.get_lines()[:3]]
    assert widths == sorted(widths, reverse=True) and widths[0] > widths[-1]


def test_fitness_ticks_are_whole_generations_and_nis_bands_labelled(figures, tmp_path):
    summary = {"best_so_far": [3.0, 2.0, 1.5], "generation_mean": [4.0, 3.0, 2.0],
               "model": "m", "parameters": ["a"], "component": "filter", "population": 4}
    plots.plot_fitness(summary, tmp_path / "f.png")
    ax = figures[0].axes[0]
    ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    assert ticks and all(float(t).is_integer() for t in ticks)
    nis = np.full(N, 2.0)
    entry = _entry("Kf", np.zeros(N), 1.0, extra={"nis": nis, "updated": np.ones(N),
                                                   "nis_dof": np.full(N, 3.0),
                                                   "nav_time": T})
    plots.plot_nis([entry], tmp_path / "n.png")
    labels = figures[1].axes[0].get_legend_handles_labels()[1]
    assert labels == ["Kf", "chi2(3) 97.5 %", "chi2(3) 2.5 %"]


def test_adaptive_plot_only_when_something_adapts(figures, tmp_path):
    flat = _entry("Kf", np.zeros(N), 1.0, extra={"q_scale": np.ones(N), "r_scale": np.ones(N),
                                                 "fading_factor": np.ones(N)})
    assert plots.plot_series([flat], ("q_scale", "r_scale", "fading_factor"),
                             tmp_path / "a.png") is None
    moving = _entry("Iakf", np.zeros(N), 1.0, extra={"q_scale": np.ones(N),
                                                     "r_scale": 1.0 + T / 100.0})
    plots.plot_series([flat, moving], ("q_scale", "r_scale", "fading_factor"),
                      tmp_path / "a.png")
    fig = figures[-1]
    assert [ax.get_ylabel() for ax in fig.axes] == ["r_scale"]
    assert ("constant over the run: q_scale = 1 (Kf, Iakf); fading_factor = 1 (Kf)"
            in [t.get_text() for t in fig.texts])
