"""The one instance interface the master steps, shared by both backends: FMUs through fmpy
(:mod:`orchestrator.cosim.fmu_instance`) and plain Python components
(:mod:`orchestrator.cosim.direct_instance`); the variable description and the parameter coercion
they share.

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

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from ..errors import NavfmuError, WiringError

NUMERIC_TYPES = ("Real", "Integer", "Boolean")


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


#: the range of an FMI 2.0 Integer (fmi2Integer is a C int, 32 bits): a value outside it is
#: refused before any conversion (ctypes and numpy would wrap it silently)
FMI_INTEGER_MIN, FMI_INTEGER_MAX = -2 ** 31, 2 ** 31 - 1


def coerce(comp: str, var: VarInfo, value: Any, source: str) -> Any:
    """Convert a parameter value to the variable's type, or raise a NavfmuError naming it."""
    try:
        if var.type == "Real":
            if isinstance(value, bool):
                raise TypeError
            return float(value)
        if var.type in ("Integer", "Enumeration"):
            if isinstance(value, bool) or (isinstance(value, float) and not value.is_integer()):
                raise TypeError
            number = int(value)
            if not FMI_INTEGER_MIN <= number <= FMI_INTEGER_MAX:
                raise NavfmuError(
                    f"component '{comp}' ({source}): parameter '{var.name}' = {value!r} does "
                    f"not fit an FMI Integer (32 bits: {FMI_INTEGER_MIN} .. {FMI_INTEGER_MAX})")
            return number
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
            f"component '{comp}' ({source}): parameter '{var.name}' is "
            f"{'an' if var.type[0] in 'IE' else 'a'} {var.type}, got {value!r}"
        ) from None


class Instance(ABC):
    """Base class: the uniform interface the master uses (see module docstring)."""

    name: str
    #: what the instance runs, for messages (FMU path or class name)
    source: str
    #: which code runs, for the results (an FMU's file, content hash and build:
    #: :mod:`orchestrator.cosim.fmu_builds`; a Python component's class)
    build_info: Dict[str, Any] = {}
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

    def names_by_type(
        self, names: Sequence[str], causalities: Iterable[str]
    ) -> Dict[str, Tuple[str, ...]]:
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

    def take_warnings(self) -> List[str]:
        """The warnings the component reported since the last call (an FMU's log messages of
        status Warning, a navcore component's notices), each ``"<instance>: <text>"``."""
        return []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.terminate()
        return False


__all__ = ["Instance", "VarInfo", "NUMERIC_TYPES", "coerce"]
