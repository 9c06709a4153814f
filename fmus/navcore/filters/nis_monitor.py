"""A warning when a filter's NIS stays far above its chi-square band: its covariance, and so
every sigma it reports, understates its real errors.

For a consistent filter the NIS of an m-dimensional innovation is chi2(m) (Bar-Shalom, Li &
Kirubarajan 2001, *Estimation with Applications to Tracking and Navigation*, sec. 5.4.2), so
an update's NIS exceeds the upper edge of its 99 % band, ``chi2_{0.01}(m)``, with probability
1 %.  :class:`NisMonitor` keeps the updates of the last ``nis_warning_s`` seconds and warns,
once per run, when more than half of them are above that edge -- the median of
``NIS / chi2_{0.01}(m)`` over the window is above 1 -- while the window holds at least
:data:`MIN_UPDATES` updates and the monitor has watched for a whole window.  For a consistent
filter that takes half of ten or more independent 1 % events (below 1e-10 per window); a
single large NIS (an outlier, the first fix after an outage) never warns, a filter whose NIS
stays four times its dof or more (3 dof or more) does within one window.  The shell every
filter shares (:mod:`navcore.components.filter_component`) runs it; the message goes out through
:meth:`navcore.core.component.Component.notify` (the FMI logger as a warning,
``navfmu: warning: ...`` in the CLI).

The message also names the two remedies of a filter fed real sensors: the factor on the IMU
noise figures to try, ``imu_noise_factor`` (:func:`navcore.filters.process_noise_factor.
suggested_factor` of the factor in use and the window's median NIS over its dof), for a Q
too small for the IMU, and ``gnss_corr_time`` for a receiver whose errors are correlated
from fix to fix (:mod:`navcore.filters.correlated_gnss`).
"""
from __future__ import annotations

from collections import deque

from ..core.component import Limits, real
from .innovation_stats import chi2_gate
from .process_noise_factor import suggested_factor

#: the upper edge of an update's band: its chi2(m) quantile at this significance
BAND_ALPHA = 0.01
#: fewest updates in a window for the test to run
MIN_UPDATES = 10

NIS_WARNING_PARAMETERS = (
    real("nis_warning_s", "s", "warn once when more than half of the updates of a window this "
         "long have an NIS above their 99 % chi-square band (0 = no warning)", 60.0,
         Limits(0.0, 1e6)),
)


class NisMonitor:
    """The NIS of the updates in a trailing window (as ratios to their band edge), and whether
    the warning was given."""

    state_fields = ("window", "first_time", "warned")
    derived_fields = ("span", "noise_factor")

    def __init__(self, span, noise_factor=1.0):
        self.span = float(span)
        self.noise_factor = float(noise_factor)   # the filter's imu_noise_factor
        #: (time, NIS / its band edge, NIS / its dof) of the updates in the window
        self.window = deque()
        self.first_time = None
        self.warned = False

    def observe(self, t, nis_value, dof):
        """Record the update at ``t``; the warning text the first time the test fails, else
        None."""
        if self.span <= 0.0 or self.warned:
            return None
        window = self.window
        window.append((float(t), float(nis_value) / chi2_gate(BAND_ALPHA, int(dof)),
                       float(nis_value) / int(dof)))
        if self.first_time is None:
            self.first_time = float(t)
        while window and window[0][0] <= t - self.span:
            window.popleft()
        if t - self.first_time < self.span or len(window) < MIN_UPDATES:
            return None
        above = sum(1 for _, r, _ in window if r > 1.0)
        if not 2 * above > len(window):
            return None
        ratios = sorted(r for _, r, _ in window)
        per_dof = sorted(x for _, _, x in window)
        self.warned = True
        median = ratios[len(ratios) // 2]
        factor = suggested_factor(self.noise_factor, per_dof[len(per_dof) // 2])
        window.clear()
        return (f"at t = {t:.6g} s {above} of the last {len(ratios)} updates ({self.span:g} s) "
                f"have an NIS above their 99 % chi-square band (median {median:.3g} times its "
                "edge): the filter's covariance and the sigmas it reports understate its real "
                "errors (its Q, R or initial state do not match the sensors); warned once.  "
                f"Q too small for a real IMU: try imu_noise_factor = {factor:g} (now "
                f"{self.noise_factor:g}); GNSS errors correlated from fix to fix: set "
                "gnss_corr_time (docs/guide/your_real_log.md)")


__all__ = ["NIS_WARNING_PARAMETERS", "NisMonitor"]
