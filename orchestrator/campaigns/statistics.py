"""Statistics over Monte Carlo runs: means with confidence intervals, paired differences,
and the orderings of filters a campaign supports.

Definitions (one each; the per-run numbers come from :mod:`orchestrator.results.metrics`):

* :func:`t_interval`: the mean of ``n`` per-run values and its two-sided ``level``
  confidence interval from Student's t with ``n - 1`` degrees of freedom,
  ``mean +- t_{(1+level)/2, n-1} s / sqrt(n)`` (``s``: sample standard deviation).  It treats
  the runs as independent draws (each run has its own seeds), not the samples inside a run.
  A run whose value is not finite (a diverged filter's NaN RMS, a missing number) is left
  out and counted in ``dropped``: ``n`` is the number of runs the interval is over.
* :func:`positive_interval`: the mean of ``n`` per-run values of a positive quantity (an
  RMS, a NEES, a time) with an interval that stays positive: Cox's interval for the mean of
  a log-normal variable (Land 1972; Zhou & Gao 1997, Stat. Med. 16:783, their eq. 3),
  ``exp(m + s^2/2 +- t_{(1+level)/2, n-1} sqrt(s^2/n + s^4/(2(n-1))))`` with ``m`` and ``s``
  the mean and sample standard deviation of the logarithms.  A t interval of such a
  quantity reaches below zero when the runs spread widely (few runs, a diverging filter);
  an RMS is skewed to the right like a log-normal one.  The printed centre stays the mean
  of the values.  Values not above 0 (an error that is exactly zero) fall back to the t
  interval, its lower end clipped at 0.
* :func:`log_interval`: a positive ratio (an RMS of one filter over another's, per run):
  its geometric mean with the t interval of the logarithms taken back,
  ``exp(m +- t_{(1+level)/2, n-1} s / sqrt(n))`` (``m``, ``s``: mean and sample standard
  deviation of ``log r_i``).  Computed on the log scale, the bounds are positive like the
  ratio, and the ratio the other way round (``1 / r_i``) gets exactly the reciprocal
  interval; a t interval of the ratios themselves reaches below zero when they spread.
  A ratio not above 0 (or not finite) is left out and counted in ``dropped``.
* :func:`paired_difference`: the t-interval of the per-run differences ``a_i - b_i`` of two
  filters run on the same seeds (paired: the truth, IMU and GNSS noise of run ``i`` are the
  same for both, so the noise they share cancels in the difference).
* :func:`supported_orderings`: for every pair of filters, ``A < B`` is supported when the
  paired interval of ``A - B`` lies entirely below 0; ``A ~ B`` when it contains 0.
"""
from __future__ import annotations

import math
from itertools import combinations
from typing import Dict, List, Mapping, Sequence

import numpy as np
from scipy import special

from ..errors import NavfmuError

#: confidence level of every interval the campaign prints
LEVEL = 0.95
#: how intervals are made, for reports
METHOD = ("Cox's log-normal interval over the runs (n - 1 dof; positive, "
          "statistics.positive_interval)")
T_METHOD = "two-sided Student t interval over the runs (n - 1 dof)"
LOG_METHOD = ("t interval of the per-run logarithms taken back (geometric mean; positive, "
              "statistics.log_interval)")
PAIRED_METHOD = "paired t interval of the per-run differences (same seeds)"


def t_quantile(p: float, dof: int) -> float:
    """The x with P(X <= x) = p for X ~ Student's t with ``dof`` degrees of freedom."""
    return float(special.stdtrit(dof, p))


def t_interval(values: Sequence[float], level: float = LEVEL) -> Dict[str, float]:
    """Mean of the finite ``values`` with its t confidence interval: dict ``mean``, ``low``,
    ``high``, ``half_width``, ``sd``, ``n`` (finite values used) and ``dropped`` (values left
    out as not finite, None included); the interval is nan for fewer than two values, the
    mean too for none."""
    x = np.array([math.nan if v is None else v for v in values], dtype=float)
    if x.ndim != 1 or x.size == 0:
        raise NavfmuError("t_interval: needs a non-empty list of per-run values")
    finite = x[np.isfinite(x)]
    n, dropped = int(finite.size), int(x.size - finite.size)
    mean = float(finite.mean()) if n else math.nan
    if n < 2:
        return {"mean": mean, "low": math.nan, "high": math.nan, "half_width": math.nan,
                "sd": math.nan, "n": n, "dropped": dropped}
    sd = float(finite.std(ddof=1))
    half = t_quantile(0.5 + level / 2.0, n - 1) * sd / math.sqrt(n)
    return {"mean": mean, "low": mean - half, "high": mean + half, "half_width": half,
            "sd": sd, "n": n, "dropped": dropped}


def positive_interval(values: Sequence[float], level: float = LEVEL) -> Dict[str, float]:
    """:func:`t_interval`'s dict for a positive quantity, the interval Cox's (module
    docstring): ``mean`` the mean of the values, ``low``/``high`` the interval,
    ``half_width`` half its length, ``sd`` the values' standard deviation."""
    t = t_interval(values, level)
    if t["n"] < 2:
        return t
    x = np.array([v for v in values if v is not None], dtype=float)
    x = x[np.isfinite(x)]
    if not np.all(x > 0.0):
        return {**t, "low": max(t["low"], 0.0), "half_width": t["half_width"]}
    logs = np.log(x)
    n, m, var = x.size, float(logs.mean()), float(logs.var(ddof=1))
    half = t_quantile(0.5 + level / 2.0, n - 1) * math.sqrt(
        var / n + var * var / (2.0 * (n - 1)))
    low, high = math.exp(m + var / 2.0 - half), math.exp(m + var / 2.0 + half)
    return {**t, "low": low, "high": high, "half_width": (high - low) / 2.0}


def log_interval(values: Sequence[float], level: float = LEVEL) -> Dict[str, float]:
    """:func:`t_interval`'s dict for a positive ratio, computed on the log scale (module
    docstring): ``mean`` the geometric mean, ``low``/``high`` the interval taken back from
    the logarithms, ``half_width`` half its length, ``sd`` the standard deviation of the
    logarithms; ``dropped`` counts the values not finite or not above 0."""
    x = np.array([math.nan if v is None else v for v in values], dtype=float)
    if x.ndim != 1 or x.size == 0:
        raise NavfmuError("log_interval: needs a non-empty list of per-run values")
    positive = x[np.isfinite(x) & (x > 0.0)]
    logs = t_interval(np.log(positive) if positive.size else [math.nan], level)
    out = {"mean": math.exp(logs["mean"]) if positive.size else math.nan,
           "low": math.exp(logs["low"]), "high": math.exp(logs["high"]),
           "sd": logs["sd"], "n": int(positive.size), "dropped": int(x.size - positive.size)}
    out["half_width"] = (out["high"] - out["low"]) / 2.0
    return out


def paired_difference(a: Sequence[float], b: Sequence[float],
                      level: float = LEVEL) -> Dict[str, float]:
    """:func:`t_interval` of ``a_i - b_i`` (same runs, same order)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        raise NavfmuError(f"paired_difference: {a.size} and {b.size} runs; pairs need the "
                          "same runs for both filters")
    return t_interval(a - b, level)


def verdict(interval: Mapping[str, float]) -> str:
    """``<`` if the interval of a difference lies below 0, ``>`` above, ``~`` otherwise."""
    if interval["high"] < 0.0:
        return "<"
    if interval["low"] > 0.0:
        return ">"
    return "~"


def supported_orderings(per_run: Mapping[str, Sequence[float]],
                        level: float = LEVEL) -> Dict[str, object]:
    """Pairwise verdicts of the filters of ``per_run`` (filter -> per-run values of one
    axis): ``pairs`` (list of dicts a, b, difference interval, verdict) and ``chain``, the
    filters by increasing mean joined by the verdict of each neighbouring pair
    (e.g. ``Iakf < SageHusaFading < Kf``)."""
    names = list(per_run)
    pairs = []
    for a, b in combinations(names, 2):
        d = paired_difference(per_run[a], per_run[b], level)
        pairs.append({"a": a, "b": b, "difference": d, "verdict": verdict(d)})
    order = sorted(names, key=lambda f: float(np.mean(per_run[f])))
    chain = order[:1]
    for lo, hi in zip(order, order[1:]):
        d = paired_difference(per_run[lo], per_run[hi], level)
        chain += ["<" if verdict(d) == "<" else "~", hi]
    return {"pairs": pairs, "chain": " ".join(chain)}


def ordering_holds(per_run: Mapping[str, Sequence[float]], ordering: List[str],
                   level: float = LEVEL) -> bool:
    """True if every ``ordering[i] < ordering[j]`` (i < j) is supported."""
    return all(verdict(paired_difference(per_run[a], per_run[b], level)) == "<"
               for a, b in combinations(ordering, 2))


__all__ = ["t_quantile", "t_interval", "positive_interval", "log_interval",
           "paired_difference", "verdict", "supported_orderings", "ordering_holds", "LEVEL",
           "METHOD", "T_METHOD", "LOG_METHOD", "PAIRED_METHOD"]
