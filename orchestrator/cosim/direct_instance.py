"""The direct backend: a plain Python component (the ``navcore.core.component.Component``
contract) stepped without FMI behind :class:`~orchestrator.cosim.backends.Instance`."""
from __future__ import annotations

import itertools
import operator
from typing import Any, Dict, Mapping, Optional, Sequence

import numpy as np

from navcore import __version__ as navfmu_version
from navcore.errors import NavcoreError, numerical_failure

from .backends import Instance, VarInfo, coerce
from ..errors import NavfmuError, SimulationError


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


def _without_model(model_name: str, exc: Exception) -> str:
    """A component's message without its leading ``"<model name>: "``."""
    text = str(exc)
    prefix = f"{model_name}: "
    return text[len(prefix):] if text.startswith(prefix) else text


def parameter_error(name: str, model_name: str, exc: Exception) -> NavfmuError:
    """A parameter value component ``name`` refused, naming the component."""
    return NavfmuError(f"component '{name}' ({model_name}): {_without_model(model_name, exc)}")


def simulation_error(name: str, model_name: str, what: str, exc: Exception,
                     time: Optional[float], at: bool = True) -> SimulationError:
    """Same shape as :meth:`FmuInstance._fail`: the component's message first, the failed
    call (``what``, at ``time`` when ``at``) on the next line."""
    when = f" at t = {time:.9g} s" if time is not None and at else ""
    if isinstance(exc, NavcoreError):
        text = _without_model(model_name, exc)
    else:                                  # an arithmetic error: the state diverged
        text = numerical_failure(exc)
    return SimulationError(f"component '{name}' ({model_name}): {text}\n"
                           f"  ({what} failed{when})", component=name, time=time,
                           log=(str(exc),))


class DirectInstance(Instance):
    """A Python object following the ``navcore.core.component.Component`` contract, stepped
    directly (no FMI): class attributes ``parameters``/``inputs``/``outputs`` (tuples of
    ``Port``), ``set_parameter(name, value)``, ``start(start_time) -> outputs`` (or
    ``initialize``), ``step(t, h, inputs) -> outputs``, ``get_state()``/``set_state()`` (the
    component's declared state as plain data, :mod:`navcore.core.state`).

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
        self.build_info = {"model": self.model_name,
                           "python_class": f"{cls.__module__}.{cls.__qualname__}",
                           "navfmu_version": navfmu_version}
        self.variables = {}
        ref = itertools.count()
        for causality, ports in (("parameter", getattr(cls, "parameters", ())),
                                 ("input", getattr(cls, "inputs", ())),
                                 ("output", getattr(cls, "outputs", ()))):
            for p in ports:
                self.variables[p.name] = VarInfo(p.name, p.type, causality, p.unit, next(ref))
        self._inputs: Dict[str, Any] = {p.name: p.default() for p in getattr(cls, "inputs", ())}
        self._outputs: Dict[str, Any] = {p.name: p.default() for p in getattr(cls, "outputs", ())}
        self._errors = (NavcoreError,)
        self._advance = getattr(component, "advance", None) or component.step
        self.time: Optional[float] = None

    @classmethod
    def from_registry(
        cls, model_name: str, name: str, registry: Mapping[str, type]
    ) -> "DirectInstance":
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
        return simulation_error(self.name, self.model_name, what, exc, time, at)

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
            value = coerce(self.name, var, value, self.source)
            if var.causality == "input":
                self._inputs[name] = value
                continue
            try:
                self.component.set_parameter(name, value)
            except self._errors as exc:
                raise parameter_error(self.name, self.model_name, exc) from None

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
        take = getattr(self.component, "initial_inputs", None)
        if take is None:
            return
        try:
            outputs = take(dict(self._inputs))
        except self._errors as exc:
            raise self._error("initialization", exc, self.time) from None
        if outputs is not None:
            self._store_outputs(outputs, "initial_inputs")

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
            outputs = self._advance(t, h, self._inputs)
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

    def take_warnings(self):
        return [f"{self.name}: {notice}" for notice in self.component.take_notices()]

    def terminate(self) -> None:
        hook = getattr(self.component, "terminate", None)
        if callable(hook):
            hook()


__all__ = ["DirectInstance", "parameter_error", "simulation_error"]
