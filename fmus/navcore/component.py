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
* ``step(t, h, inputs)`` advances from ``t`` to ``t + h`` with the input values (a dict
  name -> value, values as set by the connections at this communication point) and returns
  the outputs valid at ``t + h`` (a dict name -> value).  Bad input raises
  :class:`InputError` naming the variable.
* ``get_state()`` / ``set_state(state)`` return and restore the full internal state as a
  picklable object (default: the instance ``__dict__``, deep-copied).
"""
from __future__ import annotations

import copy
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Dict, Tuple


class NavcoreError(ValueError):
    """Base class of the errors a user can act on."""


class ParameterError(NavcoreError):
    """A parameter has an unusable value; the message names the parameter."""


class InputError(NavcoreError):
    """An input has an unusable value (NaN, inf, out of range); the message names it."""


@dataclass(frozen=True)
class Port:
    """One declared variable of a component.

    ``type`` is one of ``Real``, ``Integer``, ``Boolean``, ``String``; ``unit`` is the SI unit
    symbol written to the model description ("" for dimensionless or non-Real variables).
    """

    name: str
    type: str = "Real"
    unit: str = ""
    description: str = ""
    start: Any = 0.0

    def default(self):
        if self.type == "Real":
            return float(self.start)
        if self.type == "Integer":
            return int(self.start)
        if self.type == "Boolean":
            return bool(self.start)
        return str(self.start)


def real(name, unit="", description="", start=0.0):
    return Port(name, "Real", unit, description, start)


def integer(name, description="", start=0):
    return Port(name, "Integer", "", description, start)


def boolean(name, description="", start=False):
    return Port(name, "Boolean", "", description, start)


def string(name, description="", start=""):
    return Port(name, "String", "", description, start)


class Component(ABC):
    """Base class of the step-wise models wrapped by the FMUs (see module docstring)."""

    #: model name of the FMU wrapping this component
    model_name: ClassVar[str] = ""
    description: ClassVar[str] = ""
    parameters: ClassVar[Tuple[Port, ...]] = ()
    inputs: ClassVar[Tuple[Port, ...]] = ()
    outputs: ClassVar[Tuple[Port, ...]] = ()
    #: default experiment (start, stop, step) written to the model description
    default_experiment: ClassVar[Tuple[float, float, float]] = (0.0, 10.0, 0.01)

    def __init__(self, **params):
        self.params: Dict[str, Any] = {p.name: p.default() for p in self.parameters}
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

    def require_finite(self, *names: str) -> None:
        for n in names:
            v = self.params[n]
            if not math.isfinite(v):
                raise ParameterError(f"{self.model_name}: parameter '{n}' must be finite, got {v}")

    def require_nonnegative(self, *names: str) -> None:
        self.require_finite(*names)
        for n in names:
            if self.params[n] < 0:
                raise ParameterError(
                    f"{self.model_name}: parameter '{n}' must be >= 0, got {self.params[n]}"
                )

    def require_positive(self, *names: str) -> None:
        self.require_finite(*names)
        for n in names:
            if self.params[n] <= 0:
                raise ParameterError(
                    f"{self.model_name}: parameter '{n}' must be > 0, got {self.params[n]}"
                )

    def check_inputs_finite(self, inputs: Dict[str, Any], names) -> None:
        for n in names:
            v = inputs[n]
            if not math.isfinite(v):
                raise InputError(f"{self.model_name}: input '{n}' is {v} (must be finite)")

    # -- life cycle -------------------------------------------------------------------
    @abstractmethod
    def initialize(self, start_time: float) -> Dict[str, Any]:
        """Validate parameters, build the state, return the outputs at ``start_time``."""

    @abstractmethod
    def step(self, t: float, h: float, inputs: Dict[str, Any]) -> Dict[str, Any]:
        """Advance from ``t`` to ``t + h``; return the outputs valid at ``t + h``."""

    def get_state(self) -> Any:
        return copy.deepcopy(self.__dict__)

    def set_state(self, state: Any) -> None:
        self.__dict__.clear()
        self.__dict__.update(copy.deepcopy(state))

    # -- helpers ----------------------------------------------------------------------
    @classmethod
    def default_inputs(cls) -> Dict[str, Any]:
        return {p.name: p.default() for p in cls.inputs}
