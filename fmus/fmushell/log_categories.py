"""The FMU's log categories: every message names one of them, never none.

A host may build a string from the category of every logger call (OMSimulator does, and a
NULL category aborts it), so each message carries one declared in the model description's
``LogCategories``: an explicit one of :data:`LOG_CATEGORIES`, else its status's.  The patched
pythonfmu library does the same for the messages it writes itself, and reports messages of
status Warning or worse whatever ``loggingOn`` says (``native/vendor/pythonfmu-export``).
"""
from __future__ import annotations

from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Status

#: name -> description, as written into the model description
LOG_CATEGORIES = {
    "logEvents": "messages of status OK (debug logging: reported only with loggingOn or the "
                 "categories chosen with fmi2SetDebugLogging)",
    "logStatusWarning": "warnings: a component's notices, e.g. a fix applied late or a "
                        "filter's statistics out of bounds (always reported)",
    "logStatusDiscard": "messages of status Discard (always reported)",
    "logStatusError": "errors: a refused call, parameter or input, an instance's first error "
                      "(always reported)",
    "logStatusFatal": "fatal errors: an instance that could not be created (always reported)",
    "traceback": "the Python traceback that follows an internal error, status Error "
                 "(always reported)",
}

_BY_STATUS = {Fmi2Status.warning: "logStatusWarning", Fmi2Status.discard: "logStatusDiscard",
              Fmi2Status.error: "logStatusError", Fmi2Status.fatal: "logStatusFatal"}


def category_of(status, category=None) -> str:
    """``category`` if it is declared, else the category of ``status``."""
    if category in LOG_CATEGORIES:
        return category
    return _BY_STATUS.get(status, "logEvents")


def log(slave, msg, status=Fmi2Status.ok, category=None, debug=None):
    """pythonfmu's ``Fmi2Slave.log`` with the message's category from :func:`category_of`."""
    Fmi2Slave.log(slave, msg, status, category_of(status, category))
