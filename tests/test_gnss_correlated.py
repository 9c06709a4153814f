"""The time-correlated and biased GNSS errors (navcore.sensors.gnss_correlated) against the
first-order Gauss-Markov process's textbook moments: steady-state variance sigma^2 and lag
autocorrelation exp(-dt / tau); off by default, and the white errors of a seed unchanged."""
import math

import numpy as np
import pytest

from navcore.errors import ParameterError
from navcore.sensors.gnss_errors import GnssErrorModel

LAT, LON, H = 0.7, 2.0, 100.0


def _errors(params, n, dt=1.0, seed=5):
    model = GnssErrorModel(params, seed=seed)
    pos, vel = np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        model.measure(k * dt, LAT, LON, H, [0.0, 0.0, 0.0])
        pos[k], vel[k] = model.last_pos_error_ned, model.last_vel_error_ned
    return pos, vel


def test_the_white_errors_of_a_seed_are_unchanged_by_the_correlated_ones():
    white = {"pos_sigma_n": 2.0, "pos_sigma_d": 3.0, "vel_sigma_e": 0.1}
    pos0, vel0 = _errors(white, 500)
    pos1, vel1 = _errors({**white, "pos_gm_sigma_n": 1.0, "vel_gm_sigma_e": 0.05}, 500)
    # the white part is the same draw: the difference is the correlated part alone, which
    # is zero on the axes without it
    assert np.array_equal(pos0[:, 1:], pos1[:, 1:]) and np.array_equal(vel0[:, [0, 2]],
                                                                        vel1[:, [0, 2]])
    assert not np.array_equal(pos0[:, 0], pos1[:, 0])
    off, _ = _errors({**white, "pos_gm_tau_s": 10.0}, 500)        # sigmas 0: off
    assert np.array_equal(off, pos0)


@pytest.mark.parametrize("dt", [1.0, 0.2])
def test_gauss_markov_position_error_has_the_textbook_variance_and_autocorrelation(dt):
    sigma, tau, n = 1.5, 30.0, 60000
    pos, _ = _errors({"pos_gm_sigma_e": sigma, "pos_gm_tau_s": tau}, n, dt=dt)
    x = pos[:, 1]
    # n dt / tau independent stretches: the sample variance is within ~3 / sqrt(n dt / (2 tau))
    assert np.var(x) == pytest.approx(sigma ** 2, rel=3.0 / math.sqrt(n * dt / (2 * tau)))
    lag = int(round(tau / dt))            # one correlation time: exp(-1)
    r = np.corrcoef(x[:-lag], x[lag:])[0, 1]
    assert r == pytest.approx(math.exp(-1.0), abs=3.0 * math.sqrt(2 * tau / (n * dt)))
    r1 = np.corrcoef(x[:-1], x[1:])[0, 1]
    assert r1 == pytest.approx(math.exp(-dt / tau), abs=0.01)


def test_the_two_position_processes_add_and_the_bias_varies_slowly():
    pos, _ = _errors({"pos_bias_sigma_d": 1.0, "pos_bias_tau_s": 1800.0}, 3600)
    d = pos[:, 2]
    assert np.max(np.abs(np.diff(d))) < 0.2      # 6 x sigma sqrt(1 - exp(-2/1800)) per s
    assert np.std(d) > 0.05


def test_correlated_error_parameters_are_range_checked_by_name():
    with pytest.raises(ParameterError, match="pos_gm_sigma_n"):
        GnssErrorModel({"pos_gm_sigma_n": -1.0}, seed=1)
    with pytest.raises(ParameterError, match="vel_gm_tau_s"):
        GnssErrorModel({"vel_gm_tau_s": 0.0}, seed=1)
