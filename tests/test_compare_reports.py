"""The compare/bench reports of the three papers: tables with the paper's rows, improvement,
outlier detection and timing numbers next to the paper's, the extra plots, bench --filters."""
from __future__ import annotations

import json
import math
import re
import types

import pytest

from orchestrator.building import build as fmu_build
from orchestrator.results import metric_comparisons
from orchestrator.results import metrics as nav_metrics
from orchestrator.cli import bench
from orchestrator.running import comparison, comparison_text, run_outputs, scenarios
from orchestrator.cli.commands import main

MODELS = fmu_build.ROOT / "models"
NUMBER = re.compile(r"-?\d+\.\d+")


def _runs(scenario, filters, stop):
    model = scenarios.load_scenario(MODELS / scenario)
    return model, [scenarios.simulate_scenario(model, filter=f, backend="direct", stop_time=stop,
                                               log=None) for f in filters]


@pytest.fixture(scope="module")
def outliers():
    """Paper 004's scenario: outliers of 20 sigma every 10 s from 5 s."""
    model, runs = _runs("aircraft_outliers", ("Kf", "NewtonRobustKf"), 30.0)
    return model, runs, scenarios.paper_reference(model)


@pytest.fixture(scope="module")
def uav():
    model, runs = _runs("uav_maneuver", ("Ukf", "CtfaUkf"), 20.0)
    return model, runs, scenarios.paper_reference(model)


@pytest.fixture(scope="module")
def aircraft():
    model, runs = _runs("aircraft_500s", ("Kf", "Iakf"), 20.0)
    return model, runs, scenarios.paper_reference(model)


def _row(table, label):
    lines = [ln for ln in table.splitlines() if ln.startswith(label + " ")]
    assert len(lines) == 1, (label, table)
    return lines[0]


def _metrics(pos_ned, vel_ned=(0.0, 0.0, 0.0), att=(0.0, 0.0, 0.0)):
    return {"position_rms_m": dict(zip("ned", pos_ned)),
            "velocity_rms_mps": dict(zip("ned", vel_ned)),
            "attitude_rms_deg": dict(zip(("roll", "pitch", "yaw"), att))}


# -- metric definitions on constructed numbers ---------------------------------------------
def test_improvement_and_ratios_on_constructed_metrics():
    base = _metrics((3.0, 4.0, 0.0), (0.0, 0.3, 0.4))
    filt = _metrics((0.6, 0.8, 0.0), (0.0, 0.03, 0.04))
    assert metric_comparisons.rms_3d(base, "position") == pytest.approx(5.0)
    assert metric_comparisons.rms_3d(filt, "velocity") == pytest.approx(0.05)
    assert metric_comparisons.improvement_percent(5.0, 1.0) == pytest.approx(80.0)
    assert metric_comparisons.rms_ratio(6.0, 1.5) == pytest.approx(4.0)
    assert metric_comparisons.per_axis(base, "position") == [3.0, 4.0, 0.0]  # N, E, D

    runs = [scenarios.Run("Kf", None, None, {"filter": base}),
            scenarios.Run("Robust", None, None, {"filter": filt})]
    ref = {"improvement_percent": {"baseline": "Kf", "filter": "Robust", "position": 76.0,
                                   "velocity": 80.0, "position_ratio_ned": [5.71, 6.07, 2.39]}}
    comp = comparison.paper_comparison(runs, ref)
    items = {i["key"]: i for i in comp["improvement"]["items"]}
    assert items["position"]["ours"] == pytest.approx(80.0)
    assert items["velocity"]["ours"] == pytest.approx(90.0)
    assert items["position"]["paper"] == 76.0
    ratio = items["position_ratio_ned"]["ours"]
    assert ratio[:2] == pytest.approx([5.0, 5.0]) and math.isnan(ratio[2])  # 0 / 0 -> nan
    text = comparison_text.format_comparison(comp)
    assert "ours 80.0 % lower, paper 76.0 %" in text
    assert "ours 90.0 % lower, paper 80.0 %" in text
    assert "6.07" in text and "5.00" in text
    # a block whose filters were not run says which are missing
    comp = comparison.paper_comparison(runs[:1], ref)
    assert comp["improvement"]["missing"] == ["Robust"]
    assert "add Robust to --filters" in comparison_text.format_comparison(comp)


def test_rejection_statistics_on_constructed_epochs():
    injected = [False, True, False, False, True, False]
    n_rejected = [0, 6, 1, 0, 0, 2]
    stats = nav_metrics.rejection_statistics(injected, n_rejected, [6] * 6)
    assert (stats["injected_epochs"], stats["detected_epochs"]) == (2, 1)
    assert stats["detection_rate"] == pytest.approx(0.5)
    assert (stats["clean_epochs"], stats["false_alarm_epochs"]) == (4, 2)
    assert stats["false_alarm_rate"] == pytest.approx(0.5)
    assert stats["false_alarm_rate_per_observation"] == pytest.approx(3 / 24)
    none = nav_metrics.rejection_statistics([False, False], [0, 0], [3, 3])
    assert math.isnan(none["detection_rate"]) and none["false_alarm_rate"] == 0.0


def test_rms_table_prints_dashes_for_missing_paper_numbers():
    m = _metrics((1.0, 2.0, 3.0), (0.1, 0.2, 0.3), (0.01, 0.02, 0.03))
    table = metric_comparisons.rms_table([("ours", m)], [("paper: a", None, None),
                                                  ("paper: b", [1, None, 3], [4, 5, 6],
                                                   [0.5, 0.6, 0.7])])
    assert _row(table, "paper: a").split()[2:] == ["-"] * 9
    assert _row(table, "paper: b").split()[2:] == ["1.0000", "-", "3.0000", "4.0000", "5.0000",
                                                   "6.0000", "0.5000", "0.6000", "0.7000"]
    # ours in N, E, D order
    assert _row(table, "ours").split()[1:4] == ["1.0000", "2.0000", "3.0000"]


# -- paper 004: aircraft_outliers ----------------------------------------------------------
def test_outlier_report(outliers, tmp_path):
    model, runs, ref = outliers
    table = comparison.report_table(runs, ref)
    for label in ("Kf", "NewtonRobustKf"):
        values = [float(x) for x in NUMBER.findall(_row(table, label))]
        assert len(values) == 9 and all(math.isfinite(v) for v in values)
    # the paper gives no per-axis numbers (its tables are images): no empty paper rows
    assert "paper:" not in table

    det = runs[1].metrics["filter"]["outlier_detection"]
    # injected at 5, 15, 25 s; each such fix has every observation 20 sigma off
    epochs = nav_metrics.update_epochs(runs[1].results, "filter")
    assert epochs["time"][epochs["injected"]] == pytest.approx([5.0, 15.0, 25.0])
    assert (det["injected_epochs"], det["detected_epochs"]) == (3, 3)
    assert det["clean_epochs"] == 27 and det["clean_observations"] == 27 * 6
    assert det["false_alarm_rate_per_observation"] < 0.1
    assert det["chi2_threshold"] == {"name": "chi2_threshold", "statistic": "chi2_max",
                                     "value": 6.635, "source": "default"}
    assert det["expected_false_alarm_rate_chi2_1"] == pytest.approx(0.01, abs=1e-4)
    assert "outlier_detection" not in runs[0].metrics["filter"]  # Kf has no n_rejected

    comp = comparison.paper_comparison(runs, ref)
    items = {i["key"]: i for i in comp["improvement"]["items"]}
    kf, rob = runs[0].metrics["filter"], runs[1].metrics["filter"]
    for group, key in (("position", "position_rms_m"), ("velocity", "velocity_rms_mps")):
        b = math.sqrt(sum(v ** 2 for v in kf[key].values()))
        f = math.sqrt(sum(v ** 2 for v in rob[key].values()))
        assert items[group]["ours"] == pytest.approx(100 * (1 - f / b))
        assert items[group]["ours"] > 30.0  # the outliers hurt the plain Kf
    text = comparison_text.format_comparison(comp)
    assert "paper 76.0 %" in text and "paper 80.0 %" in text
    assert "NewtonRobustKf: detected 3/3 injected epochs (100.0 %)" in text

    written = {p.name: p for p in run_outputs.write_outputs(runs, tmp_path, reference=ref)}
    for name in ("errors.png", "nis.png", "adaptive.png", "outliers.png", "trajectory.png"):
        assert written[name].stat().st_size > 10_000, name
    assert "chi2.png" not in written and "r_estimate.png" not in written
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["outlier_detection"]["NewtonRobustKf"]["detected_epochs"] == 3
    assert report["improvement"]["items"][0]["paper"] == 76.0


def test_chi2_threshold_from_the_run_parameters(outliers):
    _, runs, _ = outliers
    res = runs[1].results
    patched = types.SimpleNamespace(columns=res.columns, metadata={
        "parameters": {"filter": dict(res.metadata["parameters"]["filter"],
                                      chi2_threshold=9.0)}})
    assert nav_metrics.chi2_thresholds(patched, "filter") == [
        {"name": "chi2_threshold", "statistic": "chi2_max", "value": 9.0,
         "source": "parameter"}]


# -- paper 000: uav_maneuver ---------------------------------------------------------------
def test_uav_report(uav, tmp_path):
    model, runs, ref = uav
    table = comparison.report_table(runs, ref)
    lines = table.splitlines()
    # our row, then the paper's row for the same filter, with the paper's attitude (Table 4)
    assert lines[2].startswith("Ukf ") and lines[3].startswith("paper: UKF ")
    assert lines[3].split()[-3:] == ["0.0780", "0.0690", "0.1680"]
    assert _row(table, "paper: CTFA-UKF").split()[-9:] == [
        "0.9970", "0.7570", "1.0410", "0.0690", "0.0540", "0.0510", "0.0140", "0.0110", "0.0330"]
    assert _row(table, "paper: IMM-UKF")  # not run: listed at the end
    for label in ("Ukf", "CtfaUkf"):
        values = [float(x) for x in NUMBER.findall(_row(table, label))]
        assert len(values) == 9 and all(math.isfinite(v) and v >= 0 for v in values)

    comp = comparison.paper_comparison(runs, ref)
    tpc = comp["time_per_cycle"]
    assert tpc["baseline"] == "Ukf" and tpc["missing"] == ["ImmUkf"]
    assert tpc["filter_step_s"] == pytest.approx(0.02)
    rows = {r["filter"]: r for r in tpc["rows"]}
    assert rows["CtfaUkf"]["paper_ratio"] == pytest.approx(0.892 / 0.646)
    assert rows["CtfaUkf"]["ours_ratio"] == pytest.approx(
        rows["CtfaUkf"]["ours_ms"] / rows["Ukf"]["ours_ms"])
    assert rows["Ukf"]["ours_ms"] > 0
    text = comparison_text.format_comparison(comp, "`navfmu bench X --filters Ukf,CtfaUkf`")
    assert "1.38" in text and "navfmu bench X --filters Ukf,CtfaUkf" in text
    # phase means from paper.json's windows: 20 s lie in the first strong phase only
    phase_rows = {(r["filter"], r["variable"]): r for r in comp["phases"]["rows"]}
    nis = runs[0].results.column("filter", "nis")[runs[0].results.column("filter", "updated") > 0.5]
    assert phase_rows[("Ukf", "nis")]["means"] == {"strong": pytest.approx(nis.mean()),
                                                   "low": None}
    assert "means per phase at the update epochs" in text

    gates = nav_metrics.chi2_thresholds(runs[1].results, "filter")
    assert [(g["name"], g["value"]) for g in gates] == [("ctfa_t1", 6.25), ("ctfa_t2", 11.35)]
    assert nav_metrics.chi2_thresholds(runs[0].results, "filter") == []  # plain Ukf: no gate

    written = {p.name: p for p in run_outputs.write_outputs(runs, tmp_path, reference=ref)}
    for name in ("errors.png", "adaptive.png", "chi2.png", "trajectory.png"):
        assert written[name].stat().st_size > 10_000, name
    assert "outliers.png" not in written


# -- paper 001: aircraft_500s --------------------------------------------------------------
def test_aircraft_report(aircraft, tmp_path):
    model, runs, ref = aircraft
    comp = comparison.paper_comparison(runs, ref)
    items = {i["key"]: i for i in comp["improvement"]["items"]}
    kf, iakf = runs[0].metrics["filter"], runs[1].metrics["filter"]
    expected = [kf["position_rms_m"][a] / iakf["position_rms_m"][a] for a in "ned"]
    assert items["position_ratio_ned"]["ours"] == pytest.approx(expected)
    assert items["position_ratio_ned"]["paper"] == [5.71, 6.07, 2.39]
    assert items["velocity_ned"]["ours"] == pytest.approx(
        [100 * (1 - iakf["velocity_rms_mps"][a] / kf["velocity_rms_mps"][a]) for a in "ned"])
    text = comparison_text.format_comparison(comp)
    assert "position RMS ratio Kf/Iakf" in text and "6.07" in text and "2.39" in text
    assert "time per filter cycle" not in text  # paper 001 gives no timing

    written = {p.name: p for p in run_outputs.write_outputs(runs, tmp_path, reference=ref)}
    assert written["r_estimate.png"].stat().st_size > 10_000
    assert written["adaptive.png"].stat().st_size > 10_000


# -- the command line ----------------------------------------------------------------------
def test_compare_cli_prints_the_report(capsys, tmp_path):
    out_dir = tmp_path / "cmp"
    with pytest.raises(SystemExit) as exc:
        main(["compare", str(MODELS / "aircraft_outliers"), "--filters", "Kf,NewtonRobustKf",
              "--backend", "direct", "--stop", "16", "--no-plots", "--out", str(out_dir)])
    out, err = capsys.readouterr()
    assert exc.value.code == 0, err
    # 16 s of a 500 s scenario: the paper's rows and improvements do not compare (the
    # formatted improvement line is checked above on a comparison of its own)
    assert "paper: robust Kalman filter" not in out and "paper 76.0 %" not in out
    assert ("the paper's numbers are left out: the run spans 0-16 s, the paper's scenario "
            "0-500 s") in out
    assert "NewtonRobustKf: detected 2/2 injected epochs (100.0 %)" in out
    assert (out_dir / "report.json").is_file()


@pytest.fixture(scope="module")
def _fmus():
    fmu_build.build(["TrajectoryImu", "GnssReceiver", "Ukf", "CtfaUkf"], log=None)


def test_bench_filters(_fmus, capsys):
    model = scenarios.load_scenario(MODELS / "uav_maneuver")
    ref = scenarios.paper_reference(model)
    out = bench.bench_filters(model, ["Ukf", "CtfaUkf"], stop_time=2.0, repeat=2,
                                  reference=ref, log=None)
    assert out["baseline"] == "Ukf" and out["repeat"] == 2 and out["stop_time"] == 2.0
    rows = out["filters"]
    assert list(rows) == ["Ukf", "CtfaUkf"]
    for r in rows.values():
        assert r["time_per_cycle_ms"] > 0 and r["wall_s"] > 0
        assert r["filter_calls"] == r["base_steps"] == 100
    assert rows["Ukf"]["ratio"] == 1.0
    assert rows["CtfaUkf"]["ratio"] == pytest.approx(
        rows["CtfaUkf"]["time_per_cycle_ms"] / rows["Ukf"]["time_per_cycle_ms"])
    assert rows["CtfaUkf"]["paper_ratio"] == pytest.approx(1.3808, abs=1e-4)

    with pytest.raises(SystemExit) as exc:
        main(["bench", str(MODELS / "uav_maneuver"), "--filters", "Ukf,CtfaUkf", "--stop", "1",
              "--repeat", "1", "--json"])
    text, err = capsys.readouterr()
    assert exc.value.code == 0, err
    data = json.loads(text)
    assert set(data["filters"]) == {"Ukf", "CtfaUkf"}
    assert data["filters"]["Ukf"]["paper_time_per_cycle_ms"] == 0.646
