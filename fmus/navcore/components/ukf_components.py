"""The unscented filter components of paper 000: Ukf, CtfaUkf and ImmUkf.

Each is an :class:`~navcore.components.filter_component.InsGnssFilter` over an engine of
:mod:`navcore.filters.ukf_filters`.  The component's parameter ports declare each option once, with
its range and default; :meth:`engine_options` hands the validated values to the engine, which has no
defaults of its own.
"""
from __future__ import annotations

from ..core.component import Limits, ParameterError, integer, real
from .filter_component import InsGnssFilter
from .ukf_batch import UkfFilterBatch
from ..filters.recovery import recovery_options
from ..filters.ukf_filters import CtfaUkfEngine, ImmUkfEngine, UkfEngine

#: accepted Q scales of the IMM models (relative to the configured Q)
_Q_SCALE = Limits(0.0, 1e12, low_open=True)
#: most IMM models a component offers (outputs model_prob_1..3)
_IMM_MAX_MODELS = 3


class Ukf(InsGnssFilter):
    """Paper 000's UKF: 15-state error-state UKF, nonlinear large-misalignment error model."""

    description = ("INS/GNSS 15-state error-state unscented Kalman filter (paper 000 eqs. 11-23) "
                   "with a nonlinear rotation-vector large-misalignment error model, fixed Q and "
                   "R, closed-loop feedback.")
    engine_class = UkfEngine
    #: many runs in one call (navcore.core.batch): the UKF family's time update
    batch_class = UkfFilterBatch
    #: paper 000's UAV flight (uav_maneuver: 60 min, IMU at 50 Hz)
    default_experiment = (0.0, 3600.0, 0.02)
    extra_parameters = (
        real("ukf_predict_interval", "s", "interval of the UKF time update (interval means of "
             "the nominal navigation; 0 = every IMU step); always also before an update",
             0.1, Limits(0.0, 3600.0)),
        real("ukf_alpha", "", "scaled unscented transform alpha (paper 000 eq. 11, 0 < alpha "
             "<= 1)", 1.0,
             Limits(0.0, 1.0, low_open=True)),
        real("ukf_beta", "", "scaled unscented transform beta (paper 000 eq. 13; 2 = "
             "Gaussian)", 2.0,
             Limits(-1e3, 1e3)),
        real("ukf_kappa", "", "scaled unscented transform kappa (paper 000 eq. 11; n + kappa > "
             "0 for the 15-state filter)", 0.0, Limits(-15.0, 1e3, low_open=True)),
    )

    def engine_options(self):
        p = self.params
        return dict(predict_interval=p["ukf_predict_interval"], alpha=p["ukf_alpha"],
                    beta=p["ukf_beta"], kappa=p["ukf_kappa"])


class CtfaUkf(Ukf):
    """CTFA-UKF: the UKF + chi-square fuzzy adaptive process noise (paper 000 eqs. 24-25)."""

    description = ("Fuzzy adaptive UKF with chi-square test (CTFA-UKF, paper 000): the UKF whose "
                   "process noise Q moves between Qmin and Qmax as a piecewise-linear function "
                   "of the innovation chi-square statistic (paper 000 eqs. 24-25).")
    engine_class = CtfaUkfEngine
    extra_parameters = Ukf.extra_parameters + (
        real("q_max_scale", "", "Qmax = q_max_scale * Qmin, Qmin = the configured Q (paper 000: "
             "an integer multiple; 100 = the noise variance of a 10 deg/s manoeuvre in "
             "models/uav_maneuver)", 100.0, Limits(1.0, 1e12)),
        real("ctfa_t1", "", "lower chi-square threshold of paper 000 eq. 25 (0 = 6.25 for a "
             "3-dimensional measurement, else the 90 % chi-square quantile)", 0.0,
             Limits(0.0, 1e4)),
        real("ctfa_t2", "", "upper chi-square threshold of paper 000 eq. 25 (0 = 11.35 for a "
             "3-dimensional measurement, else the 99 % chi-square quantile)", 0.0,
             Limits(0.0, 1e4)),
        real("ctfa_pass_decay", "", "ours, not the paper's: factor on Q - Qmin at every update "
             "whose chi-square passes (below ctfa_t1); 1 = paper 000 eq. 25 as printed (Q_k-1 "
             "kept), 0 = back to Qmin at once, in between an exponential return to Qmin", 1.0,
             Limits(0.0, 1.0)),
    )
    extra_outputs = (
        real("chi2", "", "chi-square statistic of the latest update (paper 000 eq. 24)"),
    )
    engine_diagnostics = ("chi2",)

    def engine_options(self):
        p = self.params
        return dict(super().engine_options(), q_max_scale=p["q_max_scale"], t1=p["ctfa_t1"],
                    t2=p["ctfa_t2"], pass_decay=p["ctfa_pass_decay"], **recovery_options(p))

    def make_engine(self, config, nav):
        engine = super().make_engine(config, nav)
        if not engine.schedule.T2 > engine.schedule.T1:
            raise ParameterError(f"{self.model_name}: parameters 'ctfa_t1' = "
                                 f"{engine.schedule.T1} and 'ctfa_t2' = {engine.schedule.T2} "
                                 "must satisfy t1 < t2")
        return engine


class ImmUkf(Ukf):
    """IMM-UKF (paper 000's comparison): 2 or 3 UKFs with different Q scales."""

    description = ("Interacting multiple model UKF (paper 000's IMM-UKF, its ref. [14]): 2 or 3 "
                   "UKFs with different process-noise scales, Markov model switching, mixing "
                   "once per GNSS interval, closed-loop feedback of the combined estimate.")
    engine_class = ImmUkfEngine
    extra_parameters = Ukf.extra_parameters + (
        integer("imm_models", "number of models (2 or 3)", 2, Limits(2, 3)),
        real("imm_q_scale_1", "", "Q scale of model 1 relative to the configured Q", 1.0,
             _Q_SCALE),
        real("imm_q_scale_2", "", "Q scale of model 2 (default: CtfaUkf's Qmax)", 100.0,
             _Q_SCALE),
        real("imm_q_scale_3", "", "Q scale of model 3 (used when imm_models = 3; default "
             "between models 1 and 2)", 10.0, _Q_SCALE),
        real("imm_p_stay", "", "Markov probability of staying in a model per GNSS interval "
             "(diagonal of the transition matrix; the rest spread evenly)", 0.95,
             Limits(0.0, 1.0, low_open=True, high_open=True)),
    )
    extra_outputs = tuple(
        real(f"model_prob_{j}", "", f"IMM probability of model {j} after the latest update "
             "(0 for an unused model)") for j in range(1, _IMM_MAX_MODELS + 1))
    engine_diagnostics = ("q_scale",)

    def engine_options(self):
        p = self.params
        names = [f"imm_q_scale_{j}" for j in range(1, p["imm_models"] + 1)]
        return dict(super().engine_options(), q_scales=[p[n] for n in names],
                    p_stay=p["imm_p_stay"], **recovery_options(p))

    def write_diagnostics(self, result):
        super().write_diagnostics(result)
        mu = self.engine.model_probabilities
        for j in range(_IMM_MAX_MODELS):
            self.out[f"model_prob_{j + 1}"] = float(mu[j]) if j < len(mu) else 0.0

