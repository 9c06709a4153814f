"""The FMU backend: an FMI 2.0 co-simulation FMU run through fmpy behind
:class:`~orchestrator.cosim.backends.Instance`, its log kept for error reports."""
from __future__ import annotations

import collections
import ctypes
import itertools
import shutil
import weakref
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Tuple

import numpy as np

from . import fmu_builds, source_fmus
from .backends import Instance, coerce
from .fmi3_variables import variables_of
from ..errors import NavfmuError, SimulationError

STATUS_LABELS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
#: how many of a component's most recent log messages are kept for error reports
LOG_MESSAGES_KEPT = 200

# fmpy's native logger proxy (which formats printf-style messages) forwards to ONE Python
# callback per process, so all our instances share this dispatcher; each instance passes a
# unique componentEnvironment and is found again by it (or by its instance name).
_LOG_SINKS: Dict[int, "collections.deque"] = {}
_LOG_SINKS_BY_NAME: Dict[bytes, "collections.deque"] = {}
#: the same instances' messages of status Warning, all of them (not only the latest)
_WARNING_SINKS: Dict[int, list] = {}
_WARNING_SINKS_BY_NAME: Dict[bytes, list] = {}
#: fmi2Status of a warning
_WARNING = 1
_ENV_IDS = itertools.count(1)
_LOGGER_CALLBACK = None
#: shared libraries of freed FMU instances, kept loaded for the life of the process
_LOADED_LIBRARIES: list = []


def _dispatch_log(env, instance_name, status, category, message):
    sink = _LOG_SINKS.get(env) if env is not None else None
    if sink is None:
        sink = _LOG_SINKS_BY_NAME.get(instance_name)
    label = STATUS_LABELS[status] if 0 <= status < len(STATUS_LABELS) else str(status)
    text = message.decode("utf-8", "replace") if message else ""
    cat = category.decode("utf-8", "replace") if category else ""
    line = f"[{label}] {cat + ': ' if cat else ''}{text.rstrip()}"
    if sink is None:
        # an FMU instantiated by other fmpy code in this process: print, as fmpy's default does
        print(line)
        return
    sink.append(line)
    if status == _WARNING:
        warnings = _WARNING_SINKS.get(env) if env is not None else None
        if warnings is None:
            warnings = _WARNING_SINKS_BY_NAME.get(instance_name)
        if warnings is not None:
            name = instance_name.decode("utf-8", "replace") if instance_name else "?"
            body = text.rstrip()
            warnings.append(body if body.startswith(f"{name}: ") else f"{name}: {body}")


def _logger_callback():
    global _LOGGER_CALLBACK
    if _LOGGER_CALLBACK is None:
        from fmpy.fmi2 import fmi2CallbackLoggerTYPE

        _LOGGER_CALLBACK = fmi2CallbackLoggerTYPE(_dispatch_log)
    return _LOGGER_CALLBACK


def _cleanup_files(unzipdir: Optional[str]) -> None:
    if unzipdir:
        shutil.rmtree(unzipdir, ignore_errors=True)


class FmuInstance(Instance):
    """An FMI 2.0 co-simulation FMU run through fmpy.

    The FMU is extracted to a temporary folder (or into ``unzipdir``), loaded and
    instantiated with logging on; its log messages are kept (the last
    :data:`LOG_MESSAGES_KEPT`) and included in every :class:`SimulationError`.  A status
    of Discard, Error or Fatal from any call raises :class:`SimulationError`; Warning is
    accepted (the message stays in the log).  FMI 3.0 FMUs run through the subclass
    :class:`~orchestrator.cosim.fmi3_instance.Fmi3Instance`, which replaces the FMI calls
    (:meth:`_instantiate` and the calls of the life cycle) and keeps the rest.
    """

    FMI_VERSION = "2.0"

    def __init__(self, path, name: str, unzipdir: Optional[str] = None):
        super().__init__()
        from fmpy import extract, read_model_description

        self.name = name
        self.path = Path(path)
        self.source = str(self.path)
        self.log: collections.deque = collections.deque(maxlen=LOG_MESSAGES_KEPT)
        self._fmu = None
        self._unzipdir: Optional[str] = None
        self._state = "new"
        #: an FMI call returned Error or Fatal: FMI 2.0 then allows no fmi2Terminate
        self._failed = False
        self.time = None
        if not self.path.is_file():
            raise NavfmuError(f"component '{name}': FMU file not found: {self.path}")
        try:
            md = read_model_description(str(self.path), validate=False)
        except Exception as exc:  # fmpy raises plain Exception for unreadable files
            raise NavfmuError(f"component '{name}': cannot read the model description of "
                              f"{self.path}: {exc}") from None
        self.variables = variables_of(md, name, self.path)
        if md.fmiVersion != self.FMI_VERSION:
            raise NavfmuError(f"component '{name}': {self.path} is an FMI {md.fmiVersion} FMU; "
                              f"{type(self).__name__} runs FMI {self.FMI_VERSION} FMUs")
        self.model_description = md
        self.model_name = md.modelName
        self.can_get_set_state = bool(md.coSimulation.canGetAndSetFMUstate)
        self._unzipdir = str(extract(str(self.path), unzipdir))
        self._finalizer = weakref.finalize(self, _cleanup_files, self._unzipdir)
        source_fmus.ensure_binary(self.path, md, Path(self._unzipdir), name)
        self.build_info = fmu_builds.build_info(self.path, md, Path(self._unzipdir))
        self._env_id = next(_ENV_IDS)
        _LOG_SINKS[self._env_id] = self.log
        _LOG_SINKS_BY_NAME[name.encode("utf-8")] = self.log
        self.warnings: list = []
        _WARNING_SINKS[self._env_id] = self.warnings
        _WARNING_SINKS_BY_NAME[name.encode("utf-8")] = self.warnings
        try:
            self._instantiate(md)
            self._state = "instantiated"
        except Exception as exc:
            self.terminate()
            raise NavfmuError(f"component '{name}': cannot instantiate {self.path}: {exc}"
                              f"{self._log_text()}") from None
        self._c = self._fmu.component
        self._set_calls: Tuple = ()
        self._get_calls: Tuple = ()

    def _instantiate(self, md) -> None:
        """Load and instantiate the FMU (logging on, messages into ``log``) and keep the
        per-step FMI functions."""
        from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackAllocateMemoryTYPE, \
            fmi2CallbackFreeMemoryTYPE
        from fmpy import calloc, free

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = _logger_callback()
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        callbacks.componentEnvironment = self._env_id
        try:
            from fmpy.logging import addLoggerProxy

            addLoggerProxy(ctypes.byref(callbacks))
        except Exception:  # no native proxy for this platform: messages arrive unformatted
            pass
        self._callbacks = callbacks  # keep alive as long as the instance
        self._fmu = FMU2Slave(guid=md.guid, unzipDirectory=self._unzipdir,
                              modelIdentifier=md.coSimulation.modelIdentifier,
                              instanceName=self.name)
        self._fmu.instantiate(callbacks=callbacks, loggingOn=True)
        f = self._fmu._functions
        self._fn_get = {"Real": f["fmi2GetReal"], "Integer": f["fmi2GetInteger"],
                        "Boolean": f["fmi2GetBoolean"]}
        self._fn_set = {"Real": f["fmi2SetReal"], "Integer": f["fmi2SetInteger"],
                        "Boolean": f["fmi2SetBoolean"]}
        self._fn_do_step = f["fmi2DoStep"]

    # -- messages -----------------------------------------------------------------------
    def _log_text(self) -> str:
        if not self.log:
            return ""
        return "\nFMU log:\n  " + "\n  ".join(self.log)

    def _cause(self) -> Optional[str]:
        """The FMU's own account of its failure: its first Error/Fatal log message (not a
        traceback), without the status label, category and instance-name prefixes."""
        for line in self.log:
            label, _, rest = line.partition("] ")
            if label not in ("[Error", "[Fatal"):
                continue
            category, sep, text = rest.partition(": ")
            if not sep or category == "traceback":
                continue
            for prefix in (f"{self.name}: ", f"{self.model_name}: "):
                if text.startswith(prefix):
                    text = text[len(prefix):]
            return text.splitlines()[0] if text else None
        return None

    def _fail(self, what: str, status: Optional[int] = None, time: Optional[float] = None,
              at: bool = True) -> SimulationError:
        """The error for a failed FMI call; ``time`` is stored (and shown if ``at``).  Its
        first line is the FMU's own message when it logged one (:meth:`_cause`), the failed
        call follows on the next line; the whole log stays in ``log``."""
        if status is not None and status >= 3:
            self._failed = True
        label = (f" with status {STATUS_LABELS[status]}"
                 if status is not None and 0 <= status < len(STATUS_LABELS) else "")
        when = f" at t = {time:.9g} s" if time is not None and at else ""
        call = f"{what} failed{label}{when}"
        cause = self._cause()
        head = f"component '{self.name}' ({self.path.name}): "
        msg = head + (f"{cause}\n  ({call})" if cause else call)
        return SimulationError(msg, component=self.name, time=time, log=tuple(self.log))

    def _checked(self, what: str, call, *args, time=None):
        """Call an fmpy method; turn its exceptions and bad statuses into SimulationError."""
        from fmpy.fmi1 import FMICallException

        try:
            status = call(*args)
        except FMICallException as exc:
            raise self._fail(what, exc.status, time) from None
        if isinstance(status, int) and status > 1:
            raise self._fail(what, status, time)
        return status

    # -- preparation --------------------------------------------------------------------
    def _prepared(self) -> None:
        def vr_array(names):
            return (ctypes.c_uint * len(names))(*[self.variables[n].value_reference for n in names])

        def ptr(arr):
            ctype = ctypes.c_double if arr.dtype == np.float64 else ctypes.c_int
            return arr.ctypes.data_as(ctypes.POINTER(ctype))

        sets = []
        for typ, buf in (
            ("Real", self.real_in),
            ("Integer", self.int_in),
            ("Boolean", self.bool_in),
        ):
            names = self.input_names[typ]
            if names:
                sets.append([self._fn_set[typ], vr_array(names), len(names), ptr(buf), typ, buf,
                             None])
        gets = []
        for typ, buf in (("Real", self.real_out), ("Integer", self.int_out),
                         ("Boolean", self.bool_out)):
            names = self.output_names[typ]
            if names:
                gets.append((self._fn_get[typ], vr_array(names), len(names), ptr(buf), typ))
        self._set_calls = tuple(sets)
        self._get_calls = tuple(gets)

    # -- life cycle ---------------------------------------------------------------------
    def set_parameters(self, values: Mapping[str, Any]) -> None:
        grouped: Dict[str, Tuple[list, list]] = {}
        for name, value in values.items():
            var = self.variable(name, ("parameter", "input"))
            grouped.setdefault(var.type, ([], []))
            grouped[var.type][0].append(var.value_reference)
            grouped[var.type][1].append(coerce(self.name, var, value, self.source))
        setters = {"Real": self._fmu.setReal, "Integer": self._fmu.setInteger,
                   "Enumeration": self._fmu.setInteger, "Boolean": self._fmu.setBoolean,
                   "String": self._fmu.setString}
        for typ, (vrs, vals) in grouped.items():
            self._checked(f"setting {typ} parameters", lambda: setters[typ](vrs, vals))

    def enter_initialization(self, start_time: float, stop_time: Optional[float]) -> None:
        self.time = start_time
        self._checked("fmi2SetupExperiment", self._fmu.setupExperiment, None, start_time,
                      stop_time, time=start_time)
        self._checked("fmi2EnterInitializationMode", self._fmu.enterInitializationMode,
                      time=start_time)
        self._state = "initializing"

    def exit_initialization(self) -> None:
        self._checked(f"fmi{self.FMI_VERSION[0]}ExitInitializationMode",
                      self._fmu.exitInitializationMode, time=self.time)
        self._state = "running"

    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        if real_values is not None or int_values is not None or bool_values is not None:
            self._copy_in(real_values, int_values, bool_values)
        c = self._c
        for call in self._set_calls:
            fn, vrs, n, p, typ, buf, sent = call
            if typ != "Real":
                # discrete inputs (epoch counters, flags) rarely change: an FMU keeps an input's
                # value until it is set again, so an unchanged one is not sent (saves a call)
                current = buf.tobytes()
                if current == sent:
                    continue
                call[6] = current
            status = fn(c, vrs, n, p)
            if status > 1:
                raise self._fail(f"fmi2Set{typ} of the inputs", status, self.time)

    def get_outputs(self):
        c = self._c
        for fn, vrs, n, p, typ in self._get_calls:
            status = fn(c, vrs, n, p)
            if status > 1:
                raise self._fail(f"fmi2Get{typ} of the outputs", status, self.time)
        return self.real_out, self.int_out, self.bool_out

    def do_step(self, t: float, h: float) -> None:
        status = self._fn_do_step(self._c, t, h, 1)
        if status > 1:
            raise self._fail(f"fmi2DoStep from t = {t:.9g} s to t = {t + h:.9g} s", status, t,
                             at=False)
        self.time = t + h

    def _require_state(self) -> None:
        if not self.can_get_set_state:
            raise NavfmuError(f"component '{self.name}': {self.path.name} cannot get/set its "
                              f"state (canGetAndSetFMUstate is false)")

    def get_state(self):
        self._require_state()
        return self._checked("fmi2GetFMUstate", self._fmu.getFMUstate)

    def set_state(self, state) -> None:
        self._require_state()
        self._checked("fmi2SetFMUstate", self._fmu.setFMUstate, state)

    def free_state(self, state) -> None:
        self._checked("fmi2FreeFMUstate", self._fmu.freeFMUstate, state)

    def _free_instance(self, fmu) -> None:
        fmu.fmi2FreeInstance(fmu.component)

    def take_warnings(self):
        warnings, self.warnings[:] = list(self.warnings), []
        return warnings

    def terminate(self) -> None:
        """Terminate (if it stepped and no call returned Error or Fatal: FMI 2.0 allows
        fmi2Terminate only then), free the instance, delete the extracted files.  Safe to
        call more than once and after any failure."""
        fmu, self._fmu = self._fmu, None
        if fmu is not None:
            try:
                if self._state == "running" and not self._failed:
                    fmu.terminate()
            except Exception:  # the instance is freed anyway; its failure is already reported
                pass
            try:
                if self._state != "new" and fmu.component is not None:
                    # free the instance but never unload the shared library: a pythonfmu
                    # FMU leaves Python objects behind that point into its library, and the
                    # interpreter crashes when it later collects them after a dlclose
                    self._free_instance(fmu)
                    fmu.component = None
            except Exception:
                pass
            _LOADED_LIBRARIES.append(fmu.dll)
            self._state = "terminated"
        _LOG_SINKS.pop(getattr(self, "_env_id", None), None)
        if _LOG_SINKS_BY_NAME.get(self.name.encode("utf-8")) is self.log:
            del _LOG_SINKS_BY_NAME[self.name.encode("utf-8")]
        if getattr(self, "_finalizer", None) is not None:
            self._finalizer()


__all__ = ["FmuInstance", "STATUS_LABELS", "LOG_MESSAGES_KEPT"]
