"""The UKF family's batch (:mod:`navcore.core.batch`): B runs of Ukf, CtfaUkf or ImmUkf
(:mod:`navcore.components.ukf_components`) with their IMU intervals and sigma-point
predictions computed for all runs at once.

It is the Kalman filters' batch (:mod:`navcore.components.filter_batch`: every run keeps its
own component; a fix held back or applied in the past, a checkpoint or a run not started yet
runs the run's own code, lent the batch's values first) with the UKF engines' time update
(:meth:`~navcore.filters.ukf_filters.UkfEngine.propagate`) in place of the Kf's:

* every IMU interval of all runs: the bias compensation, the mechanization and the interval
  sums in one :func:`~navcore.filters.ukf_time_update.advance_interval_rows` call, the
  function each engine calls with one run;
* the runs whose prediction interval is complete predict together: one
  :func:`~navcore.filters.ukf_time_update.predict_rows` call, the function each engine calls
  with one run (with the models of its bank for the IMM: the models of all runs' banks in
  one call, after the mixing of the banks whose cycle starts, in one
  :func:`~navcore.filters.imm.mix_banks` call, and their combination after, in one
  :func:`~navcore.filters.imm.imm_combine_rows` call: the functions each bank calls with
  one bank).  An engine that predicts otherwise (a subclass), or whose filter is
  not in the state the call expects (a covariance not finite or not symmetric, other
  unscented-transform parameters or another number of IMM models than the batch's first
  run), predicts by its own code, before the interval enters its latency history, as it
  does alone;
* the runs that apply a fix at the same step update together
  (:meth:`UkfFilterBatch._update_together`): each run's own code before the update (its
  epoch, its measurement, :meth:`~navcore.filters.ukf_filters.UkfEngine.measured_filters`),
  the filters of all runs in one :func:`~navcore.filters.unscented_rows.update_filters` call
  and the IMM banks' probabilities and combinations in one
  :func:`~navcore.filters.imm.update_banks` call (the functions each engine's own ``update``
  calls with its filters), then each run's own code after it (the feedback, the latency
  history's restart, the outputs); a run whose part fails fails alone with its own error.
"""
from __future__ import annotations

from typing import List

import numpy as np

from ..core.kernels import kernel
from ..filters.imm import ImmBank, imm_combine_rows, mix_banks
from ..filters.ukf_filters import ImmUkfEngine, UkfEngine
from ..filters.ukf_time_update import (N_SUMS, advance_interval_rows, discrete_process_noise,
                                       interval_means, predict_filter_groups, predict_rows,
                                       prediction_due)
from ..filters.unscented_rows import (checked_covariances, finite_symmetric_rows,
                                      predicted_state_error, update_filters)
from ..ins.error_model import N_STATES
from .filter_batch import InsGnssFilterBatch

#: the unscented filter's attributes stacked for a natively predicted engine
_UKF_FIELDS = ("x", "P", "sqrt_fallbacks")


class UkfFilterBatch(InsGnssFilterBatch):
    """B runs of a filter of the UKF family (module docstring)."""

    STACKED = ("gyro_bias", "accel_bias", "rate_ib", "q_scale", "sums")
    ENGINE = UkfEngine

    def _started(self, start_time: float) -> np.ndarray:
        runs = self.runs
        self._diagonal = np.zeros((runs, 15))       # of each engine's prediction_covariance
        self._predict_interval = np.zeros(runs)
        self._ukf = {}
        self._q_cache = {}
        self._models_q_cache = {}               # the kept Q of all runs, for each model
        self._models_q_scales_cache = None
        self._predicted = None                  # (x, P, views) of the last bank prediction
        alive = [m for b, m in enumerate(self.members) if b not in self._failures]
        engine = alive[0].engine if alive else None
        # the runs predict together when their engines predict as a Ukf with one transform
        self._natively_predicted, self._banks_predicted = (engine is not None and all(
            self._predicts_as(m.engine, engine, kind) for m in alive)
            for kind in (UkfEngine, ImmUkfEngine))
        if self._natively_predicted:
            self._ukf = {name: np.zeros((runs,) + np.shape(getattr(engine.ukf, name)))
                         for name in _UKF_FIELDS}
        return super()._started(start_time)

    @staticmethod
    def _predicts_as(engine, first, kind_of_engine) -> bool:
        """Whether ``engine`` predicts as ``kind_of_engine`` does (UkfEngine: one filter,
        ImmUkfEngine: a bank of models) with ``first``'s transform and number of models."""
        kind = type(engine)
        if not (kind._predict is UkfEngine._predict
                and kind.predict_filters is kind_of_engine.predict_filters
                and kind.process_noise is UkfEngine.process_noise
                and (engine.alpha, engine.beta, engine.kappa)
                == (first.alpha, first.beta, first.kappa)):
            return False
        if kind_of_engine is UkfEngine:
            return engine.ukf is not None
        return (type(engine.bank).predict_all is ImmBank.predict_all
                and isinstance(first, ImmUkfEngine)
                and len(engine.bank.filters) == len(first.bank.filters))

    # -- the runs' own objects and the batch's stacks ------------------------------------
    def _adopt(self, b: int) -> None:
        engine = self.members[b].engine
        for name, stacked in self._ukf.items():
            stacked[b] = getattr(engine.ukf, name)
        self._predict_interval[b] = engine.predict_interval
        super()._adopt(b)
        self._diagonal[b] = np.diagonal(engine.prediction_covariance())

    def _lend(self, b: int, hold_last: bool = False, fix_time=None) -> None:
        ukf = self.members[b].engine.ukf
        for name, stacked in self._ukf.items():
            value = stacked[b]
            setattr(ukf, name, int(value) if value.ndim == 0 else value.copy())
        super()._lend(b, hold_last, fix_time)

    def _kept(self, rows: List[int]) -> None:
        started = hasattr(self, "rows")
        super()._kept(rows)          # it lends every kept run first: from the stacks uncut
        if started:
            self._diagonal = self._diagonal[rows]
            self._predict_interval = self._predict_interval[rows]
            self._ukf = {k: v[rows] for k, v in self._ukf.items()}
            self._q_cache = {}
            self._models_q_cache = {}
            self._models_q_scales_cache = None
            self._predicted = None

    # -- stepping -------------------------------------------------------------------------
    def _propagate_rows(self, dtheta, dvel, dt: float) -> None:
        """:meth:`UkfEngine.propagate` of every run up to its prediction."""
        stack = self.stack
        stack["rate_ib"] = advance_interval_rows(
            self.rows, stack["sums"].reshape(len(self.rows), N_SUMS), dtheta, dvel,
            stack["gyro_bias"], stack["accel_bias"], dt)

    def _after_interval(self) -> None:
        """The runs whose prediction interval is complete predict, together where they can,
        before the interval enters their history (as in InsGnssFilter._integrate)."""
        sums = self.stack["sums"][:, 0]
        due = prediction_due(sums[:, 0], self._predict_interval)
        if not due.any():
            return
        if self._banks_predicted:
            self._predict_banks(np.flatnonzero(due))
            return
        together = due & self._predictable() if self._natively_predicted else np.zeros_like(due)
        if together.any():
            self._predict_together(np.flatnonzero(together))
        for b in np.flatnonzero(due & ~together).tolist():
            self._predict_alone(b)

    def _predictable(self) -> np.ndarray:
        """The runs whose filter state is what :func:`predict_rows` takes (finite, P
        symmetric); the others' own code raises or symmetrizes as it does alone."""
        predictable = np.empty(self.runs, dtype=bool)
        finite_symmetric_rows(self._ukf["x"], self._ukf["P"], predictable)
        return predictable

    def _predict_together(self, rows: np.ndarray) -> None:
        """:meth:`UkfEngine._predict` of the runs ``rows`` in one :func:`predict_rows` call."""
        sums = self.stack["sums"][:, 0]
        first = self.members[rows[0]].engine
        cfg = first.config
        ukf = first.ukf
        x, P, fallback, finite = predict_rows(
            self._ukf["x"][rows], self._ukf["P"][rows], interval_means(sums[rows]),
            self._process_noise(rows, sums[rows, 0]), self.stack["q_scale"][rows],
            ukf.Wm, ukf.Wc, ukf._spread, cfg.gyro_bias_tau, cfg.accel_bias_tau)
        self._ukf["x"][rows] = x
        self._ukf["P"][rows] = P
        self._ukf["sqrt_fallbacks"][rows] += fallback
        self._diagonal[rows] = np.diagonal(P, axis1=1, axis2=2)
        sums[rows] = 0.0
        for i in np.flatnonzero(~finite).tolist():
            self.fail(int(rows[i]), predicted_state_error())

    def _predict_banks(self, rows: np.ndarray) -> None:
        """:meth:`UkfEngine._predict` of the IMM runs ``rows``: the banks whose cycle starts
        mix in one :func:`mix_banks` call, the models of all banks are checked
        (:func:`checked_covariances`) and predict in one :func:`predict_rows` call (every
        run's nominal interval spread over its banks' points), and the banks combine their
        models in one :func:`imm_combine_rows` call."""
        banks = {b: self.members[b].engine.bank for b in rows.tolist()}
        cycle_starts = [b for b, bank in banks.items() if bank.needs_mixing]
        for b, error in zip(cycle_starts, mix_banks([banks[b] for b in cycle_starts])):
            if error is not None:           # the run's own error
                self.fail(b, error)
                del banks[b]
        if not banks:
            return
        models = len(next(iter(banks.values())).filters)
        filters = [flt for bank in banks.values() for flt in bank.filters]
        stacked = self._predicted_states(filters)
        if stacked is not None:
            x, P = stacked
            errors = ()
        else:
            x, _, P, errors = checked_covariances(filters)
        if any(error is not None for error in errors):
            checked = []
            for i, b in enumerate(banks):   # a run fails with its first model's error
                error = next((e for e in errors[i * models:(i + 1) * models] if e is not None),
                             None)
                if error is not None:
                    self.fail(b, error)
                checked.append(error is None)
            banks = {b: bank for (b, bank), ok in zip(banks.items(), checked) if ok}
            x = x.reshape(-1, models, N_STATES)[checked].reshape(-1, N_STATES)
            P = P.reshape(-1, models, N_STATES, N_STATES)[checked].reshape(-1, N_STATES, N_STATES)
        if banks:
            self._predict_checked_banks(banks, x, P, models)

    def _predict_checked_banks(self, banks, x, P, models: int) -> None:
        """The prediction and combination of :meth:`_predict_banks` for the banks ``banks``
        (run: bank, in the runs' order) whose models' states are ``x`` and checked
        covariances ``P``."""
        rows = np.array(list(banks))
        # every run (the usual case): slices of the stacks instead of copies
        index = slice(None) if len(rows) == self.runs else rows
        filters = [flt for bank in banks.values() for flt in bank.filters]
        sums = self.stack["sums"][:, 0]
        cfg = self.members[rows[0]].engine.config
        finite, x, P = predict_filter_groups(
            filters, x, P, interval_means(sums[index]),
            self._models_process_noise(rows, sums[index, 0], models),
            self._models_q_scales(rows), cfg.gyro_bias_tau, cfg.accel_bias_tau, models)
        sums[index] = 0.0
        if finite.all():
            self._predicted = (x, P, [flt.x for flt in filters], [flt.P for flt in filters])
        x = x.reshape(-1, models, N_STATES)
        P = P.reshape(-1, models, N_STATES, N_STATES)
        if not finite.all():
            self._predicted = None
            for b in rows[~finite].tolist():
                self.fail(b, predicted_state_error())
            if not finite.any():
                return
            rows, index, x, P = rows[finite], rows[finite], x[finite], P[finite]
        combined = [banks[b] for b in rows.tolist()]
        x, P = imm_combine_rows(np.array([bank.mu for bank in combined]), x, P)
        for bank, state, covariance in zip(combined, list(x), list(P)):
            bank.x, bank.P = state, covariance
        self._diagonal[index] = np.diagonal(P, axis1=1, axis2=2)

    def _predicted_states(self, filters):
        """The states (F, n) and covariances (F, n, n) of the filters ``filters`` as the
        last bank prediction left them, when it did and nothing has replaced them since
        (each filter's ``x`` and ``P`` are still the views of that prediction's arrays,
        which nothing writes into): finite and symmetric, as :func:`checked_covariances`
        would find them; else None."""
        predicted = self._predicted
        if predicted is None:
            return None
        x, P, states, covariances = predicted
        if len(states) != len(filters) or not all(
                flt.x is state and flt.P is covariance
                for flt, state, covariance in zip(filters, states, covariances)):
            return None
        return x, P

    def _models_process_noise(self, rows: np.ndarray, T: np.ndarray, models: int) -> np.ndarray:
        """:meth:`_process_noise` of the runs ``rows``, each repeated for its ``models``
        models (kept, as the runs' own, for all runs' one interval)."""
        Q = self._process_noise(rows, T)
        interval = T[0].item()
        if Q is not self._q_cache.get(interval):
            return np.repeat(Q, models, axis=0)
        repeated = self._models_q_cache.get(interval)
        if repeated is None:
            repeated = self._models_q_cache[interval] = np.repeat(Q, models, axis=0)
        return repeated

    def _models_q_scales(self, rows: np.ndarray) -> np.ndarray:
        """The models' Q scales (:attr:`ImmUkfEngine.q_scales`) of the runs ``rows``, one
        after the other (parameters: kept for all runs)."""
        scales = self._models_q_scales_cache
        if scales is None:
            scales = self._models_q_scales_cache = np.stack(
                [member.engine.q_scales for member in self.members])
        return (scales if len(rows) == len(scales) else scales[rows]).reshape(-1)

    def _process_noise(self, rows: np.ndarray, T: np.ndarray) -> np.ndarray:
        """Every run's :meth:`UkfEngine.process_noise` of its interval ``T`` (all runs' for
        each T, kept: the runs' intervals are nearly always one, and then all runs' are the
        kept array itself, which predict_rows only reads)."""
        intervals = T.tolist()
        for interval in set(intervals) - self._q_cache.keys():
            self._q_cache[interval] = np.stack([discrete_process_noise(q, interval)
                                                for q in self.q_density])
        first = intervals[0]
        if len(intervals) == len(self.q_density) and intervals.count(first) == len(intervals):
            return self._q_cache[first]              # rows are then every run, in order
        return np.stack([self._q_cache[interval][b]
                         for b, interval in zip(rows.tolist(), intervals)])

    def _predict_alone(self, b: int) -> None:
        """Run b's prediction by its own engine."""
        member = self.members[b]
        self._lend(b, hold_last=True)
        try:
            member.engine._predict()
        except Exception as exc:      # the run's own error
            self.fail(b, exc)
            return
        if member.applies_fixes:
            self._record_last(b)
        self._adopt(b)

    # -- fixes ----------------------------------------------------------------------------
    def _updates_like_kf(self, member) -> bool:
        """Whether the batch may update the run's filters with the other runs' (one
        :func:`update_filters` call): where its shell applies a fix as
        :meth:`InsGnssFilter._apply` and its engine updates as :meth:`UkfEngine.update` with
        the linear measurement of :meth:`UkfEngine._h`."""
        engine = type(member.engine)
        return (type(member)._apply is self.shell._apply and engine.update is UkfEngine.update
                and engine._h is UkfEngine._h)

    def _update_together(self, measured: List[tuple]) -> None:
        """The updates of the runs ``measured`` ((run, z): lent, their own code run up to
        :meth:`UkfEngine.update`): each engine's code before its filters' update
        (:meth:`UkfEngine.measured_filters`: the prediction due, CTFA's reacquisition, the
        IMM's mixing and statistic), the filters of all runs in one :func:`update_filters`
        call, the IMM banks' probabilities and combinations in one
        :meth:`UkfEngine.filters_corrected` call, then each run's own code after it
        (:meth:`UkfEngine.update_finished`, :meth:`InsGnssFilter._applied`), and the run taken
        back.  Runs of other engine classes or measurement sizes update each by its own
        :meth:`UkfEngine.update`; a run whose part fails fails alone with its own error."""
        members = [self.members[b] for b, _ in measured]
        kinds = {(type(m.engine), m.engine.m, len(z)) for m, (_, z) in zip(members, measured)}
        if len(kinds) > 1 or self._differ_in_transform(members):
            for (b, z), member in zip(measured, members):
                try:
                    member._applied(z, member.engine.update(z))
                except Exception as exc:              # the run's own error
                    self.fail(b, exc)
                    continue
                self._adopt(b)
            return
        started = []                                  # (run, z, filters, before)
        for (b, z), member in zip(measured, members):
            try:
                filters, before = member.engine.measured_filters(z)
            except Exception as exc:                  # the run's own error
                self.fail(b, exc)
                continue
            started.append((b, z, filters, before))
        if not started:
            return
        counts = [len(filters) for _, _, filters, _ in started]
        engine = self.members[started[0][0]].engine
        filters = [flt for _, _, own, _ in started for flt in own]
        corrections, errors = update_filters(
            filters, np.repeat(np.array([z for _, z, _, _ in started]), counts, axis=0),
            np.repeat(np.array([self.members[b].engine.R0 for b, *_ in started]), counts,
                      axis=0), engine._h, self._predicted_states(filters))
        corrected, first = [], 0
        for (b, z, filters, before), count in zip(started, counts):
            own = corrections[first:first + count]
            error = next((e for e in errors[first:first + count] if e is not None), None)
            first += count
            if error is not None:
                self.fail(b, error)
            else:
                corrected.append((b, z, before, own))
        if not corrected:
            return
        errors = type(engine).filters_corrected([self.members[b].engine for b, *_ in corrected],
                                                [own for *_, own in corrected])
        for (b, z, before, own), error in zip(corrected, errors):
            member = self.members[b]
            try:
                if error is not None:
                    raise error
                member._applied(z, member.engine.update_finished(before, own))
            except Exception as exc:                  # the run's own error
                self.fail(b, exc)
                continue
            self._adopt(b)

    @staticmethod
    def _differ_in_transform(members) -> bool:
        """Whether the runs' filters differ in their unscented transform (the points of all
        runs' filters are one :func:`update_filters` call of one transform)."""
        return len({(m.engine.alpha, m.engine.beta, m.engine.kappa) for m in members}) > 1

    def _covariance_diagonals(self) -> np.ndarray:
        """Every run's :meth:`UkfEngine.covariance_diagonal` (B, 15)."""
        stack = self.stack
        diagonals = np.empty_like(self._diagonal)
        _pending_noise_rows(self._diagonal, stack["q_scale"], self.q_density,
                            stack["sums"][:, 0, 0], diagonals)
        return diagonals


@kernel
def _pending_noise_rows(diagonal, q_scale, q_density, T, out):
    """Every run's covariance diagonal at its last prediction plus the noise of its pending
    interval ``T``, ``diagonal + q_scale q_density T`` in :meth:`UkfEngine.
    covariance_diagonal`'s order (the scale times the density, then times T), into ``out``."""
    for b in range(diagonal.shape[0]):
        for i in range(diagonal.shape[1]):
            out[b, i] = diagonal[b, i] + q_scale[b] * q_density[b, i] * T[b]


__all__ = ["UkfFilterBatch"]
