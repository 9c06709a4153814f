"""Modified Rodrigues parameters (MRP): conversions and the shadow set.

Definitions (Shuster 1993, "A survey of attitude representations", J. Astronautical Sciences
41(4), sec. 8.4; Schaub & Junkins, *Analytical Mechanics of Space Systems*, sec. 3.7), with the
quaternion convention of :mod:`navcore.ins.rotations` (scalar first, ``quat_to_dcm(q) = C_bn``)::

    sigma = q_v / (1 + q_0)                        |sigma| = tan(theta / 4)
    q_0 = (1 - s) / (1 + s),  q_v = 2 sigma / (1 + s),   s = sigma^T sigma

``sigma`` and its *shadow* ``sigma_S = -sigma / s`` (the MRP of ``-q``) describe the same
attitude; ``|sigma| <= 1`` for rotations up to 180 deg, so switching to the shadow whenever
``|sigma| > 1`` keeps the parameters bounded and away from the singularity at 360 deg.  A
covariance follows the switch through the Jacobian (Karlgaard & Schaub 2009, "Nonsingular
attitude filtering using modified Rodrigues parameters", J. Astronautical Sciences 57(4),
eq. 20)::

    d sigma_S / d sigma = (2 sigma sigma^T - s I) / s^2

Paper 003 (Xiao & Lu) uses the MRP as the attitude state (paper 003 eq. 23) and turns it into Euler
angles for display (paper 003 eq. 26, whose body is lost in our copy): here MRP -> quaternion ->
C_bn -> ZYX Euler angles, the same map in closed form.

Every function takes a 3-vector or an ``(N, 3)`` array of MRPs (``(N, 4)`` quaternions).
"""
from __future__ import annotations

import numpy as np

from ..core.kernels import jitable, kernel
from .rotations import dcm_to_euler, euler_to_dcm, quat_from_dcm, quat_to_dcm


@jitable
def quat_of_mrp(x, y, z):
    """The quaternion ``(w, x, y, z)`` of the MRP ``(x, y, z)`` as a float tuple (the module
    docstring's formula; the squares summed left to right, as numpy's sum over 3 does)."""
    s = x * x + y * y + z * z
    return ((1.0 - s) / (1.0 + s), 2.0 * x / (1.0 + s), 2.0 * y / (1.0 + s),
            2.0 * z / (1.0 + s))


@jitable
def mrp_of_quat(w, x, y, z):
    """The MRP of the quaternion ``(w, x, y, z)`` in the set with ``|sigma| <= 1``."""
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    return x / (1.0 + w), y / (1.0 + w), z / (1.0 + w)


@jitable
def nearer_set(x, y, z, rx, ry, rz):
    """The MRP ``(x, y, z)`` or its shadow, whichever lies nearer ``(rx, ry, rz)``."""
    s = x * x + y * y + z * z
    if s > 0.0:
        ox, oy, oz = -x / s, -y / s, -z / s
    else:
        ox, oy, oz = x, y, z
    d_own = (x - rx) * (x - rx) + (y - ry) * (y - ry) + (z - rz) * (z - rz)
    d_other = (ox - rx) * (ox - rx) + (oy - ry) * (oy - ry) + (oz - rz) * (oz - rz)
    if d_other < d_own:
        return ox, oy, oz
    return x, y, z


@kernel
def _quat_rows(sigma, out):
    for i in range(sigma.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = quat_of_mrp(sigma[i, 0], sigma[i, 1],
                                                                 sigma[i, 2])


@kernel
def _mrp_rows(q, out):
    for i in range(q.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = mrp_of_quat(q[i, 0], q[i, 1], q[i, 2], q[i, 3])


@kernel
def _nearer_rows(sigma, reference, out):
    for i in range(sigma.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = nearer_set(sigma[i, 0], sigma[i, 1], sigma[i, 2],
                                                     reference[i, 0], reference[i, 1],
                                                     reference[i, 2])


def _rows_of(function, values, width, *more):
    """``function`` (a kernel over rows) of the last axis of ``values`` (any leading axes)
    into rows of ``width``; ``more`` arrays broadcast to ``values``' rows."""
    values = np.asarray(values, dtype=float)
    rows = np.ascontiguousarray(values.reshape(-1, values.shape[-1]))
    extra = [np.ascontiguousarray(np.broadcast_to(np.asarray(m, dtype=float), rows.shape))
             for m in more]
    out = np.empty((rows.shape[0], width))
    function(rows, *extra, out)
    return out.reshape(values.shape[:-1] + (width,))


def mrp_to_quat(sigma):
    """Unit quaternion(s) ``[w, x, y, z]`` of MRP ``sigma`` (``w >= 0`` when ``|sigma| <= 1``)."""
    return _rows_of(_quat_rows, sigma, 4)


def quat_to_mrp(q):
    """MRP of quaternion(s) ``q``, in the set with ``|sigma| <= 1`` (``q`` and ``-q`` give
    the same result)."""
    return _rows_of(_mrp_rows, q, 3)


def shadow(sigma):
    """The shadow MRP ``-sigma / |sigma|^2`` (same attitude); ``sigma`` must be non-zero."""
    sigma = np.asarray(sigma, dtype=float)
    return -sigma / np.sum(sigma * sigma, axis=-1, keepdims=True)


def shadow_jacobian(sigma):
    """``d shadow(sigma) / d sigma`` for one MRP (3 x 3), see the module docstring."""
    sigma = np.asarray(sigma, dtype=float)
    s = float(sigma @ sigma)
    return (2.0 * np.outer(sigma, sigma) - s * np.eye(3)) / (s * s)


def nearest_set(sigma, reference):
    """Each MRP of ``sigma`` (``(N, 3)``) or its shadow, whichever lies nearer ``reference``
    (a 3-vector, or one per row): the points of one unscented transform must be in the same
    set to be averaged."""
    return _rows_of(_nearer_rows, sigma, 3, reference)


def mrp_to_dcm(sigma):
    """``C_bn`` of one MRP."""
    return quat_to_dcm(mrp_to_quat(sigma))


def dcm_to_mrp(C):
    """MRP (``|sigma| <= 1``) of a body-to-NED DCM."""
    return quat_to_mrp(quat_from_dcm(C))


def mrp_to_euler(sigma):
    """ZYX Euler angles ``(roll, pitch, yaw)`` of one MRP (paper 003 eq. 26)."""
    return dcm_to_euler(mrp_to_dcm(sigma))


def euler_to_mrp(roll, pitch, yaw):
    """MRP (``|sigma| <= 1``) of ZYX Euler angles."""
    return dcm_to_mrp(euler_to_dcm(roll, pitch, yaw))


@jitable
def dcm_of_quat(w, x, y, z):
    """``C_bn`` of the quaternion ``(w, x, y, z)`` by rows, 9 floats (Groves eq. 2.34,
    scalar first)."""
    return (w * w + x * x - y * y - z * z, 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), w * w - x * x + y * y - z * z, 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z)


@kernel
def _dcm_rows(sigma, out):
    for i in range(sigma.shape[0]):
        q = quat_of_mrp(sigma[i, 0], sigma[i, 1], sigma[i, 2])
        c = dcm_of_quat(q[0], q[1], q[2], q[3])
        for k in range(9):
            out[i, k] = c[k]


def mrp_to_dcm_batch(sigma):
    """``C_bn`` of every row of ``sigma`` (``(N, 3)``): shape ``(N, 3, 3)``, from the
    quaternion (:func:`dcm_of_quat`)."""
    return _rows_of(_dcm_rows, sigma, 9).reshape(-1, 3, 3)
