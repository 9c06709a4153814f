"""The campaign summary (orchestrator.campaigns.campaign_summary) on a few hand-made runs: the
axes every run has, the per-run values, the paper's numbers read from a paper.json table, the
summary's entries (means, pooled RMS, orderings, the paper's ordering) worked out by hand, and
the text of ``format_summary`` written out line by line."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from orchestrator.campaigns import campaign_summary as cs
from orchestrator.campaigns import statistics as st

ROOT = Path(__file__).resolve().parent.parent
#: the tables' order: position and velocity north, east, down, then roll, pitch, yaw
NAV_KEYS = ["pos_n", "pos_e", "pos_d", "vel_n", "vel_e", "vel_d", "att_roll", "att_pitch",
            "att_yaw"]
MISSION_KEYS = ["cross_track_rms_m", "cross_track_max_m", "outage_cross_track_max_m",
                "outage_position_error_max_m", "waypoint_miss_max_m"]


def _nav_metrics(scale):
    """Distinct values per axis: position k * scale, velocity (k + 3) * scale, attitude
    (k + 6) * scale for the k-th (from 1) component."""
    return {"position_rms_m": {"e": 1 * scale, "n": 2 * scale, "d": 3 * scale},
            "velocity_rms_mps": {"e": 4 * scale, "n": 5 * scale, "d": 6 * scale},
            "attitude_rms_deg": {"roll": 7 * scale, "pitch": 8 * scale, "yaw": 9 * scale}}


def _records(scales):
    """filter -> runs, each run's metrics _nav_metrics(scale)."""
    return {f: [{"metrics": _nav_metrics(s)} for s in runs] for f, runs in scales.items()}


def test_the_axes_in_table_order_and_only_those_every_run_has():
    assert [a[0] for a in cs.AXES] == NAV_KEYS + MISSION_KEYS
    assert [a[3] for a in cs.AXES[:9]] == ["pos N", "pos E", "pos D", "vel N", "vel E",
                                           "vel D", "roll", "pitch", "yaw"]
    assert [a[4] for a in cs.AXES] == ["m"] * 3 + ["m/s"] * 3 + ["deg"] * 3 + ["m"] * 5
    assert cs.AXES[2][1:3] == ("position_rms_m", "d") and cs.AXES[5][1:3] == (
        "velocity_rms_mps", "d")
    assert cs.AXES[9][1:4] == ("mission", "cross_track_rms_m", "xtrack RMS")
    full = _records({"Kf": [1.0, 2.0]})
    assert [a[0] for a in cs.recorded_axes(full)] == NAV_KEYS
    # one run of another filter without position and velocity: attitude only
    attitude_only = {"attitude_rms_deg": {"roll": 1.0, "pitch": 1.0, "yaw": 1.0}}
    mixed = {**full, "Ahrs": [{"metrics": attitude_only}, {"metrics": _nav_metrics(1.0)}]}
    assert [a[0] for a in cs.recorded_axes(mixed)] == ["att_roll", "att_pitch", "att_yaw"]
    mission = {k: 1.0 for k in MISSION_KEYS}
    guided = {"Kf": [{"metrics": {**_nav_metrics(1.0), "mission": mission}}]}
    assert [a[0] for a in cs.recorded_axes(guided)] == NAV_KEYS + MISSION_KEYS
    assert cs.recorded_axes({}) == [ax for ax in cs.AXES]


def test_per_run_values_are_floats_and_a_missing_metric_nan():
    runs = [{"metrics": {"position_rms_m": {"e": v}}} for v in (1, None, 2.5)]
    values = cs.per_run_values(runs, "position_rms_m", "e")
    assert values[0] == 1.0 and type(values[0]) is float
    assert math.isnan(values[1]) and values[2] == 2.5


def test_the_paper_numbers_of_paper_001():
    reference = json.loads((ROOT / "models" / "aircraft_500s" / "paper.json").read_text())
    paper = cs.paper_values(reference)
    assert sorted(paper) == ["Iakf", "Kf", "SageHusaFading"]
    # Table 1 of paper 001 (printed east, north, up: east 8.6003, north 9.4141, up 3.2837)
    assert paper["Kf"] == {"pos_e": 8.6003, "pos_n": 9.4141, "pos_d": 3.2837,
                           "vel_e": 0.5652, "vel_n": 0.9521, "vel_d": 0.3004}
    assert paper["Iakf"]["vel_d"] == 0.086


def test_paper_rows_without_a_filter_or_numbers_are_skipped():
    reference = {"table": [
        {"label": "no filter", "position_ned_m": [1.0, 2.0, 3.0]},
        {"filter": "", "position_ned_m": [1.0, 2.0, 3.0]},
        {"filter": "Kf"},                                       # no numbers at all
        {"filter": "Iakf", "position_ned_m": [2, None, None],
         "attitude_deg": [0.1, 0.2, 0.3]}]}
    paper = cs.paper_values(reference)
    assert paper == {"Iakf": {"pos_n": 2.0, "att_roll": 0.1, "att_pitch": 0.2, "att_yaw": 0.3}}
    assert type(paper["Iakf"]["pos_n"]) is float
    assert cs.paper_values(None) == {} and cs.paper_values({}) == {}


def test_summary_of_one_filter_per_axis():
    # runs of scales 1, 2, 4: pos N values 2, 4, 8 (mean 14/3, pooled RMS sqrt(84/3))
    records = _records({"Kf": [1.0, 2.0, 4.0]})
    provenance = {"scenario": "s", "commit": "abc"}
    summary = cs.summarize(records, provenance=provenance)
    assert summary["runs"] == 3 and summary["filters"] == ["Kf"]
    assert (summary["level"], summary["method"], summary["paired_method"]) == (
        0.95, st.METHOD, st.PAIRED_METHOD)
    assert summary["provenance"] == provenance and summary["provenance"] is not provenance
    assert list(summary["axes"]) == NAV_KEYS
    pos_n = summary["axes"]["pos_n"]
    assert set(pos_n) == {"label", "unit", "filters"}        # one filter: no orderings
    assert (pos_n["label"], pos_n["unit"]) == ("pos N", "m")
    kf = pos_n["filters"]["Kf"]
    assert kf["mean"] == pytest.approx(14.0 / 3.0) and kf["n"] == 3
    assert kf["pooled_rms"] == pytest.approx(math.sqrt(84.0 / 3.0))
    assert kf["paper"] is None
    assert {k: kf[k] for k in ("low", "high")} == pytest.approx(
        {k: st.positive_interval([2.0, 4.0, 8.0])[k] for k in ("low", "high")})
    yaw = summary["axes"]["att_yaw"]["filters"]["Kf"]
    assert yaw["mean"] == pytest.approx(9 * 7.0 / 3.0)
    assert (summary["axes"]["vel_d"]["label"], summary["axes"]["vel_d"]["unit"]) == (
        "vel D", "m/s")
    assert cs.summarize({})["runs"] == 0 and cs.summarize({})["provenance"] == {}


def test_summary_orderings_against_the_paper():
    # Iakf's runs 0.1 below Kf's (scale), Sage-Husa's Kf's exactly: Iakf < Kf resolved, Kf
    # and SageHusaFading the same (paired differences 0, an interval [0, 0])
    records = _records({"Kf": [1.0, 2.0, 4.0], "SageHusaFading": [1.0, 2.0, 4.0],
                        "Iakf": [0.9, 1.9, 3.9]})
    reference = {"table": [{"filter": "Kf", "position_ned_m": [1.0, 3.0, 2.0]},
                           {"filter": "Iakf", "position_ned_m": [2.0, 1.0, 1.0]}]}
    summary = cs.summarize(records, reference)
    pos_e = summary["axes"]["pos_e"]
    assert pos_e["filters"]["Kf"]["paper"] == 3.0 and pos_e["filters"]["Iakf"]["paper"] == 1.0
    assert pos_e["filters"]["SageHusaFading"]["paper"] is None
    assert [(p["a"], p["b"], p["verdict"]) for p in pos_e["orderings"]["pairs"]] == [
        ("Kf", "SageHusaFading", "~"), ("Kf", "Iakf", ">"), ("SageHusaFading", "Iakf", ">")]
    assert pos_e["orderings"]["chain"].startswith("Iakf < ")
    # the paper ranks by its numbers: Iakf (1.0) below Kf (3.0), which the runs support
    assert pos_e["paper_ordering"] == ["Iakf", "Kf"] and pos_e["paper_ordering_supported"]
    # north: the paper has Kf (1.0) below Iakf (2.0), which the runs contradict
    pos_n = summary["axes"]["pos_n"]
    assert pos_n["paper_ordering"] == ["Kf", "Iakf"]
    assert pos_n["paper_ordering_supported"] is False
    # velocity: no paper numbers, no paper ordering
    assert "paper_ordering" not in summary["axes"]["vel_e"]
    assert "orderings" in summary["axes"]["vel_e"]


def test_a_paper_ordering_needs_two_ranked_filters():
    records = _records({"Kf": [1.0, 2.0], "Iakf": [0.5, 1.5]})
    reference = {"table": [{"filter": "Kf", "position_ned_m": [1.0, 3.0, 2.0]}]}
    pos_e = cs.summarize(records, reference)["axes"]["pos_e"]
    assert "orderings" in pos_e and "paper_ordering" not in pos_e
    assert "paper_ordering_supported" not in pos_e


def _interval(mean, low, high, n=3):
    return {"mean": mean, "low": low, "high": high, "half_width": (high - low) / 2.0, "n": n}


def _axis(label, unit, kf, iakf, difference, verdict, chain, **paper):
    pair = {"a": "Kf", "b": "Iakf", "difference": difference, "verdict": verdict}
    return {"label": label, "unit": unit, "filters": {"Kf": kf, "Iakf": iakf},
            "orderings": {"pairs": [pair], "chain": chain}, **paper}


def test_the_text_of_a_two_filter_summary():
    summary = {
        "runs": 3, "filters": ["Kf", "Iakf"], "level": 0.9, "method": "the method",
        "paired_method": "the paired method",
        "provenance": {"scenario": "aircraft_500s", "seeds": "seed 7 + run",
                       "backend": "direct", "commit": "0123456789abcdef0"},
        "axes": {
            "pos_e": _axis("pos E", "m", _interval(2.0, 1.5, 2.5), _interval(1.0, 0.75, 1.25),
                           _interval(1.0, 0.5, 1.5), ">", "Iakf < Kf",
                           paper_ordering=["Iakf", "Kf"], paper_ordering_supported=True),
            "vel_e": _axis("vel E", "m/s", _interval(0.5, 0.25, 0.75),
                           _interval(0.5, 0.125, 0.875), _interval(0.0, -0.5, 0.5), "~",
                           "Kf ~ Iakf", paper_ordering=["Kf", "Iakf"],
                           paper_ordering_supported=False),
            "roll": _axis("roll", "deg", _interval(0.03125, 0.015625, 0.0625),
                          _interval(0.25, 0.125, 0.5), _interval(-0.25, -0.375, -0.125), "<",
                          "Kf < Iakf")}}
    assert cs.format_summary(summary).split("\n") == [
        "aircraft_500s: 3 runs x 2 filters (seed 7 + run; backend direct; commit 0123456789ab)",
        "RMS per run: mean [90 % CI], the method",
        "axis        " + " " * 24 + "Kf" + " " * 22 + "Iakf",
        "pos E [m]   " + " " * 6 + "2.000 [1.500, 2.500]" + " " * 6 + "1.000 [0.750, 1.250]",
        "vel E [m/s] " + " " * 3 + "0.5000 [0.2500, 0.7500]" + " " * 3
        + "0.5000 [0.1250, 0.8750]",
        "roll [deg]  " + " " * 3 + "0.0312 [0.0156, 0.0625]" + " " * 3
        + "0.2500 [0.1250, 0.5000]",
        "",
        "paired difference a - b: mean [90 % CI], the paired method; '<' / '>' when the "
        "interval excludes 0",
        "axis        " + " " * 19 + "Kf - Iakf",
        "pos E       " + " " * 6 + "1.000 [0.500, 1.500] >",
        "vel E       " + " " * 2 + "0.0000 [-0.5000, 0.5000] ~",
        "roll        " + "-0.2500 [-0.3750, -0.1250] <",
        "",
        "orderings the campaign supports ('<': paired interval below 0, '~': not resolved), "
        "and the paper's:",
        "  pos E    Iakf < Kf   paper Iakf < Kf: supported",
        "  vel E    Kf ~ Iakf   paper Kf < Iakf: not supported",
        "  roll     Kf < Iakf"]


def test_the_text_of_one_filter_and_one_run_without_provenance():
    one_run = {"mean": 2.0, "low": math.nan, "high": math.nan, "half_width": math.nan, "n": 1}
    summary = {"runs": 1, "filters": ["Kf"], "level": 0.95, "method": "m",
               "paired_method": "pm",
               "axes": {"pos_e": {"label": "pos E", "unit": "m", "filters": {"Kf": one_run}}}}
    assert cs.format_summary(summary).split("\n") == [
        ": 1 runs x 1 filters (; backend ; commit )",
        "RMS per run: mean [95 % CI], m",
        "axis        " + " " * 24 + "Kf",
        "pos E [m]   " + " " * 13 + "2.000 (n = 1)"]


def test_the_paired_columns_of_three_filters_side_by_side():
    kf, iakf = _interval(2.0, 1.5, 2.5), _interval(1.0, 0.75, 1.25)
    pairs = [{"a": a, "b": b, "difference": _interval(d, d - 0.5, d + 0.5), "verdict": v}
             for a, b, d, v in (("Kf", "Iakf", 1.0, ">"), ("Kf", "Ahrs", 2.0, ">"),
                                ("Iakf", "Ahrs", 0.0, "~"))]
    axis = {"label": "pos E", "unit": "m", "filters": {"Kf": kf, "Iakf": iakf, "Ahrs": iakf},
            "orderings": {"pairs": pairs, "chain": "Iakf ~ Ahrs < Kf"}}
    summary = {"runs": 3, "filters": ["Kf", "Iakf", "Ahrs"], "level": 0.95, "method": "m",
               "paired_method": "pm", "provenance": {}, "axes": {"pos_e": axis}}
    lines = cs.format_summary(summary).split("\n")
    assert lines[6] == ("axis        " + " " * 19 + "Kf - Iakf" + " " * 19 + "Kf - Ahrs"
                        + " " * 17 + "Iakf - Ahrs")
    assert lines[7] == ("pos E       " + " " * 6 + "1.000 [0.500, 1.500] >" + " " * 6
                        + "2.000 [1.500, 2.500] >" + " " * 5 + "0.000 [-0.500, 0.500] ~")
    assert lines[-1] == "  pos E    Iakf ~ Ahrs < Kf"
