"""Running a system model in libcosim (through libcosimpy), recorded into our :class:`Results`.

libcosim loads the model folder (or ``.ssp`` archive) with its own SSP loader and runs it with
its fixed-step algorithm, the one ``Simulation(algorithm="jacobi")`` reproduces (rule 3J of
:mod:`orchestrator.cosim.master`).  Every output of every component (Real, Integer, Boolean) is
read after every base step from a last-value observer, so the recording has the rows of our
master's (row ``j`` at ``start + j*h``) and the metrics of :mod:`orchestrator.results.metrics` apply
unchanged.  Row 0 (the values after initialization) comes from a time-series observer, which
libcosim offers for Real and Integer variables only: libcosim has no call between
initialization and the first step, so **Boolean outputs are NaN in row 0** (listed in
``metadata["unobserved_at_start"]``).

libcosim runs a model folder with that folder as the working directory: an FMU reading a
file parameter relative to it (the replay's ``log``) finds it as our loader does (relative
to the .ssd).  An ``.ssp`` archive runs in the caller's working directory: its FMU copies
carry the files their parameters name (:mod:`orchestrator.packaging.fmu_copies`).  Column
names, order and units come from each FMU's model description, as in our master.  The
loader's log is set to WARNING (:data:`LOG_LEVEL`), so a clean model prints nothing.
libcosimpy is an optional dependency (the ``test`` extra); without it,
:func:`run_libcosim` raises :class:`~orchestrator.errors.NavfmuError` saying so.
"""
from __future__ import annotations

import contextlib
import ctypes
import json
import os
import sys
import time as _time
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from .backends import NUMERIC_TYPES
from .fmi3_variables import refuse_fmi3
from .host_process import run_child
from ..errors import NavfmuError, SimulationError
from ..results.run_results import Results
from ..model.ssp_archive import load_model

#: libcosim's log level while loading and running (its loader logs at INFO by default)
LOG_LEVEL = "WARNING"
#: libcosim's clock counts integer nanoseconds
NS = 1_000_000_000
_CTYPES = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_bool}
_GETTERS = {"Real": "cosim_observer_slave_get_real", "Integer": "cosim_observer_slave_get_integer",
            "Boolean": "cosim_observer_slave_get_boolean"}


def _libcosimpy():
    try:
        from libcosimpy import CosimExecution, CosimLogging, CosimObserver
        from libcosimpy._internal import libcosimc
    except ImportError as exc:
        raise NavfmuError(
            f"libcosim runs need libcosimpy (pip install libcosimpy): {exc}"
        ) from None
    level = getattr(CosimLogging.CosimLogLevel, LOG_LEVEL)
    CosimLogging.log_output_level(level)
    return CosimExecution.CosimExecution, CosimObserver.CosimObserver, libcosimc()


class _Reader:
    """Reads one component's outputs of one type from a last-value observer into a row."""

    def __init__(self, lib, observer_ptr, slave_index: int, typ: str, vrs: List[int],
                 columns: List[int]):
        fn = getattr(lib, _GETTERS[typ])
        ctype = _CTYPES[typ]
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_uint32),
                       ctypes.c_size_t, ctypes.POINTER(ctype)]
        self.call = fn
        self.args = (ctypes.cast(observer_ptr, ctypes.c_void_p), slave_index,
                     (ctypes.c_uint32 * len(vrs))(*vrs), len(vrs))
        self.values = (ctype * len(vrs))()
        self.view = np.ctypeslib.as_array(self.values) if typ != "Boolean" else None
        self.columns = np.array(columns, dtype=np.intp)

    def read(self, row: np.ndarray) -> None:
        if self.call(*self.args, self.values) != 0:
            raise NavfmuError("libcosim: reading the outputs from the observer failed")
        row[self.columns] = self.view if self.view is not None else list(self.values)


def _outputs(model) -> Dict[str, list]:
    """component -> its Real/Integer/Boolean outputs (VarInfo) in model-description order."""
    from .component_description import describe_fmu

    result = {}
    for spec in model.components:
        d = describe_fmu(spec)
        result[spec.name] = [v for v in d.variables.values()
                             if v.causality == "output" and v.type in NUMERIC_TYPES]
    return result


def run_libcosim(source, stop_time: Optional[float] = None) -> Results:
    """Run ``source`` (a model folder, its ``.ssd`` or an ``.ssp`` archive) in libcosim from
    the model's start time to ``stop_time`` (default: the model's); every output recorded at
    every base step."""
    model = load_model(source)
    refuse_fmi3(model.components, "libcosim")
    Execution, Observer, lib = _libcosimpy()
    start = model.start_time
    stop = float(stop_time) if stop_time is not None else model.stop_time
    h_ns = int(round(model.base_step * NS))
    n_steps = int(round((stop - start) * NS)) // h_ns
    if n_steps < 1 or abs(n_steps * h_ns - (stop - start) * NS) > 1e-9 * (stop - start) * NS:
        raise NavfmuError(f"the run from {start} s to {stop} s is not an integer number of base "
                          f"steps of {model.base_step} s")
    outputs = _outputs(model)
    ssp_path = model.archive if model.archive is not None else model.path.parent
    try:
        execution = Execution.from_ssp_file(str(ssp_path), h_ns)
    except AssertionError as exc:
        raise NavfmuError(f"libcosim cannot load {ssp_path}: {exc}") from None
    last = Observer.create_last_value()
    first = Observer.create_time_series(2)
    execution.add_observer(last)
    execution.add_observer(first)
    index = {info.name.decode(): info.index for info in execution.slave_infos()}
    names = [c.name for c in model.components]
    offsets, readers, total = {}, [], 0
    for name in names:
        offsets[name] = total
        by_type: Dict[str, tuple] = {t: ([], []) for t in NUMERIC_TYPES}
        for j, v in enumerate(outputs[name]):
            by_type[v.type][0].append(v.value_reference)
            by_type[v.type][1].append(total + j)
        for t, (vrs, cols) in by_type.items():
            if vrs:
                readers.append(_Reader(lib, last.ptr(), index[name], t, vrs, cols))
        total += len(outputs[name])
    table = np.zeros((n_steps + 1, total))
    from libcosimpy.CosimEnums import CosimVariableType

    for name in names:
        for v in outputs[name]:
            if v.type != "Boolean":
                first.start_time_series(index[name], v.value_reference,
                                        getattr(CosimVariableType, v.type.upper()))
    wall = _time.perf_counter()
    with _working_directory(model.path.parent if model.archive is None else None):
        _steps(execution, lib, readers, first, table, model, names, outputs, offsets, index)
    wall = _time.perf_counter() - wall
    return _results(model, start, stop, n_steps, table, names, outputs, offsets, wall, ssp_path)


@contextlib.contextmanager
def _working_directory(folder):
    if folder is None:
        yield
        return
    previous = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(previous)


def _steps(execution, lib, readers, first, table, model, names, outputs, offsets, index):
    """Step ``execution`` once per row of ``table`` after the first, reading every output."""
    start = model.start_time
    for k in range(table.shape[0] - 1):
        if not execution.step(1):
            raise SimulationError(f"libcosim: step {k} from t = {start + k * model.base_step:.9g} "
                                  f"s failed: {_last_error(lib)}")
        row = table[k + 1]
        for r in readers:
            r.read(row)
        if k == 0:
            _first_row(lib, first, table[0], names, outputs, offsets, index)


def _first_row(lib, observer, row, names, outputs, offsets, index) -> None:
    """Row 0 from the time-series observer (its step 0 = after initialization).  Called
    directly: libcosimpy's wrapper drops every sample whose step number is 0."""
    steps = (ctypes.c_int64 * 1)()
    times = (ctypes.c_int64 * 1)()
    for name in names:
        for j, v in enumerate(outputs[name]):
            col = offsets[name] + j
            if v.type == "Boolean":
                row[col] = np.nan
                continue
            ctype = _CTYPES[v.type]
            fn = getattr(lib, f"cosim_observer_slave_get_{v.type.lower()}_samples")
            fn.restype = ctypes.c_int64
            fn.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32, ctypes.c_int64,
                           ctypes.c_size_t, ctypes.POINTER(ctype),
                           ctypes.POINTER(ctypes.c_int64), ctypes.POINTER(ctypes.c_int64)]
            value = (ctype * 1)()
            got = fn(ctypes.cast(observer.ptr(), ctypes.c_void_p), index[name],
                     v.value_reference, 0, 1, value, steps, times)
            row[col] = value[0] if got == 1 and steps[0] == 0 else np.nan


def _last_error(lib) -> str:
    fn = lib.cosim_last_error_message
    fn.restype = ctypes.c_char_p
    return (fn() or b"").decode(errors="replace")


def _results(model, start, stop, n_steps, table, names, outputs, offsets, wall, ssp_path):
    h = model.base_step
    data, columns, units = {}, {}, {}
    for name in names:
        width = len(outputs[name])
        data[name] = table[:, offsets[name]:offsets[name] + width]
        columns[name] = [v.name for v in outputs[name]]
        units[name] = [v.unit for v in outputs[name]]
    metadata = {
        "model": model.name, "ssd": str(ssp_path), "master": "libcosim",
        "base_step": h, "start_time": start, "stop_time": stop, "n_steps": n_steps,
        "record_every": 1, "wall_time_s": wall,
        "unobserved_at_start": [f"{n}.{v.name}" for n in names for v in outputs[n]
                                if v.type == "Boolean"],
    }
    return Results(time=start + np.arange(n_steps + 1) * h, data=data, columns=columns,
                   units=units, metadata=metadata)


def _run_unrecorded(source, stop_time: float) -> float:
    """Wall time of libcosim's own loop (``simulate_until``), nothing read back."""
    model = load_model(source)
    refuse_fmi3(model.components, "libcosim")
    Execution, _, _ = _libcosimpy()
    h_ns = int(round(model.base_step * NS))
    execution = Execution.from_ssp_file(str(model.archive or model.path.parent), h_ns)
    t0 = _time.perf_counter()
    with _working_directory(model.path.parent):
        if not execution.simulate_until(int(round(stop_time * NS))):
            raise SimulationError(f"libcosim: the run of {source} failed")
    return _time.perf_counter() - t0


def bench_against_libcosim(source, stop_time: float, repeat: int = 3) -> Dict[str, float]:
    """Our master (Jacobi, every output recorded) against libcosim on the same SSP and base
    step, alternating ``repeat`` times in one process; each one's fastest wall time (creation
    and initialization included) and the ratios ours / libcosim's.  libcosim runs twice per
    round: recording every output every step (as ours does), and on its own
    (``simulate_until``, nothing read back).

    libcosim loads every FMU into the process that runs it, so a model with a foreign FMU
    (:mod:`orchestrator.cosim.isolation`) is timed in a child process
    (:func:`~orchestrator.cosim.host_process.run_child`): its crash or hang ends the child and
    is this call's :class:`~orchestrator.errors.NavfmuError`.  Both masters keep their FMUs
    in the process that times them, so the two run alike."""
    from .component_description import describe_fmu

    model = load_model(source)
    refuse_fmi3(model.components, "libcosim")
    if not any(describe_fmu(spec).hosted for spec in model.components):
        return _bench(source, stop_time, repeat)
    out = run_child(__name__, {"source": str(Path(source).resolve()),
                               "stop_time": float(stop_time), "repeat": int(repeat)})
    if "error" in out:
        raise NavfmuError(f"{source}: the benchmark against libcosim, run in a process of its "
                          f"own for the model's foreign FMUs: {out['error']}")
    return out


def _bench(source, stop_time: float, repeat: int) -> Dict[str, float]:
    """:func:`bench_against_libcosim` in this process."""
    from .isolation import Isolation
    from .master import Simulation

    best = {"ours_s": float("inf"), "libcosim_recorded_s": float("inf"),
            "libcosim_unrecorded_s": float("inf")}
    for _ in range(max(1, int(repeat))):
        t0 = _time.perf_counter()
        Simulation(load_model(source), algorithm="jacobi",
                   isolation=Isolation("never")).run(stop_time)
        best["ours_s"] = min(best["ours_s"], _time.perf_counter() - t0)
        t0 = _time.perf_counter()
        run_libcosim(source, stop_time)
        best["libcosim_recorded_s"] = min(best["libcosim_recorded_s"], _time.perf_counter() - t0)
        t0 = _time.perf_counter()
        _run_unrecorded(source, stop_time)
        best["libcosim_unrecorded_s"] = min(best["libcosim_unrecorded_s"],
                                            _time.perf_counter() - t0)
    best["ratio_recorded"] = best["ours_s"] / best["libcosim_recorded_s"]
    best["ratio_unrecorded"] = best["ours_s"] / best["libcosim_unrecorded_s"]
    best["stop_time"] = float(stop_time)
    best["repeat"] = max(1, int(repeat))
    return best


def main(job_file) -> None:
    """The child of :func:`bench_against_libcosim`: its job's measurements as JSON."""
    with open(job_file, encoding="utf-8") as f:
        job = json.load(f)
    print(json.dumps(_bench(job["source"], job["stop_time"], job["repeat"])), flush=True)


__all__ = ["run_libcosim", "bench_against_libcosim", "LOG_LEVEL"]


if __name__ == "__main__":
    main(sys.argv[1])
