"""The 15-state error model against the mechanization it linearizes (as pyins tests its own):

* deterministic part: a small initial error (position, velocity, attitude, gyro and
  accelerometer bias) propagated by the discrete transition ``Phi = I + F dt`` the filters
  use, along a manoeuvring flight, matches the difference of two nonlinear strapdown runs
  (perturbed minus reference) within a stated bound per group after 60 s;
* stochastic part: the covariance the filter accumulates from the white-noise densities
  (``Qd = q dt`` propagated by ``Phi``) matches the spread of 200 strapdown runs driven by
  increments with that white noise.

These checks see the Coriolis term: removing its factor 2 from the mechanization's shared
helper makes the velocity discrepancy ten times larger (4.9e-3 relative after 60 s against
4.9e-4) and fails the first test.
"""
from __future__ import annotations

import math

import numpy as np

from navcore.ins import earth
from navcore.ins.error_model import ATT, N_STATES, POS, VEL, system_matrix
from navcore.filters.ins_gnss_kf import KfConfig, KfEngine
from navcore.ins.rotations import euler_to_dcm, rotvec_to_dcm
from navcore.ins.strapdown import Strapdown
from navcore.ins.trajectory import TrajectoryGenerator

PROFILE = {"start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 1000.0, "speed": 120.0,
                     "yaw_deg": 30.0},
           "segments": [{"type": "level", "duration": 20.0},
                        {"type": "turn", "duration": 60.0, "heading_change_deg": 120.0}]}
DT = 0.01
#: initial error: position NED [m], velocity [m/s], attitude [rad], gyro bias [rad/s]
#: (2 deg/h), accelerometer bias [m/s^2] (50 ug)
X0 = np.array([3.0, -2.0, 1.0, 0.3, -0.2, 0.1, 2e-4, -1e-4, 1e-3,
               1e-5, -5e-6, 2e-6, 5e-4, -3e-4, 2e-4])
#: relative bound |linear - nonlinear| / |nonlinear| per group after 60 s (measured:
#: position 6.1e-4, velocity 4.9e-4, attitude 2.1e-4: second-order terms of the error and
#: the transport-rate coupling the model neglects)
BOUNDS = {"position": 1.2e-3, "velocity": 1.2e-3, "attitude": 6e-4}


def _start(gen):
    s = gen.state()
    return s, euler_to_dcm(s["roll"], s["pitch"], s["yaw"])


def _error(nav, ref):
    """computed - true in the error-state convention (position NED m, velocity, phi)."""
    rn, re = earth.radii(ref.lat)
    d = np.empty(9)
    d[0] = (nav.lat - ref.lat) * (rn + ref.h)
    d[1] = (nav.lon - ref.lon) * (re + ref.h) * math.cos(ref.lat)
    d[2] = ref.h - nav.h
    d[3:6] = nav.v_ned - ref.v_ned
    D = np.eye(3) - nav.C_bn @ ref.C_bn.T  # = [phi x] to first order
    d[6:9] = 0.5 * (D[2, 1] - D[1, 2]), 0.5 * (D[0, 2] - D[2, 0]), 0.5 * (D[1, 0] - D[0, 1])
    return d


def test_phi_propagates_an_initial_error_like_two_nonlinear_runs():
    gen = TrajectoryGenerator(PROFILE, DT)
    s, C = _start(gen)
    v0 = np.array([s["vn"], s["ve"], s["vd"]])
    ref = Strapdown(s["lat"], s["lon"], s["h"], v0, C)
    rn, re = earth.radii(s["lat"])
    nav = Strapdown(s["lat"] + X0[0] / (rn + s["h"]),
                    s["lon"] + X0[1] / ((re + s["h"]) * math.cos(s["lat"])), s["h"] - X0[2],
                    v0 + X0[3:6], rotvec_to_dcm(-X0[6:9]) @ C)  # C_comp = exp(-[phi x]) C
    x = X0.copy()
    for _ in range(int(round(60.0 / DT))):
        _, dtheta, dvel = gen.step()
        ref.update(dtheta, dvel, DT)
        dtheta_c, dvel_c = dtheta + X0[9:12] * DT, dvel + X0[12:15] * DT  # biased sensors
        C_prev = nav.C_bn
        nav.update(dtheta_c, dvel_c, DT)
        F = system_matrix(nav.lat, nav.h, nav.v_ned, nav.C_bn, C_prev @ (dvel_c / DT))
        x = x + (F @ x) * DT  # Phi = I + F dt, as the filters propagate
    d = _error(nav, ref)
    assert np.linalg.norm(d[POS]) > 10.0  # the error grew well beyond the initial one
    for group, sl in (("position", POS), ("velocity", VEL), ("attitude", ATT)):
        rel = np.linalg.norm(x[sl] - d[sl]) / np.linalg.norm(d[sl])
        assert rel < BOUNDS[group], (group, rel, x[sl], d[sl])


def test_accumulated_process_noise_matches_noisy_strapdown_runs():
    """200 runs of 5 s along the turn with white noise on every increment (ARW 1e-3
    rad/sqrt(s), VRW 1e-2 m/s/sqrt(s)): the sample variances of the position, velocity and
    attitude errors match the filter's covariance from P0 = 0 within 30 % (the sampling
    spread of a variance from 200 runs is 10 %)."""
    arw, vrw, n_runs, seconds = 1e-3, 1e-2, 200, 5.0
    gen = TrajectoryGenerator(PROFILE, DT)
    for _ in range(2000):  # into the turn
        gen.step()
    s, C = _start(gen)
    state = (s["lat"], s["lon"], s["h"], np.array([s["vn"], s["ve"], s["vd"]]), C)
    steps = [gen.step()[1:] for _ in range(int(round(seconds / DT)))]
    cfg = KfConfig(p0=np.zeros(N_STATES), gyro_arw=arw, accel_vrw=vrw, gyro_bias_sigma=0.0,
                   gyro_bias_tau=0.0, accel_bias_sigma=0.0, accel_bias_tau=0.0,
                   r_sigma=np.ones(3), measurement="position")
    kf = KfEngine(cfg, Strapdown(*state))
    ref = Strapdown(*state)
    for dtheta, dvel in steps:
        kf.propagate(dtheta, dvel, DT)
        ref.update(dtheta, dvel, DT)
    predicted = np.diag(kf.covariance())[:9]
    rng = np.random.default_rng(12)
    errors = np.empty((n_runs, 9))
    for r in range(n_runs):
        nav = Strapdown(*state)
        noise = rng.standard_normal((len(steps), 6)) * np.sqrt(DT)
        for (dtheta, dvel), w in zip(steps, noise):
            nav.update(dtheta + arw * w[:3], dvel + vrw * w[3:], DT)
        errors[r] = _error(nav, ref)
    sample = np.mean(errors**2, axis=0)
    assert np.all(np.abs(sample / predicted - 1.0) < 0.3), sample / predicted
