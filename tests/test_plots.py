"""The plots read at a glance: scales from the errors, +-3 sigma in the legend, the tables'
axis names, sliding-window RMS for several filters, no flat adaptive panels."""
from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from orchestrator.results import filter_plots, plot_style, plots
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

    for module in (plots, filter_plots, plot_style):
        monkeypatch.setattr(module, "save_png", save)
    yield kept
    for fig in kept:
        plt.close(fig)


def test_single_filter_scale_from_errors_sigma_in_legend(figures, tmp_path):
    err = np.sin(T)  # |error| <= 1
    plots.plot_errors([_entry("InsOnly", err, 2e4)], tmp_path / "e.png")
    fig = figures[0]
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["position error N", "position error E", "position error D",
                      "velocity error N", "velocity error E", "velocity error D",
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
    assert ax.get_yscale() == "log" and ax.get_title() == "position error N: RMS over 10 s"
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
    filter_plots.plot_fitness(summary, tmp_path / "f.png")
    ax = figures[0].axes[0]
    ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    assert ticks and all(float(t).is_integer() for t in ticks)
    nis = np.full(N, 2.0)
    entry = _entry("Kf", np.zeros(N), 1.0, extra={"nis": nis, "updated": np.ones(N),
                                                   "nis_dof": np.full(N, 3.0),
                                                   "nav_time": T})
    filter_plots.plot_nis([entry], tmp_path / "n.png")
    labels = figures[1].axes[0].get_legend_handles_labels()[1]
    assert labels == ["Kf", "chi2(3) 97.5 %", "chi2(3) 2.5 %"]


def test_adaptive_plot_only_when_something_adapts(figures, tmp_path):
    flat = _entry("Kf", np.zeros(N), 1.0, extra={"q_scale": np.ones(N), "r_scale": np.ones(N),
                                                 "fading_factor": np.ones(N)})
    assert filter_plots.plot_series([flat], ("q_scale", "r_scale", "fading_factor"),
                             tmp_path / "a.png") is None
    moving = _entry("Iakf", np.zeros(N), 1.0, extra={"q_scale": np.ones(N),
                                                     "r_scale": 1.0 + T / 100.0})
    filter_plots.plot_series([flat, moving], ("q_scale", "r_scale", "fading_factor"),
                      tmp_path / "a.png")
    fig = figures[-1]
    assert [ax.get_ylabel() for ax in fig.axes] == ["r_scale"]
    assert ("constant over the run: q_scale = 1 (Kf, Iakf); fading_factor = 1 (Kf)"
            in [t.get_text() for t in fig.texts])


def _outside_axes(fig, ax):
    """True if the legend of ``ax`` lies entirely right of the axes' frame."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legend = ax.get_legend().get_window_extent(renderer)
    return legend.x0 >= ax.get_window_extent(renderer).x1


def test_errors_before_the_filter_starts_are_not_drawn(figures, tmp_path):
    """Rows without an estimate (valid False) are NaN in the plotted series, not 0; the
    others equal the errors and 3 sigma."""
    label, res, name, e = _entry("Kf", np.cos(T), 0.5)
    e["valid"] = T >= 20.0
    plots.plot_errors([(label, res, name, e)], tmp_path / "e.png")
    pos_e = figures[0].axes[0]
    err, s3 = pos_e.lines[0].get_ydata(), pos_e.lines[1].get_ydata()
    assert np.all(np.isnan(err[T < 20.0])) and np.all(np.isnan(s3[T < 20.0]))
    np.testing.assert_allclose(err[T >= 20.0], np.cos(T[T >= 20.0]))
    np.testing.assert_allclose(s3[T >= 20.0], 1.5)


def test_report_caption_names_the_sigma_the_figure_draws(figures, tmp_path):
    one, two = [_entry("Kf", np.sin(T), 1.0)], [_entry("Kf", np.sin(T), 1.0),
                                                _entry("Iakf", np.sin(T), 2.0)]
    assert "+-3 sigma" in plots.errors_caption(one)
    assert "1 sigma" in plots.errors_caption(two) and "3 sigma" not in plots.errors_caption(two)
    plots.plot_errors(one, tmp_path / "a.png")
    plots.plot_errors(two, tmp_path / "b.png")
    assert "+-3 sigma" in figures[0].axes[0].get_legend_handles_labels()[1][1]
    assert all("1 sigma" in lab for lab in figures[1].axes[0].get_legend_handles_labels()[1]
               if "sigma" in lab)


def test_chi2_and_nis_legends_sit_outside_the_data(figures, tmp_path):
    nis = np.linspace(1.0, 20.0, N)
    extra = {"updated": np.ones(N), "nis": nis, "nis_dof": np.full(N, 6.0), "nav_time": T,
             "chi2": nis}
    entry = _entry("CtfaUkf", np.sin(T), 1.0, extra=extra)
    filter_plots.plot_chi2([entry], tmp_path / "c.png", title="aircraft_outliers")
    filter_plots.plot_nis([entry], tmp_path / "n.png")
    for fig in figures:
        ax = fig.axes[0]
        assert _outside_axes(fig, ax)
        np.testing.assert_allclose(ax.lines[0].get_ydata(), nis)  # the series is the results'
    assert figures[0].axes[0].get_title() == ("chi-square statistic of the innovations\n"
                                              "aircraft_outliers")


def test_trajectory_title_carries_the_runs_profile(figures, tmp_path):
    cols = ["truth_time", "truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve",
            "truth_vd", "truth_roll", "truth_pitch", "truth_yaw"]
    lat = 0.7 + 1e-5 * T
    data = np.column_stack([T, lat, np.full(N, 2.0), np.full(N, 100.0)]
                           + [np.zeros(N)] * 6)
    res = Results(time=T, data={"trajectory": data}, columns={"trajectory": cols},
                  units={"trajectory": [""] * len(cols)},
                  metadata={"model": "aircraft_500s",
                            "parameters": {"trajectory": {"profile": "uav_maneuver"}}})
    plots.plot_trajectory(res, "trajectory", tmp_path / "t.png", "aircraft_500s")
    title = figures[0]._suptitle.get_text()
    assert "profile 'uav_maneuver'" in title and "0-200 s" in title
    np.testing.assert_allclose(figures[0].axes[1].lines[0].get_ydata(), 100.0)


def test_cli_figures_are_titled_from_the_run_not_the_folder(figures, tmp_path, capsys):
    """navfmu compare on a copy of aircraft_500s in a folder of another name, flown on
    another profile: every figure names the model, the filters it shows, the profile and
    the span actually run, never the folder; the errors figure still says what it draws,
    and its plotted error is the run's (the recorded results against the truth)."""
    import json
    import shutil

    from orchestrator.building import build as fmu_build
    from orchestrator.cli.commands import main
    from orchestrator.results import metrics as nav_metrics

    folder = tmp_path / "my_copy"
    shutil.copytree(fmu_build.ROOT / "models" / "aircraft_500s", folder)
    ssd = folder / "SystemStructure.ssd"
    ssd.write_text(ssd.read_text().replace("../../fmus/dist/", f"{fmu_build.DIST}/"))
    with pytest.raises(SystemExit) as exc:
        main(["compare", str(folder), "--filters", "Kf,Iakf", "--stop", "3", "--backend",
              "direct", "--set", "trajectory.profile=uav_maneuver", "--out",
              str(tmp_path / "out")])
    assert exc.value.code == 0, capsys.readouterr().err
    run = "profile 'uav_maneuver', 0-3 s"
    titles = {(fig._suptitle.get_text() if fig._suptitle else fig.axes[0].get_title())
              for fig in figures}
    assert all("my_copy" not in t for t in titles), titles
    assert {t.split("\n")[-1] for t in titles} >= {
        f"aircraft_500s: Kf, Iakf, {run}", f"aircraft_500s: Kf, {run}",
        f"aircraft_500s: Iakf, {run}", f"truth trajectory: aircraft_500s, {run}"}
    kf_errors = next(f for f in figures if f._suptitle and f._suptitle.get_text() == (
        f"errors (solid) with the filter's own +-3 sigma (dashed)\naircraft_500s: Kf, {run}"))
    results = Results.from_csv(tmp_path / "out" / "results_Kf.csv")
    results.metadata = json.loads((tmp_path / "out" / "metrics.json").read_text())["Kf"][
        "metadata"]
    e = nav_metrics.navigation_errors(results, "filter")
    drawn = kf_errors.axes[0].lines[0].get_ydata()       # position error N
    np.testing.assert_allclose(drawn[e["valid"]], e["pos_n"][e["valid"]], rtol=1e-9,
                               atol=1e-9)
    assert np.isnan(drawn[~e["valid"]]).all()


def test_mission_frame_is_around_the_route_at_equal_aspect(monkeypatch, tmp_path):
    """An estimate 50 km off does not set the frame: the route's 2 km square does, with
    equal scales on both axes; the plotted true path equals the results'."""
    from navcore.ins import earth
    from orchestrator.results import mission_plots

    kept = []
    monkeypatch.setattr(mission_plots, "save_png", lambda fig, path: kept.append(fig) or path)
    lat0, lon0 = 0.7, 2.0
    rn, re = earth.radii(lat0)
    north, east = 2000.0 * T / 200.0, 1000.0 * np.sin(T / 50.0)
    lat, lon = lat0 + north / rn, lon0 + east / (re * np.cos(lat0))
    cols = {"vehicle": ["truth_lat", "truth_lon", "truth_h", "cross_track"],
            "filter": ["nav_lat", "nav_lon"], "gnss": ["gnss_valid"]}
    data = {"vehicle": np.column_stack([lat, lon, np.full(N, 100.0), np.zeros(N)]),
            "filter": np.column_stack([lat + 50000.0 / rn * (T > 100), lon]),
            "gnss": (T < 100).astype(float)[:, None]}
    res = Results(time=T, data=data, columns=cols,
                  units={k: [""] * len(v) for k, v in cols.items()},
                  metadata={"parameters": {"vehicle": {
                      "origin_lat": lat0, "origin_lon": lon0,
                      "route": "0,0,100;2000,0,100;2000,2000,100"}}})
    mission_plots.plot_mission([("Kf", res, "filter")], "vehicle", tmp_path / "m.png")
    ax = kept[0].axes[0]
    try:
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert x1 - x0 == pytest.approx(y1 - y0) and ax.get_aspect() == 1.0
        # km: the larger extent of the route and the true path (east -0.76..2), with the
        # margin on both sides; the 50 km of the estimate do not count
        extent = max(2.0, 2.0 - 1.0 * np.sin(T / 50.0).min())
        framed = extent * (1 + 2 * mission_plots.FRAME_MARGIN)
        assert y1 - y0 == pytest.approx(framed, rel=1e-4)
        assert x0 < east.min() / 1e3 and x1 > 2.0 and y0 < 0.0 and y1 > 2.0
        true_path = ax.lines[1]
        # the plane's radii are at the route's 100 m height
        np.testing.assert_allclose(true_path.get_ydata(), north / 1e3, rtol=1e-4)
    finally:
        plt.close(kept[0])


def test_robustness_figure_has_whole_seed_ticks():
    from orchestrator.verification.filter_checks import robustness_plot
    from orchestrator.verification.verdicts import Check

    checks = [Check("robust.outage", "t", "c", "m", "pass",
                    details={"filter": [3.1, 2.0], "Kf": [2.9, 2.5]}),
              Check("robust.bias", "t", "c", "m", "pass", details={"filter": [0.4], "Kf": [0.5]})]
    fig = robustness_plot(checks)
    try:
        for ax, c in zip(fig.axes, checks):
            seeds = len(c.details["filter"])
            assert list(ax.get_xticks()) == list(range(seeds))
            assert ax.get_xlim() == (-0.5, seeds - 0.5)
            heights = [p.get_height() for p in ax.patches]
            assert heights == c.details["filter"] + c.details["Kf"]
    finally:
        plt.close(fig)
