"""Workarounds for two defects of pythonfmu 0.7's native binary that corrupted the heap.

:func:`balance_loader_decref` gives back the reference to a slave script's globals that the
loader takes at every ``fmi2Instantiate``; :func:`finalize_python_at_exit` has the interpreter
torn down before the C++ static destructors run at process exit, by every pythonfmu binary
in the process (a third-party FMU's too).
"""
from __future__ import annotations

import atexit
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


#: the symbols by which a loaded shared object is known as a pythonfmu binary (any version,
#: ours or anyone's)
_PYTHONFMU_SYMBOLS = (b"finalizePythonInterpreter", b"fmi2Instantiate",
                      b"_ZN9pythonfmu14createInstanceENS_8fmu_dataE")
_RTLD_NOLOAD = getattr(os, "RTLD_NOLOAD", 0)
_RTLD_NODELETE = getattr(os, "RTLD_NODELETE", 0)


class _DlPhdrInfo(ctypes.Structure):
    """The head of glibc's ``struct dl_phdr_info`` (``<link.h>``), up to ``dlpi_adds``."""
    _fields_ = [("addr", ctypes.c_void_p), ("name", ctypes.c_char_p),
                ("phdr", ctypes.c_void_p), ("phnum", ctypes.c_uint16),
                ("adds", ctypes.c_ulonglong)]


_DL_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(_DlPhdrInfo), ctypes.c_size_t,
                                ctypes.c_void_p)


class PythonfmuExitHooks:
    """The pythonfmu binaries of this process whose ``finalizePythonInterpreter`` is
    registered to run first thing at ``exit()``.

    Also a ``sys.meta_path`` finder that finds nothing: consulted at every import of a module
    not yet loaded, it looks for binaries loaded since it last looked (pythonfmu's loader
    imports an FMU's script at its first ``fmi2Instantiate``, just after the host loaded the
    FMU's binary).  One per process: every copy of this module (one per FMU, built with
    private package names) shares the one it finds in ``sys.meta_path``.
    """

    #: marks the one instance in sys.meta_path (checked by name: copies of this module
    #: have classes of their own)
    navfmu_pythonfmu_exit_hooks = True

    def __init__(self):
        self.hooked = set()       # paths of the binaries whose hook is registered
        self.others = set()       # paths of loaded objects that are not pythonfmu binaries
        self.seen_adds = -1       # glibc's count of objects loaded when last looked
        self.busy = False
        self.closed = False       # Python's exit began: look no more
        self._libc = ctypes.CDLL(None)
        self._libc.dlopen.restype = ctypes.c_void_p
        self._libc.dlopen.argtypes = (ctypes.c_char_p, ctypes.c_int)
        self._libc.dlsym.restype = ctypes.c_void_p
        self._libc.dlsym.argtypes = (ctypes.c_void_p, ctypes.c_char_p)
        self._libc.dlclose.argtypes = (ctypes.c_void_p,)
        self._register = getattr(self._libc, "__cxa_atexit")  # (no name mangling)
        self._register.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        self._register.restype = ctypes.c_int

    def find_spec(self, name, path=None, target=None):
        """Find nothing; first hook the pythonfmu binaries loaded since the last look (not
        once Python's exit began: in a native host that is inside exit(), after the static
        destructors of binaries loaded after ours, which must not be reset again)."""
        if not self.closed and not sys.is_finalizing():
            self.hook_loaded()
        return None

    def close(self):
        """Look no more (an ``atexit`` function: Python's exit began)."""
        self.closed = True

    def hook_loaded(self):
        """Register the exit hook of every pythonfmu binary loaded and not yet hooked."""
        if self.busy:
            return
        self.busy = True
        try:
            for name in self._loaded_names():
                if name not in self.hooked and name not in self.others:
                    (self.hooked if self._hook(name) else self.others).add(name)
        finally:
            self.busy = False

    def _loaded_names(self):
        """The paths of the loaded shared objects, or nothing when none was loaded since the
        last call (glibc counts the loads: one callback tells)."""
        names, adds = [], []

        def visit(info, size, data):
            if not adds:
                adds.append(info.contents.adds)
                if adds[0] == self.seen_adds:
                    return 1
            if info.contents.name:
                names.append(info.contents.name)
            return 0

        self._libc.dl_iterate_phdr(_DL_CALLBACK(visit), None)
        self.seen_adds = adds[0] if adds else self.seen_adds
        return names

    def _hook(self, name):
        """Register ``name``'s ``finalizePythonInterpreter`` with ``__cxa_atexit`` if it is a
        pythonfmu binary, pinning it (RTLD_NODELETE) so the hook never outlives its code;
        any other object is let go again.  True when hooked."""
        handle = self._libc.dlopen(name, os.RTLD_LAZY | _RTLD_NOLOAD)
        if not handle:
            return False
        try:
            if not all(self._libc.dlsym(handle, s) for s in _PYTHONFMU_SYMBOLS):
                return False
            pinned = self._libc.dlopen(name, os.RTLD_LAZY | _RTLD_NOLOAD | _RTLD_NODELETE)
            finalize = pinned and self._libc.dlsym(pinned, _PYTHONFMU_SYMBOLS[0])
            return bool(finalize) and self._register(finalize, None, None) == 0
        finally:
            self._libc.dlclose(handle)

    @classmethod
    def installed(cls):
        """The process's instance, put at the head of ``sys.meta_path`` by the first caller."""
        for finder in sys.meta_path:
            if getattr(finder, "navfmu_pythonfmu_exit_hooks", False):
                return finder
        finder = cls()
        sys.meta_path.insert(0, finder)
        atexit.register(finder.close)
        return finder


def finalize_python_at_exit():
    """Have every pythonfmu binary of the process tear the interpreter down first thing at
    ``exit()``, not last, and never reset its interpreter owner twice.

    pythonfmu 0.7's binary (ours before the patch, anyone's built with pythonfmu) keeps its
    interpreter owner (``PyState``) in a C++ static ``shared_ptr`` and also resets that
    pointer from an ``__attribute__((destructor))`` (``PySlaveInstance.cpp``).  At ``exit()``
    the static destructors run first, in reverse order of loading: those of every C++
    extension module imported since (scipy's ``_uarray``), then the ``shared_ptr``'s, whose
    ``Py_FinalizeEx`` (in the binary that initialized the interpreter) then meets the already
    destroyed objects of those extensions; afterwards ``_dl_fini`` runs the destructor
    function, which resets the destroyed ``shared_ptr`` again: it decrements a count inside
    the freed 128-byte block of the ``PyState``, which, when glibc has put that block in a
    bin, is the block's ``bk`` link (glibc "corrupted double-linked list" or "corrupted
    unsorted chunks", at exit, intermittently, in Python hosts too).  Each binary has its own
    static owner, so a third-party pythonfmu FMU beside ours does this whatever our binary
    does.  Registering each binary's own ``finalizePythonInterpreter`` with ``__cxa_atexit``
    after the binary was loaded runs it before its static destructor: the interpreter ends
    while everything it uses is alive, and the later resets find an empty pointer.  This is
    done now for the binaries already loaded (a host that loaded another FMU before ours) and
    by :class:`PythonfmuExitHooks` for those loaded later.  Calling a binary's hook twice
    (two copies of this module) is harmless: the second reset finds the pointer empty.
    A binary loaded and instantiated without importing anything new after our last
    instantiation (a second copy of an FMU already instantiated) stays unhooked.
    """
    if not sys.platform.startswith("linux") or not _RTLD_NOLOAD:
        return
    try:
        PythonfmuExitHooks.installed().hook_loaded()
    except (OSError, AttributeError):
        return
