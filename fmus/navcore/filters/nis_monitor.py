"""A warning when a filter's NIS stays far above its chi-square band: its covariance, and so
every sigma it reports, understates its real errors.

For a consistent filter the NIS of an m-dimensional innovation is chi2(m), and the mean of n
independent ones is chi2(n m) / n (Bar-Shalom, Li & Kirubarajan 2001, *Estimation with
Applications to Tracking and Navigation*, sec. 5.4.2, the time-average NIS test).
:class:`NisMonitor` keeps the NIS of the updates of the last ``nis_warning_s`` seconds and
warns, once per run, when their mean exceeds :data:`FAR_ABOVE` times the upper edge of that
mean's 99.9 % band, ``chi2_{0.001}(n m) / n``, while the window holds at least
:data:`MIN_UPDATES` updates and the monitor has watched for a whole window (so a short burst
of outliers, or the first seconds of a run, do not warn; an outage leaves the window thin and
suspends the test).  One filter shell (:mod:`navcore.components.filter_component`) runs it for every
filter; the message goes out through :meth:`navcore.core.component.Component.notify` (the FMI
logger as a warning, ``navfmu: warning: ...`` in the CLI).
"""
from __future__ import annotations

from collections import deque

from ..core.component import Limits, real
from .innovation_stats import chi2_gate

#: "far above": this multiple of the upper edge of the 99.9 % band of the window's mean NIS
FAR_ABOVE = 3.0
#: significance of the band's upper edge
BAND_ALPHA = 0.001
#: fewest updates in a window for the test to run
MIN_UPDATES = 5

NIS_WARNING_PARAMETERS = (
    real("nis_warning_s", "s", "warn once when the mean NIS of the updates of this long a window "
         f"stays above {FAR_ABOVE:g} times the upper edge of its 99.9 % chi-square band (0 = "
         "no warning)", 60.0, Limits(0.0, 1e6)),
)


class NisMonitor:
    """The NIS of the updates in a trailing window, and whether the warning was given."""

    state_fields = ("window", "first_time", "warned")
    derived_fields = ("span",)

    def __init__(self, span):
        self.span = float(span)
        self.window = deque()        # (time, nis, dof) of the updates in the window
        self.first_time = None
        self.warned = False

    def observe(self, t, nis_value, dof):
        """Record the update at ``t``; the warning text the first time the test fails, else
        None."""
        if self.span <= 0.0 or self.warned:
            return None
        window = self.window
        window.append((float(t), float(nis_value), int(dof)))
        if self.first_time is None:
            self.first_time = float(t)
        while window and window[0][0] <= t - self.span:
            window.popleft()
        if t - self.first_time < self.span or len(window) < MIN_UPDATES:
            return None
        n = len(window)
        mean = sum(w[1] for w in window) / n
        dof_total = sum(w[2] for w in window)
        if not mean > FAR_ABOVE * dof_total / n:   # below the band's mean: no quantile needed
            return None
        edge = chi2_gate(BAND_ALPHA, dof_total) / n
        if not mean > FAR_ABOVE * edge:
            return None
        self.warned = True
        window.clear()
        return (f"at t = {t:.6g} s the mean NIS of the last {n} updates ({self.span:g} s) is "
                f"{mean:.4g}, above {FAR_ABOVE:g} times the upper edge {edge:.3g} of its 99.9 % "
                f"chi-square band (dof {dof} per update): the filter's covariance and the "
                "sigmas it reports understate its real errors (its Q, R or initial state do "
                "not match the sensors); warned once")


__all__ = ["FAR_ABOVE", "NIS_WARNING_PARAMETERS", "NisMonitor"]
