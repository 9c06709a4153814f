"""R honest about time-correlated GNSS position errors: the variance inflation of an AR(1)
error sampled at the fix interval.

A Kalman filter takes every fix's error as independent of the last.  A receiver's position
error is not: multipath, residual atmospheric delays and an RTK solution's ambiguity set
move over tens of seconds, so 4 fixes a second at a 1-cm sigma tell the filter it knows its
position to a few millimetres while its true error is several centimetres and wanders
(on a real car drive: the Kf's mean NIS 131 on 3 dof, 13 % of its errors inside +/-3 sigma).

The remedy used here inflates R for the correlation instead of modelling it as a state (the
other standard remedy, a first-order Gauss-Markov error state per axis; Groves 2013,
*Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed.,
ch. 3 on time-correlated measurement noise: either augment the state or inflate R / thin the
measurements).  For a first-order Gauss-Markov error of correlation time ``tau`` sampled every
``T`` seconds, ``rho = exp(-T / tau)`` is the correlation of consecutive errors (AR(1)), and
the variance of a mean over many of them is ``sigma^2 / N * (1 + rho) / (1 - rho)``: the N
fixes carry the information of ``N (1 - rho) / (1 + rho)`` independent ones (the effective
number of independent observations, Bayley & Hammersley 1946, *J. R. Stat. Soc. Suppl.* 8,
184-197).  Scaling each fix's position variance by

    k = (1 + rho) / (1 - rho)   (about 2 tau / T + T / (6 tau) for tau >> T, 1 for tau -> 0)

gives the filter the information the fixes really carry.  ``T`` is the time since the
previous fix the filter applied: right after an outage (``T`` >> ``tau``) the fix is nearly
independent of the last one and keeps nearly its own sigma, so the re-acquisition is as fast
as without the inflation; the first fix of a run has nothing to be correlated with (k = 1).

``gnss_corr_time`` = 0 (the default) leaves R as it is, bit for bit: the papers' scenarios
feed white-noise fixes.  For a real receiver ``docs/guide/your_real_log.md`` gives the
value measured on a drive (the correlation time of the fixes' residuals).
"""
from __future__ import annotations

import math
from typing import Optional

from ..core.component import Limits, real

CORRELATION_PARAMETERS = (
    real("gnss_corr_time", "s", "correlation time of the GNSS position errors: each fix's "
         "position variance is scaled by (1 + rho) / (1 - rho), rho = exp(-T / tau), T the "
         "time since the previous fix applied (0 = white errors, R unchanged)", 0.0,
         Limits(0.0, 1e6)),
)


#: [s] the correlation time measured on a real RTK drive (docs/guide/your_real_log.md: the
#: value its recipe reproduces): a starting value for a receiver of one's own, written by
#: ``navfmu convert kf-gins --config``
MEASURED_CORR_TIME = 4.5

#: [s] the shortest time between two fixes the inflation takes (a fix repeated at one
#: instant, or out of order, would otherwise be infinitely correlated with the last)
MIN_GAP = 1e-3


def inflation(gap: Optional[float], tau: float) -> float:
    """``(1 + rho) / (1 - rho)`` with ``rho = exp(-gap / tau)``; 1 without correlation
    (``tau`` 0) or without an earlier fix (``gap`` None); ``|gap|`` at least :data:`MIN_GAP`."""
    if tau <= 0.0 or gap is None:
        return 1.0
    one_minus_rho = -math.expm1(-max(abs(gap), MIN_GAP) / tau)
    return (2.0 - one_minus_rho) / one_minus_rho


class CorrelatedFixes:
    """The inflation of each fix applied, from the time since the previous one."""

    state_fields = ("last_time",)
    derived_fields = ("tau",)

    def __init__(self, tau: float):
        self.tau = float(tau)
        self.last_time = None          # gnss_time of the last fix applied

    def factor(self, gnss_time: float) -> float:
        """The variance factor of the fix at ``gnss_time`` (which is then the last one)."""
        gap = None if self.last_time is None else float(gnss_time) - self.last_time
        self.last_time = float(gnss_time)
        return inflation(gap, self.tau)


__all__ = ["CORRELATION_PARAMETERS", "MEASURED_CORR_TIME", "CorrelatedFixes", "inflation"]
