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


@pytest.mark.parametrize("level", [0.5, 0.9, 0.95, 0.99])
def test_t_quantile_is_scipy_stats_t_ppf_and_printed_tables(level):
    """The quantile without scipy.stats gives scipy.stats.t.ppf's floats; t_{0.975, 4} = 2.776
    and t_{0.975, 19} = 2.093 from printed tables."""
    from scipy import stats
    for dof in (1, 2, 4, 19, 63, 1000):
        p = 0.5 + level / 2.0
        assert st.t_quantile(p, dof) == float(stats.t.ppf(p, dof))
    assert st.t_quantile(0.975, 4) == pytest.approx(2.776, abs=5e-4)
    assert st.t_quantile(0.975, 19) == pytest.approx(2.093, abs=5e-4)


def test_a_campaign_summary_does_not_import_scipy_stats():
    """scipy.stats costs most of a short command's import time (docs/speed.md)."""
    import subprocess
    import sys
    code = ("import sys; import orchestrator.cli.commands, orchestrator.campaigns.campaign; "
            "import orchestrator.campaigns.campaign_summary; "
            "print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False"


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
    from orchestrator.reporting import report_sections

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
    from_report = report_sections.per_run_interval(plan, "Kf",
                                                   lambda m: m["position_rms_m"]["e"])
    positive = st.positive_interval(values)
    assert from_report == {k: east[k] for k in from_report} == {**positive, "dropped": 2}
    assert positive["mean"] == s["mean"] and positive["n"] == s["n"]


@pytest.mark.parametrize("sigma, n", [(0.3, 3), (0.8, 5), (0.5, 10)])
def test_positive_interval_covers_a_log_normal_mean_and_stays_positive(sigma, n):
    """Over 4000 samples of n log-normal values (true mean exp(sigma^2 / 2)) Cox's 95 %
    interval covers the true mean in 95 +- 1.5 % of the cases (measured 95.3, 94.4,
    95.7 %) and never reaches 0, where the t interval of the same samples goes below 0 in
    15 % (sigma 0.3, n 3) and 31 % (sigma 0.8, n 5) of them."""
    import numpy as np

    rng = np.random.default_rng(5)
    true = math.exp(sigma ** 2 / 2)
    samples = [rng.lognormal(0.0, sigma, n) for _ in range(4000)]
    intervals = [st.positive_interval(x) for x in samples]
    hits = sum(s["low"] <= true <= s["high"] for s in intervals)
    assert 0.935 <= hits / 4000 <= 0.965
    assert all(s["low"] > 0 for s in intervals)


def test_positive_interval_of_rms_values_against_simulated_truth():
    """Per-run RMS of 5 samples of unit white noise, 3 runs: the interval covers the mean RMS
    (estimated from 200000 runs) in 95 +- 1.5 % of 4000 campaigns (measured 95.2 %)."""
    import numpy as np

    rng = np.random.default_rng(5)
    true = float(np.mean(np.sqrt((rng.normal(0, 1, (200000, 5)) ** 2).mean(1))))
    hits = 0
    for _ in range(4000):
        rms = np.sqrt((rng.normal(0, 1, (3, 5)) ** 2).mean(1))
        s = st.positive_interval(rms)
        hits += s["low"] <= true <= s["high"]
    assert 0.935 <= hits / 4000 <= 0.965


def test_positive_interval_of_one_run_and_of_zeros():
    one = st.positive_interval([2.0])
    assert one["mean"] == 2.0 and math.isnan(one["half_width"])
    zeros = st.positive_interval([0.0, 0.0, 3.0])          # t interval, clipped at 0
    assert zeros["low"] == 0.0 and zeros["high"] == st.t_interval([0.0, 0.0, 3.0])["high"]


def test_log_interval_of_ratios_is_positive_and_reciprocal():
    """Ratios spread so widely that their t interval reaches below zero: the log-scale
    interval stays positive, equals exp of the t interval of the logs (computed here with
    scipy.stats), and the inverse ratios get exactly the reciprocal interval."""
    from scipy import stats

    ratios = [0.3, 4.0, 0.5, 6.0, 0.8]
    assert st.t_interval(ratios)["low"] < 0.0
    got = st.log_interval(ratios)
    logs = [math.log(r) for r in ratios]
    m, s = sum(logs) / 5, stats.tstd(logs)
    half = stats.t.ppf(0.975, 4) * s / math.sqrt(5)
    assert got["low"] > 0.0
    assert (got["mean"], got["low"], got["high"]) == pytest.approx(
        (math.exp(m), math.exp(m - half), math.exp(m + half)), rel=1e-12)
    inverse = st.log_interval([1.0 / r for r in ratios])
    assert (inverse["low"], inverse["high"]) == pytest.approx(
        (1.0 / got["high"], 1.0 / got["low"]), rel=1e-12)
    left_out = st.log_interval(ratios + [0.0, float("nan"), None])
    assert left_out["dropped"] == 3 and left_out["low"] == pytest.approx(got["low"])
    with pytest.raises(NavfmuError):
        st.log_interval([])
