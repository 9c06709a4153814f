"""The environment a native (non-Python) FMI host needs to load our FMUs (``navfmu env``).

A pythonfmu FMU's binary embeds the Python interpreter without linking to it (its ``.so`` has
no NEEDED entry for libpython) and runs the slave script with the Python packages of the
machine.  A host process that is not Python therefore needs, on Linux:

* ``LD_PRELOAD``: this interpreter's shared library (``sysconfig`` ``LIBDIR`` and
  ``INSTSONAME``/``LDLIBRARY``), so the FMU binary finds the Python C API;
* ``PYTHONHOME``: ``sys.base_prefix``, where the standard library and ``lib-dynload`` live;
* ``PYTHONPATH``: the ``site-packages`` folders holding the packages the FMUs import beyond
  the standard library (numpy, scipy, numba and its llvmlite; pythonfmu's Python side and
  navcore travel inside every FMU under ``resources/``).

Only Linux hosts are covered (and tested, ``tests/test_chost.py``); README "Use in your
simulator" says what is known for Windows.
"""
from __future__ import annotations

import importlib.util
import json
import os
import shlex
import sys
import sysconfig
from pathlib import Path

from ..errors import NavfmuError

#: packages outside the standard library that the FMUs' scripts import at run time
RUNTIME_PACKAGES = ("numpy", "scipy", "numba", "llvmlite")


def libpython() -> Path:
    """The shared library of this interpreter, as a native host must preload it."""
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    names = [sysconfig.get_config_var(k) for k in ("INSTSONAME", "LDLIBRARY")]
    for name in filter(None, names):
        path = Path(libdir) / name
        if ".so" in name and path.is_file():
            return path
    raise NavfmuError(
        f"{sys.executable} has no shared libpython (looked for {', '.join(filter(None, names))} "
        f"in {libdir or 'an empty LIBDIR'}): a native FMI host cannot embed this Python; use an "
        "interpreter built with --enable-shared (pyenv: PYTHON_CONFIGURE_OPTS=--enable-shared)")


def package_dirs(packages=RUNTIME_PACKAGES) -> list[str]:
    """The folders (site-packages) that hold ``packages``, each once, in the given order."""
    dirs = []
    for name in packages:
        spec = importlib.util.find_spec(name)
        if spec is None or not spec.submodule_search_locations:
            raise NavfmuError(f"package {name!r}, which the FMUs import, is not installed "
                              f"for {sys.executable}")
        folder = str(Path(next(iter(spec.submodule_search_locations))).resolve().parent)
        if folder not in dirs:
            dirs.append(folder)
    return dirs


def host_environment() -> dict[str, str]:
    """Variable -> value for a native host on this machine (Linux only)."""
    if not sys.platform.startswith("linux"):
        raise NavfmuError(f"navfmu env supports Linux hosts only (this is {sys.platform}); "
                          "see README, 'Use in your simulator', for what is known elsewhere")
    return {
        "LD_PRELOAD": str(libpython()),
        "PYTHONHOME": sys.base_prefix,
        "PYTHONPATH": os.pathsep.join(package_dirs()),
    }


def render(env: dict[str, str], fmt: str = "sh") -> str:
    """``export VAR=value`` lines (``sh``, for ``eval "$(navfmu env)"``) or a JSON object."""
    if fmt == "json":
        return json.dumps(env, indent=2)
    if fmt != "sh":
        raise NavfmuError(f"--format: expected 'sh' or 'json', got {fmt!r}")
    return "\n".join(f"export {name}={shlex.quote(value)}" for name, value in env.items())
