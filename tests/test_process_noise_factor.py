"""Process noise a user can trust (navcore.filters.process_noise_factor): ``imu_noise_factor``
scales the IMU noise figures of every filter (its Q by the square), nothing at the default;
on a simulated MEMS IMU whose errors exceed its figures (models/mems_outages: scale factors and
misalignments the 15 states leave out, noise 3 times the figures) the factor makes the Kf's
sigma cover more of its error in an outage; the Sage-Husa R estimate stays at the nominal R
once the fixes' errors are declared correlated (``gnss_corr_time``)."""
from __future__ import annotations

import numpy as np
import pytest

from navcore.components import registry as components
from navcore.filters.process_noise_factor import (CONSUMER_IMU_NOISE_FACTOR, recommended_factor,
                                                  suggested_factor)
from outage_recovery import SCENARIO, recovery
from direct_replay import simulate_sensors

FILTERS = ("Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf", "CtfaUkf",
           "ImmUkf")
#: distinct figures, so that a factor applied to the wrong one shows
FIGURES = dict(q_gyro_arw_dpsh=0.2, q_accel_vrw_ugpsHz=130.0, q_gyro_bias_instability_dph=7.0,
               q_gyro_bias_tau_s=90.0, q_accel_bias_instability_ug=300.0,
               q_accel_bias_tau_s=200.0)


@pytest.mark.parametrize("name", FILTERS)
def test_the_factor_scales_every_part_of_q_by_its_square(name):
    cls = getattr(components, name)
    base = cls(**FIGURES).fresh_engine().q_density
    assert np.array_equal(cls(**FIGURES, imu_noise_factor=1.0).fresh_engine().q_density, base)
    scaled = cls(**FIGURES, imu_noise_factor=7.0).fresh_engine().q_density
    np.testing.assert_allclose(scaled, 49.0 * base, rtol=1e-13)
    assert np.count_nonzero(base) == 12            # ARW, VRW and both bias drivers


def test_the_suggested_and_recommended_factors():
    # NIS / dof times the factor in use, rounded up to one significant digit
    assert suggested_factor(1.0, 6.05) == 7.0 and suggested_factor(10.0, 6.05) == 70.0
    assert suggested_factor(1.0, 20.0) == 20.0 and suggested_factor(1.0, 20.5) == 30.0
    assert suggested_factor(30.0, 0.5) == 30.0      # an NIS below its dof asks for no more
    # a MEMS gyro's figures are a datasheet's; a fibre-optic gyro's are not
    assert recommended_factor(0.228) == CONSUMER_IMU_NOISE_FACTOR == 30.0
    assert recommended_factor(0.1) == 30.0 and recommended_factor(0.003) == 1.0


@pytest.fixture(scope="module")
def mems():
    """models/mems_outages over its first 150 s (the 10 s outage at 100-110 s)."""
    return simulate_sensors(SCENARIO, stop_time=150.0)


def test_on_an_imu_worse_than_its_figures_the_factor_makes_the_outage_sigma_honest(mems):
    """At the figures (a third of the simulated IMU's noise, no scale factors) the Kf's RMS
    error in the 10 s outage is about 7 times its RMS sigma; with the factor 3 the sigma
    covers a third more of it (4.7), with fixes the receiver's bias (not Q) dominates."""
    plain = recovery(mems, "Kf")
    assert plain.error_to_sigma_outage > 6.0, plain.error_to_sigma_outage
    honest = recovery(mems, "Kf", {"imu_noise_factor": 3.0})
    assert honest.error_to_sigma_outage < 0.75 * plain.error_to_sigma_outage, (
        honest.error_to_sigma_outage, plain.error_to_sigma_outage)


@pytest.mark.parametrize("name", ["SageHusaFading", "Iakf"])
def test_correlated_fixes_keep_the_r_estimate_at_the_nominal_r(name):
    """The floor is the nominal position R in use with gnss_corr_time set and the recovery
    guard on; without either, r_floor_fraction of it (the law as printed)."""
    r = dict(r_pos_n=0.5, r_pos_e=0.7, r_pos_d=1.1, r_vel_n=0.2, r_vel_e=0.3, r_vel_d=0.4)
    nominal = np.array([0.5, 0.7, 1.1, 0.2, 0.3, 0.4]) ** 2
    cls = getattr(components, name)
    floored = cls(**r, gnss_corr_time=30.0).fresh_engine()
    np.testing.assert_array_equal(floored.r_min, np.r_[nominal[:3], 0.01 * nominal[3:]])
    for plain in (cls(**r).fresh_engine(),
                  cls(**r, gnss_corr_time=30.0, recovery=False).fresh_engine()):
        np.testing.assert_array_equal(plain.r_min, 0.01 * nominal)


def test_on_correlated_fixes_the_sage_husa_sigma_is_as_honest_as_the_kfs(mems):
    """mems_outages' receiver errors are Gauss-Markov (60 s) and biased: with gnss_corr_time
    SageHusaFading's RMS error over RMS sigma with fixes is 4.1 against the Kf's 2.8 (the
    estimate falls no lower than the R the Kf takes); with the estimate unfloored it was 9.0,
    the filter following the fixes' slow errors."""
    settings = {"imu_noise_factor": 3.0, "gnss_corr_time": 60.0}
    kf = recovery(mems, "Kf", settings)
    sage = recovery(mems, "SageHusaFading", settings)
    assert sage.error_to_sigma_gnss < min(5.0, 1.6 * kf.error_to_sigma_gnss), (
        sage.error_to_sigma_gnss, kf.error_to_sigma_gnss)
