"""The percentage of samples inside +-3 sigma next to NEES (orchestrator.results.metrics), against
the Gaussian probability P(|e| <= 3 sigma) = erf(3 / sqrt(2)) = 99.73 % and a hand count."""
import math

import numpy as np
import pytest

from navcore.ins.earth import radii
from orchestrator.results.metrics import (INCONSISTENT_OUTSIDE_PCT, filter_metrics,
                                          inconsistency_warning)
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


def test_the_share_outside_is_pooled_over_the_axes_and_warns_above_half():
    """Errors of 4, 2 and 0.5 sigma on N, E, D (sigmas 1, 2, 3 m), 10 samples: N is outside
    every time, E and D never: 1/3 outside, no warning.  Biased errors of 4 sigma on N and
    E: 2/3 outside, the warning names the filter and the share."""
    n = 10
    std = np.tile([1.0, 2.0, 3.0], (n, 1))
    m = filter_metrics(_results(np.tile([4.0, 4.0, 1.5], (n, 1)), std), "filter",
                       truth_name="truth")
    assert m["position_outside_3sigma_pct"] == pytest.approx(100.0 / 3.0)
    assert inconsistency_warning("Iakf", m) is None
    m = filter_metrics(_results(np.tile([-4.0, 8.5, 1.5], (n, 1)), std), "filter",
                       truth_name="truth")
    assert m["position_outside_3sigma_pct"] == pytest.approx(200.0 / 3.0)
    assert inconsistency_warning("Iakf", m) == (
        "filter 'Iakf' is inconsistent: 67 % of its position errors are outside +/-3 sigma "
        "(its reported sigmas understate its error; real GNSS errors are biased and "
        "time-correlated: gnss_corr_time; a real IMU does worse than its datasheet: "
        "imu_noise_factor)")


def test_the_warning_starts_above_half_and_needs_sigmas():
    assert INCONSISTENT_OUTSIDE_PCT == 50.0
    assert inconsistency_warning("Kf", {"position_outside_3sigma_pct": 50.0}) is None
    assert "50 %" in inconsistency_warning("Kf", {"position_outside_3sigma_pct": 50.4})
    assert inconsistency_warning("Kf", {"position_rms_m": {}}) is None


def test_the_report_names_the_inconsistent_filter_and_its_runs():
    from types import SimpleNamespace
    from orchestrator.reporting.report_markdown import inconsistent_lines
    rows = [{"metrics": {"position_outside_3sigma_pct": pct}} for pct in (91.2, 12.0, 60.0)]
    plan = {"model": SimpleNamespace(name="drive"),
            "records": {"Iakf": rows, "Kf": [{"metrics": {"position_outside_3sigma_pct": 1.0}}]}}
    assert inconsistent_lines([plan]) == [
        "- drive: warning: filter 'Iakf' is inconsistent: 91 % of its position errors are "
        "outside +/-3 sigma (its reported sigmas understate its error; real GNSS errors are "
        "biased and time-correlated: gnss_corr_time; a real IMU does worse than its datasheet: "
        "imu_noise_factor) (in 2 of 3 runs)", ""]
