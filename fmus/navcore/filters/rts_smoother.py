"""Rauch-Tung-Striebel fixed-interval smoother over a recorded run of the error-state Kf.

The forward filter (:mod:`navcore.filters.ins_gnss_kf`) is closed loop: after each update it
feeds the estimated errors ``dx`` back into the nominal (strapdown) state and restarts the
error state at zero.  The smoother runs backwards over what the forward pass left
(Rauch, Tung and Striebel 1965, "Maximum likelihood estimates of linear dynamic systems",
AIAA J. 3(8); Groves 2013, *Principles of GNSS, Inertial, and Multisensor Integrated
Navigation Systems*, 2nd ed., sec. 3.4.2)::

    A_j     = P+_j Phi_{j+1}' (P-_{j+1})^-1                              (smoother gain)
    ds_j    = A_j (ds_{j+1} + dx_{j+1})                                   (smoothed error)
    Ps_j    = P+_j + A_j (Ps_{j+1} - P-_{j+1}) A_j'                       (its covariance)
    x_s,j   = x+_j corrected by ds_j          (the feedback the filter applies: Strapdown.correct)

``j`` is an IMU epoch, ``P+_j`` the covariance after the updates at ``j`` (``P-_j`` without
one; an update is any correction the filter feeds back: a fix's, or a land aid's
pseudo-measurement, ZUPT, ZARU or NHC, :mod:`navcore.filters.land_aids`), ``Phi_{j+1}``
the transition of the interval ``j -> j+1``, ``dx_{j+1}`` the correction the filter
applied at ``j+1`` (0 without an update) and ``ds_j`` the smoothed estimate of the
error of the forward nominal state ``x+_j``, the last epoch's ``ds`` being 0 (there the
smoothed and filtered solutions agree).  The textbook form ``x_s,j = x+_j + A_j (x_s,j+1 -
x-_{j+1})`` becomes the line above because the forward state ``x-_{j+1}`` predicted by the
error state is the nominal state before the update (the error state is 0 between updates),
and the nominal after the update is it less ``dx_{j+1}``.

Memory (:class:`KfRecording`): per IMU epoch only the time, the interval, the nominal
state's first 15 strapdown columns and the specific force in NED (20 floats); per update
the correction, the covariance after it and the nominal and biases after it.  The
transitions ``Phi`` are rebuilt in the backward pass from the stored nominal states with the
filter's own function (:func:`navcore.ins.error_model.transition_rows`), and the forward
covariances of one stretch between two updates at a time (the longest stretch, an outage,
sets the working memory: 15 s at 100 Hz is 1500 epochs of three 15 x 15 matrices, 8 MB).
"""
from __future__ import annotations

import numpy as np

from ..ins.error_model import ATT, BA, BG, N_STATES, POS, VEL, transition_rows, transition_template
from ..ins.strapdown import Strapdown

#: the strapdown columns kept per epoch (position, velocity, C_bn by rows)
NAV_COLUMNS = 15


def gains(phi, P_prior, P_post):
    """The smoother gains ``A_j = P+_j Phi_{j+1}' (P-_{j+1})^-1`` of a stretch, stacked
    (m, n, n): one batched solve (``P-`` symmetric, so ``A' = (P-)^-1 Phi P+``)."""
    return np.linalg.solve(P_prior, phi @ P_post).swapaxes(1, 2)


def rts_step(A, P_post, P_prior_next, Ps_next, d_next):
    """One backward step (module docstring): (``ds_j``, ``Ps_j``) from the gain ``A_j``, the
    forward covariances ``P+_j`` and ``P-_{j+1}``, the smoothed covariance ``Ps_{j+1}`` and
    ``d_next = ds_{j+1} + dx_{j+1}``."""
    Ps = P_post + A @ (Ps_next - P_prior_next) @ A.T
    return A @ d_next, 0.5 * (Ps + Ps.T)


class GrowingRows:
    """A float64 table growing by rows (amortized doubling), cut back by :meth:`truncate`."""

    def __init__(self, width):
        self.data = np.empty((1024, width))
        self.n = 0

    def append(self, *parts):
        """One row, the concatenation of ``parts`` (floats and 1-D arrays)."""
        if self.n == len(self.data):
            self.data = np.concatenate([self.data, np.empty_like(self.data)])
        row, i = self.data[self.n], 0
        for part in parts:
            size = np.size(part)
            row[i:i + size] = part
            i += size
        self.n += 1

    def truncate(self, n):
        self.n = min(self.n, n)

    @property
    def rows(self):
        return self.data[:self.n]

    @property
    def nbytes(self):
        return self.data.nbytes


class KfRecording:
    """What the forward pass of a Kf leaves for the smoother (module docstring).

    Epoch 0 is the start (the engine as built, its covariance ``P0``); each integrated IMU
    interval adds an epoch (the nominal state as propagated, before any update); each
    update at the current epoch -- a fix or a land aid -- records its correction, the
    covariance after it and the corrected nominal state (two updates at one epoch merge:
    the corrections add, the last covariance stays).  A filter that rolls back to a
    checkpoint and integrates again (a late fix) cuts the epochs after the checkpoint first
    (:meth:`truncate_after`)."""

    def __init__(self, q_density, gyro_tau, accel_tau):
        self.q_density = np.asarray(q_density, dtype=float)
        self.taus = (float(gyro_tau), float(accel_tau))
        self.epochs = GrowingRows(2 + NAV_COLUMNS + 3)     # time, dt, nav, f_ned
        self.updates = GrowingRows(1 + N_STATES + N_STATES * N_STATES + NAV_COLUMNS + 6)
        self.started = False

    def start(self, time, engine):
        """The run starts at ``time`` with ``engine`` (its nominal state and P)."""
        self.epochs.truncate(0)
        self.updates.truncate(0)
        self.started = True
        self.epochs.append(time, 0.0, engine.nav.rows[0, :NAV_COLUMNS], np.zeros(3))
        self._update_row(0, np.zeros(N_STATES), engine)

    def truncate_after(self, time):
        """Forget the epochs (and their updates) after ``time``: a rollback to it."""
        if self.epochs.data[self.epochs.n - 1, 0] <= time + 1e-9:
            return                                      # nothing after it (the usual case)
        t = self.epochs.rows[:, 0]
        self.epochs.truncate(int(np.searchsorted(t, time + 1e-9, side="right")))
        u = self.updates.rows[:, 0]
        self.updates.truncate(int(np.searchsorted(u, self.epochs.n - 1, side="right")))

    def add_epoch(self, time, dt, nav_row, f_ned):
        """An integrated IMU interval of ``dt`` ending at ``time``: the nominal state after
        it and the specific force in NED the transition was built with."""
        self.epochs.append(time, dt, nav_row[:NAV_COLUMNS], f_ned)

    def add_update(self, dx, engine):
        """The update just applied at the latest epoch with correction ``dx``."""
        k = self.epochs.n - 1
        if self.updates.n and int(self.updates.rows[-1, 0]) == k:      # merge into it
            dx = dx + self.updates.rows[-1, 1:1 + N_STATES]
            self.updates.truncate(self.updates.n - 1)
        self._update_row(k, dx, engine)

    def _update_row(self, k, dx, engine):
        self.updates.append(k, dx, engine.P.ravel(), engine.nav.rows[0, :NAV_COLUMNS],
                            engine.gyro_bias, engine.accel_bias)

    @property
    def nbytes(self):
        return self.epochs.nbytes + self.updates.nbytes


def _update_fields(row):
    """(epoch, dx, P+, nav row, gyro bias, accel bias) of a row of the updates table."""
    n, nn = N_STATES, N_STATES * N_STATES
    return (int(row[0]), row[1:1 + n], row[1 + n:1 + n + nn].reshape(n, n),
            row[1 + n + nn:1 + n + nn + NAV_COLUMNS], row[1 + n + nn + NAV_COLUMNS:][:3],
            row[1 + n + nn + NAV_COLUMNS + 3:][:3])


def _forward_stretch(rec, k0, k1, P0):
    """The transitions and forward covariances of the epochs ``k0..k1`` (an update at
    ``k0`` with ``P+ = P0``, none inside): (Phi (m, 15, 15) of the intervals ending at
    k0+1..k1, P- of the same epochs, P+ of k0..k1-1)."""
    ep = rec.epochs.rows[k0 + 1:k1 + 1]
    m = len(ep)
    phi = np.empty((m, N_STATES, N_STATES))
    nav = ep[:, 2:2 + NAV_COLUMNS]
    for dt in np.unique(ep[:, 1]):
        sel = np.flatnonzero(ep[:, 1] == dt)
        out = np.empty((len(sel), N_STATES, N_STATES))
        transition_rows(out, np.ascontiguousarray(nav[sel]),
                        np.ascontiguousarray(ep[sel, 2 + NAV_COLUMNS:]), ep[sel, 1],
                        transition_template(dt, *rec.taus))
        phi[sel] = out
    P_prior = np.empty((m, N_STATES, N_STATES))
    P_post = np.empty((m, N_STATES, N_STATES))
    P = P0
    for i in range(m):
        P_post[i] = P
        P = phi[i] @ P @ phi[i].T
        P[np.diag_indices(N_STATES)] += rec.q_density * ep[i, 1]
        P_prior[i] = P
    return phi, P_prior, P_post


def backward(phi, P_prior, P_post, dx, ds_end, Ps_end):
    """The backward pass (module docstring) over epochs ``0..m``: ``phi[i]`` (m, n, n) the
    transition into epoch i+1, ``P_prior[i]`` its covariance before its update,
    ``P_post[i]`` epoch i's after its update, ``dx[i]`` (m, n) the correction applied at
    epoch i+1; ``ds_end``, ``Ps_end`` the smoothed error and covariance of epoch m.  Returns
    the smoothed errors (m, n) and covariance diagonals (m, n) of epochs 0..m-1, and the
    smoothed covariance of epoch 0 (``Ps_end`` when m = 0)."""
    m, n = len(phi), len(ds_end)
    ds, diag = np.zeros((m, n)), np.zeros((m, n))
    d_next, Ps = np.asarray(ds_end, dtype=float), Ps_end
    A = gains(phi, P_prior, P_post) if m else None
    for i in range(m - 1, -1, -1):
        ds[i], Ps = rts_step(A[i], P_post[i], P_prior[i], Ps, d_next + dx[i])
        diag[i] = np.diagonal(Ps)
        d_next = ds[i]
    return ds, diag, Ps


def smooth(rec: KfRecording):
    """The smoothed solution of a recording, one row per epoch: dict of arrays ``time``,
    ``lat``, ``lon``, ``h``, ``vn/ve/vd``, ``roll/pitch/yaw``, ``gyro_bias``, ``accel_bias``
    (n, 3) and ``std`` (n, 15), the root of the smoothed covariance's diagonal.  The
    stretches between updates are smoothed one at a time, the last first, each from its
    update's stored covariance (:func:`_forward_stretch`)."""
    n = rec.epochs.n
    ds = np.zeros((n, N_STATES))
    Ps_diag = np.zeros((n, N_STATES))
    dx_at = np.zeros((n, N_STATES))
    fields = [_update_fields(r) for r in rec.updates.rows]
    for f in fields:
        dx_at[f[0]] = f[1]
    ks = [f[0] for f in fields] + [n - 1]
    Ps = None
    for u in range(len(fields) - 1, -1, -1):
        k0, k1 = ks[u], ks[u + 1]
        phi, P_prior, P_post = _forward_stretch(rec, k0, k1, fields[u][2])
        if Ps is None:                              # the last epoch: smoothed = filtered
            Ps = P_prior[-1] if k1 > k0 else fields[u][2]
            Ps_diag[k1] = np.diagonal(Ps)
        ds[k0:k1], Ps_diag[k0:k1], Ps = backward(phi, P_prior, P_post, dx_at[k0 + 1:k1 + 1],
                                                 ds[k1], Ps)
    return _corrected(rec, fields, ds, Ps_diag)


def _corrected(rec, fields, ds, Ps_diag):
    """The forward nominal state of every epoch (after its update) corrected by ``ds``."""
    epochs = rec.epochs.rows
    n = len(epochs)
    nav_rows = epochs[:, 2:2 + NAV_COLUMNS].copy()
    bg, ba = np.zeros((n, 3)), np.zeros((n, 3))
    starts = [f[0] for f in fields]
    for i, f in enumerate(fields):
        nav_rows[f[0]] = f[3]
        end = starts[i + 1] if i + 1 < len(starts) else n
        bg[f[0]:end], ba[f[0]:end] = f[4], f[5]
    sol = np.empty((n, 9))
    nav = Strapdown.from_euler(0.0, 0.0, 0.0, np.zeros(3), 0.0, 0.0, 0.0)
    for k in range(n):
        nav.rows[0, :NAV_COLUMNS] = nav_rows[k]
        nav.correct(ds[k, POS], ds[k, VEL], ds[k, ATT])
        sol[k] = nav.solution()
    out = {"time": epochs[:, 0].copy(),
           **{name: sol[:, i] for i, name in enumerate(
               ("lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw"))},
           "gyro_bias": bg + ds[:, BG], "accel_bias": ba + ds[:, BA],
           "std": np.sqrt(np.maximum(Ps_diag, 0.0))}
    return out


__all__ = ["GrowingRows", "KfRecording", "backward", "gains", "rts_step", "smooth"]
