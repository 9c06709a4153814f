"""R for time-correlated GNSS errors (navcore.filters.correlated_gnss): the inflation against
the variance of the mean of simulated first-order Gauss-Markov errors, and what the filter
shell does with it: each fix's position variances (the receiver's, distinct per axis, or
r_pos_*) times the factor of the time since the previous fix; nothing at the default."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from navcore.components import registry as components
from navcore.filters.correlated_gnss import CorrelatedFixes, inflation


@pytest.mark.parametrize("tau, gap", [(8.0, 0.25), (2.0, 1.0), (0.5, 1.0)])
def test_inflation_is_the_variance_of_the_mean_of_gauss_markov_errors(tau, gap):
    """N fixes of a stationary AR(1) error (unit sigma): the variance of their mean over 4000
    realizations is k / N within 7 % (the sampling spread of 4000 variances is 2.2 %), and
    not 1 / N (the white errors a plain Kalman filter assumes)."""
    rho = math.exp(-gap / tau)
    n, runs = 2000, 4000
    rng = np.random.default_rng(11)
    white = rng.standard_normal((runs, n)) * math.sqrt(1.0 - rho ** 2)
    white[:, 0] = rng.standard_normal(runs)              # stationary start
    errors = lfilter([1.0], [1.0, -rho], white, axis=1)
    k = inflation(gap, tau)
    # the finite-N variance of the mean, exact for AR(1)
    exact = (1.0 + 2.0 * sum((1 - j / n) * rho ** j for j in range(1, n))) / n
    assert k / n == pytest.approx(exact, rel=0.02)
    assert np.var(errors.mean(axis=1)) == pytest.approx(k / n, rel=0.07)
    assert k > 1.25


def test_inflation_limits():
    assert inflation(0.25, 0.0) == 1.0 and inflation(None, 8.0) == 1.0
    assert inflation(0.25, 8.0) == pytest.approx(2 * 8.0 / 0.25, rel=1e-3)   # tau >> T
    assert inflation(60.0, 8.0) == pytest.approx(1.0, abs=2e-3)              # after an outage
    assert inflation(-0.25, 8.0) == inflation(0.25, 8.0)                     # out of order
    assert math.isfinite(inflation(0.0, 8.0))
    fixes = CorrelatedFixes(8.0)
    assert [fixes.factor(t) for t in (1.0, 1.25)] == [1.0, inflation(0.25, 8.0)]


FIXES = (0.25, 0.5, 0.75, 30.75)


def _inputs(kf, t, std, fix):
    """The inputs of the IMU interval ending at ``t`` (0.25 s, level, at rest) with the
    ``fix``-th fix of FIXES (counting from 1) as the receiver's latest output."""
    inputs = {p.name: p.default() for p in kf.inputs}
    inputs.update(imu_time=t, imu_dt=0.25, imu_dvel_z=-9.8 * 0.25, gnss_time=FIXES[fix - 1],
                  gnss_lat=0.0, gnss_epoch=fix, gnss_valid=True,
                  gnss_std_n=std[0], gnss_std_e=std[1], gnss_std_d=std[2])
    return inputs


def _r_at_fixes(kf, std):
    """The position part of R after each fix of FIXES, IMU intervals of 0.25 s between."""
    kf.initialize(0.0)
    got = []
    for k in range(1, int(round(FIXES[-1] / 0.25)) + 1):
        t = k * 0.25
        fix = sum(1 for f in FIXES if f <= t + 1e-9)
        kf.step(t - 0.25, 0.25, _inputs(kf, t, std, fix))
        if any(abs(t - f) < 1e-9 for f in FIXES):
            got.append(np.diag(kf.engine.R0)[:3].copy())
    return np.array(got)


@pytest.mark.parametrize("name", ["Kf", "Iakf", "Ukf"])
@pytest.mark.parametrize("from_receiver", [True, False])
def test_each_fix_has_its_variances_times_the_factor_of_its_gap(name, from_receiver):
    """Fixes at 0.25, 0.5, 0.75 and (after a 30 s gap) 30.75 s, sigmas N/E/D distinct: the
    position part of R is sigma^2 at the first fix, sigma^2 k(0.25 s) at the next two, and
    sigma^2 k(30 s) after the gap; r_pos_* (distinct) in place of the receiver's without
    r_from_receiver."""
    std = np.array([0.01, 0.02, 0.04])
    r_pos = dict(r_pos_n=0.5, r_pos_e=0.7, r_pos_d=1.1)
    kf = getattr(components, name)(r_from_receiver=from_receiver, gnss_corr_time=8.0,
                                   measurement="position", **r_pos)
    base = std ** 2 if from_receiver else np.array(list(r_pos.values())) ** 2
    expected = [1.0, inflation(0.25, 8.0), inflation(0.25, 8.0), inflation(30.0, 8.0)]
    np.testing.assert_allclose(_r_at_fixes(kf, std) / base, np.outer(expected, np.ones(3)),
                               rtol=1e-12)


def test_default_leaves_r_as_configured():
    """gnss_corr_time 0 (the default): the configured R, every fix, bit for bit."""
    kf = components.Kf(measurement="position", r_pos_n=0.5, r_pos_e=0.7, r_pos_d=1.1)
    got = _r_at_fixes(kf, [0.01, 0.02, 0.04])
    np.testing.assert_array_equal(got, np.tile(np.array([0.5, 0.7, 1.1]) ** 2, (4, 1)))
