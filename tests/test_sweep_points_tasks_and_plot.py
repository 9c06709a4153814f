"""The parameter-scale sweep (orchestrator.campaigns.sweep) beyond its table: the base values
read against the scenario's SSV files, one sweep point against a direct run of the scenario
with the scaled parameters written out and its 3-D RMS and phase means worked out from that
run, the tasks a sweep hands to its executor, the table's rows and columns at several levels,
and the figure's panels and lines."""
from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from orchestrator.campaigns import sweep
from orchestrator.errors import NavfmuError
from orchestrator.results import plot_style
from orchestrator.running import scenarios

ROOT = Path(__file__).resolve().parent.parent
AIRCRAFT = str(ROOT / "models" / "aircraft_500s")
UAV = str(ROOT / "models" / "uav_maneuver")
SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"


def _ssv_real(component, name):
    root = ET.parse(Path(AIRCRAFT) / f"{component}.ssv").getroot()
    for p in root.iter(SSV + "Parameter"):
        if p.get("name") == name:
            return float(p.find(SSV + "Real").get("value"))
    raise KeyError(name)


def test_base_values_are_the_scenario_values_as_floats():
    model = scenarios.load_scenario(AIRCRAFT)
    names = ["gnss.pos_sigma_n", "gnss.vel_sigma_e", "gnss.fix_interval"]
    values = sweep.base_values(model, names)
    assert list(values) == names
    assert values == {n: _ssv_real(*n.split(".")) for n in names}
    assert values["gnss.pos_sigma_n"] == 5.0 and type(values["gnss.pos_sigma_n"]) is float
    assert type(sweep.base_values(model, ["gnss.seed"])["gnss.seed"]) is float
    with pytest.raises(NavfmuError, match="gnss.no_such"):
        sweep.base_values(model, ["gnss.pos_sigma_n", "gnss.no_such"])


def _direct_run(scenario, parameters, filter="Kf", stop_time=2.0):
    model = scenarios.load_scenario(scenario)
    return scenarios.simulate_scenario(model, filter=filter, backend="direct",
                                       stop_time=stop_time, parameters=parameters, build=False,
                                       log=lambda m: None)


def _rms_3d_by_hand(metrics, group):
    return math.sqrt(sum(v * v for v in metrics[group].values()))


def test_a_point_is_the_run_with_the_parameters_scaled_by_the_level(capsys):
    # level 2 of a base sigma 1.5 is a run with sigma 3; the seed given with the fixed ones;
    # the filter swapped in for the scenario's Kf
    point = sweep.run_point(AIRCRAFT, "Iakf", 2.0, {"gnss.pos_sigma_n": 1.5},
                            {"gnss.seed": 3}, 2.0)
    run = _direct_run(AIRCRAFT, {"gnss.seed": 3, "gnss.pos_sigma_n": 3.0}, filter="Iakf")
    metrics = run.metrics["filter"]
    assert point["rms_3d"] == {
        "position": _rms_3d_by_hand(metrics, "position_rms_m"),
        "velocity": _rms_3d_by_hand(metrics, "velocity_rms_mps"),
        "attitude": _rms_3d_by_hand(metrics, "attitude_rms_deg")}
    assert point["phases"] == {}            # the scenario declares no phases
    for other in (_direct_run(AIRCRAFT, {"gnss.pos_sigma_n": 3.0}, filter="Iakf"),
                  _direct_run(AIRCRAFT, {"gnss.seed": 3, "gnss.pos_sigma_n": 3.0})):
        assert _rms_3d_by_hand(other.metrics["filter"], "position_rms_m") != point["rms_3d"][
            "position"]
    # a scaled parameter also named among the fixed ones is scaled
    both = sweep.run_point(AIRCRAFT, "Iakf", 2.0, {"gnss.pos_sigma_n": 1.5},
                           {"gnss.seed": 3, "gnss.pos_sigma_n": 100.0}, 2.0)
    assert both == point
    assert capsys.readouterr().out == ""


def test_a_point_has_the_phase_means_of_the_filter_outputs():
    # uav_maneuver's phases: strong 0-600 s, low 600-1200 s, ...; a 2 s run is all "strong"
    point = sweep.run_point(UAV, "Kf", 1.0, {}, {}, 2.0)
    res = _direct_run(UAV, {}).results
    updated = res.column("filter", "updated") > 0.5
    nis = res.column("filter", "nis")[updated]
    assert point["phases"] == {"nis": {"strong": pytest.approx(float(nis.mean())),
                                       "low": None}}
    assert nis.size > 0


def test_the_skipped_settings_of_a_baseline_are_not_warned_about():
    # uav_maneuver_mems sets filter.q_max_scale, which the Kf baseline does not have
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        point = sweep.run_point(str(ROOT / "models" / "uav_maneuver_mems"), "Kf", 1.0, {}, {},
                                1.0)
    assert point["rms_3d"]["position"] > 0.0


def test_other_warnings_of_a_run_are_shown(monkeypatch):
    simulate = scenarios.simulate_scenario

    def warning_run(*args, **kwargs):
        warnings.warn("overflow in a diverging run", RuntimeWarning)
        return simulate(*args, **kwargs)

    monkeypatch.setattr(scenarios, "simulate_scenario", warning_run)
    with pytest.warns(RuntimeWarning, match="diverging"):
        sweep.run_point(AIRCRAFT, "Kf", 1.0, {}, {}, 1.0)


class _RecordingExecutor:
    """Stands in for orchestrator.campaigns.executor.Executor: runs the tasks in order."""

    made = []

    def __init__(self, workers):
        self.workers, self.tasks, self.closed = workers, None, False
        self.made.append(self)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.closed = True

    def run(self, tasks, progress=None):
        self.tasks = list(tasks)
        for i, task in enumerate(self.tasks):
            if progress:
                progress(i + 1, len(self.tasks))
            yield task.key, task()


def test_a_sweep_hands_one_task_per_level_filter_and_seed(monkeypatch):
    calls = []
    monkeypatch.setattr(sweep, "run_point", lambda *args: calls.append(args) or len(calls))
    monkeypatch.setattr(sweep, "Executor", _RecordingExecutor)
    _RecordingExecutor.made.clear()
    seeds = [{"gnss.seed": 1}, {"gnss.seed": 2}]
    progress = []
    results = sweep.sweep(Path(AIRCRAFT), ["Kf", "Iakf"], [1, 0.5], ["gnss.pos_sigma_n"],
                          seeds, stop_time=3.0, workers=2, batch=1,
                          progress=lambda done, total: progress.append((done, total)))
    ex, = _RecordingExecutor.made
    assert ex.workers == 2 and ex.closed
    keys = [(1.0, "Kf", 0), (1.0, "Kf", 1), (1.0, "Iakf", 0), (1.0, "Iakf", 1),
            (0.5, "Kf", 0), (0.5, "Kf", 1), (0.5, "Iakf", 0), (0.5, "Iakf", 1)]
    assert [t.key for t in ex.tasks] == keys and all(type(t.key[0]) is float for t in ex.tasks)
    assert results == {k: i + 1 for i, k in enumerate(keys)}
    base = {"gnss.pos_sigma_n": 5.0}
    assert calls[0] == (AIRCRAFT, "Kf", 1.0, base, {"gnss.seed": 1}, 3.0)
    assert calls[7] == (AIRCRAFT, "Iakf", 0.5, base, {"gnss.seed": 2}, 3.0)
    assert type(calls[0][0]) is str and type(calls[0][2]) is float
    assert calls[0][4] is not seeds[0]
    assert progress == [(i, 8) for i in range(1, 9)]


def test_a_sweep_in_batches_gives_the_points_of_single_runs():
    """The points of a filter as batches (the default on one worker: all of a filter's
    points in one) against one run per point: the same results, exactly."""
    args = (AIRCRAFT, ["Kf", "Iakf"], [1.0, 2.0], ["gnss.pos_sigma_n"],
            [{"gnss.seed": 1}, {"gnss.seed": 2}])
    batched = sweep.sweep(*args, stop_time=3.0)
    one_by_one = sweep.sweep(*args, stop_time=3.0, batch=1)
    assert list(batched) == list(one_by_one) and batched == one_by_one
    assert batched[(2.0, "Kf", 0)] != batched[(1.0, "Kf", 0)]


def test_a_sweep_without_seeds_runs_each_point_once_on_one_worker(monkeypatch):
    calls = []
    monkeypatch.setattr(sweep, "run_point", lambda *args: calls.append(args))
    monkeypatch.setattr(sweep, "Executor", _RecordingExecutor)
    _RecordingExecutor.made.clear()
    results = sweep.sweep(AIRCRAFT, ["Kf"], [2.0], [])
    assert list(results) == [(2.0, "Kf", 0)] and _RecordingExecutor.made[0].workers == 1
    assert calls == [(AIRCRAFT, "Kf", 2.0, {}, {}, None)]


def _point(pos, vel, att, phases=None):
    return {"rms_3d": {"position": pos, "velocity": vel, "attitude": att},
            "phases": phases or {}}


def _cells(line):
    return [c.strip() for c in line.strip("|").split("|")]


def test_the_table_at_two_levels_with_a_missing_phase_and_seed():
    results = {(2.0, "A", 0): _point(2.0, 0.5, 0.25, {"nis": {"strong": 4.0}}),
               (0.25, "B", 0): _point(1.0, 0.125, 0.5, {"nis": {"strong": None, "low": 2.0}}),
               (0.25, "A", 0): _point(4.0, 0.25, 1.0, {"q": {"low": 1.0}}),
               (0.25, "A", 1): _point(8.0, 0.75, 1.0),
               (2.0, "B", 0): _point(1.0, 1.0, 0.125, {"nis": {"strong": 3.0, "low": 1.2345}})}
    lines = sweep.sweep_table(results, ("A", "B"), ("nis", "q")).splitlines()
    assert lines[0] == ("| level | filter | pos 3-D [m] | vel 3-D [m/s] | att 3-D [deg] | "
                        "pos / A | vel / A | att / A | nis strong | nis low | q strong | q low |")
    assert lines[1] == "|" + "---|" * 12
    # levels in increasing order, the filters in the order given; A at 0.25: two seeds
    assert [_cells(x) for x in lines[2:]] == [
        ["0.25", "A", "6.000", "0.5000", "1.0000", "1.00", "1.00", "1.00", "-", "-", "-", "1"],
        ["0.25", "B", "1.000", "0.1250", "0.5000", "0.17", "0.25", "0.50", "-", "2", "-", "-"],
        ["2", "A", "2.000", "0.5000", "0.2500", "1.00", "1.00", "1.00", "4", "-", "-", "-"],
        ["2", "B", "1.000", "1.0000", "0.1250", "0.50", "2.00", "0.50", "3", "1.23", "-", "-"]]
    plain = sweep.sweep_table(results, ("B", "A")).splitlines()
    assert plain[0].endswith("| pos / B | vel / B | att / B |") and len(plain) == 6
    assert _cells(plain[3]) == ["0.25", "A", "6.000", "0.5000", "1.0000", "6.00", "4.00", "2.00"]


def test_a_filter_without_runs_at_a_level_has_nan_means():
    results = {(1.0, "A", 0): _point(2.0, 0.5, 0.25)}
    with warnings.catch_warnings():
        warnings.simplefilter("error")       # no mean of an empty list
        lines = sweep.sweep_table(results, ("A", "B")).splitlines()
    assert _cells(lines[3]) == ["1", "B", "nan", "nan", "nan", "nan", "nan", "nan"]


def test_the_figure_has_a_panel_of_ratios_per_group(monkeypatch, tmp_path):
    saved = {}
    monkeypatch.setattr(plot_style, "save_png",
                        lambda fig, path: saved.update(fig=fig) or Path(path))
    results = {(2.0, "A", 0): _point(2.0, 0.5, 0.25), (2.0, "B", 0): _point(1.0, 1.0, 1.0),
               (0.5, "A", 0): _point(4.0, 1.0, 2.0), (0.5, "A", 1): _point(2.0, 1.0, 2.0),
               (0.5, "B", 0): _point(6.0, 0.5, 1.0)}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = sweep.plot_sweep(results, ["A", "B"], tmp_path / "s.png", title="T", xlabel="k")
    assert out == tmp_path / "s.png"
    fig = saved["fig"]
    assert tuple(fig.get_size_inches()) == pytest.approx((13.0, 3.8))
    assert fig._suptitle.get_text() == "T"
    axes = fig.axes
    assert len(axes) == 3 and axes[0].get_shared_x_axes().joined(axes[0], axes[2])
    # side by side: one row of three panels
    boxes = [ax.get_position() for ax in axes]
    assert boxes[0].y0 == boxes[1].y0 == boxes[2].y0 and boxes[0].x1 < boxes[1].x0
    # A at 0.5: means 3, 1, 2 over its two seeds; B against A: at 0.5 6/3, 0.5/1, 1/2, at 2
    # 1/2, 1/0.5, 1/0.25
    b_ratios = {"position": [2.0, 0.5], "velocity": [0.5, 2.0], "attitude": [0.5, 4.0]}
    for ax, g in zip(axes, sweep.GROUPS):
        assert ax.get_title() == f"{g} 3-D RMS / A" and ax.title.get_fontsize() == 9
        assert ax.get_xlabel() == "k"
        a, b, one = ax.get_lines()
        for line, y, label, color in ((a, [1.0, 1.0], "A", "C0"), (b, b_ratios[g], "B", "C1")):
            assert list(line.get_xdata()) == [0.5, 2.0]
            assert np.allclose(line.get_ydata(), y)
            assert (line.get_label(), line.get_color()) == (label, color)
            assert (line.get_marker(), line.get_linestyle()) == ("o", "-")
        assert list(one.get_ydata()) == [1.0, 1.0] and one.get_color() == "k"
        assert one.get_linewidth() == 0.6
        grid = ax.xaxis.get_gridlines()[0]
        assert grid.get_visible() and grid.get_alpha() == 0.3
    legend = axes[0].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["A", "B"]
    assert legend.get_texts()[0].get_fontsize() == 8
    assert axes[1].get_legend() is None
    plot_style.plt.close(fig)


def test_the_figure_without_a_title_and_axis_label(monkeypatch, tmp_path):
    saved = {}
    monkeypatch.setattr(plot_style, "save_png",
                        lambda fig, path: saved.update(fig=fig) or Path(path))
    sweep.plot_sweep({(1.0, "A", 0): _point(1.0, 1.0, 1.0)}, ["A"], tmp_path / "s.png")
    fig = saved["fig"]
    assert fig._suptitle.get_text() == ""
    assert [ax.get_xlabel() for ax in fig.axes] == ["level"] * 3
    plot_style.plt.close(fig)
