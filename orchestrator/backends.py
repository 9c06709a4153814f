"""One instance interface for FMUs (through fmpy) and plain Python components.

The master steps every component through :class:`Instance`, so the same stepping code runs a
system of FMUs and the same system built from ``navcore`` component objects directly.

Life cycle, in this order::

    inst.prepare(input_names, output_names)     # once: value-reference arrays and buffers
    inst.set_parameters({...})                  # before initialization mode
    inst.enter_initialization(start, stop)
    inst.set_inputs(); inst.get_outputs()       # initial exchange (any number of times)
    inst.exit_initialization()
    loop: inst.set_inputs(); inst.do_step(t, h); inst.get_outputs()
    inst.terminate()                            # always (also after a failure)

The per-step path works on buffers allocated by :meth:`Instance.prepare`: numpy arrays
``real_in``/``int_in``/``bool_in`` (the master fills them in place) and ``real_out``/
``int_out``/``bool_out`` (filled by :meth:`Instance.get_outputs`; the master may pass views
into its own signal vectors so that outputs land where the connections read them).  For an FMU
this is one fmi2Set*/fmi2Get* call per FMI type and direction per step, straight into the numpy
memory.  Integer and Boolean values are held as ``int32`` (the FMI 2 C types).
"""
from __future__ import annotations

import collections
import ctypes
import itertools
import operator
import shutil
import weakref
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterable, Mapping, Optional, Sequence, Tuple

import numpy as np

from .errors import NavfmuError, SimulationError, WiringError

STATUS_LABELS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
NUMERIC_TYPES = ("Real", "Integer", "Boolean")
#: how many of a component's most recent log messages are kept for error reports
LOG_MESSAGES_KEPT = 200


@dataclass(frozen=True)
class VarInfo:
    """A variable of an instance: ``causality`` is parameter/calculatedParameter/input/output/
    local/independent; ``value_reference`` is the FMI value reference (an index for Python
    components)."""

    name: str
    type: str
    causality: str
    unit: str
    value_reference: int


def _coerce(comp: str, var: VarInfo, value: Any, source: str) -> Any:
    """Convert a parameter value to the variable's type, or raise a NavfmuError naming it."""
    try:
        if var.type == "Real":
            if isinstance(value, bool):
                raise TypeError
            return float(value)
        if var.type in ("Integer", "Enumeration"):
            if isinstance(value, bool) or (isinstance(value, float) and not value.is_integer()):
                raise TypeError
            return int(value)
        if var.type == "Boolean":
            if isinstance(value, str):
                low = value.strip().lower()
                if low not in ("true", "false", "1", "0"):
                    raise TypeError
                return low in ("true", "1")
            if value not in (0, 1, True, False):
                raise TypeError
            return bool(value)
        return str(value)
    except (TypeError, ValueError):
        raise NavfmuError(
            f"component '{comp}' ({source}): parameter '{var.name}' is a {var.type}, "
            f"got {value!r}"
        ) from None


class Instance(ABC):
    """Base class: the uniform interface the master uses (see module docstring)."""

    name: str
    #: what the instance runs, for messages (FMU path or class name)
    source: str
    variables: Dict[str, VarInfo]

    def __init__(self) -> None:
        self.input_names: Dict[str, Tuple[str, ...]] = {t: () for t in NUMERIC_TYPES}
        self.output_names: Dict[str, Tuple[str, ...]] = {t: () for t in NUMERIC_TYPES}
        self.real_in = np.zeros(0)
        self.int_in = np.zeros(0, dtype=np.int32)
        self.bool_in = np.zeros(0, dtype=np.int32)
        self.real_out = np.zeros(0)
        self.int_out = np.zeros(0, dtype=np.int32)
        self.bool_out = np.zeros(0, dtype=np.int32)

    # -- preparation --------------------------------------------------------------------
    def variable(self, name: str, causalities: Iterable[str] = ()) -> VarInfo:
        """Return variable ``name``; raise :class:`WiringError` if it is missing or has a
        causality outside ``causalities`` (when given)."""
        var = self.variables.get(name)
        if var is None:
            raise WiringError(f"component '{self.name}' has no variable '{name}' ({self.source})")
        causalities = tuple(causalities)
        if causalities and var.causality not in causalities:
            raise WiringError(
                f"component '{self.name}': variable '{name}' has causality '{var.causality}', "
                f"expected {' or '.join(causalities)} ({self.source})"
            )
        return var

    def names_by_type(self, names: Sequence[str], causalities: Iterable[str]) -> Dict[str, Tuple[str, ...]]:
        causalities = tuple(causalities)
        grouped: Dict[str, list] = {t: [] for t in NUMERIC_TYPES}
        for n in names:
            var = self.variable(n, causalities)
            if var.type not in grouped:
                raise WiringError(
                    f"component '{self.name}': variable '{n}' is a {var.type}; only Real, Integer "
                    f"and Boolean variables can be connected or recorded ({self.source})"
                )
            grouped[var.type].append(n)
        return {t: tuple(v) for t, v in grouped.items()}

    def prepare(self, input_names: Sequence[str], output_names: Sequence[str],
                real_out: Optional[np.ndarray] = None, int_out: Optional[np.ndarray] = None,
                bool_out: Optional[np.ndarray] = None) -> None:
        """Fix the inputs that will be set and the outputs that will be read each step.

        Names are grouped by type keeping their order (``self.input_names[type]``,
        ``self.output_names[type]``).  ``*_out`` may be preallocated contiguous arrays
        (float64 for Real, int32 for Integer/Boolean) of the right length, e.g. views into
        the master's signal vectors.
        """
        self.input_names = self.names_by_type(input_names, ("input",))
        self.output_names = self.names_by_type(output_names, ("output",))
        self.real_in = np.zeros(len(self.input_names["Real"]))
        self.int_in = np.zeros(len(self.input_names["Integer"]), dtype=np.int32)
        self.bool_in = np.zeros(len(self.input_names["Boolean"]), dtype=np.int32)
        self.real_out = self._out_buffer(real_out, "Real", np.float64)
        self.int_out = self._out_buffer(int_out, "Integer", np.int32)
        self.bool_out = self._out_buffer(bool_out, "Boolean", np.int32)
        self._prepared()

    def _out_buffer(self, given, typ, dtype):
        n = len(self.output_names[typ])
        if given is None:
            return np.zeros(n, dtype=dtype)
        if given.dtype != dtype or given.shape != (n,) or not given.flags.c_contiguous:
            raise ValueError(f"{typ} output buffer must be a contiguous {np.dtype(dtype)} array "
                             f"of length {n}")
        return given

    def _prepared(self) -> None:
        """Hook for subclasses: build what the per-step path needs."""

    def _copy_in(self, real_values, int_values, bool_values) -> None:
        if real_values is not None and real_values is not self.real_in:
            self.real_in[:] = real_values
        if int_values is not None and int_values is not self.int_in:
            self.int_in[:] = int_values
        if bool_values is not None and bool_values is not self.bool_in:
            self.bool_in[:] = bool_values

    # -- interface implemented by the back ends -----------------------------------------
    @abstractmethod
    def set_parameters(self, values: Mapping[str, Any]) -> None:
        """Set parameter (or input start) values by name, before initialization mode."""

    @abstractmethod
    def enter_initialization(self, start_time: float, stop_time: Optional[float]) -> None:
        """Set up the experiment and enter initialization mode."""

    @abstractmethod
    def exit_initialization(self) -> None:
        """Leave initialization mode; the instance is then ready to step."""

    def initialize(self, start_time: float, stop_time: Optional[float] = None) -> None:
        """Enter and exit initialization mode (for an instance used on its own)."""
        self.enter_initialization(start_time, stop_time)
        self.exit_initialization()

    @abstractmethod
    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        """Push the prepared inputs (copying the given values into the buffers first)."""

    @abstractmethod
    def get_outputs(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Read the prepared outputs into ``real_out``/``int_out``/``bool_out``."""

    @abstractmethod
    def do_step(self, t: float, h: float) -> None:
        """Advance from ``t`` to ``t + h``."""

    @abstractmethod
    def get_state(self) -> Any:
        """Return the full internal state (opaque)."""

    @abstractmethod
    def set_state(self, state: Any) -> None:
        """Restore a state returned by :meth:`get_state`."""

    @abstractmethod
    def terminate(self) -> None:
        """End the instance and release its resources (idempotent)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.terminate()
        return False


# ========================================================================================
# FMUs through fmpy
# ========================================================================================
# fmpy's native logger proxy (which formats printf-style messages) forwards to ONE Python
# callback per process, so all our instances share this dispatcher; each instance passes a
# unique componentEnvironment and is found again by it (or by its instance name).
_LOG_SINKS: Dict[int, "collections.deque"] = {}
_LOG_SINKS_BY_NAME: Dict[bytes, "collections.deque"] = {}
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

    The FMU is extracted to a temporary folder, loaded and instantiated with logging on; its
    log messages are kept (the last :data:`LOG_MESSAGES_KEPT`) and included in every
    :class:`SimulationError`.  A status of Discard, Error or Fatal from any call raises
    :class:`SimulationError`; Warning is accepted (the message stays in the log).
    """

    def __init__(self, path, name: str):
        super().__init__()
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackAllocateMemoryTYPE, \
            fmi2CallbackFreeMemoryTYPE
        from fmpy import calloc, free

        self.name = name
        self.path = Path(path)
        self.source = str(self.path)
        self.log: collections.deque = collections.deque(maxlen=LOG_MESSAGES_KEPT)
        self._fmu = None
        self._unzipdir: Optional[str] = None
        self._state = "new"
        self._fatal = False
        self.time = None
        if not self.path.is_file():
            raise NavfmuError(f"component '{name}': FMU file not found: {self.path}")
        try:
            md = read_model_description(str(self.path), validate=False)
        except Exception as exc:  # fmpy raises plain Exception for unreadable files
            raise NavfmuError(f"component '{name}': cannot read the model description of "
                              f"{self.path}: {exc}") from None
        if md.fmiVersion != "2.0":
            raise NavfmuError(f"component '{name}': {self.path} is an FMI {md.fmiVersion} FMU; "
                              f"only FMI 2.0 co-simulation FMUs are supported")
        if md.coSimulation is None:
            raise NavfmuError(f"component '{name}': {self.path} does not support co-simulation "
                              f"(model exchange only); only FMI 2.0 co-simulation is supported")
        self.model_description = md
        self.model_name = md.modelName
        self.can_get_set_state = bool(md.coSimulation.canGetAndSetFMUstate)
        self.variables = {}
        for v in md.modelVariables:
            unit = v.unit or (v.declaredType.unit if v.declaredType is not None else None) or ""
            self.variables[v.name] = VarInfo(v.name, v.type, v.causality, unit, v.valueReference)

        self._unzipdir = str(extract(str(self.path)))
        self._finalizer = weakref.finalize(self, _cleanup_files, self._unzipdir)
        self._env_id = next(_ENV_IDS)
        _LOG_SINKS[self._env_id] = self.log
        _LOG_SINKS_BY_NAME[name.encode("utf-8")] = self.log
        try:
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
                                  instanceName=name)
            self._fmu.instantiate(callbacks=callbacks, loggingOn=True)
            self._state = "instantiated"
        except Exception as exc:
            self.terminate()
            raise NavfmuError(f"component '{name}': cannot instantiate {self.path}: {exc}"
                              f"{self._log_text()}") from None
        self._c = self._fmu.component
        f = self._fmu._functions
        self._fn_get = {"Real": f["fmi2GetReal"], "Integer": f["fmi2GetInteger"],
                        "Boolean": f["fmi2GetBoolean"]}
        self._fn_set = {"Real": f["fmi2SetReal"], "Integer": f["fmi2SetInteger"],
                        "Boolean": f["fmi2SetBoolean"]}
        self._fn_do_step = f["fmi2DoStep"]
        self._set_calls: Tuple = ()
        self._get_calls: Tuple = ()

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
        if status == 4:
            self._fatal = True
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
        for typ, buf in (("Real", self.real_in), ("Integer", self.int_in), ("Boolean", self.bool_in)):
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
            grouped[var.type][1].append(_coerce(self.name, var, value, self.source))
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
        self._checked("fmi2ExitInitializationMode", self._fmu.exitInitializationMode,
                      time=self.time)
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

    def get_state(self):
        if not self.can_get_set_state:
            raise NavfmuError(f"component '{self.name}': {self.path.name} cannot get/set its "
                              f"state (canGetAndSetFMUstate is false)")
        return self._checked("fmi2GetFMUstate", self._fmu.getFMUstate)

    def set_state(self, state) -> None:
        if not self.can_get_set_state:
            raise NavfmuError(f"component '{self.name}': {self.path.name} cannot get/set its "
                              f"state (canGetAndSetFMUstate is false)")
        self._checked("fmi2SetFMUstate", self._fmu.setFMUstate, state)

    def free_state(self, state) -> None:
        self._checked("fmi2FreeFMUstate", self._fmu.freeFMUstate, state)

    def terminate(self) -> None:
        """Terminate (if initialized and not after Fatal), free the instance, delete the
        extracted files.  Safe to call more than once and after any failure."""
        fmu, self._fmu = self._fmu, None
        if fmu is not None:
            try:
                if self._state in ("initializing", "running") and not self._fatal:
                    fmu.terminate()
            except Exception:  # the instance is freed anyway; its failure is already reported
                pass
            try:
                if self._state != "new" and fmu.component is not None:
                    # free the instance but never unload the shared library: a pythonfmu
                    # FMU leaves Python objects behind that point into its library, and the
                    # interpreter crashes when it later collects them after a dlclose
                    fmu.fmi2FreeInstance(fmu.component)
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


# ========================================================================================
# Plain Python components (navcore.component.Component contract)
# ========================================================================================
def _component_error_types() -> Tuple[type, ...]:
    """The exceptions a component raises for user errors (navcore's NavcoreError)."""
    try:
        from navcore.errors import NavcoreError
    except ImportError:  # the master also runs components that do not come from navcore
        return ()
    return (NavcoreError,)


def _numerical_failure(exc: Exception) -> str:
    try:
        from navcore.errors import numerical_failure
    except ImportError:
        return f"the computation failed numerically ({exc!r})"
    return numerical_failure(exc)


def _output_writer(buf: np.ndarray, names: Sequence[str]):
    """A function copying ``outputs[name]`` for ``names`` into ``buf`` (one numpy store)."""
    if len(names) == 1:
        name = names[0]

        def write(outputs):
            buf[0] = outputs[name]
    else:
        getter = operator.itemgetter(*names)

        def write(outputs):
            buf[:] = getter(outputs)
    return write


class DirectInstance(Instance):
    """A Python object following the ``navcore.component.Component`` contract, stepped
    directly (no FMI): class attributes ``parameters``/``inputs``/``outputs`` (tuples of
    ``Port``), ``set_parameter(name, value)``, ``start(start_time) -> outputs`` (or
    ``initialize``), ``step(t, h, inputs) -> outputs``, ``get_state()``/``set_state()`` (the
    component's declared state as plain data, :mod:`navcore.state`).

    Unconnected inputs keep their declared start values.  A ``ParameterError``/``InputError``
    raised by the component becomes :class:`SimulationError` naming the component and time.
    """

    def __init__(self, component: Any, name: str, source: str = ""):
        super().__init__()
        self.component = component
        self.name = name
        cls = type(component)
        self.model_name = getattr(cls, "model_name", "") or cls.__name__
        self.source = source or f"Python component {cls.__module__}.{cls.__qualname__}"
        self.variables = {}
        ref = itertools.count()
        for causality, ports in (("parameter", getattr(cls, "parameters", ())),
                                 ("input", getattr(cls, "inputs", ())),
                                 ("output", getattr(cls, "outputs", ()))):
            for p in ports:
                self.variables[p.name] = VarInfo(p.name, p.type, causality, p.unit, next(ref))
        self._inputs: Dict[str, Any] = {p.name: p.default() for p in getattr(cls, "inputs", ())}
        self._outputs: Dict[str, Any] = {p.name: p.default() for p in getattr(cls, "outputs", ())}
        self._errors = _component_error_types()
        self.time: Optional[float] = None

    @classmethod
    def from_registry(cls, model_name: str, name: str, registry: Mapping[str, type]) -> "DirectInstance":
        """Build the component registered under ``model_name`` (an FMU model name)."""
        component_class = registry.get(model_name)
        if component_class is None:
            raise NavfmuError(
                f"component '{name}': no Python component registered for model '{model_name}' "
                f"(registered: {', '.join(sorted(registry)) or 'none'})"
            )
        return cls(component_class(), name)

    def _error(self, what: str, exc: Exception, time: Optional[float],
               at: bool = True) -> SimulationError:
        """Same shape as :meth:`FmuInstance._fail`: the component's message first, the
        failed call on the next line."""
        when = f" at t = {time:.9g} s" if time is not None and at else ""
        text = str(exc)
        if not isinstance(exc, self._errors):  # an arithmetic error: the state diverged
            text = _numerical_failure(exc)
        prefix = f"{self.model_name}: "
        if text.startswith(prefix):
            text = text[len(prefix):]
        return SimulationError(f"component '{self.name}' ({self.model_name}): {text}\n"
                               f"  ({what} failed{when})", component=self.name, time=time,
                               log=(str(exc),))

    def _prepared(self) -> None:
        self._in_real = self.input_names["Real"]
        self._in_int = self.input_names["Integer"]
        self._in_bool = self.input_names["Boolean"]
        self._writers = tuple(
            _output_writer(buf, names)
            for buf, names in ((self.real_out, self.output_names["Real"]),
                               (self.int_out, self.output_names["Integer"]),
                               (self.bool_out, self.output_names["Boolean"]))
            if names
        )

    def set_parameters(self, values: Mapping[str, Any]) -> None:
        for name, value in values.items():
            var = self.variable(name, ("parameter", "input"))
            value = _coerce(self.name, var, value, self.source)
            if var.causality == "input":
                self._inputs[name] = value
                continue
            try:
                self.component.set_parameter(name, value)
            except self._errors as exc:
                text = str(exc)
                if text.startswith(f"{self.model_name}: "):
                    text = text[len(self.model_name) + 2:]
                raise NavfmuError(f"component '{self.name}' ({self.model_name}): {text}") from None

    def enter_initialization(self, start_time: float, stop_time: Optional[float]) -> None:
        self.time = start_time
        try:
            begin = getattr(self.component, "start", None) or self.component.initialize
            outputs = begin(start_time)
            check = getattr(self.component, "check_stop_time", None)
            if check is not None and stop_time is not None:
                check(stop_time)
        except self._errors as exc:
            raise self._error("initialization", exc, start_time) from None
        self._store_outputs(outputs, "initialize")

    def exit_initialization(self) -> None:
        pass

    def _store_outputs(self, outputs, what: str) -> None:
        if outputs is None:
            raise SimulationError(f"component '{self.name}' ({self.model_name}): {what}() returned "
                                  f"no outputs", component=self.name, time=self.time)
        self._outputs = outputs

    def set_inputs(self, real_values=None, int_values=None, bool_values=None) -> None:
        if real_values is not None or int_values is not None or bool_values is not None:
            self._copy_in(real_values, int_values, bool_values)
        inputs = self._inputs
        if self._in_real:
            inputs.update(zip(self._in_real, self.real_in.tolist()))
        if self._in_int:
            inputs.update(zip(self._in_int, self.int_in.tolist()))
        if self._in_bool:
            inputs.update(zip(self._in_bool, map(bool, self.bool_in.tolist())))

    def get_outputs(self):
        out = self._outputs
        try:
            for write in self._writers:
                write(out)
        except KeyError as exc:
            raise SimulationError(
                f"component '{self.name}' ({self.model_name}) returned no value for output "
                f"{exc} at t = {self.time:.9g} s", component=self.name, time=self.time
            ) from None
        return self.real_out, self.int_out, self.bool_out

    def do_step(self, t: float, h: float) -> None:
        try:
            advance = getattr(self.component, "advance", None) or self.component.step
            outputs = advance(t, h, self._inputs)
        except self._errors + (ArithmeticError, ValueError) as exc:
            raise self._error(f"step from t = {t:.9g} s to t = {t + h:.9g} s", exc, t,
                              at=False) from None
        self.time = t + h
        self._outputs = outputs

    def get_state(self):
        """(component state, inputs, outputs, time): plain data, the component's part being
        its declared state (the same an FMU of it saves)."""
        return (self.component.get_state(), dict(self._inputs), dict(self._outputs), self.time)

    def set_state(self, state) -> None:
        comp_state, inputs, outputs, time = state
        self.component.set_state(comp_state)
        self._inputs, self._outputs, self.time = dict(inputs), dict(outputs), time

    def terminate(self) -> None:
        hook = getattr(self.component, "terminate", None)
        if callable(hook):
            hook()


__all__ = ["VarInfo", "Instance", "FmuInstance", "DirectInstance"]
