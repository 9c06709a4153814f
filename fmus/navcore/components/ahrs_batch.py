"""The AHRS filters' batch (:mod:`navcore.core.batch`): B runs of UkfAhrs or FuzzyUkfAhrs
(:mod:`navcore.components.ahrs_components`) stepped together.

Every run keeps its own component object (parameters, engine, fuzzy adaptation).  The batch
keeps the runs' filter state stacked (MRP and gyro bias ``x``, ``P``, the pending gyro
increments and interval, the R scales, the clocks) and, when every run takes the same new
IMU interval (the runs of a batch share their trajectory, so their time tags agree), does
for all runs at once what :meth:`AhrsFilter.step` does for one:

* the gyro increment into the pending time update;
* for the runs whose measurement update is due, the UKF time and measurement updates, by
  the functions the single engine calls with one run: the sigma points of all runs
  (:func:`~navcore.filters.unscented_rows.sigma_points_rows`: each covariance's Cholesky
  factor by the LAPACK routine one run alone calls, from one kernel for all runs),
  :func:`~navcore.filters.ahrs.propagate_points` and
  :func:`~navcore.filters.ahrs.measure_points` on the points of all runs, the stacked
  moments (:func:`~navcore.filters.unscented_rows.predicted_moments_rows`,
  :func:`~navcore.filters.unscented_rows.measurement_moments_rows`) and
  :func:`~navcore.filters.unscented_rows.correct_rows`; the fuzzy adaptation of R of all runs in
  one :func:`~navcore.filters.ahrs.adapt_r_scales` call (each run's window and state its own
  object's, the inferences of all runs' blocks stacked);
* the solution outputs.  The quaternion products of the gyro increments and the
  rotation-vector quaternions are the single engine's float formulas (``_qmul``,
  ``_rotvec_quat``) compiled into a kernel over the runs
  (:func:`~navcore.filters.ahrs.accumulate_rows`; compiled ``sin``, ``cos`` and ``atan2``
  are libm's, as Python's), and the outputs but the sigmas are one kernel call
  (:func:`~navcore.filters.ahrs.solution_rows`: the engine's ``_state_quat`` and Euler
  angles, the formulas the single run's ``current_quat`` and ``quat_euler`` call), whose
  pitch's ``hypot`` is Python's compiled (:func:`navcore.core.python_math.hypot`): numpy's
  and C's ``hypot`` differ from Python's in the last place for a fraction of a percent of
  arguments, as numpy's ``arctan2`` does from libm's for about 8 %, so they would not give
  each run the floats of its single run.

Everything else is the run's own component, given the batch's values first (:meth:`_lend`)
and taken back after (:meth:`_adopt`): a run not started yet (TRIAD from its first samples),
an input it refuses, an IMU interval that is not the runs' common one, a covariance that is
not finite or symmetric before an update, a non-finite attitude (its DivergenceError), and
every step of a batch whose runs differ in the constants of the stacked model (gravity,
field, alpha/beta/kappa) or whose class steps otherwise.
"""
from __future__ import annotations

import math
from typing import List

import numpy as np

from ..core import signals
from ..core.batch import ComponentBatch, open_bounds, row_accepted
from ..core.kernels import kernel
from ..core.timing import same_instant
from ..filters.ahrs import (FuzzyAdaptiveR, FuzzyWindows, UkfAhrsEngine, accumulate_rows,
                            adapt_r_scales, euler_sigma_rows, measure_points,
                            process_noise_diagonal, propagate_points, shadow_switched,
                            solution_rows)
from ..filters.fuzzy import StackedInference
from ..filters.unscented_rows import (correct_rows, correction_error,
                                      measurement_moments_rows, predicted_moments_rows,
                                      predicted_state_error, sigma_points_rows, state_error)

_INPUT_NAMES = tuple(p.name for p in signals.AHRS_INPUTS)
_DIAGONAL = np.arange(6)
#: (name, engine attribute path) of the per-run values the batch stacks
_FIELDS = (("x", "ukf.x"), ("P", "ukf.P"), ("interval", "interval"), ("r_scale", "r_scale"),
           ("last_nis", "last_nis"), ("ukf_nis", "ukf.last_nis"),
           ("log_likelihood", "ukf.last_log_likelihood"), ("fallbacks", "ukf.sqrt_fallbacks"),
           ("switches", "shadow_switches"))
#: the engine's constants the stacked model shares between the runs
_SHARED = ("gravity", "field_intensity", "inclination")
#: the methods of the filter shell and of the engine the batch stands for
_SHELL_METHODS = ("step", "_write_solution")
_ENGINE_METHODS = ("accumulate", "predict", "update", "_process", "_measure",
                   "_switch_to_shadow", "current_quat", "euler", "euler_sigma")


#: the steps of :func:`_steps_of_rows`
_NONE, _QUIET, _NATIVE, _OWN = 0, 1, 2, 3


@kernel
def _steps_of_rows(values, low, high, alive, started, native, nav_time, out, updated, step):
    """Which step each run takes on its inputs (``values`` (B, n), :data:`_INPUT_NAMES`)
    into ``step``: none for a failed run; for a started run whose inputs lie in their open
    bounds ``(low, high)`` (a ``native`` batch): quiet when no new IMU sample came (its
    ``updated`` output column of ``out`` set to 0, the others hold), the batch's step
    when the new interval starts at its ``nav_time`` (:func:`same_instant`; ``updated`` set
    to 0 too, until the run updates); else its own
    code (not started, an input refused, an interval that does not follow: its own error)."""
    for b in range(values.shape[0]):
        if not alive[b]:
            step[b] = _NONE
            continue
        v = values[b]
        imu_time, dt = v[0], v[1]
        if not (native and started[b] and row_accepted(v, low, high)):
            step[b] = _OWN
        elif not (imu_time > nav_time[b] + 0.5 * dt and dt > 0):
            out[b, updated] = 0.0
            step[b] = _QUIET
        elif same_instant(imu_time - dt, nav_time[b], dt):
            out[b, updated] = 0.0
            step[b] = _NATIVE
        else:
            step[b] = _OWN


@kernel
def _finite_rows(values, rows, out):
    """Whether every value of ``values[rows[i]]`` is finite, into ``out[i]``."""
    for i in range(rows.shape[0]):
        finite = True
        for v in values[rows[i]].flat:
            if not math.isfinite(v):
                finite = False
                break
        out[i] = finite


def finite_rows(values: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Per run of ``rows``, whether its row of ``values`` (B, ...) is finite throughout."""
    out = np.empty(len(rows), dtype=bool)
    _finite_rows(values, rows, out)
    return out


@kernel
def _near_shadow_rows(x, rows, out):
    """Whether the MRP of ``x[rows[i]]`` (its first 3 values) has a squared norm above 0.5,
    into ``out[i]``: the runs that may switch to the shadow set (which the engine's own
    test, |sigma|^2 > 1, decides)."""
    for i in range(rows.shape[0]):
        r = x[rows[i]]
        out[i] = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] > 0.5


def _engine_path(engine, path):
    obj = engine
    for part in path.split(".")[:-1]:
        obj = getattr(obj, part)
    return obj, path.split(".")[-1]


class AhrsFilterBatch(ComponentBatch):
    """B runs of an AHRS filter (module docstring)."""

    def _started(self, start_time: float) -> np.ndarray:
        runs = self.runs
        self.out = np.zeros((runs, len(self.columns)))
        self.x = np.zeros((runs, 6))
        self.P = np.zeros((runs, 6, 6))
        self.dq = np.zeros((runs, 4))
        self.interval = np.zeros(runs)
        self.r_scale = np.ones((runs, 2))
        self.last_nis = np.zeros(runs)
        self.ukf_nis = np.zeros(runs)
        self.log_likelihood = np.zeros(runs)
        self.fallbacks = np.zeros(runs, dtype=np.int64)
        self.switches = np.zeros(runs, dtype=np.int64)
        self.started = np.zeros(runs, dtype=bool)
        self.last_update = np.zeros(runs)
        self.nav_time = np.full(runs, float(start_time))
        self._everyone = np.ones(runs, dtype=bool)
        alive = [b for b in range(runs) if b not in self._failures]
        self._blocks = {}            # rows of runs -> their stacked fuzzy inferences
        self._native = bool(alive) and self._stands_for(alive)
        col = self.columns
        self._solution_columns = np.array(
            [col[n] for n in ("nav_time", "aligned", "nav_roll", "nav_pitch", "nav_yaw",
                              *signals.NAV_BG_NAMES, "r_scale_accel", "r_scale_mag")],
            dtype=np.intp)
        self._std_columns = np.array([col[n] for n in ("std_roll", "std_pitch", "std_yaw")],
                                     dtype=np.intp)
        self._constants(alive)
        for b in alive:
            self._adopt(b)
        return self.out.copy()

    def _stands_for(self, alive: List[int]) -> bool:
        """Whether the batch's stacked code is every run's own (module docstring)."""
        shell = next(c for c in self.component_class.__mro__
                     if c.__dict__.get("batch_class") is type(self))
        engines = [self.members[b].engine for b in alive]
        first = engines[0]
        same = all(all(getattr(e, k) == getattr(first, k) for k in _SHARED)
                   and (e.ukf.alpha, e.ukf.beta, e.ukf.kappa)
                   == (first.ukf.alpha, first.ukf.beta, first.ukf.kappa) for e in engines)
        return same and all(
            all(getattr(type(e), m) is getattr(UkfAhrsEngine, m) for m in _ENGINE_METHODS)
            and (e.adaptive is None or type(e.adaptive).step is FuzzyAdaptiveR.step)
            for e in engines) and all(
            getattr(type(self.members[b]), m) is getattr(shell, m)
            for b in alive for m in _SHELL_METHODS)

    def _constants(self, alive: List[int]) -> None:
        """The per-run parameters the stacked steps read, and the shared constants."""
        runs = self.runs
        self.update_interval = np.zeros(runs)
        self.max_mag_age = np.zeros(runs)
        self.field_intensity = np.ones(runs)
        self.gyro_noise = np.zeros((runs, 2))          # arw, bias random walk
        self.R0 = np.zeros((runs, 6, 6))
        for b in alive:
            member = self.members[b]
            engine = member.engine
            self.update_interval[b] = member.params["update_interval"]
            self.max_mag_age[b] = member.params["max_mag_age"]
            self.field_intensity[b] = engine.field_intensity
            self.gyro_noise[b] = engine.gyro_arw, engine.gyro_bias_rw
            self.R0[b] = engine.R0
        self._stack_windows(alive)
        if alive:
            engine = self.members[alive[0]].engine
            ukf = engine.ukf
            self.Wm, self.Wc, self.spread = ukf.Wm, ukf.Wc, ukf._spread
            self.gravity, self.field_unit = engine.gravity, engine.field_unit

    def _stack_windows(self, alive: List[int]) -> None:
        """The fuzzy adaptations of the runs that have one as the rows of one
        :class:`~navcore.filters.ahrs.FuzzyWindows` (``windows``; a run without one has
        window 0), their state taken by :meth:`_adopt`."""
        adaptives = [self.members[b].engine.adaptive if b in alive else None
                     for b in range(self.runs)]
        window = np.array([0 if a is None else a.window for a in adaptives], dtype=np.int64)
        self.windows = FuzzyWindows(
            np.zeros((self.runs, int(window.max(initial=0)), 6)),
            np.zeros(self.runs, dtype=np.int64), np.zeros((self.runs, 2)),
            np.zeros((self.runs, 2)), window,
            np.array([1.0 if a is None else a.r_scale_min for a in adaptives]),
            np.array([1.0 if a is None else a.r_scale_max for a in adaptives]))

    # -- the runs' own objects and the batch's stacks ------------------------------------
    def _adopt(self, b: int) -> None:
        """Take run b's engine and outputs into the batch (after its own code ran)."""
        member = self.members[b]
        engine = member.engine
        for name, path in _FIELDS:
            obj, attr = _engine_path(engine, path)
            getattr(self, name)[b] = getattr(obj, attr)
        self.dq[b] = engine.dq
        self.started[b] = engine.started
        adaptive = engine.adaptive
        if adaptive is not None:
            w = self.windows
            w.residuals[b, :adaptive.window] = adaptive.residuals
            w.count[b] = adaptive.count
            w.e[b], w.de[b] = adaptive.e, adaptive.de
        self.last_update[b] = member.last_update
        self.nav_time[b] = member.nav_time
        self.out[b] = self._outputs_of(member)

    def _lend(self, b: int) -> None:
        """Give run b's engine and shell the batch's values."""
        member = self.members[b]
        engine = member.engine
        for name, path in _FIELDS:
            obj, attr = _engine_path(engine, path)
            value = getattr(self, name)[b]
            setattr(obj, attr, value.item() if value.ndim == 0 else value.copy())
        engine.dq = tuple(self.dq[b].tolist())
        adaptive = engine.adaptive
        if adaptive is not None:
            w = self.windows
            adaptive.residuals = w.residuals[b, :adaptive.window].copy()
            adaptive.count = w.count[b].item()
            adaptive.e, adaptive.de = w.e[b].copy(), w.de[b].copy()
        member.nav_time = self.nav_time[b].item()
        member.last_update = self.last_update[b].item()
        out = member.out
        for name, value in zip(self.columns, self.out[b].tolist()):
            out[name] = type(out[name])(value)

    def _kept(self, rows: List[int]) -> None:
        if not hasattr(self, "x"):
            return
        for name in ("out", "x", "P", "dq", "interval", "r_scale", "last_nis", "ukf_nis",
                     "log_likelihood", "fallbacks", "switches", "started", "last_update",
                     "nav_time",
                     "update_interval", "max_mag_age", "field_intensity", "gyro_noise", "R0"):
            setattr(self, name, getattr(self, name)[rows])
        self.windows = FuzzyWindows(*(values[rows] for values in self.windows))
        self._blocks = {}                      # keyed by the runs' rows, which moved
        self._everyone = np.ones(len(rows), dtype=bool)

    def _alive(self) -> np.ndarray:
        if not self._failures:                 # the common case: one array, made once
            return self._everyone
        alive = np.ones(self.runs, dtype=bool)
        alive[list(self._failures)] = False
        return alive

    # -- stepping -------------------------------------------------------------------------
    def advance(self, t, h, inputs) -> np.ndarray:
        values = inputs.real_columns(_INPUT_NAMES)
        low, high = open_bounds(self, _INPUT_NAMES)
        step = np.empty(self.runs, dtype=np.int8)
        _steps_of_rows(values, low, high, self._alive(), self.started, self._native,
                       self.nav_time, self.out, self.columns["updated"], step)
        rows = (step == _NATIVE).nonzero()[0]
        self._step_rows(rows, values[rows])
        own = (step == _OWN).nonzero()[0].tolist()
        for b, values in zip(own, self._inputs_of_runs(own, inputs)):
            self._by_itself(b, lambda m, values=values: m.step(t, h, values))
        return self.out

    def _step_rows(self, rows: np.ndarray, v: np.ndarray) -> None:
        """:meth:`AhrsFilter.step` of the started runs ``rows`` (their inputs ``v``), each
        on the new IMU interval that follows its last one."""
        if not rows.size:
            return
        due = np.empty(len(rows), dtype=bool)
        accumulate_rows(rows, v[:, 0], v[:, 1], v[:, 2:5], v[:, 8], self.nav_time, self.dq,
                        self.interval, self.last_update, self.update_interval,
                        self.max_mag_age, due)
        updated = rows[due]
        if updated.size:
            v = v[due]
            updated = self._update_rows(updated, v[:, 5:8] / v[:, 1:2], v[:, 9:12], v[:, 0])
        self._write_solutions(rows, updated)

    def _update_rows(self, rows: np.ndarray, f_b: np.ndarray, m_b: np.ndarray,
                     imu_time: np.ndarray) -> np.ndarray:
        """:meth:`UkfAhrsEngine.update` of the runs ``rows``; the rows that updated."""
        # checked_covariance's state_error is None for every run whose x and P are finite
        usable = finite_rows(self.x, rows) & finite_rows(self.P, rows)
        if not usable.all():
            for i in (~usable).nonzero()[0].tolist():
                self.fail(int(rows[i]), state_error(self.x[rows[i]], self.P[rows[i]]))
            rows, f_b, m_b, imu_time = rows[usable], f_b[usable], m_b[usable], imu_time[usable]
        ok = self._predict_rows(rows)
        if not ok.all():
            rows, f_b, m_b, imu_time = rows[ok], f_b[ok], m_b[ok], imu_time[ok]
        ok = self._correct_rows(rows, f_b, m_b)
        if not ok.all():
            rows, imu_time = rows[ok], imu_time[ok]
        self.last_update[rows] = imu_time
        col = self.columns
        self.out[rows, col["updated"]] = 1.0
        self.out[rows, col["nis"]] = self.last_nis[rows]
        self.out[rows, col["nis_dof"]] = 6.0
        if "fuzzy_e_accel" in col and rows.size:
            fuzzy = [col[n] for n in ("fuzzy_e_accel", "fuzzy_e_mag", "fuzzy_de_accel",
                                      "fuzzy_de_mag")]
            self.out[rows[:, None], fuzzy] = np.concatenate((self.windows.e[rows],
                                                             self.windows.de[rows]), axis=1)
        return rows

    def _points(self, rows: np.ndarray) -> np.ndarray:
        """The sigma points of the runs ``rows`` (B, 13, 6), as each engine draws them
        (:meth:`UnscentedKalmanFilter.sigma_points`: a P that is not symmetric is
        symmetrized for them)."""
        X, fallback = sigma_points_rows(self.x[rows], self.P[rows], self.spread)
        self.fallbacks[rows] += fallback
        return X

    def _predict_rows(self, rows: np.ndarray) -> np.ndarray:
        """The time update of the runs ``rows``; which of them did not fail."""
        T = self.interval[rows]
        mrp = self.x[rows, :3]
        # |sigma|^2 of each run: numpy's stacked product of a row and a column takes each
        # slice's 1-D dot, the engine's float(x[:3] @ x[:3])
        squares = np.matmul(mrp[:, None, :], mrp[:, :, None])[:, 0, 0]
        diagonal = np.array([process_noise_diagonal(s, T_b, arw, rw)
                             for s, T_b, (arw, rw) in zip(squares.tolist(), T.tolist(),
                                                          self.gyro_noise[rows].tolist())])
        Q = np.zeros((len(rows), 6, 6))
        Q[:, _DIAGONAL, _DIAGONAL] = np.repeat(diagonal, 3, axis=1)
        X = self._points(rows)
        Y = propagate_points(X, self.dq[rows], T)
        x, P, finite = predicted_moments_rows(Y, self.Wm, self.Wc, Q,
                                              np.ones(len(rows)))
        taken = slice(None)
        if not finite.all():
            for b in rows[~finite].tolist():
                self.fail(b, predicted_state_error())
            rows, taken = rows[finite], finite
        self.x[rows], self.P[rows] = x[taken], P[taken]
        self.dq[rows] = (1.0, 0.0, 0.0, 0.0)
        self.interval[rows] = 0.0
        self._shadow_rows(rows)
        return finite

    def _correct_rows(self, rows: np.ndarray, f_b: np.ndarray, m_b: np.ndarray) -> np.ndarray:
        """The measurement update of the runs ``rows``; which of them did not fail."""
        X = self._points(rows)
        Z = measure_points(X.reshape(-1, 6), self.gravity, self.field_unit).reshape(X.shape)
        z = np.concatenate((f_b, m_b / self.field_intensity[rows][:, None]), axis=1)
        z_pred, Pzz, Pxz = measurement_moments_rows(X, Z, self.x[rows], self.Wm, self.Wc)
        self._adapt_r(rows, z - z_pred, Pzz)
        R = self.R0[rows] * np.repeat(self.r_scale[rows], 3, axis=1)[:, :, None]
        result = correct_rows(self.x[rows], self.P[rows], z, z_pred, Pzz + R, Pxz)
        ok = result.status == 0
        taken = slice(None)
        if not ok.all():
            for i in (~ok).nonzero()[0].tolist():
                self.fail(int(rows[i]), correction_error(result.status[i]))
            rows, taken = rows[ok], ok
        self.x[rows], self.P[rows] = result.x[taken], result.P[taken]
        self.last_nis[rows] = self.ukf_nis[rows] = result.nis[taken]
        self.log_likelihood[rows] = result.log_likelihood[taken]
        self._shadow_rows(rows)
        return ok

    def _adapt_r(self, rows: np.ndarray, innovations: np.ndarray, Pzz: np.ndarray) -> None:
        """The fuzzy adaptation of R of the runs ``rows`` that have one, in one
        :func:`~navcore.filters.ahrs.adapt_r_scales` call on the batch's windows."""
        picked = (self.windows.window[rows] > 0).nonzero()[0]
        if not picked.size:
            return
        runs = rows[picked]
        key = tuple(runs.tolist())
        blocks = self._blocks.get(key)
        if blocks is None:           # the runs' inferences, in the order of these runs
            blocks = self._blocks[key] = StackedInference(
                [self.members[b].engine.adaptive.inference for b in key for _ in range(2)])
        self.r_scale[runs] = adapt_r_scales(self.windows, runs, blocks, innovations[picked],
                                            Pzz[picked], self.R0[runs], self.r_scale[runs])[0]

    def _shadow_rows(self, rows: np.ndarray) -> None:
        """Each engine's switch to the shadow MRP (:func:`shadow_switched`, its own test)."""
        near = np.empty(len(rows), dtype=bool)
        _near_shadow_rows(self.x, rows, near)
        for b in rows[near].tolist():
            switched = shadow_switched(self.x[b], self.P[b])
            if switched is not None:
                self.x[b], self.P[b] = switched
                self.switches[b] += 1

    def _write_solutions(self, rows: np.ndarray, updated: np.ndarray) -> None:
        """:meth:`AhrsFilter._write_solution` of the runs ``rows`` (sigmas: ``updated``); a
        run whose state is not finite writes its own (its DivergenceError)."""
        finite = finite_rows(self.x, rows)
        if not finite.all():
            for b in rows[~finite].tolist():
                self._by_itself(b, lambda m: m._write_solution(sigmas=False))
            rows = rows[finite]
            updated = updated[np.isin(updated, rows)]
        solution_rows(self.out, rows, self.x, self.interval, self.dq, self.nav_time,
                      self.r_scale, self._solution_columns)
        if updated.size:
            self.out[updated[:, None], self._std_columns] = euler_sigma_rows(
                self._points(updated), self.Wm, self.Wc)


__all__ = ["AhrsFilterBatch"]
