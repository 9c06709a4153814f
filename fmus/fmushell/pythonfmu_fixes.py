"""Workarounds for two defects of pythonfmu 0.7's native binary that corrupted the heap.

:func:`balance_loader_decref` gives back the reference to a slave script's globals that the
loader takes at every ``fmi2Instantiate``; :func:`finalize_python_at_exit` has the interpreter
torn down before the C++ static destructors run at process exit.
"""
from __future__ import annotations

import ctypes
import os
import sys


def balance_loader_decref(script_frame):
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


def finalize_python_at_exit(slave):
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
