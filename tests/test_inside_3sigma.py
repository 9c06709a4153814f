"""The percentage of samples inside +-3 sigma next to NEES (orchestrator.results.metrics), against
the Gaussian probability P(|e| <= 3 sigma) = erf(3 / sqrt(2)) = 99.73 % and a hand count."""
import math

import numpy as np
import pytest

from navcore.ins.earth import radii
from orchestrator.results.metrics import filter_metrics
from orchestrator.results.run_results import Results

LAT, LON, H = 0.7, 2.0, 100.0
AXES = "ned"


def _results(pos_err_ned, std_p):
    n = len(pos_err_ned)
    t = np.arange(n, dtype=float)
    truth_cols = ["truth_time", "truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve",
                  "truth_vd", "truth_roll", "truth_pitch", "truth_yaw"]
    truth = np.column_stack([t, np.full(n, LAT), np.full(n, LON), np.full(n, H)]
                            + [np.zeros(n)] * 6)
    rn, re = radii(LAT)
    nav = {"nav_time": t, "nav_lat": LAT + pos_err_ned[:, 0] / (rn + H),
           "nav_lon": LON + pos_err_ned[:, 1] / ((re + H) * math.cos(LAT)),
           "nav_h": H - pos_err_ned[:, 2]}
    for name in ("nav_vn", "nav_ve", "nav_vd", "nav_roll", "nav_pitch", "nav_yaw"):
        nav[name] = np.zeros(n)
    for i, a in enumerate(AXES):
        nav[f"std_p{a}"] = std_p[:, i]
        nav[f"std_v{a}"] = np.full(n, 0.1)
        nav[f"std_att_{a}"] = np.full(n, 0.01)
    cols = list(nav)
    data = {"truth": truth, "filter": np.column_stack([nav[c] for c in cols])}
    return Results(time=t, data=data,
                   columns={"truth": truth_cols, "filter": cols},
                   units={"truth": [""] * len(truth_cols), "filter": [""] * len(cols)})


def test_gaussian_errors_are_inside_three_sigma_99_73_percent_of_the_time():
    rng = np.random.default_rng(11)
    n = 200_000
    sigma = np.array([2.0, 3.0, 5.0])
    m = filter_metrics(_results(rng.standard_normal((n, 3)) * sigma, np.tile(sigma, (n, 1))),
                       "filter", truth_name="truth")
    expected = 100.0 * math.erf(3.0 / math.sqrt(2.0))
    se = 100.0 * math.sqrt(0.0027 * 0.9973 / n)
    for a in AXES:
        assert m["inside_3sigma_pct"]["position"][a] == pytest.approx(expected, abs=5 * se)
    assert m["inside_3sigma_pct"]["velocity"] == {a: 100.0 for a in AXES}


def test_inside_three_sigma_counts_by_hand_and_skips_samples_without_a_sigma():
    err = np.array([[1.0, 0.0, 0.0], [3.5, 0.0, 0.0], [2.9, 0.0, 0.0], [9.0, 0.0, 0.0]])
    std = np.array([[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]])
    m = filter_metrics(_results(err, std), "filter", truth_name="truth")
    assert m["inside_3sigma_pct"]["position"]["n"] == pytest.approx(100.0 * 2 / 3)
    assert m["inside_3sigma_pct"]["position"]["e"] == 100.0
