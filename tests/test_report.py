"""navfmu report: scenario and filter discovery from models/ and paper.json; a tiny report."""
from __future__ import annotations

import re
import shutil
from pathlib import Path

from orchestrator.reporting import report

ROOT = Path(__file__).resolve().parent.parent
INS_GNSS_FILTERS = {"Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "InsOnly",
                    "Ukf", "CtfaUkf", "ImmUkf"}


def test_discovery_finds_every_scenario_and_the_filters_that_fit():
    plans = {p["model"].name: p for p in report.discover(ROOT / "models")}
    assert {"aircraft_500s", "aircraft_outliers", "uav_maneuver"} <= set(plans)
    for name in ("aircraft_500s", "aircraft_outliers", "uav_maneuver"):
        assert INS_GNSS_FILTERS <= set(plans[name]["filters"])
        assert "TrajectoryImu" not in plans[name]["filters"]
    # the paper's filters first, in the order of its table
    assert plans["uav_maneuver"]["filters"][:3] == ["Ukf", "ImmUkf", "CtfaUkf"]
    assert plans["aircraft_500s"]["reference"]["table"][0]["filter"] == "Kf"
    # attitude filters on the attitude scenario only, and only they
    assert set(plans["ahrs_turntable"]["filters"]) == {"UkfAhrs", "FuzzyUkfAhrs"}
    assert all(not {"UkfAhrs", "FuzzyUkfAhrs"} & set(p["filters"])
               for name, p in plans.items() if name != "ahrs_turntable")


def _tiny_report(tmp_path, scenario, stop_time):
    """A 2-run report of models/``scenario`` alone: its text and folder, every figure it
    links checked to exist with content."""
    models = tmp_path / "models"
    shutil.copytree(ROOT / "models" / scenario, models / scenario)
    out = tmp_path / "report"
    text = report.build_report(out, runs=2, stop_time=stop_time, models=models,
                               log=print).read_text()
    for fig in re.findall(r"\]\(figures/([^)]+)\)", text):
        assert (out / "figures" / fig).stat().st_size > 10_000
    return text, out


def test_tiny_report_has_the_papers_table_figures_and_cross_matrix(tmp_path, monkeypatch):
    """aircraft_500s alone, 2 runs of 2 s, the paper's three filters and Ukf (to keep the
    test short; discovery is tested above)."""
    shown = ["Kf", "SageHusaFading", "Iakf", "Ukf"]
    monkeypatch.setattr(report, "fitting_filters", lambda model: shown)
    text, out = _tiny_report(tmp_path, "aircraft_500s", stop_time=2.0)
    assert "## aircraft_500s: paper 001" in text
    # the paper's row printed with its number, ours with an interval
    assert "| standard Kalman filter | paper | 9.414 | 8.600 | 3.284 |" in text
    assert re.search(r"\| Iakf \| ours \| \d+\.\d{3} \[-?\d+\.\d{3}, \d+\.\d{3}\] \|", text)
    assert "2 runs (trajectory.seed 1..2, gnss.seed 1001..1002)" in text
    # the improvement ratios on the log scale: positive bounds around their geometric mean
    ratios = re.findall(r"\| position [NED] ratio base/filter \| (\S+) \[(\S+), (\S+)\] \|",
                        text)
    assert len(ratios) == 3
    assert all(0.0 < float(lo) <= float(m) <= float(hi) for m, lo, hi in ratios)
    # the text under the errors figure names the sigma it draws (several filters: 1 sigma)
    assert "RMS of the errors over a sliding window (solid) and of the filters' own 1 sigma " \
        "(dashed) and NIS of run 0" in text and "+-3 sigma and NIS" not in text
    matrix = text.split("## Cross matrix")[1]
    assert all(f"| {f} |" in matrix for f in shown)
    assert "## Consistency: NEES and NIS" in text


def test_tiny_report_of_the_attitude_scenario_has_attitude_columns_only(tmp_path):
    """ahrs_turntable (attitude-only filters, a paper without a table), 2 runs of 20 s: the
    campaign summary, figures and cross matrix carry the attitude axes and '-' elsewhere."""
    text, _ = _tiny_report(tmp_path, "ahrs_turntable", stop_time=20.0)
    assert "## ahrs_turntable: paper 003" in text
    matrix = text.split("## Cross matrix")[1]
    for f in ("UkfAhrs", "FuzzyUkfAhrs"):
        assert re.search(rf"\| {f} \| - / - / \d+\.\d{{4}} \[", matrix)
    assert "- pitch: " in text and "- pos E" not in text.split("## Consistency")[0]
