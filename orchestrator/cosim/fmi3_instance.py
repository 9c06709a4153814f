"""An FMI 3.0 co-simulation FMU behind the master's
:class:`~orchestrator.cosim.backends.Instance` interface, through fmpy's ``FMU3Slave``, and
:func:`open_fmu`, which gives either version its instance.

:class:`Fmi3Instance` is an :class:`~orchestrator.cosim.fmu_instance.FmuInstance` (the same
extraction, log, messages and clean-up) whose FMI calls are FMI 3.0's:

* instantiation with ``eventModeUsed`` and ``earlyReturnAllowed`` off (the master steps on its
  own fixed grid and uses no event mode), log messages into the instance's log (FMI 3.0 gives
  the callback no instance name: each instance has a callback of its own);
* ``fmi3EnterInitializationMode(tolerance undefined, start, stop)`` in place of
  ``fmi2SetupExperiment`` and ``fmi2EnterInitializationMode``;
* the per-step exchange, one get/set call per FMI 3.0 type and direction: Float64 into the
  Real buffers, Int32 and Int64 into the Integer buffers (an Int64 outside 32 bits refused
  when read), the one-byte Boolean into the int32 Boolean buffers
  (:mod:`orchestrator.cosim.fmi3_variables` has the mapping and what is refused before
  anything runs);
* ``fmi3DoStep``: a ``terminateSimulation`` it returns raises
  :class:`~orchestrator.errors.SimulationTerminated` saying which component asked at which
  time; the master ends the run there and keeps its rows (rule 9 of
  :mod:`orchestrator.cosim.master`);
* ``fmi3GetFMUState``/``fmi3SetFMUState``/``fmi3FreeFMUState`` when the FMU's
  ``canGetAndSetFMUState`` says it can.
"""
from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any, Dict, Mapping, Optional

import numpy as np

from .backends import NUMERIC_TYPES, FMI_INTEGER_MAX, FMI_INTEGER_MIN, coerce
from .fmi3_variables import fmi_version
from .fmu_instance import FmuInstance, _dispatch_log
from ..errors import SimulationError, SimulationTerminated

#: FMI 3.0 type -> (numpy dtype, ctypes element type) of the values passed to get/set
_C_TYPES = {"Float64": (np.float64, ctypes.c_double), "Int32": (np.int32, ctypes.c_int32),
            "Int64": (np.int64, ctypes.c_int64), "Boolean": (np.uint8, ctypes.c_bool)}
#: FMI 3.0 type of a settable parameter -> fmpy's setter
_SETTERS = {"Float64": "setFloat64", "Int32": "setInt32", "Int64": "setInt64",
            "Enumeration": "setInt64", "Boolean": "setBoolean", "String": "setString"}


class _Group:
    """The variables of one FMI 3.0 type among one buffer's: their value references, the
    buffer positions they fill or are taken from, and the values' own array."""

    def __init__(self, fn, fmi_type: str, vrs, positions):
        dtype, ctype = _C_TYPES[fmi_type]
        self.fn = fn
        self.fmi_type = fmi_type
        self.vrs = (ctypes.c_uint32 * len(vrs))(*vrs)
        self.n = len(vrs)
        self.positions = np.asarray(positions, dtype=np.intp)
        self.values = np.zeros(self.n, dtype=dtype)
        self.pointer = self.values.ctypes.data_as(ctypes.POINTER(ctype))


class Fmi3Instance(FmuInstance):
    """An FMI 3.0 co-simulation FMU run through fmpy (module docstring)."""

    FMI_VERSION = "3.0"

    def _instantiate(self, md) -> None:
        from fmpy.fmi3 import FMU3Slave

        env_id, name = self._env_id, self.name.encode("utf-8")
        #: the FMU's latest message, without its category (the reason it ends a run)
        self._last_message = last = [None]

        def log_message(env, status, category, message):
            last[0] = message.decode("utf-8", "replace").strip() if message else None
            _dispatch_log(env_id, name, status, category, message)

        self._fmi3_types = {v.name: v.type for v in md.modelVariables}
        self._fmu = FMU3Slave(guid=md.guid, unzipDirectory=self._unzipdir,
                              modelIdentifier=md.coSimulation.modelIdentifier,
                              instanceName=self.name)
        self._fmu.instantiate(loggingOn=True, eventModeUsed=False, earlyReturnAllowed=False,
                              logMessage=log_message)
        f = self._fmu._functions
        self._fn_get = {t: f[f"fmi3Get{t}"] for t in _C_TYPES}
        self._fn_set = {t: f[f"fmi3Set{t}"] for t in _C_TYPES}
        self._fn_do_step = f["fmi3DoStep"]
        self._step_flags = [ctypes.c_bool() for _ in range(3)]
        self._last_time = ctypes.c_double()

    # -- preparation --------------------------------------------------------------------
    def _groups(self, names, functions):
        by_type: Dict[str, tuple] = {}
        for j, n in enumerate(names):
            typ = self._fmi3_types[n]
            by_type.setdefault(typ, ([], []))
            by_type[typ][0].append(self.variables[n].value_reference)
            by_type[typ][1].append(j)
        return [_Group(functions[t], t, vrs, pos) for t, (vrs, pos) in by_type.items()]

    def _prepared(self) -> None:
        ins = (self.real_in, self.int_in, self.bool_in)
        outs = (self.real_out, self.int_out, self.bool_out)
        self._set_calls = tuple((buf, g) for t, buf in zip(NUMERIC_TYPES, ins)
                                for g in self._groups(self.input_names[t], self._fn_set))
        self._get_calls = tuple((buf, g, t) for t, buf in zip(NUMERIC_TYPES, outs)
                                for g in self._groups(self.output_names[t], self._fn_get))

    # -- life cycle ---------------------------------------------------------------------
    def set_parameters(self, values: Mapping[str, Any]) -> None:
        grouped: Dict[str, tuple] = {}
        for name, value in values.items():
            var = self.variable(name, ("parameter", "input"))
            typ = self._fmi3_types[name]
            grouped.setdefault(typ, ([], []))
            grouped[typ][0].append(var.value_reference)
            grouped[typ][1].append(coerce(self.name, var, value, self.source))
        for typ, (vrs, vals) in grouped.items():
            setter = getattr(self._fmu, _SETTERS[typ])
            self._checked(f"fmi3Set{typ} of the parameters", lambda: setter(vrs, vals))

    def enter_initialization(self, start_time: float, stop_time: Optional[float]) -> None:
        self.time = start_time
        self._checked("fmi3EnterInitializationMode", self._fmu.enterInitializationMode, None,
                      start_time, stop_time, time=start_time)
        self._state = "initializing"

    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        if real_values is not None or int_values is not None or bool_values is not None:
            self._copy_in(real_values, int_values, bool_values)
        c = self._c
        for buf, g in self._set_calls:
            if g.fmi_type == "Boolean":
                np.not_equal(buf[g.positions], 0, out=g.values)
            else:
                g.values[:] = buf[g.positions]
            status = g.fn(c, g.vrs, g.n, g.pointer, g.n)
            if status > 1:
                raise self._fail(f"fmi3Set{g.fmi_type} of the inputs", status, self.time)

    def get_outputs(self):
        c = self._c
        for buf, g, typ in self._get_calls:
            status = g.fn(c, g.vrs, g.n, g.pointer, g.n)
            if status > 1:
                raise self._fail(f"fmi3Get{g.fmi_type} of the outputs", status, self.time)
            if g.fmi_type == "Int64":
                self._check_int64(g)
            buf[g.positions] = g.values
        return self.real_out, self.int_out, self.bool_out

    def _check_int64(self, g: _Group) -> None:
        values = g.values
        if FMI_INTEGER_MIN <= values.min() and values.max() <= FMI_INTEGER_MAX:
            return
        bad = np.flatnonzero((values < FMI_INTEGER_MIN) | (values > FMI_INTEGER_MAX))
        if len(bad):
            name = self.output_names["Integer"][g.positions[bad[0]]]
            raise SimulationError(
                f"component '{self.name}' ({self.path.name}): Int64 output '{name}' = "
                f"{int(g.values[bad[0]])} at t = {self.time:.9g} s does not fit an FMI Integer "
                f"connector (32 bits)", component=self.name, time=self.time, log=tuple(self.log))

    def do_step(self, t: float, h: float) -> None:
        event, terminate, early = self._step_flags
        status = self._fn_do_step(self._c, t, h, True, ctypes.byref(event),
                                  ctypes.byref(terminate), ctypes.byref(early),
                                  ctypes.byref(self._last_time))
        if status > 1:
            raise self._fail(f"fmi3DoStep from t = {t:.9g} s to t = {t + h:.9g} s", status, t,
                             at=False)
        self.time = t + h
        if terminate.value:
            cause = self._cause_or_last()
            raise SimulationTerminated(
                f"component '{self.name}' ({self.path.name}) ended the simulation at "
                f"t = {t + h:.9g} s (fmi3DoStep returned terminateSimulation)"
                + (f": {cause}" if cause else ""), component=self.name, time=t + h,
                log=tuple(self.log))

    def _cause_or_last(self) -> Optional[str]:
        """The FMU's reason for ending: its error message, else its last log message."""
        return self._cause() or self._last_message[0]

    def _state_call(self, what: str, call, *args):
        self._require_state()
        return self._checked(what, call, *args)

    def get_state(self):
        return self._state_call("fmi3GetFMUState", self._fmu.getFMUState)

    def set_state(self, state) -> None:
        self._state_call("fmi3SetFMUState", self._fmu.setFMUState, state)

    def free_state(self, state) -> None:
        self._checked("fmi3FreeFMUState", self._fmu.freeFMUState, state)

    def _free_instance(self, fmu) -> None:
        fmu.fmi3FreeInstance(fmu.component)


def open_fmu(path, name: str, unzipdir: Optional[str] = None) -> FmuInstance:
    """The instance of the FMU ``path`` as component ``name``: :class:`Fmi3Instance` for an
    FMI 3.0 FMU, :class:`FmuInstance` for any other (which reports what it cannot run)."""
    cls = Fmi3Instance if Path(path).is_file() and fmi_version(path) == "3.0" else FmuInstance
    return cls(path, name, unzipdir=unzipdir)


__all__ = ["Fmi3Instance", "open_fmu"]
