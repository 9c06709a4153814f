"""Attitude representations: direction cosine matrices, Euler angles, rotation vectors,
quaternions.

Conventions (shared by all of navcore):

* ``C_bn`` is the direction cosine matrix that takes a body-frame vector (forward, right,
  down) to the NED navigation frame: ``x_n = C_bn @ x_b``.
* Euler angles are ZYX (yaw psi, then pitch theta, then roll phi):
  ``C_bn = Rz(psi) Ry(theta) Rx(phi)`` (Groves 2nd ed. eq. 2.22, transposed to body->nav).
* A rotation vector ``phi`` (axis times angle, rad) maps to ``C = exp([phi x])`` (Rodrigues,
  Groves eq. 2.26 / Savage 1998 eq. 7.1.1-4); a body frame turning through ``phi`` relative to
  a reference frame gives ``C_b(new)^(ref) = exp([phi x])``.
* Quaternions are scalar-first ``[w, x, y, z]`` (Hamilton), with ``quat_to_dcm(q)`` equal to
  the DCM of the same rotation.

The public functions work on numpy arrays.  The underscore helpers work on Python floats and
nested rows (tuples or lists): the strapdown mechanization calls them once per IMU sample,
where a numpy call on a 3-vector costs more than the arithmetic itself (``np.cross`` on two
3-vectors takes tens of microseconds).  The public functions are thin wrappers over the same
helpers, so there is one implementation of each formula; the helpers marked ``@jitable``
are also compiled into the strapdown kernels (:mod:`navcore.core.kernels`) and return tuples.
"""
from __future__ import annotations

import math

import numpy as np

from ..core.kernels import jitable
from ..core.python_math import hypot

# Below this angle [rad] the Rodrigues coefficients are evaluated by their Taylor series;
# truncation error of the kept terms is < theta^6/5040 ~ 2e-22 there, far below rounding.
_SMALL_ANGLE = 1e-3


# ---------------------------------------------------------------------------------------
# scalar helpers (Python floats, rows as tuples or lists)
# ---------------------------------------------------------------------------------------
@jitable
def _rodrigues_delta_rows(x, y, z):
    """Rows of exp([phi x]) - I for phi = (x, y, z): a [phi x] + b [phi x]^2 with
    a = sin(t)/t, b = (1 - cos t)/t^2 = 2 sin^2(t/2)/t^2 (no cancellation at small t).  Kept
    apart from the identity so that a DCM update C + dC rounds once, relative to dC, instead
    of once per product term relative to 1 (which biases the DCM by ~1e-16 per step)."""
    t2 = x * x + y * y + z * z
    if t2 < _SMALL_ANGLE * _SMALL_ANGLE:
        a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0
        b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0
    else:
        t = math.sqrt(t2)
        a = math.sin(t) / t
        s = math.sin(0.5 * t) / t
        b = 2.0 * s * s
    # [phi x]^2 = phi phi^T - t^2 I, written out so the matrix is exactly b-symmetric
    bxy = b * x * y
    bxz = b * x * z
    byz = b * y * z
    ax, ay, az = a * x, a * y, a * z
    return (
        (-b * (y * y + z * z), bxy - az, bxz + ay),
        (bxy + az, -b * (x * x + z * z), byz - ax),
        (bxz - ay, byz + ax, -b * (x * x + y * y)),
    )


@jitable
def _rodrigues_rows(x, y, z):
    """Rows of exp([phi x]) = I + (exp([phi x]) - I) (see _rodrigues_delta_rows); adding 1 to
    the diagonal gives the same floats as 1 - b (y^2 + z^2) written out."""
    (d00, d01, d02), (d10, d11, d12), (d20, d21, d22) = _rodrigues_delta_rows(x, y, z)
    return ((d00 + 1.0, d01, d02), (d10, d11 + 1.0, d12), (d20, d21, d22 + 1.0))


@jitable
def _quat_from_rows(m):
    """Shepperd's method (Shepperd 1978): pick the largest of 4w^2, 4x^2, 4y^2, 4z^2 to
    avoid dividing by a small number; returns (w, x, y, z) with w >= 0."""
    m00, m01, m02 = m[0]
    m10, m11, m12 = m[1]
    m20, m21, m22 = m[2]
    tr = m00 + m11 + m22
    if tr >= m00 and tr >= m11 and tr >= m22:
        w4 = 2.0 * math.sqrt(1.0 + tr)
        w, x, y, z = 0.25 * w4, (m21 - m12) / w4, (m02 - m20) / w4, (m10 - m01) / w4
    elif m00 >= m11 and m00 >= m22:
        x4 = 2.0 * math.sqrt(1.0 + 2.0 * m00 - tr)
        w, x, y, z = (m21 - m12) / x4, 0.25 * x4, (m01 + m10) / x4, (m02 + m20) / x4
    elif m11 >= m22:
        y4 = 2.0 * math.sqrt(1.0 + 2.0 * m11 - tr)
        w, x, y, z = (m02 - m20) / y4, (m01 + m10) / y4, 0.25 * y4, (m12 + m21) / y4
    else:
        z4 = 2.0 * math.sqrt(1.0 + 2.0 * m22 - tr)
        w, x, y, z = (m10 - m01) / z4, (m02 + m20) / z4, (m12 + m21) / z4, 0.25 * z4
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    return w, x, y, z


@jitable
def _rotvec_from_rows(m):
    """Rotation vector of a DCM given as rows, accurate for tiny angles (the vector part
    comes from the antisymmetric part of the matrix, the angle from atan2)."""
    w, x, y, z = _quat_from_rows(m)
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-8:
        # 2 atan2(n, w)/n = (2/w)(1 - n^2/(3 w^2) + ...); the dropped term is < 4e-17
        k = 2.0 / w
    else:
        k = 2.0 * math.atan2(n, w) / n
    return k * x, k * y, k * z


def _euler_rows(roll, pitch, yaw, sin=math.sin, cos=math.cos):
    """Rows of C_bn = Rz(yaw) Ry(pitch) Rx(roll); with ``sin``/``cos`` = numpy's, the same
    formula over arrays of angles (the rows are then arrays)."""
    return _euler_rows_of(sin(roll), cos(roll), sin(pitch), cos(pitch), sin(yaw), cos(yaw))


def _euler_rows_of(sr, cr, sp, cp, sy, cy):
    """:func:`_euler_rows` from the sines and cosines of roll, pitch and yaw (for a caller
    that has them already)."""
    return [
        [cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
        [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
        [-sp, sr * cp, cr * cp],
    ]


@jitable
def roll_yaw_from_elements(c00, c10, c21, c22):
    """Roll and yaw (in (-pi, pi]) of the ZYX Euler angles of a DCM from its elements
    ``C[i][j]`` (compiled ``atan2`` is the C library's, as Python's ``math.atan2``)."""
    yaw = math.atan2(c10, c00)
    return math.atan2(c21, c22), (math.pi if yaw <= -math.pi else yaw)


@jitable
def pitch_from_elements(c20, c21, c22):
    """Pitch of the ZYX Euler angles of a DCM from its elements ``C[i][j]``, by Python's
    ``math`` (numpy's vectorized ``arctan2`` and ``hypot`` round otherwise; compiled, the
    ``hypot`` is Python's own algorithm, :mod:`navcore.core.python_math`)."""
    # atan2 instead of asin: exact near +-90 deg and immune to |C20| > 1 by rounding
    return math.atan2(-c20, hypot(c21, c22))


def euler_from_elements(c00, c10, c20, c21, c22):
    """ZYX Euler angles (roll, pitch, yaw) of one DCM from its elements ``C[i][j]``."""
    roll, yaw = roll_yaw_from_elements(c00, c10, c21, c22)
    return roll, pitch_from_elements(c20, c21, c22), yaw


def _euler_from_rows(m):
    """ZYX Euler angles of one DCM given by rows (:func:`euler_from_elements`)."""
    return euler_from_elements(m[0][0], m[1][0], m[2][0], m[2][1], m[2][2])


@jitable
def _matmul_rows(a, b):
    """a b for 3x3 rows (a tuple of row tuples)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = b
    return (
        (a00 * b00 + a01 * b10 + a02 * b20, a00 * b01 + a01 * b11 + a02 * b21,
         a00 * b02 + a01 * b12 + a02 * b22),
        (a10 * b00 + a11 * b10 + a12 * b20, a10 * b01 + a11 * b11 + a12 * b21,
         a10 * b02 + a11 * b12 + a12 * b22),
        (a20 * b00 + a21 * b10 + a22 * b20, a20 * b01 + a21 * b11 + a22 * b21,
         a20 * b02 + a21 * b12 + a22 * b22),
    )


@jitable
def _matTmul_rows(a, b):
    """a^T b for 3x3 rows: :func:`_matmul_rows` of the transposed rows of ``a`` (the same
    products in the same order)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    return _matmul_rows(((a00, a10, a20), (a01, a11, a21), (a02, a12, a22)), b)


def wrap_angle(a):
    """Wrap an angle [rad] (scalar or array) to (-pi, pi]."""
    w = np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)
    return float(w) if np.ndim(w) == 0 else w


# ---------------------------------------------------------------------------------------
# public numpy API
# ---------------------------------------------------------------------------------------
def euler_to_dcm(roll, pitch, yaw):
    """C_bn (body -> NED) from ZYX Euler angles [rad]: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    return np.array(_euler_rows(float(roll), float(pitch), float(yaw)))


def euler_to_dcm_array(roll, pitch, yaw):
    """:func:`euler_to_dcm` over arrays of angles of shape (N,): shape (N, 3, 3)."""
    rows = _euler_rows(np.asarray(roll, dtype=float), np.asarray(pitch, dtype=float),
                       np.asarray(yaw, dtype=float), np.sin, np.cos)
    return np.moveaxis(np.array(rows), -1, 0)


def dcm_to_euler(C):
    """ZYX Euler angles ``(roll, pitch, yaw)`` [rad] of C_bn; yaw in (-pi, pi],
    roll in (-pi, pi], pitch in [-pi/2, pi/2]."""
    return _euler_from_rows(np.asarray(C, dtype=float).tolist())


def rotvec_to_dcm(phi):
    """exp([phi x]) by the exact Rodrigues formula, with a series for tiny angles."""
    x, y, z = (float(c) for c in phi)
    return np.array(_rodrigues_rows(x, y, z))


def dcm_to_rotvec(C):
    """Rotation vector (angle in [0, pi]) with ``rotvec_to_dcm(dcm_to_rotvec(C)) == C``;
    accurate to rounding for tiny angles, and near pi (through Shepperd's quaternion)."""
    return np.array(_rotvec_from_rows(np.asarray(C, dtype=float).tolist()))


def quat_from_dcm(C):
    """Unit quaternion [w, x, y, z] (w >= 0) of a DCM (Shepperd's method)."""
    return np.array(_quat_from_rows(np.asarray(C, dtype=float).tolist()))


def quat_to_dcm(q):
    """DCM of a quaternion [w, x, y, z] (normalised first)."""
    w, x, y, z = quat_normalize(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def quat_normalize(q):
    """Unit quaternion with the same direction; raises ValueError for a zero quaternion."""
    q = np.asarray(q, dtype=float)
    n = float(np.sqrt(q @ q))
    if not n > 0.0 or not math.isfinite(n):
        raise ValueError(f"quaternion {q} cannot be normalised")
    return q / n

