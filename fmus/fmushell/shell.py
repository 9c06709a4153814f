"""The FMI side of a slave: variables declared, life cycle, doStep, batched value access.

:func:`setup` (from the slave's ``__init__``) declares the component's variables;
:func:`bind_methods` (right after the slave class statement) gives the class the FMI methods of
this package; :func:`do_step` advances the component and turns its errors into FMI statuses.
"""
from __future__ import annotations

import operator
import sys
import traceback

from pythonfmu import Boolean, Fmi2Causality, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status

from navcore import __version__ as navcore_version
from navcore.errors import NavcoreError, RefusedCall, numerical_failure

from .fmu_state import (fmu_identity, fmu_state_from_bytes, fmu_state_to_bytes,
                        get_fmu_state, set_fmu_state)
from .log_categories import LOG_CATEGORIES, log
from .model_description import to_xml
from .private_paths import adopt_folder
from .pythonfmu_fixes import balance_loader_decref, finalize_python_at_exit
from .refusals import FmiCallRefused, refusals_return_error, refuse
from .resource_files import resolved_file_parameters
from .start_values import apply_start_values

_VAR_CLASSES = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}

def setup(slave, component_class):
    """Declare the component's variables on ``slave`` (called from the slave's __init__)."""
    cls = component_class
    slave.component_class = cls
    slave.modelName = cls.model_name
    slave.description = cls.description
    start, stop, step = cls.default_experiment
    slave.default_experiment = DefaultExperiment(start_time=start, stop_time=stop, step_size=step)
    slave.author = "navfmu"
    slave.version = navcore_version
    slave._values = {}
    slave._units = {}
    slave._input_names = tuple(p.name for p in cls.inputs)
    slave._read_inputs = _reader(slave._input_names)
    slave._component = None
    slave._entered = None      # (parameters, component) started in initialization mode
    slave._parameter_names = frozenset(p.name for p in cls.parameters)
    slave._in_initialization = False
    slave._stale_start = False  # a parameter set in initialization mode since the start
    slave._start_time = 0.0
    slave._stop_time = None
    slave._failed = None
    slave._failure_repeated = False  # the refusal after an error was logged
    slave._refused_state = None
    slave._refused = None      # a refused get/set, reported by the next do_step
    slave._vr_names = {}       # type -> {value reference: name}
    slave._settable = {}       # type -> {value reference: name} that may be set now
    slave._causality = {}
    if getattr(slave, "resources", None):     # this build's packages, searched here first
        adopt_folder(slave.resources, sys.modules[type(slave).__module__].__dict__)
    # the FMU's identity (its build file) read now, while the folder pythonfmu loaded the
    # script from exists (a host may delete it once the first instance is freed)
    fmu_identity(type(slave))
    finalize_python_at_exit()
    for port in cls.parameters:
        _register(slave, port, Fmi2Causality.parameter, Fmi2Variability.fixed, Fmi2Initial.exact)
    for port in cls.inputs:
        variability = (
            Fmi2Variability.continuous if port.type == "Real" else Fmi2Variability.discrete
        )
        _register(slave, port, Fmi2Causality.input, variability, None)
    for port in cls.outputs:
        variability = (
            Fmi2Variability.continuous if port.type == "Real" else Fmi2Variability.discrete
        )
        _register(slave, port, Fmi2Causality.output, variability, None)
    slave._start_error = apply_start_values(slave, cls.parameters)


def _reader(names):
    """A function ``values -> {name: values[name] for name in names}`` (one itemgetter: the
    inputs are read out of the value dict at every doStep)."""
    if not names:
        return lambda values: {}
    get = operator.itemgetter(*names)
    if len(names) == 1:
        return lambda values: {names[0]: get(values)}
    return lambda values: dict(zip(names, get(values)))


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


def _parameters(slave):
    """The parameter values, relative file parameters found in the resources made absolute."""
    return resolved_file_parameters(
        slave, {p.name: slave._values[p.name] for p in slave.component_class.parameters})


def enter_initialization_mode(slave):
    """Start the component already, so its outputs are valid in initialization mode (a host
    may read them then to set the inputs of others: a sensor takes its vehicle's start
    sample from them).  A parameter set in initialization mode (FMI 2.0 allows it for
    fixed parameters) starts it again at the next read of an output, so what a host reads
    there always belongs to the parameters set so far.  Nothing is reported here:
    exit_initialization_mode starts it again, with its errors, if this failed or a
    parameter changed since."""
    slave._in_initialization = True
    _start_in_initialization(slave)


def _start_in_initialization(slave):
    slave._entered, slave._stale_start = None, False
    if slave._start_error is not None:   # reported by exit_initialization_mode
        return
    params = _parameters(slave)
    try:
        component = slave.component_class(**params)
        outputs = component.start(slave._start_time)
    except Exception:  # reported by exit_initialization_mode
        return
    slave._entered = (params, component)
    slave._values.update(outputs)


def exit_initialization_mode(slave):
    values = slave._values
    slave._in_initialization = slave._stale_start = False
    if slave._start_error is not None:
        _fail(slave, slave._start_error, refuse=True)
        return
    params = _parameters(slave)
    slave._values.update(params)  # a state's parameters are those the component was built with
    inputs = set(slave._input_names)
    slave._settable = {t: {vr: n for vr, n in names.items() if n in inputs}
                       for t, names in slave._settable.items()}
    entered, slave._entered = getattr(slave, "_entered", None), None
    try:
        if entered is not None and entered[0] == params:
            slave._component = entered[1]
        else:
            slave._component = slave.component_class(**params)
            slave._values.update(slave._component.start(slave._start_time))
        started = slave._component.initial_inputs(slave._read_inputs(values))
        if started is not None:
            slave._values.update(started)
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
        if not slave._failure_repeated:  # once: a host that steps on must not flood its log
            slave._failure_repeated = True
            slave.log(f"{slave.instance_name}: refusing to step after an earlier error: "
                      f"{slave._failed} (every further step is refused without a message)",
                      Fmi2Status.error)
        return False
    if slave._refused is not None:
        message, slave._refused = slave._refused, None
        slave.log(f"{slave.instance_name}: doStep at t = {current_time!r} s refused once "
                  f"because of an earlier refused call: {message}", Fmi2Status.error)
        return False
    component = slave._component
    if component is None:
        refuse(slave, "doStep before fmi2ExitInitializationMode", later=False)
        return False
    values = slave._values
    try:
        values.update(component.advance(current_time, step_size, slave._read_inputs(values)))
    except RefusedCall as exc:
        refuse(slave, str(exc), later=False)
        return False
    except NavcoreError as exc:   # a refused input (NaN, inf, out of range), a diverged state
        _fail(slave, f"{exc} (at t = {current_time:.6g} s)", refuse=True)
        return False
    except (ArithmeticError, ValueError) as exc:  # overflow, math domain: a diverged state
        _fail(slave, f"{numerical_failure(exc)} (at t = {current_time:.6g} s)",
              traceback.format_exc(), refuse=True)
        return False
    except Exception as exc:
        _fail(slave, f"internal error: {exc!r} (at t = {current_time:.6g} s)",
              traceback.format_exc(), refuse=True)
        return False
    for notice in (component.take_notices() if component.notices else ()):
        slave.log(f"{slave.instance_name}: {notice}", Fmi2Status.warning)
    return True


def _fail(slave, message, details=None, refuse=False):
    """Record the instance's first error and log it; with ``refuse``, where the binary allows
    it, the message is the fmi2Error of the call instead (the traceback is logged before it)
    and the instance is in FMI's error state; else the call reports fmi2Discard (doStep) or
    fmi2OK with the message in the log (fmi2ExitInitializationMode)."""
    slave._failed, slave._failure_repeated = message, False
    text = f"{slave.instance_name}: {message}"
    if refuse and refusals_return_error(slave):
        if details:
            slave.log(details, Fmi2Status.error, "traceback")
        raise FmiCallRefused(text, instance_failed=True)
    slave.log(text, Fmi2Status.error)
    if details:
        slave.log(details, Fmi2Status.error, "traceback")

# -- batched value access ------------------------------------------------------------------
# pythonfmu's own get_real/set_real look every variable up through its ScalarVariable object
# and a getter closure (about 1 us per variable); these read and write the value dict
# directly, which matters because the master calls them for every component every step.
# A bad call is refused through _refuse (module docstring).
_PLACEHOLDER = {"Real": float("nan"), "Integer": 0, "Boolean": False, "String": ""}


def _getter(type_name):
    def get(slave, vrs):
        if slave._stale_start:
            _start_in_initialization(slave)
        names = slave._vr_names.get(type_name, {})
        values = slave._values
        try:
            return list(map(values.__getitem__, map(names.__getitem__, vrs)))
        except (KeyError, TypeError):
            bad = [vr for vr in vrs if names.get(vr) is None]
            refuse(slave, f"fmi2Get{type_name}: " + _unknown(slave, type_name, bad))
            return [values[names[vr]] if names.get(vr) is not None else _PLACEHOLDER[type_name]
                    for vr in vrs]
    return get


def _setter(type_name):
    def set_(slave, vrs, new_values):
        settable = slave._settable.get(type_name, {})
        try:
            names = list(map(settable.__getitem__, vrs))
        except (KeyError, TypeError):
            refuse(slave, f"fmi2Set{type_name}: " + _why_not_settable(slave, type_name, vrs))
            return
        slave._values.update(zip(names, new_values))
        if slave._in_initialization and not slave._parameter_names.isdisjoint(names):
            slave._stale_start = True
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


def bind_methods(slave_class):
    """Give an FMU script's slave class the FMI methods of this module (called right after
    the class statement in every script)."""
    balance_loader_decref(sys._getframe(1))
    slave_class.setup_experiment = setup_experiment
    slave_class.enter_initialization_mode = enter_initialization_mode
    slave_class.exit_initialization_mode = exit_initialization_mode
    slave_class._get_fmu_state = get_fmu_state
    slave_class._set_fmu_state = set_fmu_state
    slave_class._fmu_state_to_bytes = staticmethod(fmu_state_to_bytes)
    slave_class._fmu_state_from_bytes = classmethod(fmu_state_from_bytes)
    slave_class.to_xml = to_xml
    slave_class.log_categories = LOG_CATEGORIES
    slave_class.log = log
    for type_name in ("Real", "Integer", "Boolean", "String"):
        setattr(slave_class, f"get_{type_name.lower()}", _getter(type_name))
        setattr(slave_class, f"set_{type_name.lower()}", _setter(type_name))
    return slave_class
