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

The arithmetic is written on floats: numpy calls on 3-vectors cost more than the arithmetic
(``np.cross`` alone takes tens of microseconds), and this runs once per IMU sample.  The
forward update runs as a compiled kernel over a leading run axis (:func:`update_rows`,
:mod:`navcore.core.kernels`): a :class:`Strapdown` is one row of the kernel's state array
(:data:`COLUMNS`), a batch of runs is many rows, and both execute the same code on the same
floats.  The helpers the kernel calls stay plain Python functions for the interpreted callers
(the exact inverse, the trajectory, the sensors).
"""
from __future__ import annotations

import math

import numpy as np

from ..core.kernels import jitable, kernel
from . import earth
from .rotations import (_euler_from_rows, _euler_rows, _matmul_rows, _matTmul_rows,
    _rodrigues_delta_rows, _rodrigues_rows, _rotvec_from_rows, euler_from_elements)

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


@jitable
def _radii(lat):
    """(R_N, R_E) [m] as earth.radii, on Python floats."""
    s = math.sin(lat)
    w = 1.0 - _E2 * s * s
    re = _A / math.sqrt(w)
    return re * (1.0 - _E2) / w, re


@jitable
def _gravity(lat, h):
    """Normal gravity [m/s^2] as earth.gravity, on Python floats."""
    s = math.sin(lat)
    s2 = s * s        # not s ** 2: CPython's pow and a compiled x ** 2 (x * x) round apart
    g0 = earth.GAMMA_E * (1.0 + _K_SOMIGLIANA * s2) / math.sqrt(1.0 - _E2 * s2)
    return g0 * (1.0 - 2.0 / _A * (1.0 + _F + _M - 2.0 * _F * s2) * h + 3.0 * h * h / (_A * _A))


@jitable
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


@jitable
def _add_rows(a, b):
    """a + b for 3x3 rows (tuples)."""
    (a0, a1, a2), (b0, b1, b2) = a, b
    return ((a0[0] + b0[0], a0[1] + b0[1], a0[2] + b0[2]),
            (a1[0] + b1[0], a1[1] + b1[1], a1[2] + b1[2]),
            (a2[0] + b2[0], a2[1] + b2[1], a2[2] + b2[2]))


@jitable
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


@jitable
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


#: the columns of a strapdown state row (the form the kernels take, one row per run):
#: position [rad, rad, m], NED velocity [m/s], C_bn by rows, and the memory of the
#: two-sample algorithms: the velocity one update earlier and the previous increments
COLUMNS = ("lat", "lon", "h", "vn", "ve", "vd", *(f"c{i}{j}" for i in range(3) for j in range(3)),
           "vn_prev", "ve_prev", "vd_prev", "dtheta_prev_x", "dtheta_prev_y", "dtheta_prev_z",
           "dvel_prev_x", "dvel_prev_y", "dvel_prev_z")
N_COLUMNS = len(COLUMNS)
_V, _C, _V_PREV = slice(3, 6), slice(6, 15), slice(15, 18)
_DTHETA_PREV, _DVEL_PREV = slice(18, 21), slice(21, 24)


@jitable
def _velocity_attitude(r):
    """The velocity (3-tuple) and ``C_bn`` rows (3x3 tuple) of columns 3:15 of a state row
    (or of an inverse step's target)."""
    return (r[3], r[4], r[5]), ((r[6], r[7], r[8]), (r[9], r[10], r[11]), (r[12], r[13], r[14]))


@jitable
def _update_row(s, dtheta, dvel, dt):
    """:meth:`Strapdown.update` of one state row ``s`` (:data:`COLUMNS`), in place, with the
    body increments ``dtheta`` [rad] and ``dvel`` [m/s] (3 floats each) over ``dt`` [s]."""
    gx, gy, gz = dtheta[0], dtheta[1], dtheta[2]
    fx, fy, fz = dvel[0], dvel[1], dvel[2]
    v, C = _velocity_attitude(s)
    zeta, g_cor = _mid_interval_terms(s[0], s[2], v, (s[15], s[16], s[17]), dt)
    px, py, pz = s[18], s[19], s[20]
    qx, qy, qz = s[21], s[22], s[23]

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
    lat, lon, h = integrate_position(s[0], s[1], s[2], v, v_next, dt)
    # C_next = (I + N) C (I + B) = C + (C B + N (C + C B)), N, B: Rodrigues minus I;
    # summing the small terms first keeps the rounding relative to the change, so a
    # constant attitude stays constant to the last bit (no secular DCM drift).
    CB = _matmul_rows(C, _rodrigues_delta_rows(phx, phy, phz))
    NC = _matmul_rows(_rodrigues_delta_rows(-zx, -zy, -zz), _add_rows(C, CB))
    C_next = _add_rows(C, _add_rows(CB, NC))
    s[0], s[1], s[2] = lat, lon, h
    s[15], s[16], s[17] = v
    s[3], s[4], s[5] = v_next
    for i in range(3):
        s[6 + 3 * i], s[7 + 3 * i], s[8 + 3 * i] = C_next[i]
    s[18], s[19], s[20] = gx, gy, gz
    s[21], s[22], s[23] = fx, fy, fz


@kernel
def update_rows(rows, dtheta, dvel, dt):
    """:meth:`Strapdown.update` of every run of a batch: ``rows`` (B, :data:`N_COLUMNS`) in
    place, with the increments ``dtheta`` and ``dvel`` (B, 3) over ``dt`` (B,)."""
    for b in range(rows.shape[0]):
        _update_row(rows[b], dtheta[b], dvel[b], dt[b])


def _columns(first, last):
    """A property reading columns ``first:last`` of the state row as a tuple of floats and
    writing a 3-sequence there."""
    def get(self):
        return tuple(self.rows[0, first:last].tolist())

    def put(self, value):
        self.rows[0, first:last] = value
    return property(get, put)


def _column(index):
    """A property reading column ``index`` of the state row as a float."""
    def get(self):
        return float(self.rows[0, index])

    def put(self, value):
        self.rows[0, index] = value
    return property(get, put)


class _StateRow:
    """One state row of the kernels (a batch of one run) behind a subclass's declared
    state fields; the position columns as float attributes."""

    # rows: the array behind the state fields
    derived_fields = ("rows",)

    lat = _column(0)
    lon = _column(1)
    h = _column(2)

    def __init__(self, lat, lon, h):
        self.rows = np.zeros((1, N_COLUMNS))
        self.lat, self.lon, self.h = float(lat), float(lon), float(h)


class Strapdown(_StateRow):
    """NED strapdown mechanization (see the module docstring for the equations).

    Public state: ``lat, lon`` [rad], ``h`` [m] (floats), ``v_ned`` [m/s] (ndarray, 3),
    ``C_bn`` (ndarray 3x3, body -> NED).  The memory of the two-sample algorithms (previous
    increments, previous velocity) is state too.  All of it lives in ``rows``, the (1,
    :data:`N_COLUMNS`) state array of the kernels (a batch of one run); the attributes read
    copies of its columns and write into them, so ``copy.deepcopy(self)`` captures the whole
    state and assigning new values between updates is allowed.
    """

    state_fields = ("lat", "lon", "h", "v_ned", "C_bn", "_v_prev", "_dtheta_prev",
                    "_dvel_prev")

    _v_prev = _columns(15, 18)
    _dtheta_prev = _columns(18, 21)
    _dvel_prev = _columns(21, 24)

    def __init__(self, lat, lon, h, v_ned, C_bn):
        super().__init__(lat, lon, h)
        self.v_ned = np.array(v_ned, dtype=float).reshape(3)
        self.C_bn = np.array(C_bn, dtype=float).reshape(3, 3)
        vals = self.rows[0, :15].tolist()
        if not all(math.isfinite(x) for x in vals):
            raise ValueError(f"Strapdown: initial state has non-finite values: {vals}")
        #: velocity one epoch before v_ned (for the mid-interval extrapolation); the
        #: increments of the previous interval are zero before the first update
        self.rows[0, _V_PREV] = self.rows[0, _V]

    @property
    def v_ned(self):
        return self.rows[0, _V].copy()

    @v_ned.setter
    def v_ned(self, value):
        self.rows[0, _V] = np.reshape(value, 3)

    @property
    def C_bn(self):
        return self.rows[0, _C].reshape(3, 3).copy()

    @C_bn.setter
    def C_bn(self, value):
        self.rows[0, _C] = np.reshape(value, 9)

    @classmethod
    def from_euler(cls, lat, lon, h, v_ned, roll, pitch, yaw):
        """Build from ZYX Euler angles [rad]."""
        return cls(lat, lon, h, v_ned, np.array(_euler_rows(float(roll), float(pitch), float(yaw))))

    def euler(self):
        """(roll, pitch, yaw) [rad] of C_bn, yaw in (-pi, pi]."""
        return _euler_from_rows(self.C_bn.tolist())

    def solution(self):
        """(lat, lon, h, vn, ve, vd, roll, pitch, yaw) as floats (one read of the row)."""
        r = self.rows[0].tolist()      # C_bn by rows in columns 6..14: C[i][j] is 6 + 3 i + j
        return (*r[:6], *euler_from_elements(r[6], r[9], r[12], r[13], r[14]))

    # -- forward mechanization ---------------------------------------------------------
    def update(self, dtheta, dvel, dt):
        """Advance over one IMU interval of ``dt`` [s] with body increments ``dtheta``
        [rad] and ``dvel`` [m/s] (sequences of 3 floats): :func:`update_rows` of this run."""
        update_rows(self.rows, np.asarray(dtheta, dtype=float).reshape(1, 3),
                    np.asarray(dvel, dtype=float).reshape(1, 3), np.full(1, dt, dtype=float))

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
        """:meth:`inverse_update` on checked floats: ``v1`` a 3-sequence, ``C1`` rows (the
        trajectory generator, which integrates the position itself, calls it directly):
        :func:`inverse_rows` of this run."""
        increments = _step_row(self.rows, lat, lon, h, v1, C1, dt)[0]
        return increments[:3], increments[3:]

    def _move_to(self, lat, lon, h, v_prev, v1, C1, dtheta, dvel):
        """Take the state an update with increments ``dtheta``, ``dvel`` (3-tuples) from
        velocity ``v_prev`` reaches: position, ``v1``, ``C1`` (rows)."""
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C1
        self.rows[0] = (lat, lon, h, v1[0], v1[1], v1[2], c00, c01, c02, c10, c11, c12,
                        c20, c21, c22, v_prev[0], v_prev[1], v_prev[2], dtheta[0], dtheta[1],
                        dtheta[2], dvel[0], dvel[1], dvel[2])

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


@jitable
def inverse_increments(lat, h, v, v_prev, C, dtheta_prev, dvel_prev, v1, C1, dt):
    """The increments ``(dtheta, dvel)`` (3-tuples) with which :meth:`Strapdown.update` takes
    the velocity ``v`` and attitude ``C`` (rows) at latitude ``lat``, height ``h`` (with
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


@jitable
def _inverse_row(s, target, dt, increments):
    """The exact inverse of :func:`_update_row`: the increments ``(dtheta, dvel)`` (into
    ``increments``, 6 floats) that take the state row ``s`` to ``target`` (its first 15
    columns: position, velocity, attitude) over ``dt``; ``s`` then holds the state they
    lead to (the position is the target's: the caller has integrated or checked it)."""
    v, C = _velocity_attitude(s)
    v1, C1 = _velocity_attitude(target)
    dtheta, dvel = inverse_increments(s[0], s[2], v, (s[15], s[16], s[17]), C,
                                      (s[18], s[19], s[20]), (s[21], s[22], s[23]), v1, C1, dt)
    s[15], s[16], s[17] = v
    for i in range(15):
        s[i] = target[i]
    s[18], s[19], s[20] = dtheta
    s[21], s[22], s[23] = dvel
    increments[0], increments[1], increments[2] = dtheta
    increments[3], increments[4], increments[5] = dvel


@kernel
def inverse_rows(rows, targets, dt, increments):
    """:func:`_inverse_row` of every run of a batch: ``rows`` (B, :data:`N_COLUMNS`) move to
    ``targets`` (B, 15) over ``dt`` (B,); their increments go to ``increments`` (B, 6)."""
    for b in range(rows.shape[0]):
        _inverse_row(rows[b], targets[b], dt[b], increments[b])


class InverseStrapdown(_StateRow):
    """The memory of the exact inverse of :meth:`Strapdown.update`, for a sensor turning truth
    samples into increments: the position, velocity ``v`` (a tuple) and attitude ``C`` (row
    lists) of the latest sample, the velocity before it and the latest increments, in one
    state row of the kernels (``rows``, as a :class:`Strapdown`'s).  :meth:`step_to` is
    :meth:`Strapdown.inverse_update` without the position check (the same kernel, the same
    floats)."""

    state_fields = ("lat", "lon", "h", "v", "C", "v_prev", "dtheta_prev", "dvel_prev")

    v = _columns(3, 6)
    v_prev = _columns(15, 18)
    dtheta_prev = _columns(18, 21)
    dvel_prev = _columns(21, 24)

    def __init__(self, lat, lon, h, v, C):
        super().__init__(lat, lon, h)
        self.v = self.v_prev = tuple(float(x) for x in v)
        self.C = C

    @property
    def C(self):
        return self.rows[0, _C].reshape(3, 3).tolist()

    @C.setter
    def C(self, value):
        self.rows[0, _C] = np.reshape(value, 9)

    def step_to(self, lat, lon, h, v1, C1, dt):
        """The increments ``(dtheta, dvel)`` (3-tuples) from the latest sample to this one
        (position ``lat, lon, h``, velocity ``v1``, attitude rows ``C1``), which becomes the
        latest."""
        increments = _step_row(self.rows, lat, lon, h, v1, C1, dt)[0].tolist()
        return tuple(increments[:3]), tuple(increments[3:])


def _step_row(rows, lat, lon, h, v1, C1, dt):
    """:func:`inverse_rows` of the one row ``rows`` (1, :data:`N_COLUMNS`) to the sample
    ``lat, lon, h, v1, C1`` (floats, a 3-sequence, 3x3 rows) over ``dt``; the increments
    (1, 6)."""
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C1
    target = np.array(((lat, lon, h, v1[0], v1[1], v1[2], c00, c01, c02, c10, c11, c12,
                        c20, c21, c22),))
    increments = np.empty((1, 6))
    inverse_rows(rows, target, np.full(1, dt, dtype=float), increments)
    return increments
