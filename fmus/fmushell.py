"""Thin pythonfmu shell around a navcore :class:`~navcore.component.Component`.

Each FMU script in ``fmus/`` is a few lines: a class deriving directly from ``Fmi2Slave``,
defined in the script itself, whose ``__init__`` calls :func:`setup` with the navcore component
it wraps and whose other FMI methods are the functions of this module.  (pythonfmu's native
loader finds the slave class in the script's module and keeps the module alive only in that
shape: with an intermediate base class, or without an ``__init__`` of the script's own, a
second instantiation of the same FMU in one process crashed the interpreter.)  This module
does the FMI side once for all of them:

* registers every declared parameter, input and output with legal causality, variability and
  initial (Integer/Boolean ``discrete``; parameters ``fixed`` with ``initial="exact"``;
  outputs ``calculated`` and listed as InitialUnknowns);
* writes SI units and their UnitDefinitions into the model description (pythonfmu does not);
* saves the full internal state (the registered values and the component's declared state,
  :mod:`navcore.state`) behind ``canGetAndSetFMUstate`` / ``canSerializeFMUstate``, and
  serializes it in the checked plain-data format of :mod:`navcore.state_format`: a blob is
  never code, and one that is refused leaves the instance as it was (see the state section);
* never lets a Python exception escape an FMI call (but the refusals of the statuses
  paragraph below, where the binary turns them into fmi2Error): a user error (NaN input)
  is logged through the FMI logger as one message ``<instance>: <what>`` (the first
  Error-level message of the instance: a master reports it as the cause) and reported as
  fmi2Discard from ``do_step``; after such an error every further ``do_step`` is refused too.
  A bug's traceback follows in a second message (category ``traceback``).
* hands the experiment's stop time (fmi2SetupExperiment) to the component before it
  initializes, so a component can refuse a run it cannot cover.
* works around two defects of pythonfmu 0.7's native binary that corrupted the heap at
  process exit: its loader's extra ``Py_DECREF`` of the script's globals
  (:func:`_balance_loader_decref`) and its interpreter teardown running after the C++ static
  destructors (:func:`_finalize_python_at_exit`).

Hostile or careless host calls (FMI rules checked here and in
:meth:`navcore.component.Component.advance`):

* ``doStep`` whose communication point is not where the previous step ended (back or ahead),
  or whose step size is not > 0: refused, nothing changes, a following legal step works;
* get/set of an unknown value reference or one of another type, set of an output, set of a
  (fixed) parameter after ``fmi2ExitInitializationMode``: refused, nothing is written, the
  message names the value reference or variable;
* a parameter the component refuses at ``fmi2ExitInitializationMode``; a state
  ``fmi2SetFMUstate`` or ``fmi2DeSerializeFMUstate`` refuses (see the state section).

Statuses: each such call returns fmi2Error with its message logged at fmi2Error, and the
instance stays usable (:func:`_refuse` raises :class:`FmiCallRefused`), where the FMU's binary
is the patched pythonfmu library (``native/vendor/pythonfmu-export``, the Linux binary of every FMU
built where a C++ compiler is found; :func:`refusals_return_error`).  pythonfmu's own library
(Windows, macOS, no compiler) turns a Python exception in *any* call into fmi2Fatal and
releases the Python instance, so the host's next call on it reads freed memory; there nothing
may raise: a refused doStep returns fmi2Discard, a refused get/set returns fmi2OK with the
fmi2Error message in the log (a get NaN / 0 / false / "" for the bad references) and the
next doStep is refused once, a refused initialization makes every doStep fmi2Discard.
"""
from __future__ import annotations

import ctypes
import os
import sys
import traceback
from pathlib import Path
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status

from navcore import state_format
from navcore.errors import (NavcoreError, RefusedCall, StateError, StateFormatError,
                            numerical_failure)
from navcore.state import capture_value, check_kind

_DEG = 0.017453292519943295
_G0 = 9.80665
#: every unit symbol used on our interfaces: (FMI 2.0 BaseUnit exponents, factor to SI).
#: Datasheet units (only in parameters whose name says so) carry their factor; those with a
#: fractional exponent (deg/sqrt(h), ug/sqrt(Hz)) are declared without a BaseUnit.
UNITS = {
    "1": ({}, 1.0),
    "s": ({"s": 1}, 1.0),
    "m": ({"m": 1}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "m/s": ({"m": 1, "s": -1}, 1.0),
    "m/s2": ({"m": 1, "s": -2}, 1.0),
    "rad/s": ({"rad": 1, "s": -1}, 1.0),
    "T": ({"kg": 1, "s": -2, "A": -1}, 1.0),
    "Hz": ({"s": -1}, 1.0),
    "deg/h": ({"rad": 1, "s": -1}, _DEG / 3600.0),
    "ug": ({"m": 1, "s": -2}, 1e-6 * _G0),
    "ppm": ({}, 1e-6),
    "urad": ({"rad": 1}, 1e-6),
    "deg/h/g": ({"rad": 1, "s": 1, "m": -1}, _DEG / 3600.0 / _G0),
    "deg/sqrt(h)": (None, 1.0),
    "deg/h/sqrt(h)": (None, 1.0),
    "ug/sqrt(Hz)": (None, 1.0),
}

_VAR_CLASSES = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}

# FMI 2.0 order of the children of fmiModelDescription
_MD_ORDER = ["ModelExchange", "CoSimulation", "UnitDefinitions", "TypeDefinitions",
             "LogCategories", "DefaultExperiment", "VendorAnnotations", "ModelVariables",
             "ModelStructure"]


def setup(slave, component_class):
    """Declare the component's variables on ``slave`` (called from the slave's __init__)."""
    cls = component_class
    slave.component_class = cls
    slave.modelName = cls.model_name
    slave.description = cls.description
    start, stop, step = cls.default_experiment
    slave.default_experiment = DefaultExperiment(start_time=start, stop_time=stop, step_size=step)
    slave.author = "navfmu"
    slave.version = "0.1.0"
    slave._values = {}
    slave._units = {}
    slave._input_names = tuple(p.name for p in cls.inputs)
    slave._component = None
    slave._start_time = 0.0
    slave._stop_time = None
    slave._failed = None
    slave._refused_state = None
    slave._refused = None      # a refused get/set, reported by the next do_step
    slave._initialized = False
    slave._vr_names = {}       # type -> {value reference: name}
    slave._settable = {}       # type -> {value reference: name} that may be set now
    slave._causality = {}
    # the FMU's identity hashes its sources: read them now, while the folder pythonfmu loaded
    # them from exists (a host may delete it once the first instance is freed)
    _identity(type(slave))
    _finalize_python_at_exit(slave)
    for port in cls.parameters:
        _register(slave, port, Fmi2Causality.parameter, Fmi2Variability.fixed, Fmi2Initial.exact)
    for port in cls.inputs:
        variability = Fmi2Variability.continuous if port.type == "Real" else Fmi2Variability.discrete
        _register(slave, port, Fmi2Causality.input, variability, None)
    for port in cls.outputs:
        variability = Fmi2Variability.continuous if port.type == "Real" else Fmi2Variability.discrete
        _register(slave, port, Fmi2Causality.output, variability, None)


def _register(slave, port, causality, variability, initial):
    name = port.name
    slave._values[name] = port.default()
    slave._units[name] = port.unit
    values = slave._values
    var = _VAR_CLASSES[port.type](
        name,
        causality=causality,
        variability=variability,
        initial=initial,
        description=port.description or None,
        getter=lambda: values[name],
        setter=lambda v: values.__setitem__(name, v),
    )
    slave.register_variable(var, nested=False)
    slave._vr_names.setdefault(port.type, {})[var.value_reference] = name
    slave._causality[name] = causality.name
    if causality != Fmi2Causality.output:
        slave._settable.setdefault(port.type, {})[var.value_reference] = name


# -- life cycle (bound as methods of each slave class) ------------------------------------
def setup_experiment(slave, start_time, stop_time=None, tolerance=None):
    slave._start_time = float(start_time)
    slave._stop_time = None if stop_time is None else float(stop_time)


def exit_initialization_mode(slave):
    params = {p.name: slave._values[p.name] for p in slave.component_class.parameters}
    slave._initialized = True
    inputs = set(slave._input_names)
    slave._settable = {t: {vr: n for vr, n in names.items() if n in inputs}
                       for t, names in slave._settable.items()}
    try:
        slave._component = slave.component_class(**params)
        slave._values.update(slave._component.start(slave._start_time))
        if slave._stop_time is not None:
            slave._component.check_stop_time(slave._stop_time)
    except NavcoreError as exc:
        _fail(slave, str(exc), refuse=True)
    except Exception as exc:  # a bug, not a user error: still never crash the host
        _fail(slave, f"internal error during initialization: {exc!r}", traceback.format_exc(),
              refuse=True)


def do_step(slave, current_time, step_size):
    if slave._refused_state is not None:
        slave.log(f"{slave.instance_name}: step not taken: the last fmi2SetFMUstate was refused "
                  f"({slave._refused_state}); the instance kept its previous state and steps "
                  "from it at the next call", Fmi2Status.error)
        slave._refused_state = None
        return False
    if slave._failed is not None:
        slave.log(f"{slave.instance_name}: refusing to step after an earlier error: "
                  f"{slave._failed}", Fmi2Status.error)
        return False
    if slave._refused is not None:
        message, slave._refused = slave._refused, None
        slave.log(f"{slave.instance_name}: doStep at t = {current_time!r} s refused once "
                  f"because of an earlier refused call: {message}", Fmi2Status.error)
        return False
    component = slave._component
    if component is None:
        _refuse(slave, "doStep before fmi2ExitInitializationMode", later=False)
        return False
    values = slave._values
    try:
        inputs = {n: values[n] for n in slave._input_names}
        values.update(component.advance(current_time, step_size, inputs))
    except RefusedCall as exc:
        _refuse(slave, str(exc), later=False)
        return False
    except NavcoreError as exc:
        _fail(slave, f"{exc} (at t = {current_time:.6g} s)")
        return False
    except (ArithmeticError, ValueError) as exc:  # overflow, math domain: a diverged state
        _fail(slave, f"{numerical_failure(exc)} (at t = {current_time:.6g} s)",
              traceback.format_exc())
        return False
    except Exception as exc:
        _fail(slave, f"internal error: {exc!r} (at t = {current_time:.6g} s)",
              traceback.format_exc())
        return False
    for notice in (component.take_notices() if component.notices else ()):
        slave.log(f"{slave.instance_name}: {notice}", Fmi2Status.warning)
    return True


def _fail(slave, message, details=None, refuse=False):
    """Record the instance's first error and log it; with ``refuse``, where the binary allows
    it, the message is the fmi2Error of the call instead (the traceback is logged before it)."""
    slave._failed = message
    text = f"{slave.instance_name}: {message}"
    if refuse and refusals_return_error(slave):
        if details:
            slave.log(details, Fmi2Status.error, "traceback")
        raise FmiCallRefused(text)
    slave.log(text, Fmi2Status.error)
    if details:
        slave.log(details, Fmi2Status.error, "traceback")


class FmiCallRefused(Exception):
    """A refused FMI call.  The patched pythonfmu library (``native/vendor/pythonfmu-export``)
    recognizes it by ``fmi2_status``, logs its message at fmi2Error, returns fmi2Error and
    keeps the instance; pythonfmu's own library would return fmi2Fatal and drop the
    instance, so it is raised only where :func:`refusals_return_error` is true."""

    fmi2_status = "error"


def refusals_return_error(slave) -> bool:
    """True if the instance's binary is the patched library: it marks each instance it
    creates (not the class: the FMUs of one script share it, whatever their binary)."""
    return getattr(slave, "fmi2_error_on_refused_call", False) is True


# -- batched value access ------------------------------------------------------------------
# pythonfmu's own get_real/set_real look every variable up through its ScalarVariable object
# and a getter closure (about 1 us per variable); these read and write the value dict
# directly, which matters because the master calls them for every component every step.
# A bad call is refused through _refuse (module docstring).
_PLACEHOLDER = {"Real": float("nan"), "Integer": 0, "Boolean": False, "String": ""}


def _getter(type_name):
    def get(slave, vrs):
        names = slave._vr_names.get(type_name, {})
        values = slave._values
        try:
            return [values[names[vr]] for vr in vrs]
        except (KeyError, TypeError):
            bad = [vr for vr in vrs if names.get(vr) is None]
            _refuse(slave, f"fmi2Get{type_name}: " + _unknown(slave, type_name, bad))
            return [values[names[vr]] if names.get(vr) is not None else _PLACEHOLDER[type_name]
                    for vr in vrs]
    return get


def _setter(type_name):
    def set_(slave, vrs, new_values):
        settable = slave._settable.get(type_name, {})
        try:
            names = [settable[vr] for vr in vrs]
        except (KeyError, TypeError):
            _refuse(slave, f"fmi2Set{type_name}: " + _why_not_settable(slave, type_name, vrs))
            return
        slave._values.update(zip(names, new_values))
    return set_


def _unknown(slave, type_name, vrs):
    others = {vr: (t, n) for t, names in slave._vr_names.items() for vr, n in names.items()}
    parts = []
    for vr in vrs:
        if vr in others:
            t, n = others[vr]
            parts.append(f"valueReference {vr} is '{n}', of type {t}, not {type_name}")
        else:
            parts.append(f"valueReference {vr} is no variable of {slave.modelName}")
    return "; ".join(parts)


def _why_not_settable(slave, type_name, vrs):
    names = slave._vr_names.get(type_name, {})
    settable = slave._settable.get(type_name, {})
    unknown = [vr for vr in vrs if vr not in names]
    parts = [_unknown(slave, type_name, unknown)] if unknown else []
    for vr in vrs:
        name = names.get(vr)
        if name is None or vr in settable:
            continue
        if slave._causality[name] == "output":
            parts.append(f"'{name}' (valueReference {vr}) is an output; only inputs and "
                         "parameters can be set")
        else:
            parts.append(f"parameter '{name}' (valueReference {vr}) is fixed: it can only be "
                         "set before fmi2ExitInitializationMode")
    return "; ".join(parts) + " (nothing was set)"


def _refuse(slave, message, later=True):
    """Refuse the current call: fmi2Error with ``message`` where the binary allows it;
    else log it at Error and (``later``, for a get/set) have the next do_step refused once."""
    text = f"{slave.instance_name}: {message}"
    if refusals_return_error(slave):
        raise FmiCallRefused(text)
    if later:
        slave._refused = message
    slave.log(text, Fmi2Status.error)

# -- FMU state: declared data only, never code ---------------------------------------------
# A state that cannot be taken, a blob fmi2DeSerializeFMUstate refuses and a state
# fmi2SetFMUstate refuses give fmi2Error on that call (FmiCallRefused), the instance keeping
# its previous state.  With pythonfmu's own library (refusals_return_error false), which turns
# any exception into fmi2Fatal, nothing here raises: a refused blob deserializes into a
# RefusedState carrying the reason, and fmi2SetFMUstate with it (or with a state that fails
# the checks) logs the reason at status fmi2Error, keeps the previous state, and makes the
# next fmi2DoStep return fmi2Discard without stepping, so a host that ignores the log still
# learns that the state was not restored; the steps after that continue from the previous
# state.
class FmuState:
    """What fmi2GetFMUstate hands out: the state tree of an instance and its FMU identity."""

    __slots__ = ("identity", "tree", "_blob")

    def __init__(self, identity, tree):
        self.identity, self.tree, self._blob = identity, tree, None

    def to_bytes(self):
        if self._blob is None:
            self._blob = state_format.encode(self.tree, self.identity)
        return self._blob


class RefusedState:
    """A blob fmi2DeSerializeFMUstate refused (or a state that could not be taken)."""

    __slots__ = ("reason",)

    def __init__(self, reason):
        self.reason = reason


_IDENTITIES = {}


def _identity(slave_class):
    """(model name, hash of the FMU's Python sources): which FMU wrote a state."""
    identity = _IDENTITIES.get(slave_class)
    if identity is None:
        script = sys.modules[slave_class.__module__].__file__
        identity = (slave_class.__name__, state_format.build_hash(Path(script)))
        _IDENTITIES[slave_class] = identity
    return identity


def get_fmu_state(slave):
    try:
        component = slave._component
        tree = {"values": capture_value(slave._values, "values"), "failed": slave._failed,
                "start_time": slave._start_time,
                "component": (None if component is None or slave._failed is not None
                              else component.get_state())}
        return FmuState(_identity(type(slave)), tree)
    except Exception as exc:  # a bug (an undeclared attribute): report, never crash the host
        reason = f"the state could not be taken: {exc}"
        message = f"{slave.instance_name}: fmi2GetFMUstate: {reason}"
        if refusals_return_error(slave):
            raise FmiCallRefused(message) from None
        slave.log(message, Fmi2Status.error)
        return RefusedState(reason)


def set_fmu_state(slave, state):
    try:
        restored = _restored(slave, state)
    except (NavcoreError, StateError, StateFormatError) as exc:
        reason = str(exc)
    except Exception as exc:
        reason = f"internal error: {exc!r}"
    else:
        slave._values.clear()
        slave._values.update(restored["values"])
        slave._failed, slave._start_time, slave._component = (
            restored["failed"], restored["start_time"], restored["component"])
        slave._refused_state = None
        return
    message = (f"{slave.instance_name}: fmi2SetFMUstate refused the state, the instance keeps "
               f"its previous state: {reason}")
    if refusals_return_error(slave):
        raise FmiCallRefused(message)
    slave._refused_state = reason
    slave.log(message, Fmi2Status.error)


def _restored(slave, state):
    """The checked contents of ``state`` with a component rebuilt from it (raises)."""
    if isinstance(state, RefusedState):
        raise StateFormatError(state.reason)
    if not isinstance(state, FmuState):
        raise StateFormatError(f"not a state of this FMU ({type(state).__name__})")
    if state.identity != _identity(type(slave)):
        raise StateFormatError(f"the state belongs to FMU '{state.identity[0]}' (another "
                               f"build or model than '{type(slave).__name__}')")
    tree = state.tree
    if not (isinstance(tree, dict)
            and set(tree) == {"values", "failed", "start_time", "component"}):
        raise StateError("the state must have the keys values, failed, start_time, component")
    values = tree["values"]
    ports = {p.name: p for group in (slave.component_class.parameters,
                                     slave.component_class.inputs,
                                     slave.component_class.outputs) for p in group}
    if not isinstance(values, dict) or set(values) != set(ports):
        raise StateError("the state's variables are not those of this FMU")
    for name, port in ports.items():
        check_kind(port.default(), values[name], f"variable '{name}'")
    failed, start_time, component = tree["failed"], tree["start_time"], tree["component"]
    if not (failed is None or isinstance(failed, str)):
        raise StateError("the state's error message is not a string")
    if type(start_time) is not float:
        raise StateError("the state's start time is not a float")
    if component is not None:
        component = slave.component_class.from_state(component)
        for port in slave.component_class.parameters:
            if values[port.name] != component.params[port.name]:
                raise StateError(f"variable '{port.name}' differs from the parameter the "
                                 "state's component was built with")
    return {"values": dict(values), "failed": failed, "start_time": start_time,
            "component": component}


def _fmu_state_to_bytes(state):
    try:
        return state.to_bytes()
    except Exception:  # a RefusedState or a foreign object: nothing to write
        return b""


def _fmu_state_from_bytes(slave_class, blob, refusal_returns_error=False):
    """The state in ``blob``.  The patched library passes ``refusal_returns_error`` (the
    class, shared by every FMU of this script loaded in the process, cannot tell)."""
    try:
        return FmuState(_identity(slave_class), state_format.decode(blob, _identity(slave_class)))
    except StateFormatError as exc:
        reason = str(exc)
    except Exception as exc:
        reason = f"the blob could not be read: {exc!r}"
    if refusal_returns_error is True:
        raise FmiCallRefused(f"fmi2DeSerializeFMUstate refused the blob: {reason}")
    return RefusedState(reason)


def bind_methods(slave_class):
    """Give an FMU script's slave class the FMI methods of this module (called right after
    the class statement in every script)."""
    _balance_loader_decref(sys._getframe(1))
    slave_class.setup_experiment = setup_experiment
    slave_class.exit_initialization_mode = exit_initialization_mode
    slave_class._get_fmu_state = get_fmu_state
    slave_class._set_fmu_state = set_fmu_state
    slave_class._fmu_state_to_bytes = staticmethod(_fmu_state_to_bytes)
    slave_class._fmu_state_from_bytes = classmethod(_fmu_state_from_bytes)
    slave_class.to_xml = to_xml
    for type_name in ("Real", "Integer", "Boolean", "String"):
        setattr(slave_class, f"get_{type_name.lower()}", _getter(type_name))
        setattr(slave_class, f"set_{type_name.lower()}", _setter(type_name))
    return slave_class


def _balance_loader_decref(script_frame):
    """Give back the reference to the script's module dict that pythonfmu's loader takes.

    pythonfmu 0.7's native loader (``findClass`` in ``PySlaveInstance.cpp``), at every
    ``fmi2Instantiate``, executes the script once more with the module's dict as globals and a
    fresh dict as locals, then ``Py_DECREF``s the module dict, a borrowed reference: each
    instance leaves the dict one reference short.  What hides the deficit is another leak of
    the loader (the re-executed class, kept alive by an MRO list it never releases, whose
    methods defined in the script hold the dict); the crash of a second instance of a script
    without an ``__init__`` of its own (module docstring) fits this.  That re-execution is the
    only time the script's top level runs with locals that are not its globals; there we add
    the missing reference, for good (the dict lives until the process ends, as a module's
    should).
    """
    if script_frame.f_locals is not script_frame.f_globals:
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(script_frame.f_globals))


#: dlopen flags to take hold of an already loaded library for good
_RTLD_HOLD = os.RTLD_NOW | getattr(os, "RTLD_NOLOAD", 0) | getattr(os, "RTLD_NODELETE", 0)
_EXIT_HOOKED = set()


def _finalize_python_at_exit(slave):
    """Have pythonfmu tear the interpreter down first thing at ``exit()``, not last.

    pythonfmu 0.7's binary keeps its interpreter owner in a C++ static ``shared_ptr`` and
    also resets that pointer from an ``__attribute__((destructor))`` (``PySlaveInstance.cpp``).
    At ``exit()`` the static destructors run first, in reverse order of loading: those of every
    C++ extension module imported since (scipy's ``_uarray``), then the ``shared_ptr``'s, whose
    ``Py_FinalizeEx`` then meets the already destroyed objects of those extensions; afterwards
    the destructor function resets the destroyed ``shared_ptr`` again, a write into freed
    memory (glibc "corrupted double-linked list", in Python hosts too).  Registering the
    binary's own ``finalizePythonInterpreter`` with ``__cxa_atexit`` once per binary, after
    the imports, runs it before all of those: the interpreter ends while everything it uses is
    alive, and the later resets find an empty pointer.  The binary is pinned (RTLD_NODELETE;
    its STB_GNU_UNIQUE symbols make it unloadable anyway), so the hook never outlives its
    code.  A slave instantiated from Python without the binary (the FMU builder) is left alone.
    """
    resources = getattr(slave, "resources", None)
    if not resources or not sys.platform.startswith("linux"):
        return
    library = os.path.join(os.path.dirname(os.path.abspath(resources)), "binaries", "linux64",
                           f"{type(slave).__name__}.so")
    if library in _EXIT_HOOKED:
        return
    try:
        finalize = ctypes.CDLL(library, mode=_RTLD_HOLD).finalizePythonInterpreter
        register = ctypes.CDLL(None).__cxa_atexit
    except (OSError, AttributeError):
        return
    register.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    register.restype = ctypes.c_int
    if register(ctypes.cast(finalize, ctypes.c_void_p), None, None) == 0:
        _EXIT_HOOKED.add(library)


# -- model description: units, legal attributes -------------------------------------------
def to_xml(slave, model_options=None):
    options = dict(model_options or {})
    options.setdefault("canGetAndSetFMUstate", True)
    options.setdefault("canSerializeFMUstate", True)
    root = Fmi2Slave.to_xml(slave, options)
    cosim = root.find("CoSimulation")
    cosim.set("canGetAndSetFMUstate", "true")
    cosim.set("canSerializeFMUstate", "true")
    used_units = []
    output_indices = []
    for index, sv in enumerate(root.find("ModelVariables"), start=1):
        name = sv.get("name")
        child = sv[0] if len(sv) else None
        unit = slave._units.get(name, "")
        if child is not None and child.tag == "Real" and unit:
            child.set("unit", unit)
            if unit not in used_units:
                used_units.append(unit)
        if sv.get("causality") == "output":
            output_indices.append(index)
    if used_units:
        unit_defs = Element("UnitDefinitions")
        for unit in used_units:
            u = SubElement(unit_defs, "Unit", name=unit)
            exponents, factor = UNITS[unit]
            if exponents is not None:
                attrib = {k: str(v) for k, v in exponents.items()}
                if factor != 1.0:
                    attrib["factor"] = repr(factor)
                SubElement(u, "BaseUnit", attrib)
        root.append(unit_defs)
    structure = root.find("ModelStructure")
    if output_indices and structure.find("InitialUnknowns") is None:
        initial = SubElement(structure, "InitialUnknowns")
        for index in output_indices:
            SubElement(initial, "Unknown", index=str(index))
    # put the children in the order the FMI 2.0 schema prescribes
    children = list(root)
    for c in children:
        root.remove(c)
    children.sort(key=lambda e: _MD_ORDER.index(e.tag))
    root.extend(children)
    return root
