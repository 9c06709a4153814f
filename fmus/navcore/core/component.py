"""Step-wise component models: the navcore side of every FMU.

A :class:`Component` is a plain Python object that declares its parameters, inputs and
outputs (name, type, SI unit, description, default) and advances itself with
``step(t, h, inputs) -> outputs``.  It knows nothing of FMI.  The FMU slaves in ``fmus/``
wrap one component each (declaring the same variables to FMI), and the master can run
the very same objects directly (``orchestrator.direct``), which is how we check that a
system gives the same numbers through every path.

Contract of a component
-----------------------
* ``__init__(**params)`` sets parameters from the declared defaults, overridden by keyword.
  An unknown name raises :class:`ParameterError` naming it.
* ``initialize(start_time)`` validates every parameter (raising :class:`ParameterError`
  with the parameter's name and the reason) and builds the internal state.  It returns the
  outputs valid at ``start_time``.
* ``initial_inputs(inputs)`` is called once after ``start`` with the input values set in
  initialization mode (FMI: they hold at the start time); a component that needs them (a
  sensor taking its vehicle's start sample) returns its outputs updated, the others None.
* ``step(t, h, inputs)`` advances from ``t`` to ``t + h`` with the input values (a dict
  name -> value, values as set by the connections at this communication point) and returns
  the outputs valid at ``t + h`` (a dict name -> value).  Bad input raises
  :class:`InputError` naming the variable.
* ``start(start_time)`` is how the FMU shell and the master begin a run: it records the start
  time (part of the state) and calls ``initialize``.
* ``get_state()`` returns the full internal state as plain data (the parameters, the start
  time and the declared fields, see below); ``set_state(state)`` and the class method
  ``from_state(state)`` restore it into a component built from those parameters.

State
-----
Simulators save FMU states and load them back, also from files written elsewhere, so a state
is data, never code: each class *declares* which of its instance attributes define its state,
and nothing else is saved (:mod:`navcore.core.state`; the byte format is
:mod:`navcore.core.state_format`).  Two class attributes, each listing only the attributes the
class itself adds (the lists of the base classes add up)::

    state_fields = ("engine", "nav_time", "last_epoch", "out")    # change while stepping
    derived_fields = ("dt",)       # rebuilt from the parameters by __init__ / initialize

A state field may hold plain values (None, bool, int, float, str), numpy arrays of float64,
int64 or bool, lists, tuples, str-keyed dicts and deques of these, a
``numpy.random.Generator``, or an object of a class that declares its own fields the same
way (a strapdown, a Kalman filter engine, an error model: captured recursively).  To restore,
``from_state`` builds a fresh component from the saved parameters, calls ``start`` with the
saved start time (so every derived attribute is rebuilt exactly as in the original run) and
then writes each declared field, after checking that the saved value has the kind, dtype and
shape of the fresh one.  Consequences for whoever adds an attribute (a history buffer, a new
model inside a component):

* add it to ``state_fields`` if stepping changes it, to ``derived_fields`` if it is a pure
  function of the parameters; ``get_state`` refuses an object with an undeclared attribute
  (:class:`~navcore.errors.StateError` naming it), and ``tests/test_state_format.py`` walks
  every component of ``components.REGISTRY`` after stepping it;
* a derived attribute must come out bit-identical from ``__init__`` + ``start`` (the same
  test compares every attribute of a restored component with the original);
* a buffer of past values is a deque or list (of arrays, numbers, or tuples/dicts of
  them); a sub-object declares its fields.  An attribute that is None in a fresh component,
  and the items of a buffer that is empty in a fresh component, accept only numeric data
  (None, numbers, arrays and containers of them; give the attribute a start value of the
  right kind if it will hold text).

Parameter ranges
----------------
Each numeric parameter declares its accepted range once, on its :class:`Port`
(``limits``, a :class:`Limits`); :meth:`Component.set_parameter` refuses a value outside it
(every Real must also be finite) with a :class:`ParameterError` naming the parameter, the
value and the range.  Upper bounds are where physics (or the float range) gives one, so a
huge but finite value is refused here instead of overflowing inside the component.
Cross-parameter conditions (``t1 < t2``) stay in ``initialize`` (:meth:`Component.require`).
After ``start``, the FMU shell and the master call ``check_stop_time(stop_time)`` with the
experiment's stop time (when the host gives one), so a component can refuse a run it cannot
cover.
A caller (the FMU shell, the master's direct backend) drives a component through
:meth:`Component.start` and :meth:`Component.advance`, which add the rules every component
shares: communication points follow each other (``t`` of a step is where the previous one
ended, within :func:`navcore.core.timing.time_tolerance`) and a step size is > 0; a call that
breaks them raises :class:`RefusedCall` and changes nothing.  Messages a component wants a
user to see without failing (a fix it did not use, say) are queued with :meth:`notify` and
collected by the caller with :meth:`take_notices`.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Dict, List, Tuple

from . import state as _state
from ..errors import InputError, ParameterError, RefusedCall, StateError
from .limits import DIMENSIONLESS, FINITE, Limits  # noqa: F401  (part of the component API)
from .timing import time_tolerance


@dataclass(frozen=True)
class Port:
    """One declared variable of a component.

    ``type`` is one of ``Real``, ``Integer``, ``Boolean``, ``String``; ``unit`` is the SI unit
    symbol written to the model description: ``"1"`` for a dimensionless Real (NIS, scale
    factors, probabilities; :func:`real` writes it when no unit is given), ``""`` for
    Integer/Boolean/String variables, which carry no unit in FMI 2.0; ``limits`` is the
    accepted range of a Real or Integer parameter (or of an input a component checks).
    """

    name: str
    type: str = "Real"
    unit: str = ""
    description: str = ""
    start: Any = 0.0
    limits: Limits = FINITE

    def default(self):
        if self.type == "Real":
            return float(self.start)
        if self.type == "Integer":
            return int(self.start)
        if self.type == "Boolean":
            return bool(self.start)
        return str(self.start)


#: the unit of a dimensionless Real
def real(name, unit="", description="", start=0.0, limits=FINITE):
    """A Real port; without ``unit`` it is dimensionless (:data:`DIMENSIONLESS`)."""
    return Port(name, "Real", unit or DIMENSIONLESS, description, start, limits)


def integer(name, description="", start=0, limits=FINITE):
    return Port(name, "Integer", "", description, start, limits)


def boolean(name, description="", start=False):
    return Port(name, "Boolean", "", description, start)


def string(name, description="", start=""):
    return Port(name, "String", "", description, start)


class Component(ABC):
    """Base class of the step-wise models wrapped by the FMUs (see module docstring)."""

    #: model name of the FMU wrapping this component: by default the class's own name (set
    #: for each subclass by ``__init_subclass__``)
    model_name: ClassVar[str] = ""
    description: ClassVar[str] = ""
    parameters: ClassVar[Tuple[Port, ...]] = ()
    inputs: ClassVar[Tuple[Port, ...]] = ()
    outputs: ClassVar[Tuple[Port, ...]] = ()
    #: default experiment (start, stop, step) written to the model description
    default_experiment: ClassVar[Tuple[float, float, float]] = (0.0, 10.0, 0.01)
    #: String parameters that name a file or folder (an FMU resolves a relative one against
    #: its resources folder first, where ``navfmu package`` puts the files a scenario names)
    file_parameters: ClassVar[Tuple[str, ...]] = ()
    #: the inputs :meth:`initial_inputs` reads, by the outputs they set: output name -> input
    #: names (the other outputs at the end of initialization mode depend on the parameters
    #: only).  The model description's InitialUnknowns declare these dependencies; no output
    #: depends on an input between two steps (a component computes its outputs in ``step``).
    initial_dependencies: ClassVar[Dict[str, Tuple[str, ...]]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "model_name" not in cls.__dict__:
            cls.model_name = cls.__name__

    def __init__(self, **params):
        self.params: Dict[str, Any] = {p.name: p.default() for p in self.parameters}
        self.notices: List[str] = []
        for name, value in params.items():
            self.set_parameter(name, value)

    # -- parameters -------------------------------------------------------------------
    def set_parameter(self, name: str, value: Any) -> None:
        port = self.parameter_port(name)
        try:
            if port.type == "Real":
                value = float(value)
            elif port.type == "Integer":
                if isinstance(value, float) and not value.is_integer():
                    raise ValueError(value)
                value = int(value)
            elif port.type == "Boolean":
                value = bool(value)
            else:
                value = str(value)
        except (TypeError, ValueError):
            raise ParameterError(
                f"{self.model_name}: parameter '{name}' expects a {port.type}, got {value!r}"
            ) from None
        if port.type in ("Real", "Integer") and not port.limits.contains(value):
            raise ParameterError(
                f"{self.model_name}: parameter '{name}' = {value!r} is outside the accepted "
                f"range {port.limits.text(port.unit)}")
        self.params[name] = value

    @classmethod
    def parameter_port(cls, name: str) -> Port:
        for p in cls.parameters:
            if p.name == name:
                return p
        raise ParameterError(f"{cls.model_name}: unknown parameter '{name}'")

    # helpers for validation in initialize()
    def require(self, name: str, ok: bool, requirement: str) -> None:
        """Raise a :class:`ParameterError` naming parameter ``name``, its value and the
        ``requirement`` it breaks (e.g. "must be in (0, 1)") unless ``ok``."""
        if not ok:
            raise ParameterError(f"{self.model_name}: parameter '{name}' = "
                                 f"{self.params[name]!r} {requirement}")

    def check_inputs(self, inputs: Dict[str, Any], names) -> None:
        """Raise an :class:`InputError` naming the first of the Real inputs ``names`` that is
        not finite or outside the range its port declares."""
        # fast path: the declared bounds by comparison; finiteness by one sum (NaN and inf
        # propagate into it) over the inputs whose range has an infinite end (within finite
        # bounds a value is finite); anything doubtful goes through the full check below
        bounded, open_ended = type(self)._input_checks(names)
        for n, low, high, low_open, high_open in bounded:
            v = inputs[n]
            if not ((v > low if low_open else v >= low)
                    and (v < high if high_open else v <= high)):
                break
        else:
            if math.isfinite(sum([inputs[n] for n in open_ended])):
                return
        ports = type(self)._input_ports()
        for n in names:
            v = inputs[n]
            port = ports.get(n)
            limits = port.limits if port is not None else FINITE
            if not limits.contains(v):
                raise InputError(f"{self.model_name}: input '{n}' = {v} is outside the accepted "
                                 f"range {limits.text(port.unit if port else '')}")

    @classmethod
    def _input_checks(cls, names) -> Tuple[Tuple[Tuple[str, float, float, bool, bool], ...],
                                           Tuple[str, ...]]:
        """``(bounded, open_ended)`` of the inputs ``names``: ``(name, low, high, low_open,
        high_open)`` of those whose port declares a range narrower than finite, and the
        names of those whose range has an infinite end."""
        cache = cls.__dict__.get("_input_check_cache")
        if cache is None:
            cache = cls._input_check_cache = {}
        if type(names) is not tuple:   # the cache's keys: tuples of names
            names = tuple(names)
        checks = cache.get(names)
        if checks is None:
            ports = cls._input_ports()
            limits = [(n, ports[n].limits if n in ports else FINITE) for n in names]
            checks = cache[names] = (
                tuple((n, x.low, x.high, x.low_open, x.high_open)
                      for n, x in limits if x != FINITE),
                tuple(n for n, x in limits if not (math.isfinite(x.low)
                                                   and math.isfinite(x.high))))
        return checks

    @classmethod
    def _input_ports(cls) -> Dict[str, Port]:
        ports = cls.__dict__.get("_input_port_map")
        if ports is None:
            ports = {p.name: p for p in cls.inputs}
            cls._input_port_map = ports
        return ports

    # -- life cycle -------------------------------------------------------------------
    @abstractmethod
    def initialize(self, start_time: float) -> Dict[str, Any]:
        """Validate parameters, build the state, return the outputs at ``start_time``."""

    @abstractmethod
    def step(self, t: float, h: float, inputs: Dict[str, Any]) -> Dict[str, Any]:
        """Advance from ``t`` to ``t + h``; return the outputs valid at ``t + h``."""

    def initial_inputs(self, inputs: Dict[str, Any]):
        """The inputs at the end of initialization mode (module docstring); None: the outputs
        do not depend on them."""
        return None

    def check_stop_time(self, stop_time: float) -> None:
        """Raise a :class:`ParameterError` if this component, started, cannot run until
        ``stop_time`` (the experiment's; default: any stop time is fine)."""

    def start(self, start_time: float) -> Dict[str, Any]:
        """Begin a run at ``start_time``: record it (it is part of the state) and
        :meth:`initialize`."""
        self.initial_time = float(start_time)
        outputs = self.initialize(self.initial_time)
        self.communication_time = self.initial_time
        return outputs

    # -- state (module docstring) ----------------------------------------------------------
    #: instance attributes that change while stepping (restored by set_state)
    state_fields: ClassVar[Tuple[str, ...]] = ("communication_time",)
    #: instance attributes rebuilt from the parameters by __init__ and initialize (the
    #: notices are transient: the caller collects them after every step)
    derived_fields: ClassVar[Tuple[str, ...]] = ("params", "initial_time", "notices")
    #: start time of a component initialized without :meth:`start`
    initial_time: float = 0.0
    #: end of the last step (the start time until the first one)
    communication_time: float = 0.0

    def get_state(self) -> Dict[str, Any]:
        """The state as plain data: ``{"params", "initial_time", "fields"}``."""
        return {"params": dict(self.params), "initial_time": float(self.initial_time),
                "fields": _state.capture(self, self.model_name or type(self).__name__)}

    @classmethod
    def from_state(cls, state: Any) -> "Component":
        """A component built from the saved parameters and started at the saved time, with
        the saved fields written into it.  Raises :class:`~navcore.errors.StateError` (or
        :class:`ParameterError` for unusable parameters) and builds nothing on any mismatch."""
        where = cls.model_name or cls.__name__
        if not (isinstance(state, dict) and set(state) == {"params", "initial_time", "fields"}):
            raise StateError(f"{where}: a component state has the keys params, "
                                    "initial_time and fields")
        params, start_time = state["params"], state["initial_time"]
        names = [p.name for p in cls.parameters]
        if not isinstance(params, dict) or sorted(params) != sorted(names):
            raise StateError(f"{where}: the state's parameters are not those of {where}")
        for port in cls.parameters:
            _state.check_kind(port.default(), params[port.name], f"{where}.{port.name}")
        if type(start_time) is not float or not math.isfinite(start_time):
            raise StateError(f"{where}: the state's start time is not a finite float")
        component = cls(**params)
        component.start(start_time)
        _state.restore(component, state["fields"], where)
        return component

    def advance(self, t: float, h: float, inputs: Dict[str, Any]) -> Dict[str, Any]:
        """:meth:`step` from ``t`` to ``t + h`` after checking that ``t`` is where the previous
        step ended and ``h > 0`` (:class:`RefusedCall` otherwise, nothing changed)."""
        if not h > 0:  # also NaN
            raise RefusedCall(f"{self.model_name}: communication step size {h} s at t = {t} s "
                              "must be > 0")
        expected = self.communication_time
        if not abs(t - expected) <= time_tolerance(h, expected):
            raise RefusedCall(
                f"{self.model_name}: doStep at t = {t!r} s but the previous step ended at "
                f"t = {expected!r} s; communication points must follow each other (restore "
                "an FMU state to go back)")
        outputs = self.step(t, h, inputs)
        self.communication_time = t + h
        return outputs

    def notify(self, message: str) -> None:
        """Queue a message for the user (logged by the caller as a warning)."""
        self.notices.append(message)

    def take_notices(self) -> List[str]:
        """The queued messages, oldest first; the queue is emptied."""
        notices, self.notices = self.notices, []
        return notices

    def set_state(self, state: Any) -> None:
        """Become the component of ``state`` (see :meth:`from_state`); unchanged on error."""
        restored = self.from_state(state)
        self.__dict__.clear()
        self.__dict__.update(restored.__dict__)
