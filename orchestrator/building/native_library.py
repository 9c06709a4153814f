"""The FMUs' Linux binary: pythonfmu's export library with navfmu's patch, built here.

pythonfmu 0.7.0's library answers every Python exception of an FMI call with fmi2Fatal and
drops the instance, so a refused call (an unknown value reference, a foreign FMU state) could
not return fmi2Error.  ``native/vendor/pythonfmu-export/`` holds its C++ sources with a small patch
(listed in the README there): an exception whose class has ``fmi2_status = "error"``
(``fmushell.FmiCallRefused``) returns fmi2Error and leaves the instance usable.

This module compiles those sources with CMake and the system C++ compiler against this
interpreter's headers, caches the library in ``fmus/dist/native/<key>/`` (the key hashes the
sources, the Python version and the platform) and puts it into a built FMU in place of the
wheel's ``binaries/linux64`` library.  Without a compiler or CMake, or off Linux, the FMUs keep
the wheel's library (its refused calls report as before: see fmushell), as they do with
``NAVFMU_PYTHONFMU_LIBRARY=wheel``; the Windows and macOS binaries are always the wheel's.
"""
from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import zipfile
from pathlib import Path
from typing import Optional

from ..errors import NavfmuError
from ..results.run_results import atomic_write

ROOT = Path(__file__).resolve().parents[2]
SOURCES = ROOT / "native" / "vendor" / "pythonfmu-export"
CACHE = ROOT / "fmus" / "dist" / "native"
LIBRARY_NAME = "libpythonfmu-export.so"
#: the pythonfmu release whose C++ sources are vendored (its Python side calls them)
UPSTREAM_VERSION = "0.7."
#: the attribute the patched library sets on each slave instance (fmushell.refusals_return_error)
MARKER = b"fmi2_error_on_refused_call"
#: where FmuBuilder puts the Linux library inside an FMU
MEMBER_DIR = "binaries/linux64"


#: set to "wheel" to build the FMUs with pythonfmu's own library
CHOICE_VARIABLE = "NAVFMU_PYTHONFMU_LIBRARY"


def sources_hash() -> str:
    """SHA-256 of the vendored library's build inputs (CMakeLists.txt and src/)."""
    h = hashlib.sha256()
    files = [SOURCES / "CMakeLists.txt", *(p for p in (SOURCES / "src").rglob("*") if p.is_file())]
    for f in sorted(files):
        h.update(f.relative_to(SOURCES).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def cache_key() -> str:
    """The cache folder's name: sources, Python version and platform."""
    tag = f"{sys.implementation.cache_tag}-{sys.platform}-{platform.machine()}"
    return f"{tag}-{hashlib.sha256((sources_hash() + tag).encode()).hexdigest()[:16]}"


def cached_library() -> Path:
    return CACHE / cache_key() / LIBRARY_NAME


def _cmake() -> Optional[str]:
    found = shutil.which("cmake")
    if found:
        return found
    try:  # the cmake distribution from PyPI, when its script is not on PATH
        import cmake

        candidate = Path(cmake.CMAKE_BIN_DIR) / "cmake"
        return str(candidate) if candidate.is_file() else None
    except (ImportError, AttributeError):
        return None


def _compiler() -> Optional[str]:
    names = [os.environ["CXX"]] if os.environ.get("CXX") else ["c++", "g++", "clang++"]
    return next((shutil.which(n) for n in names if shutil.which(n)), None)


def unavailable_reason() -> Optional[str]:
    """Why the patched library cannot be used on this machine, or None."""
    if os.environ.get(CHOICE_VARIABLE, "") == "wheel":
        return f"{CHOICE_VARIABLE}=wheel is set"
    if cached_library().is_file():
        return None
    if not sys.platform.startswith("linux"):
        return f"no patched pythonfmu library for {sys.platform} (Linux only)"
    try:
        from pythonfmu import __version__ as pythonfmu_version
    except ImportError:
        return "pythonfmu is not installed"
    if not pythonfmu_version.startswith(UPSTREAM_VERSION):
        return (f"the patched library is pythonfmu {UPSTREAM_VERSION}x's; pythonfmu "
                f"{pythonfmu_version} is installed")
    if _cmake() is None:
        return "CMake not found (pip install cmake)"
    if _compiler() is None:
        return "no C++ compiler found (c++, g++, clang++ or $CXX)"
    return None


def fallback_note(reason: str) -> str:
    """The one line a build prints when the FMUs keep the wheel's library."""
    return (f"note: {reason}: the FMUs keep pythonfmu's own library, so a refused FMI call "
            "reports fmi2OK with an Error message and fmi2Discard at the next doStep instead "
            "of fmi2Error")


def build_library() -> Path:
    """Compile the patched library (always) and return it; raises NativeBuildError."""
    cmake, compiler = _cmake(), _compiler()
    if cmake is None or compiler is None:
        raise NativeBuildError(unavailable_reason() or "CMake or C++ compiler missing")
    with tempfile.TemporaryDirectory(prefix="navfmu_native_") as tmp:
        work = Path(tmp)
        configure = [cmake, "-S", str(SOURCES), "-B", str(work), "-DCMAKE_BUILD_TYPE=Release",
                     f"-DCMAKE_CXX_COMPILER={compiler}",
                     f"-DPython3_INCLUDE_DIR={sysconfig.get_paths()['include']}"]
        for command in (configure, [cmake, "--build", str(work)]):
            proc = subprocess.run(command, capture_output=True, text=True)
            if proc.returncode != 0:
                lines = (proc.stderr.strip() or proc.stdout.strip()).splitlines()
                raise NativeBuildError(f"building {SOURCES.name} failed: "
                                       f"{lines[-1] if lines else 'no message'}")
        built = work / LIBRARY_NAME
        target = cached_library()
        target.parent.mkdir(parents=True, exist_ok=True)
        with open(built, "rb") as src:
            atomic_write(target, lambda f: shutil.copyfileobj(src, f), binary=True)
    return target


def library() -> Path:
    """The cached patched library, built when missing (raises NativeBuildError)."""
    cached = cached_library()
    return cached if cached.is_file() else build_library()


def replace_in_fmu(fmu: Path, model: str, lib: Path) -> None:
    """Put ``lib`` into ``fmu`` as its Linux binary, in place of the one FmuBuilder copied."""
    member = f"{MEMBER_DIR}/{model}.so"
    fd, partial = tempfile.mkstemp(dir=fmu.parent, prefix=f".{fmu.stem}.", suffix=".zip")
    os.close(fd)
    try:
        with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(partial, "w") as dst:
            for info in src.infolist():
                if info.filename != member:
                    dst.writestr(info, src.read(info))
            dst.write(lib, member)
        os.replace(partial, fmu)
    finally:
        if os.path.exists(partial):
            os.remove(partial)


def fmu_has_patched_library(fmu: Path) -> bool:
    """True if the FMU's Linux binary is the patched library (it carries the patch's marker
    attribute name, which pythonfmu's own library does not)."""
    with zipfile.ZipFile(fmu) as z:
        member = f"{MEMBER_DIR}/{Path(fmu).stem}.so"
        return member in z.namelist() and MARKER in z.read(member)


class NativeBuildError(NavfmuError):
    """The patched library could not be built."""
