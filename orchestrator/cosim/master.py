"""The co-simulation master: fixed base step, integer decimation, Gauss-Seidel or Jacobi exchange.

Semantics
---------
These rules are exact; the tests check them with numbers.

1. **Time grid.**  The base step ``h`` comes from the system model
   (``osp:FixedStepAlgorithm baseStepSize``) unless overridden.  The run covers
   ``[start, stop]`` in ``N = (stop - start) / h`` macro steps (it is an error if that is not
   an integer within 1e-9 relative).  Macro step ``k`` (``k = 0 .. N-1``) goes from
   ``t_k = start + k*h`` to ``t_{k+1}``; every time is computed as ``start + k*h`` from the
   integer ``k``, never accumulated, so there is no drift over 360 000 steps.

2. **Decimation.**  Component ``i`` with an ``osp:StepSizeHint`` ``H_i`` runs every
   ``n_i = round(H_i / h)`` macro steps (``n_i = 1`` without a hint; ``H_i`` must be an
   integer multiple of ``h``).  It is *due* in macro step ``k`` when ``(k + 1) % n_i == 0`` and
   then steps once over ``[t_{k+1} - n_i*h, t_{k+1}]``.  Between its steps its outputs hold
   (zero-order hold).  If ``N`` is not a multiple of ``n_i``, the last ``N % n_i`` base steps
   are not stepped by that component and its outputs hold to the end.

3. **Order (Gauss-Seidel, the default).**  Within a macro step the due components are stepped one
after the other in a
   fixed order: a topological order of the component graph (an edge for every connection,
   source component -> destination component), ties broken by declaration order in the SSD
   (among the components whose sources are all placed, the earliest-declared goes next).
   For each due component, in that order: set its inputs from the *latest* values of their
   source outputs, call ``do_step``, read its outputs.  So an input whose source comes earlier
   in the order sees that source's output at ``t_{k+1}`` (if the source was due in this macro
   step; otherwise its held value); this is Gauss-Seidel.  A decimated component, when due,
   sees its inputs' values at the end of its own step, ``t_{k+1}``.

3J. **Jacobi** (``algorithm="jacobi"``, ``navfmu run --algorithm jacobi``): libcosim's
   fixed-step algorithm (``src/cosim/algorithm/fixed_step_algorithm.cpp``), exactly.  With
   the macro-step counter ``c`` (``c = k`` during macro step ``k``):

   * component ``i`` is due in macro step ``k`` when ``k % n_i == 0`` and steps over
     ``[t_k, t_k + n_i*h]`` (the same windows as rule 2, started at their beginning); a
     window that would end after the stop is not started (libcosim starts it; no recorded
     value differs);
   * all due components step from the same instant, in declaration order, each on the
     input values *transferred* to it so far (order does not matter);
   * after the steps, ``c = k + 1``; every component whose window ends (``c % n_i == 0``)
     has its outputs read: they appear in the recording and to connections only now, at
     the end of its window, while the values it computed were final at its start;
   * then every connection ``s.out -> d.in`` with ``c % lcm(n_s, n_d) == 0`` is
     transferred (``d.in`` := ``s.out``'s latest read value); ``d`` receives it at its next
     step.  So a decimated component's inputs are its sources' outputs at the *start* of
     its window, and a component reading a decimated one sees that one's window ``m``
     output from the end of window ``m``, one window after its inputs were taken (in
     ``aircraft_500s``: the fix taken from the truth at t = 1 s reaches the filter at
     t = 2 s).  Between transfers an input holds.

   The tests check this against libcosim itself (bit for bit on every model) and with toy
   components by hand.  There is no algebraic-loop rule: every connection is one step late.

4. **Algebraic loops.**  If the graph has a cycle, no component of it can go first.  When no
   component is ready, the earliest-declared component that lies on a cycle is chosen; its
   input connections coming from components of the same strongly connected component are
   *delayed*, and ordering continues.  A delayed connection's input sees the source's output
   from the previous macro step (value at ``t_k``, or the held value), because the source is
   stepped later in the same macro step.  A connection from a component to itself is always
   delayed.  The delayed connections are listed in :attr:`Simulation.delayed_connections`
   and in the results' metadata.  A cycle is not an error.

5. **Initialization.**  All components are instantiated; the SSD parameter values, then the
   user's overrides (``parameters={"Component.variable": value}``), are set before
   initialization mode; every component enters initialization mode (``setupExperiment(start,
   stop)``); initial values are exchanged once in the order of rule 3 (for each component:
   set its connected inputs from the current source values, read its outputs); every
   component exits initialization mode; then all outputs are read again: these are the
   outputs at ``start`` (row 0 of the recording) and the values the first macro step uses.
   Unconnected inputs keep their start values.

5J. **Initialization under Jacobi** (libcosim's ``initialize``): parameters set and
   initialization mode entered as in rule 5, outputs read; then as many iterations as there
   are components of: set the transferred inputs (none in the first), read the outputs,
   transfer every connection; then set the transferred inputs, exit initialization mode,
   read the outputs, transfer every connection.  (libcosim sets the parameters once more in
   initialization mode, with the same values.)

6. **Recording.**  Every output of every component (or the selection given by ``record``:
   component names and/or ``"Component.variable"``) is recorded in preallocated arrays,
   Real/Integer/Boolean as float; row 0 holds the initial outputs, row ``j`` the outputs after
   macro step ``j*record_every - 1`` (time ``start + j*record_every*h``).  String variables
   are never recorded.  The rows stay in memory, or, given a sink, are streamed to it in
   chunks of :data:`~orchestrator.results.recorder.DEFAULT_CHUNK_ROWS` rows
   (:mod:`orchestrator.results.recorder`).

7. **Timing.**  For every component the master measures (``perf_counter_ns``) the wall time
   of each ``do_step`` call alone, and of the whole set-inputs/do-step/get-outputs sequence.
   ``Results.step_time_s[c]`` is the mean ``do_step`` time per call;
   ``Results.exchange_step_time_s[c]`` the mean of the whole sequence;
   ``metadata["master_overhead_s_per_step"]`` the loop's wall time not spent in those
   sequences, per macro step (index gathering, recording, bookkeeping).  Under Jacobi a
   decimated component's outputs are read at the end of its window; that read is added to
   the sequence of its step.

The exchange itself (both algorithms, sharing one input-copying path) is
:mod:`orchestrator.cosim.exchange`.

8. **Swaps and wiring checks.**  Before anything runs, every connected variable must exist
   in its component's FMU/Python component with the right causality (output at the start,
   input at the end) and the connector's type; every SSD parameter and override must exist as
   a parameter (or input).  Otherwise :class:`~orchestrator.errors.WiringError` names the
   component, the variable and the FMU file.  For a component whose source was replaced
   (:meth:`SystemModel.replace_source`), SSD parameters the new FMU does not have are skipped
   (a filter swap keeps the scenario's parameters that still apply) and listed in
   :attr:`Simulation.skipped_parameters`; those of a swap variant file written for the new
   FMU (``file.MODEL.ssv`` next to a bound ``file.ssv``, :mod:`orchestrator.model.ssp`) are never
   skipped.  Units (:mod:`orchestrator.model.units`): a connector's declared unit and the
   variable's, and the two ends of a connection, must be one unit (no connection converts);
   a bound Real given with a ``unit`` is converted to the variable's unit, or refused.
   A component given a lever arm whose attitude inputs no connection feeds is named in a
   warning (:mod:`.lever_arm_wiring`).

9. **Failures.**  A component failing mid-run (FMU status Discard/Error/Fatal, or a Python
   component raising ParameterError/InputError) raises
   :class:`~orchestrator.errors.SimulationError` naming the component and the time, with the
   component's log; every instance is terminated and freed, and no results are returned.
   A component that *asks* to end the simulation (an FMI 3.0 FMU returning
   ``terminateSimulation`` from ``fmi3DoStep`` in macro step ``k``:
   :class:`~orchestrator.errors.SimulationTerminated`) ends the run cleanly: the results
   keep the rows up to the last one recorded at or before ``t_k`` (the last communication
   point every component reached), ``metadata["ended_by"]`` names the component, its time
   and message, and a :class:`~orchestrator.errors.NavfmuWarning` says so; had no row been
   recorded after the initial one, the run fails with that error instead.

10. **Host processes.**  An FMU the isolation puts in a host process of its own (by
   default every foreign FMU: :mod:`orchestrator.cosim.isolation`) is stepped by these same
   rules through the same interface, one round trip per step
   (:mod:`orchestrator.cosim.hosted_instance`), with the same numbers bit for bit.  Its host
   dying (a segfault, an abort) or a call of it outlasting the call timeout is a
   :class:`~orchestrator.errors.SimulationError` naming the component, the FMI call and the
   time, handled as in rule 9; Ctrl-C kills the host at once.  ``metadata["hosted"]`` lists
   those components.
"""
from __future__ import annotations

import warnings
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Tuple

import numpy as np

from .backends import NUMERIC_TYPES, Instance
from .component_description import describe_direct, describe_fmu
from ..errors import NavfmuError, NavfmuWarning
from .exchange import ALGORITHMS, Timing, exchange_for, slots_for, step_order
from .isolation import Isolation
from .lever_arm_wiring import unconnected_lever_arms
from .macro_loop import MacroLoop
from .model_checks import ModelChecks
from .result_assembly import SIGNAL_DTYPES, ResultAssembly, row_recorder
from ..results.recorder import Recording
from ..results.run_results import Results
from ..model.ssp import Connection, SystemModel


class Simulation(ModelChecks, MacroLoop, ResultAssembly):
    """Run a :class:`SystemModel` by the rules of the module docstring.

    ``backend`` is ``"fmu"`` (every component's ``source`` FMU through fmpy) or ``"direct"``
    (the Python component registered under the FMU's model name in ``registry``, a mapping
    model name -> component class).  ``record`` selects what is recorded (None: every output).
    ``parameters`` overrides values as ``{"Component.variable": value}``.  ``isolation``
    (:mod:`orchestrator.cosim.isolation`, default: foreign FMUs) says which FMUs run in a
    host process of their own (rule 10).
    Construction checks the wiring (rule 8, :mod:`.model_checks`); :meth:`run` instantiates,
    runs (:mod:`.macro_loop`) and terminates, and assembles the Results (:mod:`.result_assembly`).
    """

    def __init__(self, model: SystemModel, backend: str = "fmu",
                 registry: Optional[Mapping[str, type]] = None,
                 record: Optional[Iterable[str]] = None,
                 parameters: Optional[Mapping[str, Any]] = None,
                 base_step: Optional[float] = None, record_every: int = 1,
                 algorithm: str = "gauss-seidel", isolation: Optional[Isolation] = None):
        if backend not in ("fmu", "direct"):
            raise NavfmuError(f"unknown backend '{backend}' (use 'fmu' or 'direct')")
        if algorithm not in ALGORITHMS:
            raise NavfmuError(f"unknown algorithm '{algorithm}' (use {' or '.join(ALGORITHMS)})")
        self.algorithm = algorithm
        if backend == "direct" and registry is None:
            raise NavfmuError("the 'direct' backend needs a registry of Python components "
                              "(model name -> component class)")
        if int(record_every) != record_every or record_every < 1:
            raise NavfmuError(f"record_every must be a positive integer, got {record_every}")
        self.model = model
        self.backend = backend
        self.record_every = int(record_every)
        self.base_step = float(base_step) if base_step is not None else model.base_step
        if not self.base_step > 0:
            raise NavfmuError(f"the base step must be > 0, got {self.base_step}")
        self.isolation = isolation if isolation is not None else Isolation()
        self.components = [
            describe_fmu(c, self.isolation) if backend == "fmu" else describe_direct(c, registry)
            for c in model.components
        ]
        self.names = [c.spec.name for c in self.components]
        self._index = {n: i for i, n in enumerate(self.names)}
        self.decimation = {c.spec.name: self._decimation(c.spec) for c in self.components}
        self._check_wiring()
        self.parameter_values, self.skipped_parameters = self._parameters(parameters or {})
        for message in unconnected_lever_arms(self.components, self.parameter_values,
                                              model.connections):
            warnings.warn(message, NavfmuWarning, stacklevel=2)
        self.recorded = self._recorded(record)
        edges = [(self._index[c.start_component], self._index[c.end_component], c)
                 for c in model.connections]
        order, delayed = step_order(len(self.names), edges)
        self.order: List[str] = [self.names[i] for i in order]
        # under Jacobi every connection is one step late: no loop needs breaking
        self.delayed_connections: List[Connection] = delayed if algorithm != "jacobi" else []

    # -- running ------------------------------------------------------------------------
    def _layout(self):
        """Signal vectors (per type, every component's read outputs, one slice each), the
        position of every (component, output) in them, and every component's input sources."""
        comps = self.components
        source_of: Dict[str, Dict[str, Tuple[str, str]]] = {n: {} for n in self.names}
        needed: Dict[str, set] = {n: set(self.recorded[n]) for n in self.names}
        for conn in self.model.connections:
            source_of[conn.end_component][conn.end_connector] = (conn.start_component,
                                                                 conn.start_connector)
            needed[conn.start_component].add(conn.start_connector)
        out_names = {d.spec.name: [v.name for v in d.variables.values()
                                   if v.name in needed[d.spec.name]] for d in comps}
        position: Dict[Tuple[str, str], Tuple[str, int]] = {}
        slices: Dict[str, Dict[str, Tuple[int, int]]] = {n: {} for n in self.names}
        sizes = {t: 0 for t in NUMERIC_TYPES}
        for d in comps:
            n = d.spec.name
            for t in NUMERIC_TYPES:
                names = [v for v in out_names[n] if d.variables[v].type == t]
                slices[n][t] = (sizes[t], sizes[t] + len(names))
                for j, v in enumerate(names):
                    position[(n, v)] = (t, sizes[t] + j)
                sizes[t] += len(names)
        vectors = {t: np.zeros(sizes[t], dtype=SIGNAL_DTYPES[t]) for t in NUMERIC_TYPES}
        return vectors, position, slices, out_names, source_of

    def _prepare(self, instances, vectors, slices, out_names, source_of) -> None:
        for d, inst in zip(self.components, instances):
            n = d.spec.name
            views = [vectors[t][slice(*slices[n][t])] for t in NUMERIC_TYPES]
            inst.prepare(list(source_of[n]), out_names[n], *views)

    def _exchange(self, instances, vectors, position, source_of, start: float, n_steps: int,
                  timing: Timing):
        """The exchange of the algorithm over prepared ``instances``."""
        slots = slots_for(self.names, self.decimation, instances, position, source_of)
        order = [self._index[n] for n in self.order]
        return exchange_for(self.algorithm, slots, order, vectors, start, self.base_step,
                            n_steps, timing)

    def run(self, stop_time: Optional[float] = None,
            progress: Optional[Callable[[int, int], None]] = None, sink=None) -> Results:
        """Run from the model's start time to ``stop_time`` (default: the model's).

        ``progress(steps_done, n_steps)`` is called about every 1 % of the run and at the end.
        ``sink`` (see :mod:`orchestrator.results.recorder`): stream the recorded rows to it in
        chunks instead of keeping them; the Results returned then have no rows (columns, units,
        step times and metadata only) and ``sink.close`` has received them.
        """
        start = self.model.start_time
        stop = float(stop_time) if stop_time is not None else self.model.stop_time
        n_steps = self._n_steps(start, stop)
        vectors, position, slices, out_names, source_of = self._layout()
        rec_index = self._rec_index(position)
        recording = Recording(n_steps // self.record_every + 1,
                              {t: len(rec_index[t]) for t in NUMERIC_TYPES}, SIGNAL_DTYPES,
                              lambda first, n, bufs: self._chunk(first, n, bufs, rec_index,
                                                                 position),
                              sink=sink)
        record = row_recorder(vectors, rec_index, recording.buffers)
        timing = Timing(len(self.components))
        instances: List[Instance] = []
        try:
            for d in self.components:
                instances.append(d.make())
            self._prepare(instances, vectors, slices, out_names, source_of)
            exchange = self._exchange(instances, vectors, position, source_of, start, n_steps,
                                      timing)
            for d, inst in zip(self.components, instances):
                inst.set_parameters(self.parameter_values[d.spec.name])
            exchange.initialize(start, stop)
            record(recording.slot(0))
            loop_ns, done, ended = self._loop(exchange.step, record, recording, n_steps,
                                              progress)
            if ended is not None:
                stop, n_steps = self._ended(ended, start, done, recording)
            recording.finish()
            warnings_reported = [w for inst in instances for w in inst.take_warnings()]
        except BaseException:
            if sink is not None:
                sink.abort()
            raise
        finally:
            for inst in instances:
                inst.terminate()

        results = self._results(start, stop, n_steps, recording.size if sink is None else 0,
                                recording.buffers, rec_index, position, timing, loop_ns)
        results.metadata["warnings"] = warnings_reported
        if ended is not None:
            results.metadata["ended_by"] = {"component": ended.component, "time": ended.time,
                                            "message": str(ended)}
        results.metadata["builds"] = {d.spec.name: inst.build_info
                                      for d, inst in zip(self.components, instances)}
        if sink is not None:
            sink.close(results)
        return results



def simulate(model: SystemModel, backend: str = "fmu", stop_time: Optional[float] = None,
             progress: Optional[Callable[[int, int], None]] = None, **options) -> Results:
    """Shorthand for ``Simulation(model, backend, **options).run(stop_time, progress)``."""
    return Simulation(model, backend=backend, **options).run(stop_time=stop_time, progress=progress)


__all__ = ["Simulation", "simulate", "step_order"]
