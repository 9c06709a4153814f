"""NED strapdown inertial navigation driven by angle and velocity increments.

One call of :meth:`Strapdown.update` advances the navigation state over one IMU interval
``[t_{k-1}, t_k]`` of length ``dt`` given the gyro angle increment ``dtheta_k`` [rad] and the
accelerometer velocity increment ``dvel_k`` [m/s] (both in body axes, integrals of the
inertial angular rate and of the specific force over the interval).  The algorithm is the
two-sample (previous-interval) form of the classical attitude / velocity / position
updates: Savage, *Strapdown Analytics* (2000) ch. 7 & 19 and "Strapdown inertial navigation
integration algorithm design, parts 1-2", JGCD 21(1-2), 1998; Groves, *Principles of GNSS,
Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., sect. 5.4-5.5; Qin
Yongyuan, *Inertial Navigation* (2nd ed.), sect. 9.2-9.4.

Equations (k: end of the current interval, k-1: its start, [a x]: cross-product matrix)

1. Mid-interval navigation quantities, extrapolated from the past only (so the scheme is
   explicit and exactly invertible)::

       v_mid   = 3/2 v_{k-1} - 1/2 v_{k-2}
       p_mid   = p_{k-1} + dt/2 * (5/4 v_{k-1} - 1/4 v_{k-2})     (lat, h; lon unused)
       zeta    = (omega_ie^n(p_mid) + omega_en^n(p_mid, v_mid)) dt
       g_cor   = g^n(p_mid) - (2 omega_ie^n + omega_en^n) x v_mid

   (on the first interval v_{k-2} = v_{k-1}).

2. Attitude: rotation vector with the two-sample coning correction (Savage eq. 7.2.2.2-22
   with the previous-sample form; Qin eq. 9.2.45)::

       phi_k  = dtheta_k + 1/12 dtheta_{k-1} x dtheta_k
       C_bn_k = exp(-[zeta x]) C_bn_{k-1} exp([phi_k x])          (exact Rodrigues)

3. Velocity: specific-force increment with rotation compensation and two-sample sculling
   (Savage eq. 7.2.2.2-23/ 7.2.2.2-30; Qin eq. 9.3.19)::

       dv_rot = dvel_k + 1/2 dtheta_k x dvel_k
                + 1/12 (dtheta_{k-1} x dvel_k + dvel_{k-1} x dtheta_k)
       v_k    = v_{k-1} + (I - 1/2 [zeta x]) C_bn_{k-1} dv_rot + g_cor dt

4. Position: trapezoid of v_{k-1} and v_k with radii at the mid-interval position
   (:func:`integrate_position`; Groves eq. 5.56 with mid-point radii).

Position is driven by velocity only, so a trajectory generator that defines position by
:func:`integrate_position` and attitude/velocity freely can recover the increments that
reproduce it exactly: :meth:`Strapdown.inverse_update` solves steps 2 and 3 for ``dtheta_k``
and ``dvel_k``.  Both directions share the private helpers below, so they are inverse to
rounding.

The arithmetic is done on Python floats: numpy calls on 3-vectors cost more than the
arithmetic (``np.cross`` alone takes tens of microseconds), and this runs once per IMU sample.
"""
from __future__ import annotations

import math

import numpy as np

from . import earth
from .rotations import (_euler_from_rows, _euler_rows, _matmul_rows, _matTmul_rows,
    _rodrigues_delta_rows, _rodrigues_rows, _rotvec_from_rows)

_A = earth.A
_E2 = earth.E2
_F = earth.F
_W_IE = earth.OMEGA_IE
# the constants of earth.gravity (Somigliana + free-air series, Groves 2.134); tests check
# _radii/_gravity against earth.radii/earth.gravity
_K_SOMIGLIANA = earth.SOMIGLIANA_K
_M = earth.GRAVITY_M

#: tolerance [m] on the position handed to inverse_update vs integrate_position
POSITION_TOLERANCE = 1e-6


def _radii(lat):
    """(R_N, R_E) [m] as earth.radii, on Python floats."""
    s = math.sin(lat)
    w = 1.0 - _E2 * s * s
    re = _A / math.sqrt(w)
    return re * (1.0 - _E2) / w, re


def _gravity(lat, h):
    """Normal gravity [m/s^2] as earth.gravity, on Python floats."""
    s2 = math.sin(lat) ** 2
    g0 = earth.GAMMA_E * (1.0 + _K_SOMIGLIANA * s2) / math.sqrt(1.0 - _E2 * s2)
    return g0 * (1.0 - 2.0 / _A * (1.0 + _F + _M - 2.0 * _F * s2) * h + 3.0 * h * h / (_A * _A))


def _solve_skew(wx, wy, wz, r):
    """Solve (I + [w x]) x = r in closed form:
    (I + [w x])^-1 = (I - [w x] + w w^T) / (1 + |w|^2)."""
    rx, ry, rz = r
    d = wx * rx + wy * ry + wz * rz
    k = 1.0 / (1.0 + wx * wx + wy * wy + wz * wz)
    return (
        k * (rx - (wy * rz - wz * ry) + wx * d),
        k * (ry - (wz * rx - wx * rz) + wy * d),
        k * (rz - (wx * ry - wy * rx) + wz * d),
    )


def _add_rows(a, b):
    """a + b for 3x3 row lists."""
    (a0, a1, a2), (b0, b1, b2) = a, b
    return [[a0[0] + b0[0], a0[1] + b0[1], a0[2] + b0[2]],
            [a1[0] + b1[0], a1[1] + b1[1], a1[2] + b1[2]],
            [a2[0] + b2[0], a2[1] + b2[1], a2[2] + b2[2]]]


def integrate_position(lat, lon, h, v_prev, v_next, dt):
    """Position after ``dt`` by the trapezoid of two NED velocities [m/s].

    ``h_k = h - dt (vd_prev + vd_next)/2``; latitude and longitude advance by the mean
    north/east velocity over the meridian/transverse radii evaluated at the mid-interval
    latitude (predicted with the start radii) and mid-interval height.  Second-order
    accurate; shared by :class:`Strapdown` and the trajectory generator so that truth and
    mechanization agree to rounding.  Returns ``(lat, lon, h)`` [rad, rad, m] as floats
    (longitude is not wrapped).
    """
    vn = 0.5 * (v_prev[0] + v_next[0])
    ve = 0.5 * (v_prev[1] + v_next[1])
    vd = 0.5 * (v_prev[2] + v_next[2])
    h_next = h - vd * dt
    h_mid = 0.5 * (h + h_next)
    rn, _ = _radii(lat)
    lat_mid = lat + 0.5 * dt * vn / (rn + h_mid)
    rn, re = _radii(lat_mid)
    lat_next = lat + dt * vn / (rn + h_mid)
    lon_next = lon + dt * ve / ((re + h_mid) * math.cos(lat_mid))
    return float(lat_next), float(lon_next), float(h_next)


def _mid_interval_terms(lat, h, v, vp, dt):
    """zeta = (omega_ie + omega_en) dt and g_cor = g - (2 omega_ie + omega_en) x v_mid of an
    interval of ``dt`` from latitude ``lat``, height ``h`` and velocity ``v`` (the previous
    velocity ``vp``), extrapolated to mid-interval (module docstring, step 1)."""
    vmn = 1.5 * v[0] - 0.5 * vp[0]
    vme = 1.5 * v[1] - 0.5 * vp[1]
    vmd = 1.5 * v[2] - 0.5 * vp[2]
    rn, _ = _radii(lat)
    half = 0.5 * dt
    h_mid = h - half * (1.25 * v[2] - 0.25 * vp[2])
    lat_mid = lat + half * (1.25 * v[0] - 0.25 * vp[0]) / (rn + h)
    rn, re = _radii(lat_mid)
    sl, cl = math.sin(lat_mid), math.cos(lat_mid)
    rnh = rn + h_mid
    reh = re + h_mid
    # omega_ie^n (Groves 5.41) and omega_en^n (Groves 5.44)
    wie_n, wie_d = _W_IE * cl, -_W_IE * sl
    wen_n, wen_e, wen_d = vme / reh, -vmn / rnh, -vme * sl / (cl * reh)
    zeta = ((wie_n + wen_n) * dt, wen_e * dt, (wie_d + wen_d) * dt)
    # (2 omega_ie + omega_en) x v_mid
    ax, ay, az = 2.0 * wie_n + wen_n, wen_e, 2.0 * wie_d + wen_d
    g = _gravity(lat_mid, h_mid)
    g_cor = (
        -(ay * vmd - az * vme),
        -(az * vmn - ax * vmd),
        g - (ax * vme - ay * vmn),
    )
    return zeta, g_cor


class Strapdown:
    """NED strapdown mechanization (see the module docstring for the equations).

    Public state: ``lat, lon`` [rad], ``h`` [m] (floats), ``v_ned`` [m/s] (ndarray, 3),
    ``C_bn`` (ndarray 3x3, body -> NED).  The memory of the two-sample algorithms (previous
    increments, previous velocity) lives in plain attributes, so ``copy.deepcopy(self)`` or
    ``self.__dict__`` captures the whole state.  Assigning new values to the public
    attributes between updates is allowed (they are read at the start of every update).
    """

    state_fields = ("lat", "lon", "h", "v_ned", "C_bn", "_v_prev", "_dtheta_prev",
                    "_dvel_prev")

    def __init__(self, lat, lon, h, v_ned, C_bn):
        self.lat = float(lat)
        self.lon = float(lon)
        self.h = float(h)
        self.v_ned = np.array(v_ned, dtype=float).reshape(3)
        self.C_bn = np.array(C_bn, dtype=float).reshape(3, 3)
        vals = [self.lat, self.lon, self.h, *self.v_ned.tolist(), *self.C_bn.ravel().tolist()]
        if not all(math.isfinite(x) for x in vals):
            raise ValueError(f"Strapdown: initial state has non-finite values: {vals}")
        #: velocity one epoch before v_ned (for the mid-interval extrapolation)
        self._v_prev = tuple(self.v_ned.tolist())
        #: increments of the previous interval (zero before the first update)
        self._dtheta_prev = (0.0, 0.0, 0.0)
        self._dvel_prev = (0.0, 0.0, 0.0)

    @classmethod
    def from_euler(cls, lat, lon, h, v_ned, roll, pitch, yaw):
        """Build from ZYX Euler angles [rad]."""
        return cls(lat, lon, h, v_ned, np.array(_euler_rows(float(roll), float(pitch), float(yaw))))

    def euler(self):
        """(roll, pitch, yaw) [rad] of C_bn, yaw in (-pi, pi]."""
        return _euler_from_rows(self.C_bn.tolist())

    # -- shared pieces of update / inverse_update ----------------------------------------
    def _nav_terms(self, v, dt):
        """zeta = (omega_ie + omega_en) dt and g_cor = g - (2 omega_ie + omega_en) x v_mid,
        from the position and velocity extrapolated to mid-interval
        (:func:`_mid_interval_terms` of this state)."""
        return _mid_interval_terms(self.lat, self.h, v, self._v_prev, dt)

    # -- forward mechanization ---------------------------------------------------------
    def update(self, dtheta, dvel, dt):
        """Advance over one IMU interval of ``dt`` [s] with body increments ``dtheta``
        [rad] and ``dvel`` [m/s] (sequences of 3 floats)."""
        gx, gy, gz = float(dtheta[0]), float(dtheta[1]), float(dtheta[2])
        fx, fy, fz = float(dvel[0]), float(dvel[1]), float(dvel[2])
        dt = float(dt)
        v = np.asarray(self.v_ned, dtype=float).tolist()
        C = np.asarray(self.C_bn, dtype=float).tolist()
        zeta, g_cor = self._nav_terms(v, dt)
        px, py, pz = self._dtheta_prev
        qx, qy, qz = self._dvel_prev

        # coning: phi = dtheta + 1/12 dtheta_prev x dtheta
        c12 = 1.0 / 12.0
        phx = gx + c12 * (py * gz - pz * gy)
        phy = gy + c12 * (pz * gx - px * gz)
        phz = gz + c12 * (px * gy - py * gx)

        # rotation + sculling: dv_rot = dvel + (dtheta/2 + dtheta_prev/12) x dvel
        #                                + 1/12 dvel_prev x dtheta
        wx, wy, wz = 0.5 * gx + c12 * px, 0.5 * gy + c12 * py, 0.5 * gz + c12 * pz
        dvx = fx + (wy * fz - wz * fy) + c12 * (qy * gz - qz * gy)
        dvy = fy + (wz * fx - wx * fz) + c12 * (qz * gx - qx * gz)
        dvz = fz + (wx * fy - wy * fx) + c12 * (qx * gy - qy * gx)

        # to NED at t_{k-1}, then the half-interval nav-frame rotation (I - 1/2 [zeta x])
        c0, c1, c2 = C
        ux = c0[0] * dvx + c0[1] * dvy + c0[2] * dvz
        uy = c1[0] * dvx + c1[1] * dvy + c1[2] * dvz
        uz = c2[0] * dvx + c2[1] * dvy + c2[2] * dvz
        zx, zy, zz = zeta
        v_next = (
            v[0] + ux - 0.5 * (zy * uz - zz * uy) + g_cor[0] * dt,
            v[1] + uy - 0.5 * (zz * ux - zx * uz) + g_cor[1] * dt,
            v[2] + uz - 0.5 * (zx * uy - zy * ux) + g_cor[2] * dt,
        )

        self.lat, self.lon, self.h = integrate_position(self.lat, self.lon, self.h, v, v_next, dt)
        # C_next = (I + N) C (I + B) = C + (C B + N (C + C B)), N, B: Rodrigues minus I;
        # summing the small terms first keeps the rounding relative to the change, so a
        # constant attitude stays constant to the last bit (no secular DCM drift).
        CB = _matmul_rows(C, _rodrigues_delta_rows(phx, phy, phz))
        NC = _matmul_rows(_rodrigues_delta_rows(-zx, -zy, -zz), _add_rows(C, CB))
        self._v_prev = tuple(v)
        self.v_ned = np.array(v_next)
        self.C_bn = np.array(_add_rows(C, _add_rows(CB, NC)))
        self._dtheta_prev = (gx, gy, gz)
        self._dvel_prev = (fx, fy, fz)

    # -- exact inverse -----------------------------------------------------------------
    def inverse_update(self, lat, lon, h, v_ned, C_bn, dt):
        """Increments ``(dtheta, dvel)`` (ndarrays, rad and m/s) that take the current state
        to ``(lat, lon, h, v_ned, C_bn)`` through :meth:`update`, and advance the state to it.

        Attitude: ``exp([phi x]) = C_bn_{k-1}^T exp([zeta x]) C_bn_k``, then the coning
        relation ``(I + 1/12 [dtheta_{k-1} x]) dtheta_k = phi`` is solved for ``dtheta_k``.
        Velocity: ``dv_rot = C_bn_{k-1}^T (I - 1/2 [zeta x])^-1 (v_k - v_{k-1} - g_cor dt)``,
        then ``(I + [(dtheta_k/2 + dtheta_{k-1}/12) x]) dvel_k = dv_rot - 1/12 dvel_{k-1} x
        dtheta_k``.  Position is not driven by the increments: the target position must be
        ``integrate_position(lat_{k-1}, lon_{k-1}, h_{k-1}, v_{k-1}, v_k, dt)``; a mismatch
        above 1e-6 m raises ValueError.  ``C_bn`` must be a rotation matrix.
        """
        dt = float(dt)
        v = np.asarray(self.v_ned, dtype=float).tolist()
        v1 = [float(v_ned[0]), float(v_ned[1]), float(v_ned[2])]
        C1 = C_bn.tolist() if isinstance(C_bn, np.ndarray) else [list(map(float, r)) for r in C_bn]
        lat, lon, h = float(lat), float(lon), float(h)

        plat, plon, ph = integrate_position(self.lat, self.lon, self.h, v, v1, dt)
        rn, re = _radii(lat)
        mismatch = max(abs(lat - plat) * (rn + h),
                       abs(lon - plon) * (re + h) * math.cos(lat),
                       abs(h - ph))
        if not mismatch <= POSITION_TOLERANCE:
            raise ValueError(
                f"Strapdown.inverse_update: target position differs by {mismatch:.3g} m from "
                f"integrate_position of the velocities (tolerance {POSITION_TOLERANCE} m); "
                "position must be integrated with navcore.ins.strapdown.integrate_position")
        return self._inverse_to(lat, lon, h, v1, C1, dt)

    def _inverse_to(self, lat, lon, h, v1, C1, dt):
        """:meth:`inverse_update` on checked floats: ``v1`` a 3-sequence, ``C1`` row lists
        (the trajectory generator, which integrates the position itself, calls it directly)."""
        v = np.asarray(self.v_ned, dtype=float).tolist()
        dtheta, dvel = inverse_increments(self.lat, self.h, v, self._v_prev,
                                          np.asarray(self.C_bn, dtype=float).tolist(),
                                          self._dtheta_prev, self._dvel_prev, v1, C1, dt)
        self._move_to(lat, lon, h, tuple(v), v1, C1, dtheta, dvel)
        return np.array(dtheta), np.array(dvel)

    def _move_to(self, lat, lon, h, v_prev, v1, C1, dtheta, dvel):
        """Take the state an update with increments ``dtheta``, ``dvel`` (3-tuples) from
        velocity ``v_prev`` reaches: position, ``v1``, ``C1`` (row lists)."""
        self.lat, self.lon, self.h = lat, lon, h
        self._v_prev = v_prev
        self.v_ned = np.array(v1)
        self.C_bn = np.array(C1)
        self._dtheta_prev = dtheta
        self._dvel_prev = dvel

    # -- closed-loop feedback ----------------------------------------------------------
    def correct(self, dr_ned, dv_ned, phi_ned):
        """Remove estimated errors from the state (closed-loop error-state feedback).

        Error convention (the filters rely on it):

        * ``dr_ned`` [m]: computed minus true position, resolved in NED;
        * ``dv_ned`` [m/s]: computed minus true velocity;
        * ``phi_ned`` [rad]: attitude error with ``C_bn_computed = (I - [phi x]) C_bn_true``.

        Correction: ``lat -= dr_n/(R_N+h)``, ``lon -= dr_e/((R_E+h) cos lat)``,
        ``h += dr_d``, ``v -= dv``, ``C_bn = exp([phi x]) C_bn``.  The velocity memory of
        the mid-interval extrapolation is shifted by the same ``dv`` so the correction does
        not look like an acceleration to the next update.
        """
        dn, de, dd = (float(x) for x in dr_ned)
        dv = np.array(dv_ned, dtype=float).reshape(3)
        phi = [float(x) for x in phi_ned]
        if not all(math.isfinite(x) for x in (dn, de, dd, *dv.tolist(), *phi)):
            raise ValueError("Strapdown.correct: non-finite correction "
                             f"dr={dr_ned}, dv={dv_ned}, phi={phi_ned}")
        lat, h = self.lat, self.h
        rn, re = _radii(lat)
        self.lat = lat - dn / (rn + h)
        self.lon = self.lon - de / ((re + h) * math.cos(lat))
        self.h = h + dd
        self.v_ned = self.v_ned - dv
        vp = self._v_prev
        dvl = dv.tolist()
        self._v_prev = (vp[0] - dvl[0], vp[1] - dvl[1], vp[2] - dvl[2])
        self.C_bn = np.array(_matmul_rows(_rodrigues_rows(*phi), self.C_bn.tolist()))


def inverse_increments(lat, h, v, v_prev, C, dtheta_prev, dvel_prev, v1, C1, dt):
    """The increments ``(dtheta, dvel)`` (3-tuples) with which :meth:`Strapdown.update` takes
    the velocity ``v`` and attitude ``C`` (row lists) at latitude ``lat``, height ``h`` (with
    the previous velocity ``v_prev`` and increments ``dtheta_prev``, ``dvel_prev``) to ``v1``
    and ``C1`` over ``dt`` (the equations of :meth:`Strapdown.inverse_update`)."""
    zeta, g_cor = _mid_interval_terms(lat, h, v, v_prev, dt)
    zx, zy, zz = zeta
    px, py, pz = dtheta_prev
    qx, qy, qz = dvel_prev
    c12 = 1.0 / 12.0

    # attitude: C1 = exp(-[zeta x]) C exp([phi x])  =>  exp([phi x]) = C^T exp([zeta x]) C1
    M = _matTmul_rows(C, _matmul_rows(_rodrigues_rows(zx, zy, zz), C1))
    phi = _rotvec_from_rows(M)
    gx, gy, gz = _solve_skew(c12 * px, c12 * py, c12 * pz, phi)

    # velocity
    dvn = (v1[0] - v[0] - g_cor[0] * dt,
           v1[1] - v[1] - g_cor[1] * dt,
           v1[2] - v[2] - g_cor[2] * dt)
    ux, uy, uz = _solve_skew(-0.5 * zx, -0.5 * zy, -0.5 * zz, dvn)
    c0, c1, c2 = C
    dv_rot = (c0[0] * ux + c1[0] * uy + c2[0] * uz,
              c0[1] * ux + c1[1] * uy + c2[1] * uz,
              c0[2] * ux + c1[2] * uy + c2[2] * uz)
    rhs = (dv_rot[0] - c12 * (qy * gz - qz * gy),
           dv_rot[1] - c12 * (qz * gx - qx * gz),
           dv_rot[2] - c12 * (qx * gy - qy * gx))
    fx, fy, fz = _solve_skew(0.5 * gx + c12 * px, 0.5 * gy + c12 * py,
                             0.5 * gz + c12 * pz, rhs)
    return (gx, gy, gz), (fx, fy, fz)


class InverseStrapdown:
    """The memory of the exact inverse of :meth:`Strapdown.update` on plain floats, for a
    sensor turning truth samples into increments: the position, velocity ``v`` and attitude
    ``C`` (row lists) of the latest sample, the velocity before it and the latest increments.
    :meth:`step_to` is :meth:`Strapdown.inverse_update` without the position check and
    without the arrays of a :class:`Strapdown` (the same function, the same floats)."""

    state_fields = ("lat", "lon", "h", "v", "C", "v_prev", "dtheta_prev", "dvel_prev")

    def __init__(self, lat, lon, h, v, C):
        self.lat, self.lon, self.h = float(lat), float(lon), float(h)
        self.v = tuple(float(x) for x in v)
        self.C = [[float(x) for x in row] for row in C]
        self.v_prev = self.v
        self.dtheta_prev = self.dvel_prev = (0.0, 0.0, 0.0)

    def step_to(self, lat, lon, h, v1, C1, dt):
        """The increments ``(dtheta, dvel)`` (3-tuples) from the latest sample to this one
        (position ``lat, lon, h``, velocity ``v1``, attitude rows ``C1``), which becomes the
        latest."""
        dtheta, dvel = inverse_increments(self.lat, self.h, self.v, self.v_prev, self.C,
                                          self.dtheta_prev, self.dvel_prev, v1, C1, dt)
        self.lat, self.lon, self.h = lat, lon, h
        self.v_prev, self.v, self.C = self.v, tuple(v1), C1
        self.dtheta_prev, self.dvel_prev = dtheta, dvel
        return dtheta, dvel
