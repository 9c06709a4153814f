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

import time as _time
import warnings
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Tuple

import numpy as np
from navcore.core.timing import TIME_TOLERANCE

from .backends import NUMERIC_TYPES, Instance
from .component_description import describe_direct, describe_fmu
from ..errors import (NavfmuError, NavfmuWarning, SimulationTerminated,
                      SkippedParametersWarning, WiringError)
from .exchange import ALGORITHMS, Timing, exchange_for, slots_for, step_order
from .isolation import Isolation
from .lever_arm_wiring import unconnected_lever_arms
from ..results.recorder import Recording
from ..results.run_results import Results
from ..model.ssp import ComponentSpec, Connection, SystemModel
from ..model import units
from ..model.suggestions import did_you_mean
#: the types a parameter value can be set to
SETTABLE_TYPES = ("Real", "Integer", "Enumeration", "Boolean", "String")
_DTYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.int32}


def _row_recorder(vectors, rec_index, recordings):
    """``record(row)``: copy the recorded signals into row ``row`` of the recording buffers;
    a type recorded whole, in vector order, is one row copy.  The vectors may carry a leading
    run axis (a batch, :mod:`orchestrator.cosim.batch`); the buffers' rows then do too."""
    whole = [t for t in NUMERIC_TYPES
             if np.array_equal(rec_index[t], np.arange(vectors[t].shape[-1]))]
    picked = [t for t in NUMERIC_TYPES if t not in whole and len(rec_index[t])]

    def record(row):
        for t in whole:
            recordings[t][row] = vectors[t]
        for t in picked:
            vectors[t].take(rec_index[t], axis=-1, out=recordings[t][row], mode="clip")

    return record


def _column_blocks(sources):
    """``sources[j]`` = (type, column) of output column j as blocks ``(j, type, column,
    width)`` of consecutive columns of one type on both sides (one slice copy each instead
    of one per column)."""
    blocks = []
    for j, (t, c) in enumerate(sources):
        if blocks:
            start, bt, bc, width = blocks[-1]
            if bt == t and bc + width == c:
                blocks[-1] = (start, bt, bc, width + 1)
                continue
        blocks.append((j, t, c, 1))
    return blocks


# ----------------------------------------------------------------------------------------
# Simulation
def _parameter_hint(d, name: str) -> str:
    """The component's parameters close to the unknown ``name``, or all of them."""
    names = sorted(v.name for v in d.variables.values() if v.causality == "parameter")
    return did_you_mean(name, names) or f" (its parameters: {', '.join(names)})"


def _check_settable(d, var) -> None:
    """Refuse setting a parameter of a type no parameter value maps onto (an FMI 3.0
    Float32, UInt8, array...: :mod:`orchestrator.cosim.fmi3_variables`)."""
    if var.type not in SETTABLE_TYPES:
        raise WiringError(f"component '{d.spec.name}' ({d.source}): parameter '{var.name}' has "
                          f"type {var.type}, which cannot be set (settable: "
                          f"{', '.join(SETTABLE_TYPES)})")


# ----------------------------------------------------------------------------------------
class Simulation:
    """Run a :class:`SystemModel` by the rules of the module docstring.

    ``backend`` is ``"fmu"`` (every component's ``source`` FMU through fmpy) or ``"direct"``
    (the Python component registered under the FMU's model name in ``registry``, a mapping
    model name -> component class).  ``record`` selects what is recorded (None: every output).
    ``parameters`` overrides values as ``{"Component.variable": value}``.  ``isolation``
    (:mod:`orchestrator.cosim.isolation`, default: foreign FMUs) says which FMUs run in a
    host process of their own (rule 10).
    Construction checks the wiring (rule 8); :meth:`run` instantiates, runs and terminates.
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

    # -- checks -------------------------------------------------------------------------
    def _decimation(self, spec: ComponentSpec) -> int:
        if spec.step_hint is None:
            return 1
        ratio = spec.step_hint / self.base_step
        n = int(round(ratio))
        if n < 1 or abs(ratio - n) > TIME_TOLERANCE * ratio:
            raise NavfmuError(f"component '{spec.name}': its step {spec.step_hint} s is not an "
                              f"integer multiple of the base step {self.base_step} s")
        return n

    def _check_wiring(self) -> None:
        for conn in self.model.connections:
            for comp_name, var_name, causality in (
                    (conn.start_component, conn.start_connector, "output"),
                    (conn.end_component, conn.end_connector, "input")):
                d = self.components[self._index[comp_name]]
                var = d.variables.get(var_name)
                where = f"component '{comp_name}' ({d.source})"
                if var is None:
                    raise WiringError(f"{where} has no variable '{var_name}', which the connection "
                                      f"{conn} needs")
                if var.causality != causality:
                    raise WiringError(f"{where}: variable '{var_name}' has causality "
                                      f"'{var.causality}', but the connection {conn} needs an "
                                      f"{causality}")
                declared = d.spec.connectors.get(var_name, (None, None))[1]
                if declared is not None and var.type != declared:
                    raise WiringError(f"{where}: variable '{var_name}' is a {var.type}, but the "
                                      f"system structure declares it as {declared} "
                                      f"(connection {conn})")
                if var.type not in NUMERIC_TYPES:
                    raise WiringError(f"{where}: variable '{var_name}' is a {var.type}; only Real, "
                                      f"Integer and Boolean variables can be connected")
                units.check_same(d.spec.units.get(var_name, ""), var.unit,
                                 f"{where}: the system structure's connector '{var_name}' "
                                 "against the FMU's variable")
            self._check_connection_units(conn)

    def _check_connection_units(self, conn: Connection) -> None:
        """Both ends of ``conn`` in one unit (rule 8: the value passes unchanged)."""
        ends = [self.components[self._index[c]].variables[v] for c, v in (
            (conn.start_component, conn.start_connector),
            (conn.end_component, conn.end_connector))]
        units.check_same(ends[0].unit, ends[1].unit, f"connection {conn}")

    def _parameters(self, overrides: Mapping[str, Any]):
        values: Dict[str, Dict[str, Any]] = {n: {} for n in self.names}
        skipped: List[str] = []
        settable = ("parameter", "input")
        for d in self.components:
            swapped = d.spec.name in self.model.replaced_sources
            for pname, (_, value) in d.spec.parameters.items():
                var = d.variables.get(pname)
                if var is None or var.causality not in settable:
                    if swapped and pname not in d.spec.variant_parameters:
                        skipped.append(f"{d.spec.name}.{pname}")
                        continue
                    raise WiringError(
                        f"component '{d.spec.name}' ({d.source}): the system structure sets "
                        f"parameter '{pname}', which "
                        + ("does not exist" if var is None else
                           f"has causality '{var.causality}' (not settable)")
                    )
                _check_settable(d, var)
                unit = d.spec.parameter_units.get(pname)
                if unit:
                    value = units.convert(value, unit, var.unit,
                                          f"component '{d.spec.name}' ({d.source}): parameter "
                                          f"'{pname}' = {value!r} {unit}")
                values[d.spec.name][pname] = value
        if skipped:
            warnings.warn("parameters not present in the swapped-in component(s), skipped: "
                          + ", ".join(skipped), SkippedParametersWarning, stacklevel=3)
        for key, value in overrides.items():
            comp, var_name = self._split(key, "parameter override")
            d = self.components[self._index[comp]]
            var = d.variables.get(var_name)
            if var is None or var.causality not in settable:
                raise WiringError(
                    f"parameter override '{key}': component '{comp}' ({d.source}) has no "
                    f"parameter '{var_name}'" + (_parameter_hint(d, var_name) if var is None
                                                 else f" (it is an {var.causality})")
                )
            _check_settable(d, var)
            values[comp][var_name] = value
        return values, skipped

    def _split(self, key: str, what: str) -> Tuple[str, str]:
        comp, dot, var = key.partition(".")
        if comp not in self._index:
            raise WiringError(f"{what} '{key}': no component named '{comp}' "
                              f"(components: {', '.join(self.names)})"
                              + did_you_mean(comp, self.names))
        return comp, var if dot else ""

    def _recorded(self, record: Optional[Iterable[str]]) -> Dict[str, List[str]]:
        """component -> recorded output names, in the component's variable order."""
        def outputs(d):
            return [v.name for v in d.variables.values()
                    if v.causality == "output" and v.type in NUMERIC_TYPES]

        if record is None:
            return {d.spec.name: outputs(d) for d in self.components}
        wanted: Dict[str, set] = {n: set() for n in self.names}
        for item in ([record] if isinstance(record, str) else record):
            comp, var_name = self._split(item, "record")
            d = self.components[self._index[comp]]
            if not var_name:
                wanted[comp].update(outputs(d))
                continue
            var = d.variables.get(var_name)
            if var is None or var.causality != "output" or var.type not in NUMERIC_TYPES:
                raise WiringError(f"record '{item}': component '{comp}' ({d.source}) has no "
                                  f"Real/Integer/Boolean output '{var_name}'")
            wanted[comp].add(var_name)
        return {d.spec.name: [n for n in outputs(d) if n in wanted[d.spec.name]]
                for d in self.components}

    # -- running ------------------------------------------------------------------------
    def _n_steps(self, start: float, stop: float) -> int:
        if not stop > start:
            raise NavfmuError(f"the stop time {stop} must be greater than the start time {start}")
        ratio = (stop - start) / self.base_step
        n = int(round(ratio))
        if n < 1 or abs(ratio - n) > TIME_TOLERANCE * max(ratio, 1.0):
            raise NavfmuError(f"the run from {start} s to {stop} s is not an integer number of "
                              f"base steps of {self.base_step} s")
        return n

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
        vectors = {t: np.zeros(sizes[t], dtype=_DTYPES[t]) for t in NUMERIC_TYPES}
        return vectors, position, slices, out_names, source_of

    def _prepare(self, instances, vectors, slices, out_names, source_of) -> None:
        for d, inst in zip(self.components, instances):
            n = d.spec.name
            views = [vectors[t][slice(*slices[n][t])] for t in NUMERIC_TYPES]
            inst.prepare(list(source_of[n]), out_names[n], *views)

    def _rec_index(self, position) -> Dict[str, np.ndarray]:
        """Per type, the positions of the recorded signals in the signal vector."""
        return {t: np.array([position[(n, v)][1] for n in self.names
                             for v in self.recorded[n] if position[(n, v)][0] == t],
                            dtype=np.intp) for t in NUMERIC_TYPES}

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
                              {t: len(rec_index[t]) for t in NUMERIC_TYPES}, _DTYPES,
                              lambda first, n, bufs: self._chunk(first, n, bufs, rec_index,
                                                                 position),
                              sink=sink)
        record = _row_recorder(vectors, rec_index, recording.buffers)
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

    def _loop(self, step, record, recording, n_steps: int, progress):
        """The macro steps 0 .. n_steps-1, each row recorded when due; returns the loop's
        wall time [ns], the macro steps done and the :class:`SimulationTerminated` that
        ended it early (or None).  ``progress`` is called about every 1 % and at the end."""
        record_every = self.record_every
        progress_every = max(1, n_steps // 100)
        next_progress = progress_every if progress is not None else n_steps + 1
        ended = None
        loop_start = _time.perf_counter_ns()
        for k in range(n_steps):
            try:
                step(k)
            except SimulationTerminated as exc:
                ended, n_steps = exc, k
                break
            kp1 = k + 1
            if kp1 % record_every == 0:
                record(recording.slot(kp1 // record_every))
            if kp1 == next_progress:
                progress(kp1, n_steps)
                next_progress = kp1 + progress_every
        loop_ns = _time.perf_counter_ns() - loop_start
        if progress is not None and n_steps % progress_every:
            progress(n_steps, n_steps)
        return loop_ns, n_steps, ended

    def _ended(self, ended: SimulationTerminated, start: float, done: int, recording):
        """A component ended the simulation in macro step ``done`` (rule 9): the run ends at
        its last recorded row before it, which every component reached; returns that stop
        time and its macro steps.  With no row past the initial one, the run fails."""
        rows = done // self.record_every
        if rows == 0:
            raise ended
        recording.end_at(rows + 1)
        n_steps = rows * self.record_every
        stop = start + n_steps * self.base_step
        warnings.warn(f"{ended}; the results end at t = {stop:.9g} s, the last recorded "
                      f"communication point every component reached", NavfmuWarning,
                      stacklevel=3)
        return stop, n_steps

    # -- results ------------------------------------------------------------------------
    def _chunk(self, first_row, n_rows, recordings, rec_index, position) -> Results:
        """Rows ``first_row ..`` of the recording from the first ``n_rows`` buffer rows."""
        time_column = (self.model.start_time + (first_row + np.arange(n_rows, dtype=np.float64))
                       * (self.record_every * self.base_step))
        # column of each recorded (component, variable) inside its type's recording
        rec_col = {t: {int(g): j for j, g in enumerate(rec_index[t])} for t in NUMERIC_TYPES}
        data, columns, units = {}, {}, {}
        for d in self.components:
            n = d.spec.name
            names = self.recorded[n]
            arr = np.empty((n_rows, len(names)), dtype=np.float64)
            sources = [position[(n, v)] for v in names]
            for j, t, c, width in _column_blocks([(t, rec_col[t][g]) for t, g in sources]):
                arr[:, j:j + width] = recordings[t][:n_rows, c:c + width]
            data[n] = arr
            columns[n] = list(names)
            units[n] = [d.variables[v].unit or d.spec.units.get(v, "") for v in names]
        return Results(time=time_column, data=data, columns=columns, units=units)

    def _results(self, start, stop, n_steps, n_rows, recordings, rec_index, position,
                 timing, loop_ns) -> Results:
        h = self.base_step
        chunk = self._chunk(0, n_rows, recordings, rec_index, position)
        time_column, data, columns, units = chunk.time, chunk.data, chunk.columns, chunk.units
        do_ns, all_ns, calls = timing.do_ns, timing.all_ns, timing.calls
        step_time = {}
        exchange_time = {}
        for i, n in enumerate(self.names):
            step_time[n] = do_ns[i] / calls[i] * 1e-9 if calls[i] else float("nan")
            exchange_time[n] = all_ns[i] / calls[i] * 1e-9 if calls[i] else float("nan")
        overhead = (loop_ns - sum(all_ns)) * 1e-9 / n_steps
        metadata = {
            "model": self.model.name,
            "ssd": str(self.model.path),
            "backend": self.backend,
            "algorithm": self.algorithm,
            "base_step": h,
            "start_time": start,
            "stop_time": stop,
            "n_steps": n_steps,
            "record_every": self.record_every,
            "order": list(self.order),
            "decimation": dict(self.decimation),
            "delayed_connections": [str(c) for c in self.delayed_connections],
            "sources": {d.spec.name: d.source for d in self.components},
            "model_names": {d.spec.name: d.model_name for d in self.components},
            "hosted": [d.spec.name for d in self.components if d.hosted],
            "replaced_sources": {k: str(v) for k, v in self.model.replaced_sources.items()},
            "skipped_parameters": list(self.skipped_parameters),
            "parameters": {n: {k: v for k, v in p.items()}
                           for n, p in self.parameter_values.items()},
            "step_calls": {n: calls[i] for i, n in enumerate(self.names)},
            "wall_time_s": loop_ns * 1e-9,
            "master_overhead_s_per_step": overhead,
        }
        return Results(time=time_column, data=data, columns=columns, units=units,
                       step_time_s=step_time, exchange_step_time_s=exchange_time,
                       metadata=metadata)


def simulate(model: SystemModel, backend: str = "fmu", stop_time: Optional[float] = None,
             progress: Optional[Callable[[int, int], None]] = None, **options) -> Results:
    """Shorthand for ``Simulation(model, backend, **options).run(stop_time, progress)``."""
    return Simulation(model, backend=backend, **options).run(stop_time=stop_time, progress=progress)


__all__ = ["Simulation", "simulate", "step_order"]
