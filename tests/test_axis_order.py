"""One axis order, north/east/down, in every table, key and figure; a paper.json of the earlier
east/north/up keys is still read, rearranged (the papers' own numbers unchanged)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from orchestrator.errors import NavfmuError
from orchestrator.results import metric_comparisons, metrics
from orchestrator.running.paper_shape import check_reference

ROOT = Path(__file__).resolve().parent.parent

#: paper 001's Table 1 as the paper prints it (east, north, up) and its improvement text
OLD_001 = {"table": [{"label": "KF", "filter": "Kf", "position_enu_m": [8.6003, 9.4141, 3.2837],
                      "velocity_enu_mps": [0.5652, 0.9521, None]}],
           "improvement_percent": {"baseline": "Kf", "filter": "Iakf", "position": 80.0,
                                   "position_enu": [83.5, 82.5, 58.1],
                                   "position_ratio_enu": [6.07, 5.71, 2.39]}}


def test_an_east_north_up_paper_json_is_read_in_north_east_down():
    ref = check_reference(json.loads(json.dumps(OLD_001)), "p.json")
    row = ref["table"][0]
    assert row == {"label": "KF", "filter": "Kf", "position_ned_m": [9.4141, 8.6003, 3.2837],
                   "velocity_ned_mps": [0.9521, 0.5652, None]}
    imp = ref["improvement_percent"]
    assert imp["position_ned"] == [82.5, 83.5, 58.1]
    assert imp["position_ratio_ned"] == [5.71, 6.07, 2.39] and imp["position"] == 80.0
    assert not any("enu" in k for k in imp)


def test_the_repository_paper_json_holds_the_papers_numbers_in_ned():
    """aircraft_500s: the file migrated in the repository equals the paper's printed
    east/north/up table read through the migration."""
    ours = check_reference(json.loads((ROOT / "models" / "aircraft_500s" / "paper.json")
                                      .read_text()), "p")
    assert ours["table"][0]["position_ned_m"] == check_reference(
        OLD_001, "p")["table"][0]["position_ned_m"]
    assert ours["improvement_percent"]["position_ratio_ned"] == [5.71, 6.07, 2.39]
    assert ours["span_s"] == [0, 500]


def test_both_orders_of_one_entry_refused():
    row = {"label": "KF", "position_enu_m": [1, 2, 3], "position_ned_m": [2, 1, 3]}
    with pytest.raises(NavfmuError, match=r"p.json: table\[0\].position_enu_m: expected only "
                                          r"one of 'position_enu_m' \(east, north, up\) and "
                                          r"'position_ned_m'"):
        check_reference({"table": [row]}, "p.json")


@pytest.mark.parametrize("span", [[500, 0], [0], "0-500", [0, float("nan")]])
def test_a_paper_span_not_start_before_stop_refused(span):
    with pytest.raises(NavfmuError, match="span_s: expected"):
        check_reference({"span_s": span}, "p.json")


def test_tables_and_figure_panels_in_north_east_down():
    m = {"position_rms_m": {"n": 1.0, "e": 2.0, "d": 3.0},
         "velocity_rms_mps": {"n": 0.1, "e": 0.2, "d": 0.3}}
    table = metric_comparisons.rms_table([("ours", m)])
    assert table.splitlines()[0].split()[2:8] == ["pos", "N", "pos", "E", "pos", "D"]
    assert table.splitlines()[2].split()[1:7] == ["1.0000", "2.0000", "3.0000", "0.1000",
                                                  "0.2000", "0.3000"]
    assert metric_comparisons.per_axis(m, "velocity") == [0.1, 0.2, 0.3]
    assert metrics.AXES == ("n", "e", "d")
    from orchestrator.results import plots

    panels = {group: [(axis, key) for axis, key, _ in spec] for group, _, _, spec in plots._PANELS}
    assert panels["position"] == [("N", "pos_n"), ("E", "pos_e"), ("D", "pos_d")]
    assert panels["velocity"] == [("N", "vel_n"), ("E", "vel_e"), ("D", "vel_d")]
