"""Kf consistency where its noise model matches the simulated errors (20 seeds).

The IMU has white noise (ARW, VRW) and per-axis constant biases drawn with the filter's P0
sigmas; the GNSS has white noise with the filter's R; the filter starts with an initial error
drawn from its P0.  Then the normalized errors must be about 1 and the mean NIS must lie in
the chi-square 95 % band of its degrees of freedom.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from navcore.components.registry import GnssReceiver, Kf, TrajectoryImu
from navcore.ins.earth import radii
from navcore.ins.rotations import euler_to_dcm

DT = 0.02          # 50 Hz IMU keeps the 20 runs short
DURATION = 120.0
SEEDS = range(1, 21)
P0 = {"p0_pos": 3.0, "p0_vel": 0.2, "p0_att_level": math.radians(0.1),
      "p0_att_yaw": math.radians(0.5), "p0_gyro_bias_dph": 10.0, "p0_accel_bias_ug": 500.0}
ARW_DPSH, VRW_UGPSHZ = 0.1, 100.0
R_POS, R_VEL = 2.0, 0.1


def _run(seed):
    rng = np.random.default_rng(1000 + seed)
    traj = TrajectoryImu(profile="aircraft_500s", imu_period=DT, seed=seed,
                         gyro_arw_dpsh=ARW_DPSH, accel_vrw_ugpsHz=VRW_UGPSHZ,
                         gyro_bias_dph=P0["p0_gyro_bias_dph"],
                         accel_bias_ug=P0["p0_accel_bias_ug"])
    gnss = GnssReceiver(seed=100 + seed, fix_interval=1.0,
                        **{f"pos_sigma_{a}": R_POS for a in "ned"},
                        **{f"vel_sigma_{a}": R_VEL for a in "ned"})
    t0 = traj.initialize(0.0)
    gnss.initialize(0.0)
    d_pos = rng.normal(0.0, P0["p0_pos"], 3)
    d_vel = rng.normal(0.0, P0["p0_vel"], 3)
    d_att = rng.normal(0.0, 1.0, 3) * [P0["p0_att_level"], P0["p0_att_level"], P0["p0_att_yaw"]]
    rn = 6378137.0
    kf = Kf(init_lat=t0["truth_lat"] + d_pos[0] / rn,
            init_lon=t0["truth_lon"] + d_pos[1] / (rn * math.cos(t0["truth_lat"])),
            init_h=t0["truth_h"] - d_pos[2],
            init_vn=d_vel[0], init_ve=d_vel[1], init_vd=d_vel[2],
            init_roll=t0["truth_roll"] + d_att[0], init_pitch=t0["truth_pitch"] + d_att[1],
            init_yaw=t0["truth_yaw"] + d_att[2],
            q_gyro_arw_dpsh=ARW_DPSH, q_accel_vrw_ugpsHz=VRW_UGPSHZ,
            **{f"r_pos_{a}": R_POS for a in "ned"}, **{f"r_vel_{a}": R_VEL for a in "ned"}, **P0)
    kf.initialize(0.0)
    per = round(1.0 / DT)
    ratios = {"pos": [], "vel": [], "att": []}
    nis = []
    truth_keys = ("truth_time", "truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve",
                  "truth_vd")
    g = {}
    for k in range(round(DURATION / DT)):
        tr = traj.step(k * DT, DT, {})
        if (k + 1) % per == 0:
            g = gnss.step((k + 1) * DT - 1.0, 1.0, {n: tr[n] for n in truth_keys})
        u = {n: tr[n] for n in ("imu_time", "imu_dt", "imu_dtheta_x", "imu_dtheta_y",
                                "imu_dtheta_z", "imu_dvel_x", "imu_dvel_y", "imu_dvel_z")}
        u.update(g or gnss.out)
        out = kf.step(k * DT, DT, u)
        if out["updated"]:
            nis.append(out["nis"])
        if (k + 1) % per == 0:
            r_n, r_e = radii(tr["truth_lat"])
            e_pos = [(out["nav_lat"] - tr["truth_lat"]) * (r_n + tr["truth_h"]),
                     (out["nav_lon"] - tr["truth_lon"]) * (r_e + tr["truth_h"])
                     * math.cos(tr["truth_lat"]),
                     -(out["nav_h"] - tr["truth_h"])]
            e_vel = [out["nav_vn"] - tr["truth_vn"], out["nav_ve"] - tr["truth_ve"],
                     out["nav_vd"] - tr["truth_vd"]]
            ratios["pos"] += [e / out[f"std_p{a}"] for e, a in zip(e_pos, "ned")]
            ratios["vel"] += [e / out[f"std_v{a}"] for e, a in zip(e_vel, "ned")]
            phi = _attitude_error(out, tr)
            ratios["att"] += [e / out[f"std_att_{a}"] for e, a in zip(phi, "ned")]
    return ratios, nis


def _attitude_error(out, tr):
    """phi (NED) with C_est = (I - [phi x]) C_true."""
    c_est = euler_to_dcm(out["nav_roll"], out["nav_pitch"], out["nav_yaw"])
    c_true = euler_to_dcm(tr["truth_roll"], tr["truth_pitch"], tr["truth_yaw"])
    d = c_est @ c_true.T
    return -0.5 * np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]])


def test_kf_is_consistent_over_20_seeds():
    all_ratios = {"pos": [], "vel": [], "att": []}
    all_nis = []
    for seed in SEEDS:
        ratios, nis = _run(seed)
        for k in all_ratios:
            all_ratios[k] += ratios[k]
        all_nis += nis
    for group, values in all_ratios.items():
        rms = float(np.sqrt(np.mean(np.square(values))))
        print(f"RMS(error/sigma) {group}: {rms:.3f}")
        assert rms < 1.5, group
        assert rms > 0.5, group  # not grossly pessimistic either
    n = len(all_nis)
    dof = 6
    lo, hi = stats.chi2.ppf([0.025, 0.975], n * dof) / n
    mean = float(np.mean(all_nis))
    print(f"mean NIS {mean:.3f} over {n} updates, 95 % band {lo:.3f}-{hi:.3f}")
    assert lo <= mean <= hi
