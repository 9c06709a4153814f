"""Batches: B runs of one component class stepped together, every run on its own row.

A component class whose per-run work can be done for all runs in one call names a
``batch_class`` (a subclass of :class:`ComponentBatch`); a caller that runs many seeds of one
system (the master's batches, ``orchestrator.cosim.batch``) then steps that class's B runs
with one call per communication step instead of B.  The contract is the component's
(:mod:`navcore.core.component`) with a run axis:

* one component object per run holds that run's parameters (set and checked by the
  component's own :meth:`~navcore.core.component.Component.set_parameter`) and, after
  :meth:`start`, whatever per-run state the batch keeps there;
* ``start``, ``advance`` return the outputs as one ``(B, n_outputs)`` float array, columns
  in the order of the class's ``outputs``; inputs come as ``name -> (B,) array``;
* an error of one run does not raise: it is kept (:meth:`take_failures`, batch row -> the
  error its single run would raise) and that run's row holds its last values until the
  caller drops it (:meth:`keep`);
* notices are per run (:meth:`take_notices`).

Every run of a batch computes the floats of its single run: a batch class's tests compare
each row with the component run alone, bit for bit.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
import math
import operator
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from ..errors import NavcoreError
from .kernels import jitable, kernel
from .limits import FINITE


class BatchInputs(dict):
    """The inputs of a batch's step: ``name -> (B,) array``, and the Real ones also as one
    ``(B, n)`` matrix (:attr:`real`, its columns named by :attr:`real_names`)."""

    def __init__(self, values, real: np.ndarray, real_names: Tuple[str, ...],
                 index_cache: Optional[Dict[Tuple[str, ...], np.ndarray]] = None):
        super().__init__(values)
        self.real = real
        self.real_names = real_names
        #: names -> their columns in ``real``: a caller stepping with the same ``real_names``
        #: may pass one dict for all its steps
        self._index = {} if index_cache is None else index_cache

    def real_columns(self, names: Tuple[str, ...]) -> np.ndarray:
        """The Real inputs ``names`` as a (B, len(names)) matrix."""
        index = self._index.get(names)
        if index is None:
            index = self._index[names] = np.array([self.real_names.index(n) for n in names],
                                                  dtype=np.intp)
        return self.real[:, index]


class ComponentBatch(ABC):
    """B runs of ``component_class`` (module docstring); subclasses implement
    :meth:`_started` and :meth:`advance`."""

    def __init__(self, component_class, runs: int):
        self.component_class = component_class
        self.model_name = component_class.model_name
        self.members: List[Any] = [component_class() for _ in range(runs)]
        self.columns = {p.name: j for j, p in enumerate(component_class.outputs)}
        self._failures: Dict[int, Exception] = {}

    @property
    def runs(self) -> int:
        return len(self.members)

    def _each(self, call) -> None:
        """``call(b, member)`` for every run not failed; an error fails that run alone."""
        for b, member in enumerate(self.members):
            if b in self._failures:
                continue
            try:
                call(b, member)
            except NavcoreError as exc:
                self._failures[b] = exc

    def set_parameters(self, values: Sequence[Mapping[str, Any]]) -> None:
        """``values[b]``: the parameters of run b, by name."""
        def set_all(b, member):
            for name, value in values[b].items():
                member.set_parameter(name, value)
        self._each(set_all)

    def take_failures(self) -> Dict[int, Exception]:
        """The runs that failed since the last call: batch row -> error."""
        failures, self._failures = self._failures, {}
        return failures

    def fail(self, b: int, exc: Exception) -> None:
        self._failures.setdefault(b, exc)

    def keep(self, rows: Sequence[int]) -> None:
        """Keep the runs of batch ``rows``, in that order."""
        rows = list(rows)
        self._kept(rows)
        self.members = [self.members[i] for i in rows]

    def accepted_rows(self, values: np.ndarray, names: Tuple[str, ...]) -> np.ndarray:
        """Per run (row of ``values``, one column per input of ``names``), whether every
        input lies in its port's range and is finite (what
        :meth:`~navcore.core.component.Component.check_inputs` enforces; a run refused here
        gets its own component's error from its own code)."""
        low, high = open_bounds(self, names)
        accepted = np.empty(len(values), dtype=bool)
        accepted_into(values, low, high, accepted)
        return accepted

    def _open_bounds(self, names: Tuple[str, ...]) -> Tuple[np.ndarray, np.ndarray]:
        """The ranges of the inputs ``names`` as open bounds (low, high): a closed bound is
        the next float outside it (``x >= low`` is ``x > nextafter(low, -inf)`` for every
        float x; NaN passes neither), an infinite one stays open (refusing the infinity)."""
        ports = self.component_class._input_ports()
        limits = [ports[n].limits if n in ports else FINITE for n in names]
        low = [x.low if x.low_open or not math.isfinite(x.low) else
               math.nextafter(x.low, -math.inf) for x in limits]
        high = [x.high if x.high_open or not math.isfinite(x.high) else
                math.nextafter(x.high, math.inf) for x in limits]
        return np.array(low, dtype=float), np.array(high, dtype=float)

    def _by_itself(self, b: int, call, **lend) -> None:
        """``call(member)`` for run b on its own objects, given the batch's values first
        (:meth:`_lend`, with ``lend``) and taken back after (:meth:`_adopt`); an error fails
        that run alone."""
        self._lend(b, **lend)
        try:
            call(self.members[b])
        except Exception as exc:          # the run's own error (InputError, divergence)
            self.fail(b, exc)
            return
        self._adopt(b)

    def _outputs_of(self, member) -> Tuple[Any, ...]:
        """Run ``member``'s outputs (its ``out`` dict) in the batch's column order."""
        getter = self.__dict__.get("_output_getter")
        if getter is None:
            names = tuple(self.columns)
            getter = self._output_getter = (operator.itemgetter(*names) if len(names) > 1
                                            else lambda out: (out[names[0]],))
        return getter(member.out)

    @staticmethod
    def _inputs_of_runs(runs: Sequence[int], inputs) -> List[Dict[str, float]]:
        """The inputs of each of the runs ``runs`` of a batch step, as its own component
        takes them (Python numbers; every input's column converted once)."""
        columns = [(name, values.tolist()) for name, values in inputs.items()]
        return [{name: column[b] for name, column in columns} for b in runs]

    def _lend(self, b: int) -> None:
        """Hook of :meth:`_by_itself`: give run b's own objects the batch's values."""

    def _adopt(self, b: int) -> None:
        """Hook of :meth:`_by_itself`: take run b's own objects' values into the batch."""

    def _kept(self, rows: List[int]) -> None:
        """Hook: compact the batch's own per-run arrays (``self.members`` are still all
        the runs; batch row ``i`` becomes ``rows.index(i)``)."""

    def take_notices(self, b: int) -> List[str]:
        return self.members[b].take_notices()

    def start(self, start_time: float) -> np.ndarray:
        """Start every run (each member's own ``start``: its parameters are validated
        there) and the batch's shared part; the outputs at the start."""
        self._each(lambda b, member: member.start(start_time))
        return self._started(float(start_time))

    def check_stop_time(self, stop_time: float) -> None:
        self._each(lambda b, member: member.check_stop_time(stop_time))

    def initial_inputs(self, inputs: Mapping[str, np.ndarray]):
        """The inputs at the end of initialization mode (None: outputs unchanged)."""
        return None

    @abstractmethod
    def _started(self, start_time: float) -> np.ndarray:
        """The batch's shared part, built after every run's own ``start``; the outputs."""

    @abstractmethod
    def advance(self, t: float, h: float, inputs: Mapping[str, np.ndarray]) -> np.ndarray:
        """Step every run from ``t`` to ``t + h``; the outputs (module docstring)."""


def open_bounds(batch: ComponentBatch, names: Tuple[str, ...]) -> Tuple[np.ndarray, np.ndarray]:
    """The ranges of ``batch``'s inputs ``names`` as open bounds
    (:meth:`ComponentBatch._open_bounds`), built once per batch."""
    cache = batch.__dict__.setdefault("_ranges", {})
    bounds = cache.get(names)
    if bounds is None:
        bounds = cache[names] = batch._open_bounds(names)
    return bounds


@jitable
def row_accepted(row, low, high) -> bool:
    """Whether every value of ``row`` lies inside its open bounds ``(low, high)``
    (:func:`open_bounds`; NaN lies inside none)."""
    for j in range(row.shape[0]):
        x = row[j]
        if not (x > low[j] and x < high[j]):
            return False
    return True


@kernel
def accepted_into(values, low, high, accepted) -> None:
    """:func:`row_accepted` of every row of ``values`` (B, n), into ``accepted`` (B,)."""
    for b in range(values.shape[0]):
        accepted[b] = row_accepted(values[b], low, high)


__all__ = ["ComponentBatch"]
