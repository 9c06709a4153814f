"""The IMU's time offset to the GNSS clock as the maximum-likelihood estimate over the whole
run: the offset whose filter run fits its fixes best, for the smoother
(:meth:`navcore.components.smoothing.SmoothingSession.synchronize`) when the course-rate
estimate (:mod:`navcore.filters.imu_time_offset`) is unavailable (no turns) or rejected (a
walker's heading leads its course, so the lag of the course is not the clock's).

The cost of an offset ``tau`` is the mean negative log-likelihood per fix of the filter
run with every fix's time moved to the IMU's clock (``gnss_time + tau``)::

    J(tau) = 1/N sum_j (v_j' S_j^-1 v_j + ln det S_j) / 2      (v_j, S_j of the run at tau)

the prediction-error decomposition of the fixes' likelihood (Schweppe 1965, "Evaluation
of likelihood functions for Gaussian signals", IEEE Trans. Inf. Theory 11(1)); its minimum
is the maximum-likelihood offset, the batch counterpart of the online temporal calibration
that carries the offset as a filter state (Li and Mourikis 2014, "Online temporal
calibration for camera-IMU systems: theory and algorithms", IJRR 33(7)).  Each ``J(tau)``
is one run of the filter, so the search is a bounded scalar one with a fixed budget:

1. a coarse grid of spacing :attr:`OffsetSearch.step` over ``[-bound, bound]`` (the
   offsets already run, such as 0 and the course estimate, reused), which keeps a cost
   with more than one dip from trapping the refinement;
2. bounded Brent (:func:`scipy.optimize.minimize_scalar`, golden section and parabolas)
   within one grid step of the best point so far, to :attr:`OffsetSearch.tolerance`, at
   most :attr:`OffsetSearch.refinements` runs.

The offsets are rounded to the millisecond, and each is run once.  The best offset is
taken only when the likelihood-ratio test rejects "no offset" (:func:`significant`):
``2 N (J(0) - J(tau))`` above the chi-square quantile of one degree of freedom at
:data:`SIGNIFICANCE` (Wilks 1938), so a run whose fixes barely depend on the offset (no
acceleration, no turn) keeps its own clock.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.stats import chi2

from ..errors import NavcoreError

#: the likelihood-ratio test's level: the chance of taking an offset when there is none
SIGNIFICANCE = 0.01


@dataclass(frozen=True)
class OffsetSearch:
    """The search's bounds and budget: offsets within +/-``bound`` [s], a coarse grid of
    spacing ``step`` [s], then at most ``refinements`` runs of bounded Brent to
    ``tolerance`` [s].  The runs: ``2 bound / step + 1`` grid points less those already
    run, plus ``refinements`` (the defaults: at most 4 + 8 = 12)."""

    bound: float = 0.5
    step: float = 0.25
    tolerance: float = 0.01
    refinements: int = 8
    #: [s] with a course estimate kept: refine it within +/- this (0: taken as it is)
    around_start: float = 0.0

    def __post_init__(self):
        if not (self.step > 0 and self.bound >= 0 and self.tolerance > 0
                and self.refinements >= 0 and self.around_start >= 0):
            raise NavcoreError(f"the time offset search: step and tolerance must be positive, "
                               f"bound, refinements and around_start not negative ({self})")

    def grid(self):
        """The coarse grid's offsets [s]."""
        n = int(round(self.bound / self.step))
        return self.step * np.arange(-n, n + 1)


def _key(offset):
    return round(float(offset), 3)


def _cached(cost, known):
    """(cost with each millisecond-rounded offset run once, the costs so far)."""
    costs = {_key(k): float(v) for k, v in known.items()}

    def at(offset):
        key = _key(offset)
        if key not in costs:
            costs[key] = float(cost(key))
        return costs[key]

    return at, costs


def _brent(at, lo, hi, settings):
    if settings.refinements > 0 and hi > lo:
        minimize_scalar(at, bounds=(lo, hi), method="bounded",
                        options={"xatol": settings.tolerance,
                                 "maxiter": settings.refinements})


def search(cost, known, settings: OffsetSearch = OffsetSearch()):
    """(the offset of the smallest cost, {offset: cost} of every offset run) minimizing
    ``cost(offset)`` (one filter run each) over ``settings`` (module docstring); ``known``:
    {offset: cost} already run (reused, never run again)."""
    at, costs = _cached(cost, known)
    for offset in settings.grid():
        at(offset)
    inside = {k: v for k, v in costs.items() if abs(k) <= settings.bound + 1e-9}
    best = min(inside, key=inside.get)
    _brent(at, max(-settings.bound, best - settings.step),
           min(settings.bound, best + settings.step), settings)
    best = min(costs, key=costs.get)
    return best, costs


def refine(cost, start, known, settings: OffsetSearch = OffsetSearch()):
    """(best offset, costs) as :func:`search`, but bounded Brent only, within
    +/-``settings.around_start`` of ``start`` (an estimate from elsewhere, the course's)."""
    at, costs = _cached(cost, known)
    _brent(at, start - settings.around_start, start + settings.around_start, settings)
    best = min(costs, key=costs.get)
    return best, costs


def significant(fit_zero, fit, fixes) -> bool:
    """Whether a run with a mean negative log-likelihood per fix ``fit`` explains the
    ``fixes`` fixes better than the run without an offset (``fit_zero``) beyond chance: the
    likelihood-ratio statistic ``2 fixes (fit_zero - fit)`` above the chi-square quantile
    of one degree of freedom (the offset) at :data:`SIGNIFICANCE`."""
    return 2.0 * fixes * (fit_zero - fit) > chi2.ppf(1.0 - SIGNIFICANCE, 1)


__all__ = ["OffsetSearch", "SIGNIFICANCE", "refine", "search", "significant"]
