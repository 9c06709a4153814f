"""Land-vehicle aids of the INS/GNSS filters: ZUPT, ZARU and the non-holonomic constraint.

A wheeled vehicle or a walker gives the filter information no sensor measures: at rest its
velocity and angular rate are zero; a car's wheels neither slip sideways nor leave the road.
Each aid is a pseudo-measurement, applied every ``aid_interval_s`` after the IMU interval
that completes it, through the engine's :meth:`aid_update` (a plain linear Kalman update of
the error state, never through a filter's adaptive or robust law: those adapt on the GNSS
innovations only, so a Sage-Husa R, an IGG-III weight or a CTFA Q scale is not moved by a
measurement whose noise is set by the user).  The equations and references:
``docs/guide/land_aids.md``.

* **Stationarity** (:class:`StationaryDetector`): over the last ``stationary_window_s`` of
  IMU samples, the moving standard deviation of the specific force (the "MV" detector of
  Skog et al. 2010) at most ``stationary_accel_std`` and the RMS of the bias-compensated
  angular rate (their "ARE" detector) at most ``stationary_rate_rms``; and, while fixes
  arrive, the last fix's horizontal speed at most ``stationary_gnss_speed``.
* **ZUPT**: ``z = v_INS`` (NED), ``H = [0 I 0 0 0]``, sigma ``zupt_sigma``.
* **ZARU**: ``z = w_c - C_nb w_ie^n`` (the mean bias-compensated rate of the aid interval
  minus the Earth rate the body feels at rest), ``H = [0 0 0 I 0]``: it observes the gyro
  bias directly, sigma ``zaru_sigma``.
* **NHC**: the velocity of the non-holonomic point (``nhc_lever_*``, body, from the IMU) in
  the vehicle frame (``nhc_mount_*``: Euler angles of the vehicle frame in the IMU's body
  frame) has no lateral and no vertical part::

      v^v = C_vb (C_nb v^n + w_c x l),  z = (v^v_y, v^v_z),
      H_v = A C_nb,  H_phi = -A C_nb [v^n x],  H_bg = -A [l x],   A = rows y, z of C_vb

  with the error convention of :meth:`navcore.ins.strapdown.Strapdown.correct`
  (``C_bn_computed = (I - [phi x]) C_bn``, gyro bias error = computed minus true rate).  It
  applies while the vehicle moves (forward speed at least ``nhc_speed_min``, yaw rate at
  most ``nhc_rate_max``), with sigma ``nhc_sigma`` while fixes arrive and
  ``nhc_sigma_outage`` after :data:`OUTAGE_AFTER_S` without one.

The aids hold their detector and accumulators as declared state of the engine (field
``aids``), so a filter's latency history rolls them back and replays them with it.
"""
from __future__ import annotations

import math

import numpy as np

from ..core.component import Limits, boolean, real
from ..ins import earth
from ..ins.error_model import ATT, BG, N_STATES, VEL
from ..ins.rotations import euler_to_dcm

#: after this long without an applied fix the NHC takes its outage sigma [s]
OUTAGE_AFTER_S = 2.0
#: a fix's speed vetoes stationarity for this long after the fix [s]
FIX_SPEED_AGE_S = 1.0

_POSITIVE = Limits(0.0, 1e3, low_open=True)
_MOUNT = Limits(-math.pi, math.pi)

LAND_AID_PARAMETERS = (
    boolean("zupt", "zero-velocity update while the IMU (and GNSS speed) says stationary", False),
    boolean("zaru", "zero angular-rate update (observes the gyro bias) while stationary", False),
    boolean("nhc", "non-holonomic constraint of a wheeled vehicle: zero lateral and vertical "
            "velocity of the point nhc_lever_* in the vehicle frame, while moving", False),
    real("aid_interval_s", "s", "the land aids' pseudo-measurements at most this often", 0.1,
         Limits(0.0, 60.0, low_open=True)),
    real("stationary_window_s", "s", "window of the stationarity detector", 0.5,
         Limits(0.0, 60.0, low_open=True)),
    real("stationary_accel_std", "m/s2", "stationary needs the moving standard deviation of "
         "the specific force over the window at most this", 0.15, _POSITIVE),
    real("stationary_rate_rms", "rad/s", "stationary needs the RMS of the bias-compensated "
         "angular rate over the window at most this", math.radians(0.5), _POSITIVE),
    real("stationary_gnss_speed", "m/s", "stationary needs the horizontal speed of a fix of "
         "the last second at most this (0: GNSS speed not used)", 0.3, Limits(0.0, 1e3)),
    real("zupt_sigma", "m/s", "1-sigma of the zero-velocity pseudo-measurement", 0.01,
         _POSITIVE),
    real("zaru_sigma", "rad/s", "1-sigma of the zero angular-rate pseudo-measurement",
         math.radians(0.01), _POSITIVE),
    real("nhc_sigma", "m/s", "1-sigma of the NHC pseudo-measurement while fixes arrive", 0.1,
         _POSITIVE),
    real("nhc_sigma_outage", "m/s", "1-sigma of the NHC pseudo-measurement in a GNSS outage",
         0.05, _POSITIVE),
    real("nhc_speed_min", "m/s", "NHC only at a forward speed of at least this", 1.0,
         Limits(0.0, 1e3)),
    real("nhc_rate_max", "rad/s", "NHC only at a yaw rate of at most this (skids in tight "
         "turns)", math.radians(20.0), _POSITIVE),
    *(real(f"nhc_mount_{a}", "rad", f"{a} of the vehicle frame in the IMU's body frame "
           "(Euler ZYX)", 0.0, _MOUNT) for a in ("roll", "pitch", "yaw")),
    *(real(f"nhc_lever_{a}", "m", f"body {a} (forward/right/down) from the IMU to the "
           "non-holonomic point (rear axle on the ground)", 0.0, Limits(-100.0, 100.0))
      for a in "xyz"),
)


def skew(a):
    """``[a x]``: the matrix of the cross product with ``a``."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def linear_update(x, P, z, H, R):
    """Kalman update of mean ``x`` and covariance ``P`` with the linear measurement
    ``z = H x + noise(R)`` (Joseph form).  Returns (x, P)."""
    v = z - H @ x
    PHt = P @ H.T
    S = H @ PHt + R
    K = np.linalg.solve(S, PHt.T).T
    IKH = np.eye(len(x)) - K @ H
    P = IKH @ P @ IKH.T + K @ R @ K.T
    return x + K @ v, 0.5 * (P + P.T)


def nhc_constraint(C_bn, v_ned, rate, C_vb, lever):
    """The non-holonomic velocities (v^v_y, v^v_z) [m/s] of the point ``lever`` (body) with
    body rate ``rate``, and the vehicle-frame velocity v^v (3,)."""
    v_v = C_vb @ (C_bn.T @ v_ned + np.cross(rate, lever))
    return v_v[1:], v_v


def nhc_jacobian(C_bn, v_ned, C_vb, lever):
    """H (2, 15) of :func:`nhc_constraint` with respect to the error state (module
    docstring)."""
    A = C_vb[1:]
    H = np.zeros((2, N_STATES))
    H[:, VEL] = A @ C_bn.T
    H[:, ATT] = -A @ C_bn.T @ skew(v_ned)
    H[:, BG] = -A @ skew(lever)
    return H


class StationaryDetector:
    """Moving-window stationarity test (module docstring) over the specific force and the
    bias-compensated angular rate of each IMU interval."""

    state_fields = ("force", "rate2", "count")
    derived_fields = ("window_s", "accel_std", "rate_rms")

    def __init__(self, window_s, accel_std, rate_rms):
        self.window_s, self.accel_std, self.rate_rms = window_s, accel_std, rate_rms
        self.force = None          # (N, 3) ring of the window's specific forces
        self.rate2 = None          # (N,) ring of the squared rates
        self.count = 0

    def add(self, force, rate, dt):
        """One IMU interval's specific force and compensated rate (the window's length in
        samples is fixed by the first interval's ``dt``)."""
        if self.force is None:
            n = max(2, int(round(self.window_s / dt)))
            self.force, self.rate2 = np.zeros((n, 3)), np.zeros(n)
        k = self.count % len(self.rate2)
        self.force[k] = force
        self.rate2[k] = rate @ rate
        self.count += 1

    def statistics(self):
        """(specific-force standard deviation [m/s^2], rate RMS [rad/s]) over the window,
        or None before a full window."""
        if self.rate2 is None or self.count < len(self.rate2):
            return None
        f = self.force
        spread = f - f.mean(axis=0)
        return (math.sqrt(float(np.einsum("ij,ij->", spread, spread)) / len(f)),
                math.sqrt(float(self.rate2.mean())))

    def stationary(self):
        stats = self.statistics()
        return stats is not None and stats[0] <= self.accel_std and stats[1] <= self.rate_rms


class LandAids:
    """The aids of one filter (module docstring), from the component's parameters ``p``."""

    state_fields = ("detector", "elapsed", "dtheta_sum", "fix_time", "fix_speed",
                    "n_zupt", "n_nhc")
    derived_fields = ("p", "C_vb", "lever")

    def __init__(self, p):
        self.p = {q.name: p[q.name] for q in LAND_AID_PARAMETERS}
        self.detector = StationaryDetector(p["stationary_window_s"], p["stationary_accel_std"],
                                           p["stationary_rate_rms"])
        self.C_vb = euler_to_dcm(p["nhc_mount_roll"], p["nhc_mount_pitch"],
                                 p["nhc_mount_yaw"]).T
        self.lever = np.array([p["nhc_lever_x"], p["nhc_lever_y"], p["nhc_lever_z"]])
        self.elapsed = 0.0
        self.dtheta_sum = np.zeros(3)
        self.fix_time = -math.inf
        self.fix_speed = 0.0
        self.n_zupt = 0           # aid epochs with ZUPT/ZARU applied
        self.n_nhc = 0            # aid epochs with the NHC applied

    @staticmethod
    def wanted(p):
        """Whether any aid is on in the parameters ``p``."""
        return p["zupt"] or p["zaru"] or p["nhc"]

    def note_fix(self, gnss_time, v_ned):
        """A fix applied: its time and horizontal speed (the detector's GNSS veto)."""
        self.fix_time = float(gnss_time)
        speed = math.hypot(v_ned[0], v_ned[1])
        self.fix_speed = speed if math.isfinite(speed) else 0.0

    def stationary(self, t):
        """The detector's verdict at ``t`` with the GNSS speed veto."""
        gate = self.p["stationary_gnss_speed"]
        if gate > 0.0 and t - self.fix_time <= FIX_SPEED_AGE_S and self.fix_speed > gate:
            return False
        return self.detector.stationary()

    def after_interval(self, engine, dtheta, dvel, dt, t):
        """One IMU interval integrated by ``engine`` (raw increments) ending at ``t``: feed
        the detector; at the end of an aid interval apply the aids due."""
        dtheta_c = dtheta - engine.gyro_bias * dt
        self.detector.add(dvel / dt - engine.accel_bias, dtheta_c / dt, dt)
        self.dtheta_sum += dtheta_c
        self.elapsed += dt
        if self.elapsed < self.p["aid_interval_s"] * (1.0 - 1e-9):
            return
        rate = self.dtheta_sum / self.elapsed
        self.elapsed, self.dtheta_sum = 0.0, np.zeros(3)
        rows = (self._rest_rows(engine, rate) if self.stationary(t)
                else self._nhc_rows(engine, rate, t))
        if rows:
            H, z, sigma = (np.concatenate(parts) for parts in zip(*rows))
            engine.aid_update(H, z, np.diag(sigma ** 2))

    def _rest_rows(self, engine, rate):
        """[(H, z, sigmas)] of ZUPT and ZARU, as switched on."""
        rows = []
        p = self.p
        if p["zupt"]:
            H = np.zeros((3, N_STATES))
            H[:, VEL] = np.eye(3)
            rows.append((H, np.array(engine.nav.v_ned, dtype=float), np.full(3, p["zupt_sigma"])))
        if p["zaru"]:
            nav = engine.nav
            H = np.zeros((3, N_STATES))
            H[:, BG] = np.eye(3)
            z = rate - nav.C_bn.T @ earth.earth_rate_ned(nav.lat)
            rows.append((H, z, np.full(3, p["zaru_sigma"])))
        if rows:
            self.n_zupt += 1
        return rows

    def _nhc_rows(self, engine, rate, t):
        """[(H, z, sigmas)] of the NHC when on and the vehicle moves."""
        p = self.p
        if not p["nhc"]:
            return []
        nav = engine.nav
        C_bn, v = nav.C_bn, np.array(nav.v_ned, dtype=float)
        z, v_v = nhc_constraint(C_bn, v, rate, self.C_vb, self.lever)
        yaw_rate = (self.C_vb @ rate)[2]
        if abs(v_v[0]) < p["nhc_speed_min"] or abs(yaw_rate) > p["nhc_rate_max"]:
            return []
        outage = t - self.fix_time > OUTAGE_AFTER_S
        sigma = p["nhc_sigma_outage"] if outage else p["nhc_sigma"]
        self.n_nhc += 1
        return [(nhc_jacobian(C_bn, v, self.C_vb, self.lever), z, np.full(2, sigma))]


__all__ = ["LAND_AID_PARAMETERS", "LandAids", "StationaryDetector", "linear_update",
           "nhc_constraint", "nhc_jacobian", "skew"]
