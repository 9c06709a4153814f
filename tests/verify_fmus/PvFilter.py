"""Test FMU written without navfmu: a position-velocity Kalman filter on the GNSS fixes with
a constant-velocity model per NED axis (the IMU only clocks it), in plain pythonfmu and
numpy.  It takes the INS/GNSS filter contract's inputs and outputs the solution, its
1-sigma and the innovation statistic; its attitude is the track angle (roll and pitch 0)."""
import math

import numpy as np
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real

A, E2 = 6378137.0, 6.69437999014e-3
INPUTS = ("imu_time", "imu_dt", "imu_dtheta_x", "imu_dtheta_y", "imu_dtheta_z", "imu_dvel_x",
          "imu_dvel_y", "imu_dvel_z", "gnss_time", "gnss_lat", "gnss_lon", "gnss_h", "gnss_vn",
          "gnss_ve", "gnss_vd")
SOLUTION = ("nav_time", "nav_lat", "nav_lon", "nav_h", "nav_vn", "nav_ve", "nav_vd",
            "nav_roll", "nav_pitch", "nav_yaw", "std_pn", "std_pe", "std_pd", "std_vn",
            "std_ve", "std_vd", "nis")
PARAMETERS = {"init_lat": 0.0, "init_lon": 0.0, "init_h": 0.0, "r_pos_n": 5.0, "r_pos_e": 5.0,
              "r_pos_d": 5.0, "r_vel_n": 0.3, "r_vel_e": 0.3, "r_vel_d": 0.3,
              "q_accel": 1.0, "p0_pos": 5.0, "p0_vel": 0.3}


def radii(lat):
    s = 1.0 - E2 * math.sin(lat) ** 2
    return A * (1.0 - E2) / s ** 1.5, A / math.sqrt(s)


class PvFilter(Fmi2Slave):
    author = "verify test"
    description = "constant-velocity position-velocity filter on GNSS fixes"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name, value in PARAMETERS.items():
            setattr(self, name, value)
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        for name in INPUTS:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        self.gnss_valid, self.gnss_epoch = False, 0
        for var in (Boolean("gnss_valid", causality=Fmi2Causality.input,
                            variability=Fmi2Variability.discrete),
                    Integer("gnss_epoch", causality=Fmi2Causality.input,
                            variability=Fmi2Variability.discrete)):
            self.register_variable(var)
        for name in SOLUTION:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.output))
        self.nis_dof, self.updated = 0, False
        for var in (Integer("nis_dof", causality=Fmi2Causality.output,
                            variability=Fmi2Variability.discrete),
                    Boolean("updated", causality=Fmi2Causality.output,
                            variability=Fmi2Variability.discrete)):
            self.register_variable(var)
        self.x = None

    def _start(self):
        self.origin = (self.init_lat, self.init_lon, self.init_h)
        self.x = np.zeros(6)
        self.P = np.diag([self.p0_pos ** 2] * 3 + [self.p0_vel ** 2] * 3)
        self.last_epoch = self.gnss_epoch
        self.nav_time = self.imu_time
        self._write()

    def _to_ned(self, lat, lon, h):
        lat0, lon0, h0 = self.origin
        rn, re = radii(lat0)
        return np.array([(lat - lat0) * (rn + h0), (lon - lon0) * (re + h0) * math.cos(lat0),
                         -(h - h0)])

    def _predict(self, dt):
        F = np.eye(6)
        F[:3, 3:] = dt * np.eye(3)
        q = self.q_accel ** 2
        Q = np.zeros((6, 6))
        Q[:3, :3] = q * dt ** 3 / 3 * np.eye(3)
        Q[:3, 3:] = Q[3:, :3] = q * dt ** 2 / 2 * np.eye(3)
        Q[3:, 3:] = q * dt * np.eye(3)
        self.x = F @ self.x
        self.P = F @ self.P @ F.T + Q

    def _update(self):
        z = np.concatenate([self._to_ned(self.gnss_lat, self.gnss_lon, self.gnss_h),
                            [self.gnss_vn, self.gnss_ve, self.gnss_vd]])
        R = np.diag([self.r_pos_n, self.r_pos_e, self.r_pos_d, self.r_vel_n, self.r_vel_e,
                     self.r_vel_d]) ** 2
        y = z - self.x
        S = self.P + R
        K = self.P @ np.linalg.inv(S)
        self.x = self.x + K @ y
        self.P = (np.eye(6) - K) @ self.P
        self.nis, self.nis_dof, self.updated = float(y @ np.linalg.solve(S, y)), 6, True

    def _write(self):
        lat0, lon0, h0 = self.origin
        rn, re = radii(lat0)
        n, e, d, vn, ve, vd = self.x.tolist()
        self.nav_lat = lat0 + n / (rn + h0)
        self.nav_lon = lon0 + e / ((re + h0) * math.cos(lat0))
        self.nav_h = h0 - d
        self.nav_vn, self.nav_ve, self.nav_vd = vn, ve, vd
        self.nav_yaw = math.atan2(ve, vn) if math.hypot(vn, ve) > 1.0 else 0.0
        sig = np.sqrt(np.diag(self.P)).tolist()
        self.std_pn, self.std_pe, self.std_pd, self.std_vn, self.std_ve, self.std_vd = sig

    def exit_initialization_mode(self):
        self._start()

    def do_step(self, current_time, step_size):
        self.updated = False
        if self.imu_time > self.nav_time + 0.5 * self.imu_dt and self.imu_dt > 0:
            self._predict(self.imu_time - self.nav_time)
            self.nav_time = self.imu_time
        if self.gnss_epoch != self.last_epoch:
            self.last_epoch = self.gnss_epoch
            if self.gnss_valid:
                self._update()
        self._write()
        return True
