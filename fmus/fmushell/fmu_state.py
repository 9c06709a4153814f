"""FMU states: the declared data of an instance, taken, restored and serialized, never code.

A state holds the registered values and the component's declared state (:mod:`navcore.core.state`);
a blob is the checked plain-data format of :mod:`navcore.core.state_format`, stamped with the FMU's
identity (model name and the hash of its Python sources).
"""
from __future__ import annotations

import json
from pathlib import Path

from pythonfmu.enums import Fmi2Status

from navcore.core import state_format
from navcore.errors import NavcoreError, StateError, StateFormatError
from navcore.core.state import capture_value, check_kind

from .refusals import FmiCallRefused, refusals_return_error


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

    @property
    def fmi2_phase(self):
        """The state of FMI's state machine the instance is in once this state is restored,
        for a state the patched library deserialized (it records the phase of a state it
        took itself): ``error`` after a failure, ``stepComplete`` once the component started,
        else ``instantiated``."""
        if self.tree.get("failed") is not None:
            return "error"
        return "stepComplete" if self.tree.get("component") is not None else "instantiated"

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


def fmu_identity(slave_class):
    """(model name, hash of the FMU's Python sources): which FMU wrote a state."""
    identity = _IDENTITIES.get(slave_class)
    if identity is None:
        # the file the class's own __init__ was compiled from (every FMU script defines one):
        # sys.modules may still hold a module of the same name loaded from another FMU's
        # folder, since deleted (an FMU loaded in this process before this one was built)
        script = Path(slave_class.__init__.__code__.co_filename)
        identity = (slave_class.__name__, _build_of(script))
        _IDENTITIES[slave_class] = identity
    return identity


def _build_of(script: Path) -> str:
    """The build hash of the FMU whose slave script is ``script``: the one its build recorded
    (a built FMU's packages have private names, so their folders are not the ones hashed), else
    the hash of the sources beside the script (a slave run from the source tree)."""
    recorded = script.parent / state_format.BUILD_FILE
    if recorded.is_file():
        return json.loads(recorded.read_text(encoding="utf-8"))["build"]
    return state_format.build_hash(script)


def get_fmu_state(slave):
    try:
        component = slave._component
        tree = {"values": capture_value(slave._values, "values"), "failed": slave._failed,
                "start_time": slave._start_time,
                "component": (None if component is None or slave._failed is not None
                              else component.get_state())}
        return FmuState(fmu_identity(type(slave)), tree)
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
    except NavcoreError as exc:   # StateError and StateFormatError among them
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
    if state.identity != fmu_identity(type(slave)):
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


def fmu_state_to_bytes(state):
    try:
        return state.to_bytes()
    except Exception:  # a RefusedState or a foreign object: nothing to write
        return b""


def fmu_state_from_bytes(slave_class, blob, refusal_returns_error=False):
    """The state in ``blob``.  The patched library passes ``refusal_returns_error`` (the
    class, shared by every FMU of this script loaded in the process, cannot tell)."""
    try:
        identity = fmu_identity(slave_class)
        return FmuState(identity, state_format.decode(blob, identity))
    except StateFormatError as exc:
        reason = str(exc)
    except Exception as exc:
        reason = f"the blob could not be read: {exc!r}"
    if refusal_returns_error is True:
        raise FmiCallRefused(f"fmi2DeSerializeFMUstate refused the blob: {reason}")
    return RefusedState(reason)
