"""The instances of a batch of runs (:mod:`orchestrator.cosim.batch`): one component of the
system holding B runs, behind the :class:`~orchestrator.cosim.backends.Instance` interface with
a leading run axis on every buffer (``real_in`` is ``(B, n_inputs)``, ``real_out`` a
``(B, n_outputs)`` view into the master's signal matrix).

:class:`LoopBatchInstance` serves a component class without a batched implementation: one
:class:`~orchestrator.cosim.direct_instance.DirectInstance` per run, stepped one after the
other, each reading and writing its own row of the batch's buffers, so every run computes
exactly what it computes alone.  :class:`NativeBatchInstance` serves a component class that
steps all runs in one call (its ``batch_class``, :mod:`navcore.core.batch`).

A run that fails (a refused parameter value, a divergence, a refused input) does not stop the
others: its error goes into the ``failures`` mapping the master shares with every instance
(batch row -> :class:`~orchestrator.errors.NavfmuError`), the failed row is no longer stepped,
and after the macro step the master drops it from every instance (:meth:`keep`).
"""
from __future__ import annotations

from abc import abstractmethod
from typing import Any, Dict, List, Mapping, Sequence

import numpy as np

from navcore.core.batch import BatchInputs
from navcore.errors import NavcoreError

from .backends import Instance, coerce
from .direct_instance import DirectInstance, parameter_error, simulation_error
from ..errors import NavfmuError

_BUFFERS = ("real_in", "int_in", "bool_in", "real_out", "int_out", "bool_out")


class BatchInstance(Instance):
    """What both kinds share: the (B, n) buffers, the shared failures, :meth:`keep`."""

    def __init__(self, name: str, variables, source: str, model_name: str, runs: int,
                 failures: Dict[int, NavfmuError]):
        super().__init__()
        self.name = name
        self.variables = variables
        self.source = source
        self.model_name = model_name
        self.runs = runs
        self.failures = failures

    def prepare(self, input_names: Sequence[str], output_names: Sequence[str],
                real_out=None, int_out=None, bool_out=None) -> None:
        """As :meth:`Instance.prepare`, every buffer with the run axis first; the output
        buffers are the master's ``(B, n)`` views."""
        self.input_names = self.names_by_type(input_names, ("input",))
        self.output_names = self.names_by_type(output_names, ("output",))
        b = self.runs
        self.real_in = np.zeros((b, len(self.input_names["Real"])))
        self.int_in = np.zeros((b, len(self.input_names["Integer"])), dtype=np.int32)
        self.bool_in = np.zeros((b, len(self.input_names["Boolean"])), dtype=np.int32)
        self.real_out, self.int_out, self.bool_out = real_out, int_out, bool_out
        self._bound()

    def keep(self, rows: Sequence[int], real_out, int_out, bool_out) -> None:
        """Keep the runs of batch ``rows`` (in that order), with the master's new output
        views; the inputs set so far stay (a Jacobi input holds between transfers)."""
        rows = list(rows)
        self.real_in, self.int_in, self.bool_in = (self.real_in[rows], self.int_in[rows],
                                                   self.bool_in[rows])
        self.real_out, self.int_out, self.bool_out = real_out, int_out, bool_out
        self.runs = len(rows)
        self._kept(rows)
        self._bound()

    def _bound(self) -> None:
        """Hook: the buffers are (re)bound."""

    def _kept(self, rows: List[int]) -> None:
        """Hook: drop the runs not in ``rows``."""

    def set_parameters(self, values: Mapping[str, Any]) -> None:
        self.set_run_parameters([values] * self.runs)

    @abstractmethod
    def set_run_parameters(self, values: Sequence[Mapping[str, Any]]) -> None:
        """Parameters per run (``values[b]`` for batch row b)."""

    def get_state(self):
        raise NavfmuError(f"component '{self.name}': a batch of runs has no saved state "
                          "(run one run to save and restore states)")

    def set_state(self, state) -> None:
        self.get_state()

    def take_run_warnings(self, row: int) -> List[str]:
        """The warnings of batch row ``row`` since the last call."""
        return []


class LoopBatchInstance(BatchInstance):
    """B :class:`DirectInstance` members, one per run (module docstring)."""

    def __init__(self, members: Sequence[DirectInstance], failures: Dict[int, NavfmuError]):
        first = members[0]
        super().__init__(first.name, first.variables, first.source, first.model_name,
                         len(members), failures)
        self.members: List[DirectInstance] = list(members)

    def prepare(self, input_names, output_names, real_out=None, int_out=None,
                bool_out=None) -> None:
        for b, member in enumerate(self.members):
            member.prepare(input_names, output_names, real_out[b], int_out[b], bool_out[b])
        super().prepare(input_names, output_names, real_out, int_out, bool_out)

    def _bound(self) -> None:
        """Every member reads and writes its row of the batch's buffers."""
        for b, member in enumerate(self.members):
            for buffer in _BUFFERS:
                setattr(member, buffer, getattr(self, buffer)[b])
            member._prepared()

    def _kept(self, rows: List[int]) -> None:
        kept = [self.members[i] for i in rows]
        for i, member in enumerate(self.members):
            if i not in rows:
                member.terminate()
        self.members = kept

    def _each(self, call) -> None:
        """``call(member)`` for every run still alive; an error fails that run alone."""
        failures = self.failures
        for b, member in enumerate(self.members):
            if b in failures:
                continue
            try:
                call(member)
            except NavfmuError as exc:
                failures[b] = exc

    def set_run_parameters(self, values: Sequence[Mapping[str, Any]]) -> None:
        failures = self.failures
        for b, member in enumerate(self.members):
            if b in failures:
                continue
            try:
                member.set_parameters(values[b])
            except NavfmuError as exc:
                failures[b] = exc

    def enter_initialization(self, start_time, stop_time) -> None:
        self._each(lambda member: member.enter_initialization(start_time, stop_time))

    def exit_initialization(self) -> None:
        self._each(DirectInstance.exit_initialization)

    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        self._copy_in(real_values, int_values, bool_values)
        for member in self.members:
            member.set_inputs()

    def get_outputs(self):
        self._each(DirectInstance.get_outputs)
        return self.real_out, self.int_out, self.bool_out

    def do_step(self, t: float, h: float) -> None:
        failures = self.failures
        for b, member in enumerate(self.members):
            if failures and b in failures:
                continue
            try:
                member.do_step(t, h)
            except NavfmuError as exc:
                failures[b] = exc

    def take_run_warnings(self, row: int) -> List[str]:
        return self.members[row].take_warnings()

    def terminate(self) -> None:
        for member in self.members:
            member.terminate()


class NativeBatchInstance(BatchInstance):
    """A component class's ``batch_class`` (:mod:`navcore.core.batch`): every run in one
    call; inputs as ``name -> (B,) array``, outputs one ``(B, n_outputs)`` array."""

    def __init__(self, batch, name: str, variables, source: str,
                 failures: Dict[int, NavfmuError]):
        super().__init__(name, variables, source, batch.model_name, batch.runs, failures)
        self.batch = batch
        self.time = None
        self._outputs = None          # (B, n_outputs), columns in the class's output order
        #: per run, every input's value before any connection: its declared start, or the
        #: value set for it with the parameters (as a DirectInstance keeps them)
        self._start_inputs = [{p.name: p.default() for p in batch.component_class.inputs}
                              for _ in range(batch.runs)]

    def _bound(self) -> None:
        self._in_names = [(self.input_names[t], buf) for t, buf in
                          (("Integer", self.int_in), ("Boolean", self.bool_in))
                          if self.input_names[t]]
        self._column_index = {}           # BatchInputs.real_columns' cache for this layout
        connected = set(sum(self.input_names.values(), ()))
        self._held_inputs = {name: np.array([run[name] for run in self._start_inputs])
                             for name in self._start_inputs[0] if name not in connected}
        columns = self.batch.columns
        self._out_columns = [(_columns_index([columns[n] for n in self.output_names[t]]), buf)
                             for t, buf in (("Real", self.real_out), ("Integer", self.int_out),
                                            ("Boolean", self.bool_out))
                             if self.output_names[t]]

    def _kept(self, rows: List[int]) -> None:
        self.batch.keep(rows)
        self._start_inputs = [self._start_inputs[i] for i in rows]
        if self._outputs is not None:
            self._outputs = self._outputs[rows]

    def _error(self, what, exc: Exception, time, at: bool = True):
        """The run's error; ``what`` (the call that failed) a string or a function that
        gives it (formatted only when a run fails)."""
        return simulation_error(self.name, self.model_name, what if isinstance(what, str)
                                else what(), exc, time, at)

    def _collect(self, what, time, at: bool = True) -> None:
        """Move the batch's per-run errors of the latest call into the shared failures."""
        for b, exc in self.batch.take_failures().items():
            if b not in self.failures:
                self.failures[b] = self._error(what, exc, time, at)

    def _call(self, what, time, call, at: bool = True):
        try:
            result = call()
        except NavcoreError as exc:       # one error for every run (none told which)
            for b in range(self.runs):
                self.failures.setdefault(b, self._error(what, exc, time, at))
            return None
        self._collect(what, time, at)
        return result

    def set_run_parameters(self, values: Sequence[Mapping[str, Any]]) -> None:
        """As :meth:`DirectInstance.set_parameters` for each run: every value converted to
        its variable's type (:func:`~orchestrator.cosim.backends.coerce`), an input's value
        kept as that run's start value, a parameter set on that run's component."""
        parameters = []
        for b, run in enumerate(values):
            mine = {}
            try:
                for name, value in run.items():
                    var = self.variable(name, ("parameter", "input"))
                    value = coerce(self.name, var, value, self.source)
                    if var.causality == "input":
                        self._start_inputs[b][name] = value
                    else:
                        mine[name] = value
            except NavfmuError as exc:           # this run's value: this run fails
                self.failures.setdefault(b, exc)
            parameters.append(mine)
        self.batch.set_parameters(parameters)
        for b, exc in self.batch.take_failures().items():
            self.failures.setdefault(b, parameter_error(self.name, self.model_name, exc))
        self._bound()

    def enter_initialization(self, start_time, stop_time) -> None:
        self.time = start_time
        batch = self.batch

        def begin():
            outputs = batch.start(start_time)
            if stop_time is not None:
                batch.check_stop_time(stop_time)
            return outputs
        outputs = self._call("initialization", start_time, begin)
        if outputs is not None:
            self._outputs = outputs

    def exit_initialization(self) -> None:
        outputs = self._call("initialization", self.time,
                             lambda: self.batch.initial_inputs(self._inputs()))
        if outputs is not None:
            self._outputs = outputs

    def _inputs(self) -> BatchInputs:
        real = self.real_in.copy()         # the batch may keep what it is given
        names = self.input_names["Real"]
        values = BatchInputs(self._held_inputs, real, names, self._column_index)
        values.update(zip(names, real.T))
        for names, buf in self._in_names:
            values.update(zip(names, buf.T.copy()))
        return values

    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        self._copy_in(real_values, int_values, bool_values)

    def get_outputs(self):
        out = self._outputs
        for columns, buf in self._out_columns:
            if buf.dtype == out.dtype and not isinstance(columns, slice):
                out.take(columns, 1, buf, "clip")    # no temporary; the columns are valid
            else:
                buf[:] = out[:, columns]
        return self.real_out, self.int_out, self.bool_out

    def do_step(self, t: float, h: float) -> None:
        outputs = self._call(lambda: f"step from t = {t:.9g} s to t = {t + h:.9g} s", t,
                             lambda: self.batch.advance(t, h, self._inputs()), at=False)
        self.time = t + h
        if outputs is not None:
            self._outputs = outputs

    def take_run_warnings(self, row: int) -> List[str]:
        return [f"{self.name}: {notice}" for notice in self.batch.take_notices(row)]

    def terminate(self) -> None:
        pass


def _columns_index(columns):
    """An index of the columns ``columns``: a slice where they are consecutive (a view, no
    gather), else the array of them."""
    first = columns[0]
    if columns == list(range(first, first + len(columns))):
        return slice(first, first + len(columns))
    return np.array(columns, dtype=np.intp)


__all__ = ["BatchInstance", "LoopBatchInstance", "NativeBatchInstance"]
