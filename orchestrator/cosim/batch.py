"""A batch: B runs of one system on the direct backend, stepped together.

The runs differ only in their parameter values (the seeds of a Monte Carlo campaign, the
genes of a tuning population); they share the model, the time grid, the algorithm and the
recorded signals.  Every rule of :mod:`orchestrator.cosim.master` holds for each run as if it
ran alone: the signal vectors become matrices with one row per run, every component is one
instance holding all runs (:mod:`orchestrator.cosim.batch_instance`), the exchange moves the
values of every run in one indexed copy per type, and each run's recorded rows go to its own
sink, chunk by chunk (:mod:`orchestrator.results.batch_recording`).

Equality: a component class without a batched implementation runs one navcore component per
run (each on its own row), so each run of the batch computes the floats of its single run,
bit for bit; ``tests/test_batch_simulation.py`` checks that on the scenarios.

Failures: a run whose parameter value is refused, or whose component fails while stepping,
ends with its own error (the :class:`~orchestrator.errors.SimulationError` its single run
would raise) and is dropped at the end of that macro step (its sink aborted); the others
finish.  The outcome of :meth:`BatchSimulation.run` is one entry per run, its
:class:`~orchestrator.results.run_results.Results` or its error.

Timing: one call steps every run, so ``step_time_s`` and ``exchange_step_time_s`` of each
run's Results are the batch's time per call divided by its runs (a run's share);
``metadata["batch_runs"]`` says how many runs shared them.
"""
from __future__ import annotations

import warnings
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from .backends import NUMERIC_TYPES
from .batch_instance import BatchInstance, LoopBatchInstance, NativeBatchInstance
from .exchange import Timing
from .master import Simulation
from .result_assembly import SIGNAL_DTYPES, row_recorder
from ..errors import NavfmuError, SkippedParametersWarning
from ..results.batch_recording import BatchRecording
from ..results.run_results import Results

Outcome = Union[Results, NavfmuError]


class _AllFailed(Exception):
    """Every run of the batch has failed: nothing is left to step."""


class _Batch:
    """The mutable part of one batch run: live rows, instances, vectors, exchange."""

    def __init__(self, sim: "BatchSimulation", runs: int, sinks, start: float, n_steps: int):
        self.sim = sim
        self.alive: List[int] = list(range(runs))        # run of each batch row
        self.failures: Dict[int, NavfmuError] = {}       # batch row -> error, this step
        self.outcomes: List[Optional[Outcome]] = [None] * runs
        self.sinks = list(sinks)
        self.start, self.n_steps = start, n_steps
        single, self.position, self.slices, self.out_names, self.source_of = sim._layout()
        self.vectors = {t: np.zeros((runs,) + v.shape, dtype=v.dtype) for t, v in single.items()}
        self.timing = Timing(len(sim.components))
        self.instances: List[BatchInstance] = []
        self.exchange = None

    def views(self, name: str):
        return [self.vectors[t][:, slice(*self.slices[name][t])] for t in NUMERIC_TYPES]

    def build(self, runs: int) -> None:
        sim = self.sim
        self.instances = [sim._batch_instance(d, runs, self.failures) for d in sim.components]
        for d, inst in zip(sim.components, self.instances):
            n = d.spec.name
            inst.prepare(list(self.source_of[n]), self.out_names[n], *self.views(n))
        self.exchange = sim._exchange(self.instances, self.vectors, self.position,
                                      self.source_of, self.start, self.n_steps, self.timing)

    def drop_failed(self, recording: BatchRecording) -> None:
        """End the failed runs (error as outcome, sink aborted), keep the others."""
        failures = self.failures
        for row in sorted(failures):
            run = self.alive[row]
            self.outcomes[run] = failures[row]
            if self.sinks[run] is not None:
                self.sinks[run].abort()
        rows = [r for r in range(len(self.alive)) if r not in failures]
        failures.clear()
        self.alive = [self.alive[r] for r in rows]
        if not rows:
            raise _AllFailed
        for t in NUMERIC_TYPES:
            self.vectors[t] = np.ascontiguousarray(self.vectors[t][rows])
        for d, inst in zip(self.sim.components, self.instances):
            inst.keep(rows, *self.views(d.spec.name))
        recording.keep(rows)
        self.exchange = self.sim._exchange(self.instances, self.vectors, self.position,
                                           self.source_of, self.start, self.n_steps,
                                           self.timing)

    def step(self, k: int, recording: BatchRecording) -> None:
        self.exchange.step(k)
        if self.failures:
            self.drop_failed(recording)

    def warnings_of(self, row: int) -> List[str]:
        return [w for inst in self.instances for w in inst.take_run_warnings(row)]


class BatchSimulation(Simulation):
    """B runs of ``model`` on the direct backend (module docstring).

    ``parameter_sets[b]`` overrides parameters of run b as ``{"Component.variable": value}``
    (the ``parameters`` of :class:`Simulation`); every set must name the same variables.
    """

    def __init__(self, model, registry: Mapping[str, type],
                 parameter_sets: Sequence[Mapping[str, Any]], record=None,
                 base_step: Optional[float] = None, record_every: int = 1,
                 algorithm: str = "gauss-seidel"):
        sets = [dict(p) for p in parameter_sets]
        if not sets:
            raise NavfmuError("a batch needs at least one run")
        keys = set(sets[0])
        for b, p in enumerate(sets):
            if set(p) != keys:
                raise NavfmuError(f"run {b} of the batch sets other parameters than run 0: "
                                  f"{sorted(set(p) ^ keys)}")
        super().__init__(model, backend="direct", registry=registry, record=record,
                         parameters=sets[0], base_step=base_step, record_every=record_every,
                         algorithm=algorithm)
        self.registry = registry
        with warnings.catch_warnings():   # the same skipped names as run 0's, said once
            warnings.simplefilter("ignore", SkippedParametersWarning)
            self.run_parameter_values = [self.parameter_values] + [
                self._parameters(p)[0] for p in sets[1:]]

    @property
    def runs(self) -> int:
        return len(self.run_parameter_values)

    def _batch_instance(self, d, runs: int, failures) -> BatchInstance:
        component_class = self.registry[d.model_name]
        batch_class = getattr(component_class, "batch_class", None)
        if batch_class is not None:
            return NativeBatchInstance(batch_class(component_class, runs), d.spec.name,
                                       d.variables, d.source, failures)
        return LoopBatchInstance([d.make() for _ in range(runs)], failures)

    def run(self, stop_time: Optional[float] = None, progress=None,
            sinks: Optional[Sequence[Any]] = None) -> List[Outcome]:
        """Run every run of the batch; one outcome per run (its Results, or its error).

        ``sinks[b]`` (see :mod:`orchestrator.results.recorder`) receives run b's rows; a run
        that fails has its sink aborted.  ``progress`` as in :meth:`Simulation.run`."""
        start = self.model.start_time
        stop = float(stop_time) if stop_time is not None else self.model.stop_time
        n_steps = self._n_steps(start, stop)
        sinks = [None] * self.runs if sinks is None else list(sinks)
        if len(sinks) != self.runs:
            raise NavfmuError(f"a batch of {self.runs} runs needs {self.runs} sinks, "
                              f"got {len(sinks)}")
        batch = _Batch(self, self.runs, sinks, start, n_steps)
        rec_index = self._rec_index(batch.position)
        recording = BatchRecording(
            n_steps // self.record_every + 1, sinks,
            {t: len(rec_index[t]) for t in NUMERIC_TYPES}, SIGNAL_DTYPES,
            lambda first, n, bufs: self._chunk(first, n, bufs, rec_index, batch.position))
        try:
            loop_ns = self._run_batch(batch, recording, start, stop, n_steps, progress)
        except _AllFailed:
            return list(batch.outcomes)
        except BaseException:
            for run in batch.alive:
                if sinks[run] is not None:
                    sinks[run].abort()
            raise
        finally:
            for inst in batch.instances:
                inst.terminate()
        return self._outcomes(batch, recording, rec_index, start, stop, n_steps, loop_ns)

    def _run_batch(self, batch: _Batch, recording, start, stop, n_steps, progress) -> int:
        batch.build(self.runs)
        for d, inst in zip(self.components, batch.instances):
            inst.set_run_parameters([values[d.spec.name] for values in
                                     self.run_parameter_values])
        if batch.failures:
            batch.drop_failed(recording)
        batch.exchange.initialize(start, stop)
        if batch.failures:
            batch.drop_failed(recording)
        record = row_recorder(batch.vectors, self._rec_index(batch.position),
                               recording.buffers)
        record(recording.slot(0))
        # its components are Python components: none ends the simulation early
        loop_ns, _, _ = self._loop(lambda k: batch.step(k, recording), record, recording,
                                   n_steps, progress)
        recording.finish()
        return loop_ns

    def _outcomes(self, batch: _Batch, recording, rec_index, start, stop, n_steps,
                  loop_ns) -> List[Outcome]:
        n_rows = 0 if recording.streamed else recording.size
        for row, run in enumerate(batch.alive):
            results = self._results(start, stop, n_steps, n_rows, recording.run_buffers(row),
                                    rec_index, batch.position, batch.timing, loop_ns)
            results.metadata["parameters"] = {n: dict(p) for n, p in
                                              self.run_parameter_values[run].items()}
            results.metadata["warnings"] = batch.warnings_of(row)
            results.metadata["batch_runs"] = self.runs
            for times in (results.step_time_s, results.exchange_step_time_s):
                times.update({c: v / self.runs for c, v in times.items()})
            if batch.sinks[run] is not None:
                batch.sinks[run].close(results)
            batch.outcomes[run] = results
        return list(batch.outcomes)


__all__ = ["BatchSimulation", "Outcome"]
