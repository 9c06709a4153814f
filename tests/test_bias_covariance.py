"""Bias-error covariance of the Kf and Ukf engines against the Gauss-Markov variance formula.

A first-order Gauss-Markov bias error ``d(db)/dt = -db / tau + w`` with the driver of
``navcore.ins.error_model.process_noise_density`` (``q = 2 sigma^2 / tau``) has the variance
``P(t) = P0 exp(-2 t / tau) + sigma^2 (1 - exp(-2 t / tau))``; a random constant (``tau = 0``)
keeps ``P0``.  The bias rows do not depend on the other states, so without updates each
engine's bias block must follow this formula whatever the navigation does.

The case ``sigma = 0, tau > 0`` is the trap the oracle run of ``uav_maneuver_mems`` fell into
(docs/uav_maneuver.md): the filter then believes that the bias error decays to zero with
certainty, its bias variance collapses (exp(-2) of P0 after one tau, exp(-24) after 1200 s at
tau = 100 s) while the simulated turn-on bias is a random constant, and the heading NEES grows.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.ins.error_model import BA, BG, N_STATES
from navcore.components.registry import Ukf
from navcore.filters.ins_gnss_kf import KfConfig, KfEngine
from navcore.ins.strapdown import Strapdown
from navcore.filters.ukf_filters import UkfEngine

DT = 0.05
DURATION = 100.0
P0_GYRO, P0_ACCEL = 5.0 * math.pi / 180.0 / 3600.0, 1e-3      # rad/s, m/s^2


def _config(sigma_scale, tau):
    p0 = np.full(N_STATES, 1e-3)
    p0[BG], p0[BA] = P0_GYRO, P0_ACCEL
    return KfConfig(p0=p0, gyro_arw=1e-4, accel_vrw=1e-4,
                    gyro_bias_sigma=sigma_scale * P0_GYRO, gyro_bias_tau=tau,
                    accel_bias_sigma=sigma_scale * P0_ACCEL, accel_bias_tau=tau,
                    r_sigma=np.ones(3), measurement="position")


def _bias_variance_after(engine_class, config):
    nav = Strapdown(0.6, 1.9, 500.0, np.array([20.0, 10.0, 0.0]), np.eye(3))
    # the UKF with its component's default options (prediction interval, unscented parameters)
    options = Ukf().engine_options() if engine_class is UkfEngine else {}
    engine = engine_class(config, nav, **options)
    dtheta = np.array([1e-4, -2e-4, 3e-4]) * DT
    dvel = np.array([0.5, -0.2, -9.8]) * DT
    for _ in range(round(DURATION / DT)):
        engine.propagate(dtheta, dvel, DT)
    P = engine.covariance()
    return np.diagonal(P)[BG], np.diagonal(P)[BA]


@pytest.mark.parametrize("engine_class", [KfEngine, UkfEngine])
@pytest.mark.parametrize("sigma_scale, tau", [(0.0, 100.0), (0.5, 100.0), (0.0, 0.0)])
def test_bias_variance_follows_gauss_markov_formula(engine_class, sigma_scale, tau):
    decay = math.exp(-2.0 * DURATION / tau) if tau > 0 else 1.0
    gyro, accel = _bias_variance_after(engine_class, _config(sigma_scale, tau))
    for got, p0 in ((gyro, P0_GYRO), (accel, P0_ACCEL)):
        expected = p0 ** 2 * decay + (sigma_scale * p0) ** 2 * (1.0 - decay)
        np.testing.assert_allclose(got, expected, rtol=0.01)
