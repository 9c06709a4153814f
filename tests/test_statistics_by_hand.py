"""Campaign statistics (orchestrator.campaigns.statistics) at few runs, at levels other than
95 % and the pairwise orderings of filters, against intervals worked out by hand with Student t
quantiles from printed tables: t_{0.95,1} = 6.314, t_{0.975,1} = 12.706, t_{0.95,4} = 2.132,
t_{0.975,2} = 4.303, t_{0.75,2} = 0.8165.
"""
from __future__ import annotations

import math
import warnings

import pytest

from orchestrator.campaigns import statistics as st

TABLE = 1e-3   # relative tolerance of a 4-digit table quantile
#: the keys of every interval (the docstring of t_interval)
KEYS = {"mean", "low", "high", "half_width", "sd", "n", "dropped"}


def test_interval_of_one_value_and_of_none():
    with warnings.catch_warnings():
        warnings.simplefilter("error")      # no numpy warning for an empty mean
        none = st.t_interval([None, math.nan])
    assert set(none) == KEYS and (none["n"], none["dropped"]) == (0, 2)
    assert all(math.isnan(none[k]) for k in ("mean", "low", "high", "half_width", "sd"))
    one = st.t_interval([5.0, None])
    assert set(one) == KEYS and (one["mean"], one["n"], one["dropped"]) == (5.0, 1, 1)
    assert all(math.isnan(one[k]) for k in ("low", "high", "half_width", "sd"))
    assert set(st.positive_interval([5.0])) == KEYS


def test_t_interval_of_two_values():
    # 1, 2: mean 1.5, s = sqrt(0.5); half width t_{0.975,1} s / sqrt(2) = 6.353
    ci = st.t_interval([1.0, 2.0])
    assert set(ci) == KEYS and ci["n"] == 2
    assert ci["sd"] == pytest.approx(math.sqrt(0.5))
    assert ci["half_width"] == pytest.approx(12.706 * 0.5, rel=TABLE)
    assert ci["low"] == pytest.approx(1.5 - 12.706 * 0.5, rel=TABLE)


def test_t_and_paired_intervals_at_90_percent():
    # values 1..5: mean 3, s = sqrt(2.5); half width t_{0.95,4} s / sqrt(5)
    half = 2.132 * math.sqrt(2.5) / math.sqrt(5)
    ci = st.t_interval([1, 2, 3, 4, 5], level=0.90)
    assert ci["half_width"] == pytest.approx(half, rel=TABLE)
    d = st.paired_difference([11, 12, 13, 14, 15], [10, 10, 10, 10, 10], level=0.90)
    assert (d["mean"], d["n"]) == (3.0, 5)
    assert (d["low"], d["high"]) == pytest.approx((3 - half, 3 + half), rel=TABLE)


def test_cox_interval_of_two_runs():
    # logs 0 and 1: m = 0.5, s^2 = 0.5; exp(m + s^2/2 -+ t_{0.95,1} sqrt(s^2/2 + s^4/2))
    half = 6.314 * math.sqrt(0.5 / 2 + 0.25 / 2)
    ci = st.positive_interval([1.0, math.e], level=0.90)
    assert set(ci) == KEYS
    assert ci["mean"] == pytest.approx((1 + math.e) / 2)
    assert math.log(ci["low"]) == pytest.approx(0.75 - half, rel=TABLE)
    assert math.log(ci["high"]) == pytest.approx(0.75 + half, rel=TABLE)
    assert ci["half_width"] == pytest.approx((ci["high"] - ci["low"]) / 2)


def test_positive_interval_with_a_zero_is_the_clipped_t_interval():
    # 0, 1, 2: mean 1, s = 1, half width t_{0.975,2} / sqrt(3) = 2.484: low clipped to 0
    ci = st.positive_interval([0.0, 1.0, 2.0])
    assert set(ci) == KEYS
    assert ci["low"] == 0.0
    assert ci["high"] == pytest.approx(1 + 4.303 / math.sqrt(3), rel=TABLE)
    assert ci["half_width"] == pytest.approx(4.303 / math.sqrt(3), rel=TABLE)
    # at 90 %: t_{0.95,2} = 2.920
    assert st.positive_interval([0.0, 1.0, 2.0], level=0.9)["high"] == pytest.approx(
        1 + 2.920 / math.sqrt(3), rel=TABLE)


@pytest.mark.parametrize("low, high, expected", [(-2.0, -1e-12, "<"), (-2.0, 0.0, "~"),
                                                 (0.0, 2.0, "~"), (1e-12, 2.0, ">"),
                                                 (-1.0, 1.0, "~")])
def test_verdict_needs_the_interval_strictly_off_zero(low, high, expected):
    assert st.verdict({"low": low, "high": high}) == expected


# three filters on three seeds.  A - B = (-1, -1.1, -0.9): mean -1, s = 0.1, 95 % half width
# 4.303 * 0.1 / sqrt(3) = 0.248: below 0.  B - C = (-1, 1, -0.5): s = 1.041, contains 0 at 95 %
# (half 2.59) and at 50 % (half 0.8165 * 1.041 / sqrt(3) = 0.491, [-0.66, 0.32]).
# A - C = (-2, -0.1, -1.4): mean -1.167, s = 0.971: [-3.58, 1.25] at 95 %, below 0 at 50 %
# ([-1.62, -0.71]).  Means: A 2, B 3, C 3.167.
PER_RUN = {"A": [1.0, 2.0, 3.0], "B": [2.0, 3.1, 3.9], "C": [3.0, 2.1, 4.4]}


def _verdicts(result):
    return {(p["a"], p["b"]): p["verdict"] for p in result["pairs"]}


def test_supported_orderings_pairs_and_chain_at_95_percent():
    result = st.supported_orderings(PER_RUN)
    assert _verdicts(result) == {("A", "B"): "<", ("A", "C"): "~", ("B", "C"): "~"}
    ab = result["pairs"][0]["difference"]
    assert (ab["low"], ab["high"]) == pytest.approx((-1 - 0.2484, -1 + 0.2484), rel=TABLE)
    assert result["chain"] == "A < B ~ C"


def test_supported_orderings_at_50_percent():
    result = st.supported_orderings(PER_RUN, level=0.5)
    assert _verdicts(result) == {("A", "B"): "<", ("A", "C"): "<", ("B", "C"): "~"}
    two = {"C": PER_RUN["C"], "A": PER_RUN["A"]}
    # the chain runs by increasing mean whatever the order given
    assert st.supported_orderings(two, level=0.5)["chain"] == "A < C"
    assert st.supported_orderings(two)["chain"] == "A ~ C"


def test_ordering_holds_only_when_every_pair_is_supported():
    assert st.ordering_holds(PER_RUN, ["A", "B"])
    assert not st.ordering_holds(PER_RUN, ["A", "C"])
    assert st.ordering_holds(PER_RUN, ["A", "C"], level=0.5)
    assert not st.ordering_holds(PER_RUN, ["A", "B", "C"], level=0.5)
    assert not st.ordering_holds(PER_RUN, ["B", "A"])


def test_paired_difference_drops_a_run_missing_in_either_filter():
    # the pairs (11, 10), (12, 10), (13, 10) remain: differences 1, 2, 3
    for a, b in (([11, 12, 13, None], [10, 10, 10, 10]), ([11, 12, 13, 14], [10, 10, 10, None])):
        d = st.paired_difference(a, b)
        assert (d["mean"], d["n"], d["dropped"]) == (2.0, 3, 1)
        assert d["half_width"] == pytest.approx(4.303 / math.sqrt(3), rel=TABLE)
