"""The errors a user can act on: one hierarchy for navcore and the master.

Every error raised on purpose derives from :class:`NavfmuError`; its message says what is wrong
and names the file, component, variable or parameter.  navcore ships inside the FMUs and knows
nothing of the master, so the root lives here and ``orchestrator.errors`` derives the master's
errors (SSP files, wiring, simulation, tasks) from it.  The command line prints the message of a
:class:`NavfmuError` as ``navfmu: error: ...`` (no traceback); the FMU shell turns a
:class:`NavcoreError` into an FMI Error/Discard status with the message in the log.  Any other
exception is a bug.

::

    NavfmuError
      NavcoreError (also a ValueError: a bad argument of a navcore function)
        ParameterError      a parameter has an unusable value
          LogError          a sensor log breaks a rule of the format
        InputError          an input has an unusable value (NaN, inf, out of range)
          StepSizeError     the host's communication step does not fit the component
        DivergenceError     the state diverged (non-finite outputs, a numerical failure)
        RefusedCall         a call refused before anything changed
        StateError          a state cannot be taken or restored
        StateFormatError    a serialized state is refused
      the master's: SspError, WiringError, SimulationError (orchestrator.errors),
        TaskError (orchestrator.campaigns.executor), NativeBuildError
        (orchestrator.building.native_library)
"""
from __future__ import annotations


class NavfmuError(Exception):
    """Base class of every user-facing error; the message says what is wrong and where."""


class NavcoreError(NavfmuError, ValueError):
    """An error a navcore component or function raises for a user to act on."""


class ParameterError(NavcoreError):
    """A parameter has an unusable value; the message names the parameter."""


class LogError(ParameterError):
    """A sensor log breaks a rule of the format; the message names the file and line."""


class InputError(NavcoreError):
    """An input has an unusable value (NaN, inf, out of range); the message names it."""


class StepSizeError(InputError):
    """The host steps a component in a way it cannot follow (an IMU interval skipped or
    overlapping because the communication step is coarser than the sensor's period)."""


class DivergenceError(NavcoreError):
    """The component's state diverged: an output became non-finite or the arithmetic failed."""


class RefusedCall(NavcoreError):
    """A call the component refused before changing anything (a communication point that
    jumps, a step size <= 0): the caller may go on with a legal call."""


class StateError(NavcoreError):
    """A state cannot be taken or restored; the message names the field and the reason."""


class StateFormatError(NavcoreError):
    """A serialized state is refused; the message says why."""


def numerical_failure(exc: Exception) -> str:
    """The message for an arithmetic error (overflow, math domain) escaping a component's
    step: its state diverged, which declared ranges alone cannot rule out."""
    return (f"the computation failed numerically ({exc!r}): the state diverged; the inputs or "
            "parameters are outside what the component can follow")


__all__ = ["NavfmuError", "NavcoreError", "ParameterError", "LogError", "InputError",
           "StepSizeError", "DivergenceError", "RefusedCall", "StateError", "StateFormatError",
           "numerical_failure"]
