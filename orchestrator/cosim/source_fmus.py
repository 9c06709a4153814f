"""Source FMUs: an FMU with C sources but no binary for this platform is compiled on first use.

Open-source Modelica compilers (Rumoca, OpenModelica's source export) and several C tools
ship *source FMUs*: ``sources/`` with the C code and its build description, no
``binaries/<platform>/``.  Before such an FMU is loaded, :func:`ensure_binary` puts a binary for
this platform into its unpacked folder, compiled by fmpy's CMake project (``fmpy.build``: the
same build as ``fmpy compile``) with CMake and the system C compiler.  FMI 2.0 and FMI 3.0
source FMUs compile the same way (fmpy reads both build descriptions; the binary goes to
``binaries/linux64`` or ``binaries/x86_64-linux`` as the version says).

The compiled library is cached, keyed on the FMU file's SHA-256 and the platform folder, in
``$NAVFMU_SOURCE_FMU_CACHE`` if set, else ``$XDG_CACHE_HOME/navfmu/source-fmus`` (by default
``~/.cache/navfmu/source-fmus``): an FMU is compiled once, a changed FMU again; deleting the
folder clears the cache.  A library is built in a ``.build-*`` folder there and moved into
place whole (a rename), so parallel runs compiling the same FMU leave one complete library.
Without CMake, a C compiler or ``make`` the FMU is refused in one line naming what is missing.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import List, Optional

from . import fmu_builds
from ..errors import NavfmuError

#: the environment variable naming the cache folder
CACHE_VARIABLE = "NAVFMU_SOURCE_FMU_CACHE"
#: how much of a failed build's output an error shows
OUTPUT_LINES_SHOWN = 15


def cache_root() -> Path:
    """The folder compiled source FMUs are cached in (see the module docstring)."""
    given = os.environ.get(CACHE_VARIABLE)
    if given:
        return Path(given)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "navfmu" / "source-fmus"


def platform_folder(fmi_version: str) -> str:
    """The ``binaries/`` folder of this platform for an FMU of ``fmi_version``."""
    import fmpy

    return fmpy.platform if fmi_version.startswith("2.") else fmpy.platform_tuple


def _model_identifier(md) -> str:
    interface = md.coSimulation or md.modelExchange
    return interface.modelIdentifier


def binary_member(md) -> str:
    """The path of this platform's binary inside the FMU of model description ``md``."""
    import fmpy

    return (f"binaries/{platform_folder(md.fmiVersion)}/"
            f"{_model_identifier(md)}{fmpy.sharedLibraryExtension}")


def missing_tools() -> List[str]:
    """The build tools not found on PATH: ``cmake``, a C compiler (``$CC`` or cc/gcc/clang),
    ``make`` (CMake's generator here)."""
    missing = []
    if not shutil.which("cmake"):
        missing.append("cmake")
    compilers = [os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"]
    if not any(shutil.which(c) for c in compilers):
        missing.append("a C compiler (" + (f"CC={compilers[0]}" if os.environ.get("CC")
                                           else "cc, gcc or clang") + ")")
    if not os.environ.get("CMAKE_GENERATOR") and not shutil.which("make"):
        missing.append("make")
    return missing


def ensure_binary(fmu: Path, md, unzipdir: Path, component: str) -> Optional[Path]:
    """Give the FMU ``fmu`` unpacked in ``unzipdir`` a binary for this platform if it has none
    but has ``sources/``: the cached library, compiled now if not cached.  Returns the cached
    library's path, or None when the FMU brought its own binary (or has no sources: loading it
    then fails with fmpy's message naming the missing library)."""
    member = binary_member(md)
    target = Path(unzipdir) / member
    if target.is_file() or not (Path(unzipdir) / "sources").is_dir():
        return None
    folder = platform_folder(md.fmiVersion)
    cached = cache_root() / f"{fmu_builds.file_sha256(fmu)[:32]}-{folder}" / target.name
    if not cached.is_file():
        _compile(fmu, md, cached, component)
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(cached, target)
    return cached


def _compile(fmu: Path, md, cached: Path, component: str) -> None:
    """Compile the source FMU ``fmu`` with fmpy's CMake project and move the library to
    ``cached``; a missing tool or a failed build raises a NavfmuError naming it."""
    head = (f"component '{component}': {fmu} is a source FMU (no binary for "
            f"{platform_folder(md.fmiVersion)})")
    missing = missing_tools()
    if missing:
        raise NavfmuError(f"{head}; compiling it needs {', '.join(missing)}, not found on "
                          f"PATH (install them, or use an FMU with a binary for this platform)")
    from fmpy import extract
    from fmpy.build import create_cmake_settings

    import fmpy

    try:
        cached.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise NavfmuError(f"{head}; cannot create the cache folder {cached.parent}: {exc} "
                          f"(set {CACHE_VARIABLE} to a writable folder)") from None
    with tempfile.TemporaryDirectory(dir=cached.parent, prefix=".build-") as tmp:
        unzipped, build = Path(tmp) / "fmu", Path(tmp) / "build"
        extract(str(fmu), str(unzipped))
        build.mkdir()
        try:
            create_cmake_settings(unzipped, build)
        except Exception as exc:  # fmpy raises plain exceptions for a bad build description
            raise NavfmuError(f"{head}; its build description cannot be read: {exc}") from None
        source = Path(fmpy.__file__).parent / "c-code"
        for command in (["cmake", "-S", str(source), "-B", str(build)],
                        ["cmake", "--build", str(build), "--target", "install",
                         "--config", "Release"]):
            done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True, errors="replace")
            if done.returncode != 0:
                tail = "\n  ".join(done.stdout.strip().splitlines()[-OUTPUT_LINES_SHOWN:])
                raise NavfmuError(f"{head}; compiling it failed ({' '.join(command[:2])} "
                                  f"exited with {done.returncode}):\n  {tail}")
        built = unzipped / binary_member(md)
        if not built.is_file():
            raise NavfmuError(f"{head}; its build made no {binary_member(md)}")
        os.replace(built, cached)


__all__ = ["CACHE_VARIABLE", "binary_member", "cache_root", "ensure_binary", "missing_tools",
           "platform_folder"]
