"""The Kalman filter components: Kf (baseline) and the adaptive and robust filters of papers
001 and 004 (SageHusaFading, Iakf, NewtonRobustKf, Igg3RobustKf) and InsOnly.

Each is an :class:`~navcore.components.filter_component.InsGnssFilter` over an engine of
:mod:`navcore.filters.ins_gnss_kf` or :mod:`navcore.filters.adaptive_filters`.  The component's
parameter ports declare each option once, with its range and default; :meth:`engine_options` hands
the validated values to the engine, which has no defaults of its own.
"""
from __future__ import annotations

from ..core import signals
from ..filters.adaptive_filters import IakfEngine, InsOnlyEngine, SageHusaFadingEngine
from ..filters.robust_filters import (REPLACEMENT_VARIANCES, Igg3RobustKfEngine,
                                      NewtonRobustKfEngine)
from ..filters.adaptive_laws import DEFAULT_R_FLOOR_FRACTION
from ..core.component import Limits, integer, real, string
from .filter_component import InsGnssFilter
from ..filters.innovation_stats import CHI2_THRESHOLD_PAPER_004
from ..filters.recovery import R_MAX_SCALE, recovery_options

class Kf(InsGnssFilter):
    """Baseline 15-state loosely coupled error-state Kalman filter (closed loop)."""

    description = ("INS/GNSS loosely coupled 15-state error-state Kalman filter with closed-loop "
                   "feedback (baseline, fixed Q and R).")


_R_EST_OUTPUTS = (
    *(real(f"r_est_p{a}", "m", f"Sage-Husa estimate of the GNSS position 1-sigma, {a.upper()} "
           "(sqrt of the R diagonal after the latest update)") for a in signals.AXES_NED),
    *(real(f"r_est_v{a}", "m/s", f"Sage-Husa estimate of the GNSS velocity 1-sigma, {a.upper()} "
           "(0 when velocity is not measured)") for a in signals.AXES_NED),
)
_R_EST_NAMES = tuple(p.name for p in _R_EST_OUTPUTS)


class SageHusaFading(InsGnssFilter):
    """Simplified Sage-Husa R estimation + fading memory (paper 001 eqs. 9-12)."""

    description = ("INS/GNSS 15-state error-state KF with the simplified Sage-Husa measurement-"
                   "noise estimator (paper 001 eq. 9) and the fading-memory filter (paper 001 "
                   "eqs. 10-12).")
    engine_class = SageHusaFadingEngine
    extra_parameters = (
        real("forgetting_factor", "", "Sage-Husa forgetting factor b, 0 < b <= 1 (paper 001: "
             "0.95-0.99; memory about 1/(1-b) updates)", 0.95,
             Limits(0.0, 1.0, low_open=True)),
        real("reserve_gamma", "", "reserve coefficient gamma of the divergence test (paper 001 "
             "eq. 11; 1 = strictest)", 10.0, Limits(0.0, 1e12, low_open=True)),
        real("r_floor_fraction", "", "floor of the estimated R as a fraction of the initial R "
             "diagonal (variances)", DEFAULT_R_FLOOR_FRACTION, Limits(0.0, 1e6, low_open=True)),
        real("max_fading_factor", "", "cap on the fading factor lambda (0 = no cap, as in the "
             "paper; else >= 1)", 0.0, Limits(0.0, 1e6)),
        R_MAX_SCALE,
    )
    extra_outputs = _R_EST_OUTPUTS

    def engine_options(self):
        p = self.params
        cap = p["max_fading_factor"]
        self.require("max_fading_factor", not 0.0 < cap < 1.0, "must be 0 (no cap) or >= 1")
        return dict(forgetting_factor=p["forgetting_factor"], reserve_gamma=p["reserve_gamma"],
                    r_floor_fraction=p["r_floor_fraction"], max_fading_factor=cap or None,
                    r_max_scale=p["r_max_scale"], **recovery_options(p),
                    r_floor_nominal=bool(p["recovery"]) and p["gnss_corr_time"] > 0.0)

    def write_diagnostics(self, result):
        super().write_diagnostics(result)
        sigma = self.engine.r_sigma_estimate()
        for i, value in enumerate(sigma):
            self.out[_R_EST_NAMES[i]] = float(value)


class Iakf(SageHusaFading):
    """Improved adaptive KF: Sage-Husa + fading + outlier compression (paper 001 eqs. 9-14)."""

    description = ("Improved adaptive Kalman filter of paper 001: simplified Sage-Husa R "
                   "estimation, fading memory and chi-square outlier compression of the "
                   "innovation (paper 001 eqs. 9-14), on the 15-state INS/GNSS "
                   "error-state KF.")
    engine_class = IakfEngine
    extra_parameters = SageHusaFading.extra_parameters + (
        real("outlier_alpha", "", "significance alpha of the chi2(m) outlier gate (paper 001 "
             "eq. 14; the paper uses 0.05 or 0.02)", 0.02,
             Limits(0.0, 1.0, low_open=True, high_open=True)),
    )
    extra_outputs = SageHusaFading.extra_outputs + (
        real("compression", "", "outlier compression factor Y of the latest update (paper 001 "
             "eq. 14; 1 = no outlier)", 1.0),
    )
    engine_diagnostics = ("compression",)

    def engine_options(self):
        options = super().engine_options()
        options["outlier_alpha"] = self.params["outlier_alpha"]
        return options


class NewtonRobustKf(InsGnssFilter):
    """Paper 004: per-observation chi-square test + Newton extrapolation of failed ones."""

    description = ("Robust INS/GNSS KF of paper 004: per-observation chi-square test "
                   "(threshold 6.635) and replacement of failed observations by the Newton "
                   "forward extrapolation of the previous observations.")
    engine_class = NewtonRobustKfEngine
    extra_parameters = (
        real("chi2_threshold", "", "gate of the per-observation chi-square statistic "
             "v_i^2/S_ii (paper 004: 6.635 = chi2(1) at alpha 0.01)", CHI2_THRESHOLD_PAPER_004,
             Limits(0.0, 1e6, low_open=True)),
        integer("newton_order", "order of the Newton extrapolation polynomial (paper 004: 4)", 4,
                Limits(0, 10)),
        string("replacement_variance", "R of a replaced observation: 'propagated' (R times the "
               "noise gain of the extrapolation) or 'nominal' (R unchanged)", "propagated"),
    )
    extra_outputs = (
        real("chi2_max", "", "largest per-observation chi-square statistic of the latest "
             "update"),
        integer("n_rejected", "observation components replaced at the latest update"),
    )
    engine_diagnostics = ("chi2_max", "n_rejected")

    def engine_options(self):
        p = self.params
        self.require("replacement_variance", p["replacement_variance"] in REPLACEMENT_VARIANCES,
                     f"is not one of {list(REPLACEMENT_VARIANCES)}")
        return dict(chi2_threshold=p["chi2_threshold"], newton_order=p["newton_order"],
                    replacement_variance=p["replacement_variance"], **recovery_options(p))


class Igg3RobustKf(InsGnssFilter):
    """IGG-III equivalent-weight robust KF (the equivalent-weight method of paper 004 1.2)."""

    description = ("Robust INS/GNSS KF with IGG-III equivalent weights on the standardized "
                   "innovations (R_ii / w_i; w = 1 below k0, 0 above k1).")
    engine_class = Igg3RobustKfEngine
    extra_parameters = (
        real("igg_k0", "", "IGG-III constant k0: standardized innovations up to k0 keep full "
             "weight", 1.5, Limits(0.0, 100.0, low_open=True)),
        real("igg_k1", "", "IGG-III constant k1: standardized innovations above k1 are "
             "rejected", 3.0, Limits(0.0, 100.0, low_open=True)),
    )
    extra_outputs = (
        real("min_weight", "", "smallest IGG-III weight of the latest update (1 = none "
             "down-weighted)", 1.0),
        integer("n_rejected", "observation components rejected (weight 0) at the latest update"),
    )
    engine_diagnostics = ("n_rejected",)

    def engine_options(self):
        p = self.params
        self.require("igg_k1", p["igg_k1"] > p["igg_k0"], f"must be > igg_k0 = {p['igg_k0']}")
        return dict(igg_k0=p["igg_k0"], igg_k1=p["igg_k1"], **recovery_options(p))

    def write_diagnostics(self, result):
        super().write_diagnostics(result)
        self.out["min_weight"] = float(self.engine.weights.min())


class InsOnly(InsGnssFilter):
    """Free inertial navigation: the Kf's mechanization with no measurement update.

    GNSS inputs are accepted (same contract as every filter, so it swaps in) and ignored:
    ``updated`` stays False, the diagnostics keep their start values, and the std_* outputs
    show the covariance propagated from P0 with the process noise alone.
    """

    description = ("Free strapdown inertial navigation (no GNSS update), same inputs and "
                   "outputs as the INS/GNSS filters; the covariance only propagates.")
    engine_class = InsOnlyEngine
    applies_fixes = False

    def _fix_to_apply(self, inputs):
        """No measurement update: the GNSS fix is ignored."""
        return None

