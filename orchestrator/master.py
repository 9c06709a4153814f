"""The co-simulation master: fixed base step, integer decimation, Gauss-Seidel ordering.

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

3. **Order.**  Within a macro step the due components are stepped one after the other in a
   fixed order: a topological order of the component graph (an edge for every connection,
   source component -> destination component), ties broken by declaration order in the SSD
   (among the components whose sources are all placed, the earliest-declared goes next).
   For each due component, in that order: set its inputs from the *latest* values of their
   source outputs, call ``do_step``, read its outputs.  So an input whose source comes earlier
   in the order sees that source's output at ``t_{k+1}`` (if the source was due in this macro
   step; otherwise its held value); this is Gauss-Seidel.  A decimated component, when due,
   sees its inputs' values at the end of its own step, ``t_{k+1}``.

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

6. **Recording.**  Every output of every component (or the selection given by ``record``:
   component names and/or ``"Component.variable"``) is recorded in preallocated arrays,
   Real/Integer/Boolean as float; row 0 holds the initial outputs, row ``j`` the outputs after
   macro step ``j*record_every - 1`` (time ``start + j*record_every*h``).  String variables
   are never recorded.

7. **Timing.**  For every component the master measures (``perf_counter_ns``) the wall time
   of each ``do_step`` call alone, and of the whole set-inputs/do-step/get-outputs sequence.
   ``Results.step_time_s[c]`` is the mean ``do_step`` time per call;
   ``Results.exchange_step_time_s[c]`` the mean of the whole sequence;
   ``metadata["master_overhead_s_per_step"]`` the loop's wall time not spent in those
   sequences, per macro step (index gathering, recording, bookkeeping).

8. **Swaps and wiring checks.**  Before anything runs, every connected variable must exist
   in its component's FMU/Python component with the right causality (output at the start,
   input at the end) and the connector's type; every SSD parameter and override must exist as
   a parameter (or input).  Otherwise :class:`~orchestrator.errors.WiringError` names the
   component, the variable and the FMU file.  For a component whose source was replaced
   (:meth:`SystemModel.replace_source`), SSD parameters the new FMU does not have are skipped
   (a filter swap keeps the scenario's parameters that still apply) and listed in
   :attr:`Simulation.skipped_parameters`.

9. **Failures.**  A component failing mid-run (FMU status Discard/Error/Fatal, or a Python
   component raising ParameterError/InputError) raises
   :class:`~orchestrator.errors.SimulationError` naming the component and the time, with the
   component's log; every instance is terminated and freed, and no results are returned.
"""
from __future__ import annotations

import time as _time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .backends import NUMERIC_TYPES, DirectInstance, FmuInstance, Instance, VarInfo
from .errors import NavfmuError, WiringError
from .results import Results
from .ssp import ComponentSpec, Connection, SystemModel

#: relative tolerance for "the run length / a step hint is an integer multiple of h"
MULTIPLE_TOLERANCE = 1e-9
_DTYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.int32}


# ----------------------------------------------------------------------------------------
# Ordering
# ----------------------------------------------------------------------------------------
def _reachable(n: int, edges: Iterable[Tuple[int, int]]) -> List[set]:
    succ: List[set] = [set() for _ in range(n)]
    for a, b in edges:
        succ[a].add(b)
    reach = []
    for s in range(n):
        seen, stack = set(), [s]
        while stack:
            for nxt in succ[stack.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    stack.append(nxt)
        reach.append(seen)
    return reach


def step_order(n_components: int, connections: Sequence[Tuple[int, int, Any]]
               ) -> Tuple[List[int], List[Any]]:
    """Order components 0..n-1 (declaration order) by the rules 3 and 4 of the module docstring.

    ``connections`` are ``(source, destination, key)``; returns the order and the keys of the
    delayed connections (in the order given).
    """
    delayed = {id(c): c for c in connections if c[0] == c[1]}
    active = [c for c in connections if c[0] != c[1]]
    remaining = list(range(n_components))
    order: List[int] = []
    while remaining:
        rem = set(remaining)
        blocked = {b for a, b, _ in active if a in rem and b in rem}
        ready = [i for i in remaining if i not in blocked]
        if ready:
            order.append(ready[0])
            remaining.remove(ready[0])
            continue
        # no component is ready: break the cycle at its earliest-declared component
        sub = [(a, b) for a, b, _ in active if a in rem and b in rem]
        reach = _reachable(n_components, sub)
        on_cycle = [i for i in remaining if i in reach[i]]
        victim = on_cycle[0]
        same_scc = {j for j in remaining if j in reach[victim] and victim in reach[j]}
        for c in list(active):
            if c[1] == victim and c[0] in same_scc:
                delayed[id(c)] = c
                active.remove(c)
    return order, [c[2] for c in connections if id(c) in delayed]


# ----------------------------------------------------------------------------------------
# Per-component description (known before anything is instantiated)
# ----------------------------------------------------------------------------------------
@dataclass
class _Described:
    spec: ComponentSpec
    variables: Dict[str, VarInfo]
    source: str            # FMU path or Python class, for messages
    model_name: str
    make: Callable[[], Instance]


def _model_name_of_fmu(path: Path) -> str:
    from fmpy import read_model_description

    try:
        return read_model_description(str(path), validate=False).modelName
    except Exception as exc:  # fmpy raises plain Exception for unreadable files
        raise NavfmuError(f"cannot read the model description of {path}: {exc}") from None


def _describe_fmu(spec: ComponentSpec) -> _Described:
    from fmpy import read_model_description

    path = spec.source
    if not path.is_file():
        raise NavfmuError(f"component '{spec.name}': FMU file not found: {path}")
    try:
        md = read_model_description(str(path), validate=False)
    except Exception as exc:  # fmpy raises plain Exception for unreadable files
        raise NavfmuError(f"component '{spec.name}': cannot read the model description of "
                          f"{path}: {exc}") from None
    variables = {}
    for v in md.modelVariables:
        unit = v.unit or (v.declaredType.unit if v.declaredType is not None else None) or ""
        variables[v.name] = VarInfo(v.name, v.type, v.causality, unit, v.valueReference)
    return _Described(spec, variables, str(path), md.modelName,
                      lambda: FmuInstance(path, spec.name))


def _describe_direct(spec: ComponentSpec, registry: Mapping[str, type]) -> _Described:
    model_name = spec.source.stem
    if model_name not in registry and spec.source.is_file():
        model_name = _model_name_of_fmu(spec.source)
    probe = DirectInstance.from_registry(model_name, spec.name, registry)
    return _Described(spec, probe.variables, probe.source, model_name,
                      lambda: DirectInstance.from_registry(model_name, spec.name, registry))


# ----------------------------------------------------------------------------------------
# Simulation
# ----------------------------------------------------------------------------------------
class Simulation:
    """Run a :class:`SystemModel` by the rules of the module docstring.

    ``backend`` is ``"fmu"`` (every component's ``source`` FMU through fmpy) or ``"direct"``
    (the Python component registered under the FMU's model name in ``registry``, a mapping
    model name -> component class).  ``record`` selects what is recorded (None: every output).
    ``parameters`` overrides values as ``{"Component.variable": value}``.
    Construction checks the wiring (rule 8); :meth:`run` instantiates, runs and terminates.
    """

    def __init__(self, model: SystemModel, backend: str = "fmu",
                 registry: Optional[Mapping[str, type]] = None,
                 record: Optional[Iterable[str]] = None,
                 parameters: Optional[Mapping[str, Any]] = None,
                 base_step: Optional[float] = None, record_every: int = 1):
        if backend not in ("fmu", "direct"):
            raise NavfmuError(f"unknown backend '{backend}' (use 'fmu' or 'direct')")
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
        self.components = [
            _describe_fmu(c) if backend == "fmu" else _describe_direct(c, registry)
            for c in model.components
        ]
        self.names = [c.spec.name for c in self.components]
        self._index = {n: i for i, n in enumerate(self.names)}
        self.decimation = {c.spec.name: self._decimation(c.spec) for c in self.components}
        self._check_wiring()
        self.parameter_values, self.skipped_parameters = self._parameters(parameters or {})
        self.recorded = self._recorded(record)
        edges = [(self._index[c.start_component], self._index[c.end_component], c)
                 for c in model.connections]
        order, delayed = step_order(len(self.names), edges)
        self.order: List[str] = [self.names[i] for i in order]
        self.delayed_connections: List[Connection] = delayed

    # -- checks -------------------------------------------------------------------------
    def _decimation(self, spec: ComponentSpec) -> int:
        if spec.step_hint is None:
            return 1
        ratio = spec.step_hint / self.base_step
        n = int(round(ratio))
        if n < 1 or abs(ratio - n) > MULTIPLE_TOLERANCE * ratio:
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

    def _parameters(self, overrides: Mapping[str, Any]):
        values: Dict[str, Dict[str, Any]] = {n: {} for n in self.names}
        skipped: List[str] = []
        settable = ("parameter", "input")
        for d in self.components:
            swapped = d.spec.name in self.model.replaced_sources
            for pname, (_, value) in d.spec.parameters.items():
                var = d.variables.get(pname)
                if var is None or var.causality not in settable:
                    if swapped:
                        skipped.append(f"{d.spec.name}.{pname}")
                        continue
                    raise WiringError(
                        f"component '{d.spec.name}' ({d.source}): the system structure sets "
                        f"parameter '{pname}', which "
                        + ("does not exist" if var is None else
                           f"has causality '{var.causality}' (not settable)")
                    )
                values[d.spec.name][pname] = value
        if skipped:
            warnings.warn("parameters not present in the swapped-in component(s), skipped: "
                          + ", ".join(skipped), stacklevel=3)
        for key, value in overrides.items():
            comp, var_name = self._split(key, "parameter override")
            d = self.components[self._index[comp]]
            var = d.variables.get(var_name)
            if var is None or var.causality not in settable:
                raise WiringError(
                    f"parameter override '{key}': component '{comp}' ({d.source}) has no "
                    f"parameter '{var_name}'" + ("" if var is None else
                                                 f" (it is an {var.causality})")
                )
            values[comp][var_name] = value
        return values, skipped

    def _split(self, key: str, what: str) -> Tuple[str, str]:
        comp, dot, var = key.partition(".")
        if comp not in self._index:
            raise WiringError(f"{what} '{key}': no component named '{comp}' "
                              f"(components: {', '.join(self.names)})")
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
        if n < 1 or abs(ratio - n) > MULTIPLE_TOLERANCE * max(ratio, 1.0):
            raise NavfmuError(f"the run from {start} s to {stop} s is not an integer number of "
                              f"base steps of {self.base_step} s")
        return n

    def run(self, stop_time: Optional[float] = None,
            progress: Optional[Callable[[int, int], None]] = None) -> Results:
        """Run from the model's start time to ``stop_time`` (default: the model's).

        ``progress(steps_done, n_steps)`` is called about every 1 % of the run and at the end.
        """
        start = self.model.start_time
        stop = float(stop_time) if stop_time is not None else self.model.stop_time
        h = self.base_step
        n_steps = self._n_steps(start, stop)
        record_every = self.record_every
        n_rows = n_steps // record_every + 1

        comps = self.components
        idx = self._index
        # inputs of every component (connection order) and the outputs it must provide
        inputs: Dict[str, List[Connection]] = {n: [] for n in self.names}
        needed: Dict[str, set] = {n: set(self.recorded[n]) for n in self.names}
        for conn in self.model.connections:
            inputs[conn.end_component].append(conn)
            needed[conn.start_component].add(conn.start_connector)
        out_names = {d.spec.name: [v.name for v in d.variables.values()
                                   if v.name in needed[d.spec.name]] for d in comps}

        # global signal vectors: per type, every component's read outputs, one slice each
        offsets: Dict[str, Dict[str, int]] = {t: {} for t in NUMERIC_TYPES}
        by_type: Dict[str, Dict[str, List[str]]] = {t: {} for t in NUMERIC_TYPES}
        position: Dict[Tuple[str, str], Tuple[str, int]] = {}
        sizes = {t: 0 for t in NUMERIC_TYPES}
        for d in comps:
            n = d.spec.name
            for t in NUMERIC_TYPES:
                names = [v for v in out_names[n] if d.variables[v].type == t]
                by_type[t][n] = names
                offsets[t][n] = sizes[t]
                for j, v in enumerate(names):
                    position[(n, v)] = (t, sizes[t] + j)
                sizes[t] += len(names)
        vectors = {t: np.zeros(sizes[t], dtype=_DTYPES[t]) for t in NUMERIC_TYPES}
        rec_index = {t: np.array([position[(n, v)][1] for n in self.names
                                  for v in self.recorded[n] if position[(n, v)][0] == t],
                                 dtype=np.intp) for t in NUMERIC_TYPES}
        recordings = {t: np.zeros((n_rows, len(rec_index[t])), dtype=_DTYPES[t])
                      for t in NUMERIC_TYPES}
        # recording everything in vector order: one row copy per type and step
        rec_all = {t: np.array_equal(rec_index[t], np.arange(sizes[t])) for t in NUMERIC_TYPES}

        instances: List[Instance] = []
        try:
            for d in comps:
                instances.append(d.make())
            plan = []
            for i, (d, inst) in enumerate(zip(comps, instances)):
                n = d.spec.name
                views = {t: vectors[t][offsets[t][n]:offsets[t][n] + len(by_type[t][n])]
                         for t in NUMERIC_TYPES}
                in_names = [c.end_connector for c in inputs[n]]
                source_of = {c.end_connector: (c.start_component, c.start_connector)
                             for c in inputs[n]}
                inst.prepare(in_names, out_names[n], views["Real"], views["Integer"],
                             views["Boolean"])
                src = []
                for t in NUMERIC_TYPES:
                    names = inst.input_names[t]
                    src.append(np.array([position[source_of[v]][1] for v in names], dtype=np.intp)
                               if names else None)
                plan.append((i, self.decimation[n], src[0], src[1], src[2],
                             inst.real_in, inst.int_in, inst.bool_in,
                             inst.set_inputs, inst.do_step, inst.get_outputs))
            ordered_plan = [plan[idx[n]] for n in self.order]
            # bound ndarray.take with mode="clip" (indices are valid by construction) costs
            # a fraction of np.take(..., out=...) per call
            take_real, take_int, take_bool = (vectors[t].take for t in NUMERIC_TYPES)

            def exchange(entry):
                _, _, rs, is_, bs, rin, iin, bin_, set_in, _, get_out = entry
                if rs is not None:
                    take_real(rs, out=rin, mode="clip")
                if is_ is not None:
                    take_int(is_, out=iin, mode="clip")
                if bs is not None:
                    take_bool(bs, out=bin_, mode="clip")
                set_in()
                get_out()

            # -- initialization (rule 5) ------------------------------------------------
            for d, inst in zip(comps, instances):
                inst.set_parameters(self.parameter_values[d.spec.name])
            for inst in instances:
                inst.enter_initialization(start, stop)
            for entry in ordered_plan:
                exchange(entry)
            for n in self.order:
                instances[idx[n]].exit_initialization()
            for n in self.order:
                instances[idx[n]].get_outputs()

            def record(row):
                for t in NUMERIC_TYPES:
                    if rec_all[t]:
                        recordings[t][row] = vectors[t]
                    elif len(rec_index[t]):
                        vectors[t].take(rec_index[t], out=recordings[t][row], mode="clip")

            record(0)

            # -- macro steps (rules 1-3) ------------------------------------------------
            n_comp = len(comps)
            do_ns = [0] * n_comp
            all_ns = [0] * n_comp
            calls = [0] * n_comp
            progress_every = max(1, n_steps // 100)
            next_progress = progress_every if progress is not None else n_steps + 1
            real_rec, int_rec, bool_rec = (recordings[t] for t in NUMERIC_TYPES)
            real_vec, int_vec, bool_vec = (vectors[t] for t in NUMERIC_TYPES)
            real_all, int_all, bool_all = (rec_all[t] for t in NUMERIC_TYPES)
            simple_record = real_all and int_all and bool_all
            clock = _time.perf_counter_ns
            loop_start = clock()
            for k in range(n_steps):
                kp1 = k + 1
                for (i, n, rs, is_, bs, rin, iin, bin_, set_in, do_step, get_out) in ordered_plan:
                    if n != 1 and kp1 % n:
                        continue
                    t0 = clock()
                    if rs is not None:
                        take_real(rs, out=rin, mode="clip")
                    if is_ is not None:
                        take_int(is_, out=iin, mode="clip")
                    if bs is not None:
                        take_bool(bs, out=bin_, mode="clip")
                    set_in()
                    t1 = clock()
                    do_step(start + (kp1 - n) * h, n * h)
                    t2 = clock()
                    get_out()
                    t3 = clock()
                    do_ns[i] += t2 - t1
                    all_ns[i] += t3 - t0
                    calls[i] += 1
                if kp1 % record_every == 0:
                    row = kp1 // record_every
                    if simple_record:
                        real_rec[row] = real_vec
                        int_rec[row] = int_vec
                        bool_rec[row] = bool_vec
                    else:
                        record(row)
                if kp1 == next_progress:
                    progress(kp1, n_steps)
                    next_progress = kp1 + progress_every
            loop_ns = clock() - loop_start
            if progress is not None and n_steps % progress_every:
                progress(n_steps, n_steps)
        finally:
            for inst in instances:
                inst.terminate()

        return self._results(start, stop, n_steps, n_rows, recordings, rec_index, position,
                             do_ns, all_ns, calls, loop_ns)

    # -- results ------------------------------------------------------------------------
    def _results(self, start, stop, n_steps, n_rows, recordings, rec_index, position,
                 do_ns, all_ns, calls, loop_ns) -> Results:
        h = self.base_step
        time_column = start + np.arange(n_rows, dtype=np.float64) * (self.record_every * h)
        # column of each recorded (component, variable) inside its type's recording
        rec_col = {t: {int(g): j for j, g in enumerate(rec_index[t])} for t in NUMERIC_TYPES}
        data, columns, units = {}, {}, {}
        for d in self.components:
            n = d.spec.name
            names = self.recorded[n]
            arr = np.empty((n_rows, len(names)), dtype=np.float64)
            for j, v in enumerate(names):
                t, g = position[(n, v)]
                arr[:, j] = recordings[t][:, rec_col[t][g]]
            data[n] = arr
            columns[n] = list(names)
            units[n] = [d.variables[v].unit or d.spec.units.get(v, "") for v in names]
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
