"""Test FMU written without navfmu: a loosely coupled INS/GNSS error-state EKF (15 states:
position, velocity, attitude, gyro and accelerometer biases, NED, closed loop) in plain
pythonfmu and numpy, after the textbook equations (Groves 2013, ch. 5 and 14) and the
filter contract of docs/guide/filters.md and docs/signals.md:

* outputs valid from initialization (set in exit_initialization_mode), ``nav_time`` the
  IMU's time tag;
* a fix counts at its ``gnss_time``: the INS is carried back to it by its velocity (fixes up
  to ``max_fix_age`` old), once per new ``gnss_epoch``, only when ``gnss_valid``;
* the antenna lever arm ``lever_arm_x/y/z`` (body FRD, IMU to antenna) in the measurement;
* ``InitialUnknowns`` declared (pythonfmu writes none, which ``fmpy validate`` rejects);
* the whole filter state behind get/set/serialize FMU state (JSON, floats exact).

``BUG`` switches on one realistic defect (the tests build one FMU per value; the class is
renamed with it, so every FMU carries its own module): see ``BUGS``.
"""
import json
import math

import numpy as np
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real

BUG = ""
BUGS = {
    "": "none",
    "lever_sign": "the lever arm with its sign flipped",
    "no_bias_feedback": "the gyro-bias estimate never compensates the gyro increments",
    "ne_swap": "the fix's north and east velocity swapped (read as east, north, down)",
    "time_tag": "a fix applied at its arrival, its gnss_time ignored",
    "overconfident": "output sigmas x0.3",
    "underconfident": "output sigmas x3",
    "forgets_covariance": "a restored FMU state keeps the covariance it replaces",
    "nan_after_gap": "the first fix after a gap of more than 10 s makes the state NaN",
    "crash": "an exception inside do_step from 5 s on",
}
CRASH_AT_S = 5.0

A, E2, OMEGA = 6378137.0, 6.69437999014e-3, 7.292115e-5
GAMMA_E, K_SOM, F_FLAT, M_GRAV = 9.7803253359, 0.00193185265241, 1 / 298.257223563, 0.00344978600308
D2R, UG = math.pi / 180.0, 9.80665e-6

INPUTS = ("imu_time", "imu_dt", "imu_dtheta_x", "imu_dtheta_y", "imu_dtheta_z", "imu_dvel_x",
          "imu_dvel_y", "imu_dvel_z", "gnss_time", "gnss_lat", "gnss_lon", "gnss_h", "gnss_vn",
          "gnss_ve", "gnss_vd")
OUTPUTS = ("nav_time", "nav_lat", "nav_lon", "nav_h", "nav_vn", "nav_ve", "nav_vd", "nav_roll",
           "nav_pitch", "nav_yaw", "std_pn", "std_pe", "std_pd", "std_vn", "std_ve", "std_vd",
           "std_att_n", "std_att_e", "std_att_d", "nis")
PARAMETERS = {"init_lat": 0.0, "init_lon": 0.0, "init_h": 0.0, "init_vn": 0.0, "init_ve": 0.0,
              "init_vd": 0.0, "init_roll": 0.0, "init_pitch": 0.0, "init_yaw": 0.0,
              "p0_pos": 5.0, "p0_vel": 0.3, "p0_att_level": 0.0175, "p0_att_yaw": 0.0175,
              "p0_gyro_bias_dph": 0.1, "p0_accel_bias_ug": 100.0, "q_gyro_arw_dpsh": 0.001,
              "q_accel_vrw_ugpsHz": 5.0, "q_gyro_bias_instability_dph": 0.0,
              "q_gyro_bias_tau_s": 0.0, "q_accel_bias_instability_ug": 0.0,
              "q_accel_bias_tau_s": 0.0, "r_pos_n": 5.0, "r_pos_e": 5.0, "r_pos_d": 5.0,
              "r_vel_n": 0.3, "r_vel_e": 0.3, "r_vel_d": 0.3, "lever_arm_x": 0.0,
              "lever_arm_y": 0.0, "lever_arm_z": 0.0, "max_fix_age": 1.5}
STATE = ("lat", "lon", "h", "v", "C", "bg", "ba", "P", "rate", "t_nav", "epoch", "t_fix")


def skew(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def rot(a):
    """Rotation matrix of the rotation vector ``a`` (Rodrigues)."""
    n = math.sqrt(a @ a)
    k = skew(a)
    if n < 1e-12:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + math.sin(n) / n * k + (1 - math.cos(n)) / n ** 2 * k @ k


def euler_dcm(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch),
                              math.sin(pitch), math.cos(yaw), math.sin(yaw))
    return np.array([[cp * cy, -cr * sy + sr * sp * cy, sr * sy + cr * sp * cy],
                     [cp * sy, cr * cy + sr * sp * sy, -sr * cy + cr * sp * sy],
                     [-sp, sr * cp, cr * cp]])


def radii(lat):
    w = 1.0 - E2 * math.sin(lat) ** 2
    return A * (1.0 - E2) / w ** 1.5, A / math.sqrt(w)


def gravity(lat, h):
    s2 = math.sin(lat) ** 2
    g0 = GAMMA_E * (1.0 + K_SOM * s2) / math.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F_FLAT + M_GRAV - 2.0 * F_FLAT * s2) * h
                 + 3.0 * h ** 2 / A ** 2)


class RefEkf(Fmi2Slave):
    author = "verify test"
    description = "loosely coupled INS/GNSS error-state EKF, plain pythonfmu and numpy"

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
        self.register_variable(Boolean("gnss_valid", causality=Fmi2Causality.input,
                                       variability=Fmi2Variability.discrete))
        self.register_variable(Integer("gnss_epoch", causality=Fmi2Causality.input,
                                       variability=Fmi2Variability.discrete))
        for name in OUTPUTS:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.output))
        self.nis_dof, self.updated = 0, False
        self.register_variable(Integer("nis_dof", causality=Fmi2Causality.output,
                                       variability=Fmi2Variability.discrete))
        self.register_variable(Boolean("updated", causality=Fmi2Causality.output,
                                       variability=Fmi2Variability.discrete))
        self.P = None

    # -- the model description: pythonfmu lists no InitialUnknowns --------------------------
    def to_xml(self, model_options=dict()):
        root = super().to_xml(model_options)
        structure = root.find("ModelStructure")
        unknowns = structure.makeelement("InitialUnknowns", {})
        for i, v in enumerate(self.vars.values()):
            if v.causality == Fmi2Causality.output:
                unknowns.append(unknowns.makeelement("Unknown", {"index": str(i + 1)}))
        structure.append(unknowns)
        return root

    # -- FMU state: the filter's own state besides the variables ---------------------------
    def _get_fmu_state(self):
        state = super()._get_fmu_state()
        for name in STATE:
            value = getattr(self, name)
            state["_" + name] = value.tolist() if isinstance(value, np.ndarray) else value
        return state

    def _set_fmu_state(self, state):
        own = {k: v for k, v in state.items() if k.startswith("_")}
        super()._set_fmu_state({k: v for k, v in state.items() if not k.startswith("_")})
        for name in STATE:
            if BUG == "forgets_covariance" and name == "P":
                continue
            value = own["_" + name]
            setattr(self, name, np.array(value) if isinstance(value, list) else value)

    @staticmethod
    def _fmu_state_to_bytes(state):
        return json.dumps(state).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(data):
        return json.loads(data.decode("utf-8"))

    # -- initialization ---------------------------------------------------------------------
    def exit_initialization_mode(self):
        self.lat, self.lon, self.h = self.init_lat, self.init_lon, self.init_h
        self.v = np.array([self.init_vn, self.init_ve, self.init_vd])
        self.C = euler_dcm(self.init_roll, self.init_pitch, self.init_yaw)
        self.bg, self.ba, self.rate = np.zeros(3), np.zeros(3), np.zeros(3)
        sg, sa = self.p0_gyro_bias_dph * D2R / 3600, self.p0_accel_bias_ug * UG
        self.P = np.diag([self.p0_pos ** 2] * 3 + [self.p0_vel ** 2] * 3
                         + [self.p0_att_level ** 2] * 2 + [self.p0_att_yaw ** 2]
                         + [sg ** 2] * 3 + [sa ** 2] * 3)
        self.t_nav, self.epoch, self.t_fix = self.imu_time, self.gnss_epoch, self.imu_time
        self._write(False, 0.0)

    # -- one communication step ------------------------------------------------------------
    def do_step(self, current_time, step_size):
        if BUG == "crash" and current_time >= CRASH_AT_S:
            raise np.linalg.LinAlgError("Matrix is not positive definite")
        if self.imu_dt > 0 and self.imu_time > self.t_nav + 1e-9:
            self._propagate(self.imu_dt)
            self.t_nav = self.imu_time
        updated, nis = False, 0.0
        if self.gnss_epoch != self.epoch:
            self.epoch = self.gnss_epoch
            if self.gnss_valid:
                updated, nis = self._update()
        self._write(updated, nis)
        return True

    def _propagate(self, dt):
        dth = np.array([self.imu_dtheta_x, self.imu_dtheta_y, self.imu_dtheta_z])
        if BUG != "no_bias_feedback":
            dth = dth - self.bg * dt
        dvb = np.array([self.imu_dvel_x, self.imu_dvel_y, self.imu_dvel_z]) - self.ba * dt
        lat, h, v = self.lat, self.h, self.v
        rn, re = radii(lat)
        w_ie = OMEGA * np.array([math.cos(lat), 0.0, -math.sin(lat)])
        w_en = np.array([v[1] / (re + h), -v[0] / (rn + h), -v[1] * math.tan(lat) / (re + h)])
        w_in = w_ie + w_en
        dv_n = (np.eye(3) - 0.5 * skew(w_in * dt)) @ self.C @ (dvb + 0.5 * np.cross(dth, dvb))
        g = np.array([0.0, 0.0, gravity(lat, h)])
        v_new = v + dv_n + (g - np.cross(2 * w_ie + w_en, v)) * dt
        vm = 0.5 * (v + v_new)
        h_new = h - vm[2] * dt
        hm = 0.5 * (h + h_new)
        lat_new = lat + vm[0] / (rn + hm) * dt
        lm = 0.5 * (lat + lat_new)
        self.lon += vm[1] / ((radii(lm)[1] + hm) * math.cos(lm)) * dt
        self.lat, self.h, self.v = lat_new, h_new, v_new
        self.C = rot(-w_in * dt) @ self.C @ rot(dth)
        self.rate = dth / dt
        self._covariance(dt, dv_n / dt, w_in)

    def _covariance(self, dt, f_n, w_in):
        F = np.zeros((15, 15))
        F[0:3, 3:6] = np.eye(3)
        F[3:6, 6:9] = skew(f_n)
        F[3:6, 12:15] = -self.C
        F[6:9, 6:9] = -skew(w_in)
        F[6:9, 9:12] = self.C
        q = np.zeros(15)
        q[3:6] = (self.q_accel_vrw_ugpsHz * UG) ** 2
        q[6:9] = (self.q_gyro_arw_dpsh * D2R / 60) ** 2
        for sl, sigma, tau in ((slice(9, 12), self.q_gyro_bias_instability_dph * D2R / 3600,
                                self.q_gyro_bias_tau_s),
                               (slice(12, 15), self.q_accel_bias_instability_ug * UG,
                                self.q_accel_bias_tau_s)):
            if tau > 0:
                F[sl, sl] = -np.eye(3) / tau
                q[sl] = 2 * sigma ** 2 / tau
        Phi = np.eye(15) + F * dt
        self.P = Phi @ self.P @ Phi.T + np.diag(q * dt)

    def _update(self):
        gap = self.t_nav - self.t_fix
        self.t_fix = self.t_nav
        if BUG == "nan_after_gap" and gap > 10.0:
            self.P = self.P * np.sqrt(10.0 - gap)
        age = 0.0 if BUG == "time_tag" else self.t_nav - self.gnss_time
        if abs(age) > self.max_fix_age:
            return False, 0.0
        lever = np.array([self.lever_arm_x, self.lever_arm_y, self.lever_arm_z])
        if BUG == "lever_sign":
            lever = -lever
        rn, re = radii(self.lat)
        w_ie = OMEGA * np.array([math.cos(self.lat), 0.0, -math.sin(self.lat)])
        arm = self.C @ lever
        z = np.empty(6)
        z[0] = (self.lat - self.gnss_lat) * (rn + self.h)
        z[1] = (self.lon - self.gnss_lon) * (re + self.h) * math.cos(self.lat)
        z[2] = -(self.h - self.gnss_h)
        z[0:3] += arm - self.v * age
        fix_v = np.array([self.gnss_vn, self.gnss_ve, self.gnss_vd])
        if BUG == "ne_swap":      # the receiver's velocity read as east, north, down
            fix_v = fix_v[[1, 0, 2]]
        z[3:6] = self.v + self.C @ np.cross(self.rate, lever) - np.cross(w_ie, arm) - fix_v
        H = np.zeros((6, 15))
        H[:, :6] = np.eye(6)
        R = np.diag([self.r_pos_n ** 2, self.r_pos_e ** 2, self.r_pos_d ** 2,
                     self.r_vel_n ** 2, self.r_vel_e ** 2, self.r_vel_d ** 2])
        S = H @ self.P @ H.T + R
        K = np.linalg.solve(S, H @ self.P).T
        dx = K @ z
        IKH = np.eye(15) - K @ H
        self.P = IKH @ self.P @ IKH.T + K @ R @ K.T
        self.lat -= dx[0] / (rn + self.h)
        self.lon -= dx[1] / ((re + self.h) * math.cos(self.lat))
        self.h += dx[2]
        self.v = self.v - dx[3:6]
        self.C = rot(dx[6:9]) @ self.C
        self.bg, self.ba = self.bg - dx[9:12], self.ba - dx[12:15]
        return True, float(z @ np.linalg.solve(S, z))

    def _write(self, updated, nis):
        self.nav_time = self.t_nav
        self.nav_lat, self.nav_lon, self.nav_h = self.lat, self.lon, self.h
        self.nav_vn, self.nav_ve, self.nav_vd = (float(x) for x in self.v)
        C = self.C
        self.nav_roll = math.atan2(C[2, 1], C[2, 2])
        self.nav_pitch = -math.asin(max(-1.0, min(1.0, C[2, 0])))
        self.nav_yaw = math.atan2(C[1, 0], C[0, 0])
        scale = {"overconfident": 0.3, "underconfident": 3.0}.get(BUG, 1.0)
        std = scale * np.sqrt(np.diag(self.P)[:9])
        (self.std_pn, self.std_pe, self.std_pd, self.std_vn, self.std_ve, self.std_vd,
         self.std_att_n, self.std_att_e, self.std_att_d) = (float(s) for s in std)
        self.updated, self.nis, self.nis_dof = updated, nis, 6 if updated else 0
