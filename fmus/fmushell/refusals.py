"""How a refused FMI call is reported, which depends on the FMU's binary.

Where the binary is the patched pythonfmu library (``native/vendor/pythonfmu-export``, the Linux
binary of every FMU built where a C++ compiler is found; :func:`refusals_return_error`), a
refused call raises :class:`FmiCallRefused`: the call returns fmi2Error with its message logged
at fmi2Error, and the instance stays usable.  pythonfmu's own library (Windows, macOS, no
compiler) turns a Python exception in *any* call into fmi2Fatal and releases the Python
instance, so the host's next call on it reads freed memory; there nothing may raise: a refused
doStep (a refused input among them) returns fmi2Discard, a refused get/set returns fmi2OK with
the fmi2Error message in the log (a get NaN / 0 / false / "" for the bad references) and the
next doStep is refused once, a
refused initialization makes every doStep fmi2Discard.
"""
from __future__ import annotations

from pythonfmu.enums import Fmi2Status


class FmiCallRefused(Exception):
    """A refused FMI call.  The patched pythonfmu library (``native/vendor/pythonfmu-export``)
    recognizes it by ``fmi2_status``, logs its message at fmi2Error, returns fmi2Error and
    keeps the instance; pythonfmu's own library would return fmi2Fatal and drop the
    instance, so it is raised only where :func:`refusals_return_error` is true.

    ``instance_failed`` says that the instance cannot go on (its component failed: an input
    or parameter it refuses, a diverged state): the library then puts it into FMI's error
    state, where only fmi2Reset, fmi2SetFMUstate, the get and state calls and
    fmi2FreeInstance are allowed.  Without it the refused call changed nothing and the
    instance goes on with a legal call."""

    fmi2_status = "error"

    def __init__(self, message, instance_failed=False):
        super().__init__(message)
        self.instance_failed = instance_failed


def refusals_return_error(slave) -> bool:
    """True if the instance's binary is the patched library: it marks each instance it
    creates (not the class: the FMUs of one script share it, whatever their binary)."""
    return getattr(slave, "fmi2_error_on_refused_call", False) is True


def refuse(slave, message, later=True):
    """Refuse the current call: fmi2Error with ``message`` where the binary allows it;
    else log it at Error and (``later``, for a get/set) have the next do_step refused once."""
    text = f"{slave.instance_name}: {message}"
    if refusals_return_error(slave):
        raise FmiCallRefused(text)
    if later:
        slave._refused = message
    slave.log(text, Fmi2Status.error)
