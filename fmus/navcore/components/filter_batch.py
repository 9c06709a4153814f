"""The Kalman filters' batch (:mod:`navcore.core.batch`): B runs of one INS/GNSS filter of the
Kf family (:mod:`navcore.components.kf_components`) with their IMU intervals propagated in
one call.

Every run keeps its own component object (its parameters, engine, latency history,
initializer, NIS monitor: the single run's code).  What a batch does for all runs at once is
the work of every IMU interval, when every run takes the same interval (the runs of a batch
share their trajectory, so their time tags agree):

* the mechanization and covariance propagation by :func:`~navcore.filters.ins_gnss_kf.
  propagate_rows`, the function each engine's own ``propagate`` calls with one run, on the
  runs' state stacked here (the strapdown rows are the engines' own: each engine's
  ``nav.rows`` is a view of its row);
* the solution outputs (position, velocity, attitude from the rows, biases, the sigmas of
  the covariance diagonal), by the same functions as :meth:`InsGnssFilter._write_solution`,
  after the runs' new GNSS epochs;
* the arithmetic of the updates of the runs that apply a fix at the same step: a Kf's by
  :func:`~navcore.filters.ins_gnss_kf.predicted_rows` and :func:`~navcore.filters.
  ins_gnss_kf.kalman_rows`, an adaptive or robust law's by its engines'
  :meth:`~navcore.filters.adaptive_filters.RowUpdates.updates` (the functions each engine's
  own ``update`` calls with one run), each run's own code running before it (the epoch,
  the measurement) and after it (the feedback, the law's counters and history, the latency
  history's restart, the outputs and the NIS monitor).

Everything else is the run's own component, called for that run only: a new GNSS epoch
(its fix held or rolled back; applied, for an engine that updates otherwise), a checkpoint
of its latency history falling due, a run not started yet (initial state from the data), a
fix waiting in the future, an input it refuses, an IMU interval that is not the runs'
common one.  Before such a call the run's
engine is given the batch's values (:meth:`_lend`: its propagated parts, the IMU intervals
its history and its clocks have not seen yet, in order) and after it the batch takes the
engine's (:meth:`_adopt`), so the run computes exactly what it computes alone.
"""
from __future__ import annotations

import math
from typing import Dict, List

import numpy as np

from ..core import signals
from ..core.batch import ComponentBatch, open_bounds, row_accepted
from ..core.kernels import kernel
from ..core.timing import same_time, time_tolerance
from ..filters.adaptive_filters import RowUpdates
from ..filters.ins_gnss_kf import KfEngine, kalman_rows, predicted_rows, propagate_rows
from ..filters.latency import checkpoint_due, checkpoint_spacing
from ..ins.error_model import transition_template
from ..ins.rotations import pitch_from_elements, roll_yaw_from_elements
from ..ins.strapdown import Strapdown

_IMU = ("imu_time", "imu_dt", "imu_dtheta_x", "imu_dtheta_y", "imu_dtheta_z", "imu_dvel_x",
        "imu_dvel_y", "imu_dvel_z")
_STD_NAMES = tuple(p.name for p in signals.FILTER_OUTPUTS if p.name.startswith("std_"))
_STACKED = ("gyro_bias", "accel_bias", "phi_acc", "q_acc", "rate_ib", "P")


class InsGnssFilterBatch(ComponentBatch):
    """B runs of a Kf-family filter (module docstring)."""

    def _started(self, start_time: float) -> np.ndarray:
        runs = self.runs
        self.out = np.zeros((runs, len(self.columns)))
        alive = [b for b in range(runs) if b not in self._failures]
        first = self.members[alive[0]] if alive else None
        # an engine that propagates otherwise (a subclass's own law) runs its own code
        # the land aids update inside the run's own integration: each run steps by itself
        self._native = (first is not None and self._propagates_like_kf(first)
                        and not any(self.members[b].engine.aids is not None for b in alive))
        self._together = self._native and (self._updates_like_kf(first)
                                           or self._updates_in_rows(first))
        self._taus = len({(m.engine.config.gyro_bias_tau, m.engine.config.accel_bias_tau)
                          for b, m in enumerate(self.members) if b in alive}) == 1
        self.rows = np.zeros((runs, 24))
        self._views = [None] * runs             # each engine's nav.rows: its row here
        self.stack = {name: np.zeros((runs,) + np.shape(getattr(first.engine, name)))
                      for name in self.STACKED} if first is not None else {}
        self.q_density = np.zeros((runs, 15))
        # per run, what decides whether its own code runs this step (kept by _sync)
        self.own = np.ones(runs, dtype=bool)    # not started yet, or a fix held back
        self.last_epoch = np.zeros(runs, dtype=np.int64)
        self.last_checkpoint = np.full(runs, np.inf)
        self.max_fix_age = np.zeros(runs)
        self.dense = np.zeros(runs, dtype=bool)
        self._earliest_checkpoint = None        # (time, dt): no checkpoint due before
        self.seen: List[int] = [0] * runs       # log entries each run's engine has seen
        self.log: List[tuple] = []              # (imu_time, dtheta (B,3), dvel (B,3), dt)
        self.first_entry = 0                    # log index of self.log[0]
        self.nav_time = start_time
        self._template = (None, None)
        c = self.columns
        names = signals.NAV_SOLUTION_NAMES + signals.NAV_BG_NAMES + signals.NAV_BA_NAMES \
            + _STD_NAMES
        first_col = c[names[0]]
        # the solution outputs are consecutive columns (signals.FILTER_OUTPUTS)
        assert [c[n] for n in names] == list(range(first_col, first_col + len(names)))
        self._solution_col = first_col
        self._solution_names = names
        for b in alive:
            self._adopt(b)
        return self.out.copy()

    #: the methods of the filter shell (the class that names this batch) it stands for
    SHELL_METHODS = ("step", "_new_interval", "_integrate", "_take_epoch", "_write_solution")

    @property
    def shell(self):
        """The class of the component's hierarchy that names this batch class."""
        return next(c for c in self.component_class.__mro__
                    if c.__dict__.get("batch_class") is type(self))

    #: the engine's attributes the batch stacks (what an IMU interval changes, and what the
    #: solution outputs read), and the engine class whose propagation it stands for
    STACKED = _STACKED
    ENGINE = KfEngine

    def _propagates_like_kf(self, member) -> bool:
        """The batch stands for the run's own code only where that is the shell's and the
        engine's (:attr:`ENGINE`; a subclass that steps or propagates otherwise runs its own
        code)."""
        engine = type(member.engine)
        return (engine.propagate is self.ENGINE.propagate
                and engine.covariance_diagonal is self.ENGINE.covariance_diagonal
                and type(member.engine.nav).update is Strapdown.update
                and all(getattr(type(member), name) is getattr(self.shell, name)
                        for name in self.SHELL_METHODS))

    def _updates_like_kf(self, member) -> bool:
        """Whether the batch may compute the run's updates with the other runs' (one call
        of :func:`~navcore.filters.ins_gnss_kf.predicted_rows` and
        :func:`~navcore.filters.ins_gnss_kf.kalman_rows`): where its shell applies a fix
        as :meth:`InsGnssFilter._apply` (measure, update, take the result) and its engine
        updates as :meth:`KfEngine.update` (those two functions, then its ``updated``)."""
        engine = type(member.engine)
        return (type(member)._apply is self.shell._apply
                and all(getattr(engine, name) is getattr(KfEngine, name)
                        for name in ("update", "predicted_parts", "kalman_update")))

    def _updates_in_rows(self, member) -> bool:
        """Whether the batch may compute the run's updates with the other runs' by one call
        of its engine's :meth:`~navcore.filters.adaptive_filters.RowUpdates.updates`: where
        its shell applies a fix as :meth:`InsGnssFilter._apply` and its engine updates as
        :meth:`RowUpdates.update` (the adaptive and robust laws)."""
        engine = type(member.engine)
        return (type(member)._apply is self.shell._apply and issubclass(engine, RowUpdates)
                and engine.update is RowUpdates.update)

    # -- the runs' own objects and the batch's stacks ------------------------------------
    def _adopt(self, b: int) -> None:
        """Take run b's engine and outputs into the batch (after its own code ran)."""
        member = self.members[b]
        engine = member.engine
        nav = engine.nav
        if nav.rows is not self._views[b]:      # a new engine (a start, a rollback)
            self.rows[b] = nav.rows[0]
            nav.rows = self._views[b] = self.rows[b:b + 1]
        for name, stacked in self.stack.items():
            stacked[b] = getattr(engine, name)
        self.q_density[b] = engine.q_density
        self.seen[b] = self.first_entry + len(self.log)
        self.out[b] = self._outputs_of(member)
        self._sync(b)

    def _sync(self, b: int) -> None:
        """Run b's flags that the batch reads every step, from its own objects."""
        member = self.members[b]
        self.own[b] = not member.initializer.done or bool(member.pending)
        self.last_epoch[b] = member.last_epoch
        self.last_checkpoint[b] = (member.history.checkpoints[-1][0] if member.applies_fixes
                                   else np.inf)
        self.max_fix_age[b] = member.max_fix_age
        self.dense[b] = member.late_fixes
        self._earliest_checkpoint = None

    def _lend(self, b: int, hold_last: bool = False, fix_time=None) -> None:
        """Give run b's engine, history and clocks what the batch did since its last turn
        (``hold_last``: the history all but the latest interval, which
        :meth:`_record_last` adds after the engine's own work on that interval;
        ``fix_time``: the time of a valid fix the run receives next, whose
        :meth:`~InsGnssFilter.applies_at_once` leaves its history untouched, as the update
        restarts it)."""
        member = self.members[b]
        engine = member.engine
        for name, stacked in self.stack.items():
            value = stacked[b]
            setattr(engine, name, value.item() if value.ndim == 0 else value.copy())
        entries = self.log[self.seen[b] - self.first_entry:]
        if type(engine).advance_clocks is not KfEngine.advance_clocks:   # its own, per dt
            for entry in entries:
                engine.advance_clocks(entry[3])
        elif type(engine).advance_clocks_over is not KfEngine.advance_clocks_over:
            engine.advance_clocks_over([entry[3] for entry in entries])
        if entries:
            member.nav_time, member.imu_dt = entries[-1][0], entries[-1][3]
        if entries and member.applies_fixes and (
                fix_time is None or not member.applies_at_once(fix_time)):
            # only the latest interval can be due for a checkpoint: the batch lends a run
            # at every interval that is (_propagate)
            # (views: the log's arrays are never written after they are logged)
            increments = [(t, dtheta[b], dvel[b], dt) for t, dtheta, dvel, dt in entries]
            history = member.history
            history.extend(increments[:-1], member.max_fix_age + entries[-1][3])
            if hold_last:
                self._held = increments[-1]
            else:
                history.record(increments[-1], engine, member.max_fix_age + entries[-1][3],
                               member.late_fixes)
        self.seen[b] = self.first_entry + len(self.log)
        self._sync(b)

    def _lend_solution(self, b: int) -> None:
        """Give run b's outputs the solution the batch wrote last, before a step of its
        own code (one that integrates nothing nor updates leaves them as they are)."""
        out = self.members[b].out
        names, c = self._solution_names, self._solution_col
        out.update(zip(names, self.out[b, c:c + len(names)].tolist()))
        out["nav_time"] = self.out[b, self.columns["nav_time"]].item()

    def _record_last(self, b: int) -> None:
        """The interval :meth:`_lend` held back, into run b's history now."""
        member, increment = self.members[b], self._held
        member.history.record(increment, member.engine, member.max_fix_age + increment[3],
                              member.late_fixes)

    def _kept(self, rows: List[int]) -> None:
        if not hasattr(self, "rows"):
            return
        for old in rows:        # every kept run up to date: the log restarts for them
            self._lend(old)
        members = [self.members[i] for i in rows]
        for name in ("rows", "q_density", "out", "own", "last_epoch", "last_checkpoint",
                     "max_fix_age", "dense"):
            setattr(self, name, getattr(self, name)[rows])
        self.stack = {k: v[rows] for k, v in self.stack.items()}
        self._earliest_checkpoint = None
        self.seen = [self.first_entry + len(self.log)] * len(rows)
        self._views = [None] * len(rows)
        for b, member in enumerate(members):
            member.engine.nav.rows = self._views[b] = self.rows[b:b + 1]

    def _trim_log(self) -> None:
        """Forget the log entries every run has seen."""
        oldest = min(self.seen)
        if oldest > self.first_entry:
            del self.log[:oldest - self.first_entry]
            self.first_entry = oldest

    # -- stepping -------------------------------------------------------------------------
    def advance(self, t, h, inputs) -> np.ndarray:
        imu = inputs.real_columns(_IMU)
        interval = self._common_interval(imu)
        if interval is None:
            runs = [b for b in range(self.runs) if b not in self._failures]
            for b, values in zip(runs, self._inputs_of_runs(runs, inputs)):
                self._lend_solution(b)
                self._by_itself(b, lambda m, values=values: m.step(t, h, values))
            self.nav_time = self.members[0].nav_time
            return self.out
        imu_time, dt = interval
        self._propagate(imu, imu_time, dt)
        epoch = inputs["gnss_epoch"]
        taken = (self._take_epochs(np.flatnonzero(epoch != self.last_epoch).tolist(), inputs)
                 if _any_new_epoch(epoch, self.last_epoch) else ())
        self._write_solutions()
        updated = self.columns["updated"]
        for b in taken:            # the solution rows' updated = 0 is not theirs
            self.out[b, updated] = self.members[b].out["updated"]
        self._trim_log()
        return self.out

    def _take_epochs(self, epochs: List[int], inputs) -> List[int]:
        """The runs ``epochs`` take their new GNSS epoch by their own code (the part of
        :meth:`InsGnssFilter.step` after the integration but the solution, which
        :meth:`_write_solutions` writes next for every run by the same functions); the
        fixes they apply at once update together where the runs update as a Kf
        (:meth:`_update_together`).  Returns the runs that took their epoch without error."""
        taken, measured = [], []
        for b, values in zip(epochs, self._inputs_of_runs(epochs, inputs)):
            if b in self._failures:
                continue
            fix_time = values["gnss_time"] if values["gnss_valid"] else None
            if not self._together:
                self._by_itself(b, lambda m: self._epoch(m, values), fix_time=fix_time)
            else:
                self._lend(b, fix_time=fix_time)
                member = self.members[b]
                try:
                    member.out["updated"] = False
                    fix = member._epoch_fix(values)
                    z = None if fix is None else member._measure(fix)
                except Exception as exc:          # the run's own error
                    self.fail(b, exc)
                    continue
                if z is not None:
                    measured.append((b, z))
                    continue
                self._adopt(b)
            if b not in self._failures:
                taken.append(b)
        if measured:
            self._update_together(measured)
            taken += [b for b, _ in measured if b not in self._failures]
        return taken

    def _update_together(self, measured: List[tuple]) -> None:
        """The updates of the runs ``measured`` ((run, z): lent, their own code run up to
        :meth:`KfEngine.update`): its arithmetic for all of them in one call of
        :func:`~navcore.filters.ins_gnss_kf.predicted_rows` and
        :func:`~navcore.filters.ins_gnss_kf.kalman_rows` on the batch's stacks (the values
        each engine was lent), then each run's own code after it
        (:meth:`KfEngine.updated`, :meth:`InsGnssFilter._applied`), and the run taken back.
        When the runs measure different quantities or a run's solve fails (a singular or
        non-finite innovation covariance fails the whole call), every run updates by its
        own :meth:`KfEngine.update`, which fails that run alone."""
        rows = [b for b, _ in measured]
        members = [self.members[b] for b in rows]
        together = None
        if len({len(z) for _, z in measured}) == 1 and isinstance(members[0].engine, RowUpdates):
            self._update_in_rows(measured, members)
            return
        if len({len(z) for _, z in measured}) == 1:
            stack = self.stack
            try:
                P_pred = (predicted_rows(stack["P"][rows], stack["phi_acc"][rows])
                          + stack["q_acc"][rows])
                together = kalman_rows(P_pred, np.array([z for _, z in measured]),
                                       np.array([m.engine.R0 for m in members]),
                                       members[0].engine.H)
            except np.linalg.LinAlgError:
                together = None
        for i, (b, z) in enumerate(measured):
            member = members[i]
            try:
                if together is None:
                    result = member.engine.update(z)
                else:
                    dx, P, v, S, _ = (part[i] for part in together)
                    result = member.engine.updated(dx, P, v, S)
                member._applied(z, result)
            except Exception as exc:              # the run's own error
                self.fail(b, exc)
                continue
            self._adopt(b)

    def _update_in_rows(self, measured: List[tuple], members: list) -> None:
        """:meth:`_update_together` of runs whose engines update by their laws' rows: one
        call of the engines' :meth:`~navcore.filters.adaptive_filters.RowUpdates.updates`
        on the batch's stacks, which returns each run's result or its own error, then each
        run's own :meth:`InsGnssFilter._applied`."""
        rows = [b for b, _ in measured]
        stack = self.stack
        results = type(members[0].engine).updates(
            [member.engine for member in members], np.array([z for _, z in measured]),
            stack["P"][rows], stack["phi_acc"][rows], stack["q_acc"][rows])
        for (b, z), member, result in zip(measured, members, results):
            try:
                if isinstance(result, Exception):
                    raise result
                member._applied(z, result)
            except Exception as exc:              # the run's own error
                self.fail(b, exc)
                continue
            self._adopt(b)

    @staticmethod
    def _epoch(member, inputs) -> None:
        """:meth:`InsGnssFilter.step` after the integration, for a new epoch, but the
        solution outputs."""
        member.out["updated"] = False
        member._take_epoch(inputs)

    def _common_interval(self, imu: np.ndarray):
        """(imu_time, imu_dt) when every run integrates that same new interval now; None
        when any run needs its own code for this step."""
        if not self._native or not self._taus or self._failures:
            return None
        low, high = open_bounds(self, _IMU)
        if not _one_accepted_interval(imu, low, high, self.own):
            return None
        imu_time, dt = imu[0, :2].tolist()
        nav_time = self.nav_time
        if not (imu_time > nav_time + 0.5 * dt and dt > 0
                and same_time(imu_time - dt, nav_time, dt)):
            return None
        return imu_time, dt

    def _propagate(self, imu: np.ndarray, imu_time: float, dt: float) -> None:
        dtheta, dvel = imu[:, 2:5], imu[:, 5:8]
        self._propagate_rows(dtheta, dvel, dt)
        self.log.append((imu_time, dtheta, dvel, dt))
        self.nav_time = imu_time
        self._after_interval()
        earliest = self._earliest_checkpoint
        if earliest is None or earliest[1] != dt:
            times = self.last_checkpoint + checkpoint_spacing(self.max_fix_age + dt, self.dense)
            earliest = self._earliest_checkpoint = (float(times.min(initial=np.inf)), dt)
        # no run's checkpoint falls due before its last one plus its spacing, less the time
        # tolerance (twice: the rounding of both sums)
        if imu_time < earliest[0] - 2.0 * time_tolerance(dt, imu_time):
            return
        due = checkpoint_due(imu_time, self.last_checkpoint, dt, self.max_fix_age + dt,
                             self.dense)
        if due.any():
            for b in np.flatnonzero(due).tolist():    # its latency history checkpoints now
                self._lend(b)

    def _after_interval(self) -> None:
        """Hook: the runs' own code an engine runs after an interval (none for the Kf)."""

    def _propagate_rows(self, dtheta, dvel, dt: float) -> None:
        """Every run's interval (:func:`~navcore.filters.ins_gnss_kf.propagate_rows`)."""
        stack = self.stack
        key, template = self._template
        if key != dt:            # the runs' time constants are one (_common_interval)
            cfg = self.members[0].engine.config
            template = transition_template(dt, cfg.gyro_bias_tau, cfg.accel_bias_tau)
            self._template = (dt, template)
        stack["phi_acc"], stack["q_acc"], stack["rate_ib"] = propagate_rows(
            self.rows, stack["gyro_bias"], stack["accel_bias"], stack["phi_acc"],
            stack["q_acc"], self.q_density, dtheta, dvel, dt, template)

    def _write_solutions(self) -> None:
        """The solution outputs of every run (InsGnssFilter._write_solution's values)."""
        out = self.out
        rows = self.rows
        stack = self.stack
        c = self._solution_col
        columns = self.columns
        _solution_rows(out, c, rows, stack["gyro_bias"], stack["accel_bias"],
                       self._covariance_diagonals(), float(self.nav_time),
                       columns["nav_time"], columns["updated"])
        if math.isfinite(out.sum()):     # NaN or inf anywhere makes the sum non-finite
            return
        for b in np.flatnonzero(~np.isfinite(out).all(axis=1)).tolist():
            self._by_itself(b, lambda m: m._write_solution())

    def _covariance_diagonals(self) -> np.ndarray:
        """Every run's :meth:`KfEngine.covariance_diagonal` (B, 15)."""
        stack = self.stack
        phi = stack["phi_acc"]
        return (np.einsum("bij,bij->bi", phi @ stack["P"], phi)
                + np.diagonal(stack["q_acc"], axis1=1, axis2=2))


@kernel
def _one_accepted_interval(imu, low, high, own) -> bool:
    """Whether every run's IMU inputs (rows of ``imu``, columns :data:`_IMU`) have the first
    run's ``imu_time`` and ``imu_dt`` and lie in their ranges (:func:`~navcore.core.batch.
    row_accepted`), and no run is ``own``."""
    if imu.shape[0] == 0:
        return False
    imu_time, dt = imu[0, 0], imu[0, 1]
    for b in range(imu.shape[0]):
        if own[b] or imu[b, 0] != imu_time or imu[b, 1] != dt:
            return False
        if not row_accepted(imu[b], low, high):
            return False
    return True


@kernel
def _any_new_epoch(epoch, last_epoch) -> bool:
    """Whether any run's ``gnss_epoch`` input differs from the last epoch it took."""
    for b in range(epoch.shape[0]):
        if epoch[b] != last_epoch[b]:
            return True
    return False


@kernel
def _solution_rows(out, col, rows, gyro_bias, accel_bias, diagonal, nav_time, time_col,
                   updated_col):
    """The solution outputs of every run, into ``out`` (B, n_outputs) from column ``col``
    on, in :data:`~navcore.core.signals.FILTER_OUTPUTS`' order: position and velocity (the
    strapdown rows' first six columns), roll, pitch and yaw
    (:func:`~navcore.ins.rotations.roll_yaw_from_elements` and
    :func:`~navcore.ins.rotations.pitch_from_elements`, as :meth:`Strapdown.solution`),
    the biases, the sigmas ``sqrt(max(d, 0))`` of the covariance diagonals ``d`` (as numpy's
    ``maximum``: NaN and -0.0 pass), then ``nav_time`` and ``updated`` = 0."""
    for b in range(rows.shape[0]):
        o = out[b]
        r = rows[b]
        for j in range(6):
            o[col + j] = r[j]
        # C_bn by rows in columns 6..14: C[i][j] is column 6 + 3 i + j
        o[col + 6], o[col + 8] = roll_yaw_from_elements(r[6], r[9], r[13], r[14])
        o[col + 7] = pitch_from_elements(r[12], r[13], r[14])
        for j in range(3):
            o[col + 9 + j] = gyro_bias[b, j]
            o[col + 12 + j] = accel_bias[b, j]
        for j in range(diagonal.shape[1]):
            d = diagonal[b, j]
            o[col + 15 + j] = math.sqrt(d if d >= 0.0 or d != d else 0.0)
        o[time_col] = nav_time
        o[updated_col] = 0.0


__all__ = ["InsGnssFilterBatch"]
