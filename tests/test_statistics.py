"""Confidence intervals against textbook numbers; paired differences; orderings."""
from __future__ import annotations

import math

import pytest

from orchestrator.campaigns import statistics as st
from orchestrator.errors import NavfmuError


def test_t_interval_textbook_example():
    """Values 1..5: mean 3, s = sqrt(2.5); t_{0.975, 4} = 2.776 (printed t tables)."""
    s = st.t_interval([1.0, 2.0, 3.0, 4.0, 5.0])
    assert s["mean"] == 3.0 and s["n"] == 5
    assert s["sd"] == pytest.approx(math.sqrt(2.5))
    assert s["half_width"] == pytest.approx(2.776 * math.sqrt(2.5) / math.sqrt(5), rel=2e-4)
    assert s["low"] == pytest.approx(3.0 - s["half_width"])


def test_t_interval_covers_the_mean_at_the_stated_rate():
    """Over 4000 samples of 5 normal values the 95 % interval covers the true mean in
    95 +- 1 % of the cases (binomial sd 0.34 %)."""
    import numpy as np

    rng = np.random.default_rng(11)
    hits = sum(s["low"] <= 2.0 <= s["high"] for s in
               (st.t_interval(rng.normal(2.0, 0.7, 5)) for _ in range(4000)))
    assert 0.94 <= hits / 4000 <= 0.96


def test_paired_difference_removes_the_shared_noise():
    """Two filters whose per-run RMS share a large run-to-run spread but differ by a
    constant 0.1: unpaired intervals overlap, the paired interval excludes 0."""
    shared = [3.0, 5.0, 2.0, 6.0, 4.0]
    a = [x + 0.1 + e for x, e in zip(shared, [0.01, -0.02, 0.0, 0.02, -0.01])]
    ia, ib = st.t_interval(a), st.t_interval(shared)
    assert ia["low"] < ib["high"]
    d = st.paired_difference(a, shared)
    assert d["mean"] == pytest.approx(0.1)
    assert st.verdict(d) == ">"
    order = st.supported_orderings({"A": a, "B": shared})
    assert order["chain"] == "B < A"
    assert st.ordering_holds({"A": a, "B": shared}, ["B", "A"])
    assert not st.ordering_holds({"A": a, "B": shared}, ["A", "B"])


def test_bad_inputs():
    with pytest.raises(NavfmuError, match="same runs"):
        st.paired_difference([1.0, 2.0], [1.0])
    with pytest.raises(NavfmuError, match="non-empty"):
        st.t_interval([])
    single = st.t_interval([2.0])
    assert single["mean"] == 2.0 and math.isnan(single["half_width"])


def test_non_finite_runs_left_out_and_counted_the_same_by_report_and_summary():
    """A diverged run (NaN RMS) or a missing number is left out of the interval by
    t_interval itself, so the campaign summary and the report give the same interval."""
    from orchestrator.campaigns import campaign_summary
    from orchestrator.reporting import report

    values = [1.0, float("nan"), 2.0, 3.0, None, 4.0, float("inf"), 5.0]
    s = st.t_interval(values)
    assert s == {**st.t_interval([1.0, 2.0, 3.0, 4.0, 5.0]), "dropped": 3}
    assert s["n"] == 5 and s["mean"] == 3.0
    none = st.t_interval([float("nan")])
    assert none["n"] == 0 and none["dropped"] == 1 and math.isnan(none["mean"])
    rows = [v for v in values if v is not None]
    records = {"Kf": [{"metrics": {"position_rms_m": {"e": v, "n": v, "d": v}}} for v in rows]}
    east = campaign_summary.summarize(records)["axes"]["pos_e"]["filters"]["Kf"]
    plan = {"records": records}
    from_report = report._per_run(plan, "Kf", lambda m: m["position_rms_m"]["e"])
    assert from_report == {k: east[k] for k in from_report} == {**s, "dropped": 2}
