"""Compiled kernels: the one decorator of every navcore function numba compiles.

A kernel is a plain Python function on floats, tuples and numpy arrays that numba compiles to
machine code (``nopython`` mode).  The per-sample float arithmetic of the mechanization runs
as kernels over a leading *run axis*: row ``b`` of every array argument is run ``b`` of a batch,
and a single run is a batch of one, so a run alone and a run inside a batch execute the same
compiled code on the same floats.  numba compiles IEEE double arithmetic as written: without
``fastmath`` no multiply-add is fused and nothing is reassociated, and ``math.sin``/``cos``/
``sqrt``/``atan2`` call the same C library as CPython, so a kernel gives the floats the
interpreted function gives, bit for bit (the tests of each kernel check it on the interpreted
function, :attr:`py_func` of the kernel, which *is* the same source).  One exception: a
compiled ``x ** 2`` is ``x * x``, CPython's is ``pow(x, 2.0)``, and the two round apart about
once in a thousand; kernels write squares as ``x * x``.

Compiling costs a few seconds per process (4.4 s for all kernels); the machine code is
therefore cached on disk, in ``$NAVFMU_KERNEL_CACHE`` or else the user's cache folder
(``$XDG_CACHE_HOME/navfmu/kernels``, by default ``~/.cache/navfmu/kernels``).  The cache is
keyed by the *content* of every navcore source file, not by its path: an FMU unpacks navcore
into a new temporary folder at every instantiation, and numba's own cache (keyed by path and
modification time) would compile again every time.  A change to any navcore file starts a
new cache entry; the :data:`KEEP_ENTRIES` most recently used entries are kept.  When no
cache folder is writable, kernels compile in memory (slower to start, same numbers).

A helper a kernel calls is marked :func:`jitable`: it stays a plain Python function for its
other callers (the interpreted code of the trajectory and the sensors) and is compiled into
the kernels that call it, so each formula has one definition.

``NUMBA_DISABLE_JIT=1`` (numba's own switch) runs every kernel as the interpreted function:
the same numbers, slower; mutation testing and coverage use it.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from pathlib import Path
from typing import Optional

import numba
from numba.core import caching
from numba.extending import register_jitable

#: environment variable naming the kernel cache folder ("" or "0": no disk cache)
CACHE_ENV = "NAVFMU_KERNEL_CACHE"
#: cache entries (navcore contents) kept in the folder; older ones are removed
KEEP_ENTRIES = 8
_PACKAGE = Path(__file__).resolve().parents[1]      # the navcore folder (in a checkout or FMU)


def _content_key() -> str:
    """sha256 (first 20 hex digits) over the names and bytes of every navcore source file."""
    h = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        h.update(path.relative_to(_PACKAGE).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:20]


def _cache_root() -> Optional[Path]:
    """The writable folder of this navcore's kernel cache, or None."""
    given = os.environ.get(CACHE_ENV)
    if given is not None and given.strip() in ("", "0"):
        return None
    if given:
        base = Path(given)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        base = Path(xdg) / "navfmu" / "kernels"
    root = base / f"navcore-{_content_key()}"
    try:
        root.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=root).close()
        os.utime(root)
    except OSError:
        return None
    _prune(base)
    return root


def _prune(base: Path) -> None:
    """Remove all but the :data:`KEEP_ENTRIES` most recently used entries of ``base``."""
    try:
        entries = sorted(base.glob("navcore-*"), key=lambda p: p.stat().st_mtime, reverse=True)
        for old in entries[KEEP_ENTRIES:]:
            shutil.rmtree(old, ignore_errors=True)
    except OSError:
        pass                     # another process pruning at the same time


_ROOT = _cache_root()
def _in_package(py_file) -> Optional[Path]:
    """The path of ``py_file`` inside this navcore package, or None.  Matched on the package's
    folder name, not its place: in a built FMU the package's later modules may be imported from
    another FMU's copy of the same build (``fmushell.private_paths``), the same content in
    another folder."""
    parts = Path(py_file).resolve().parts
    if _PACKAGE.name not in parts:
        return None
    last = len(parts) - 1 - parts[::-1].index(_PACKAGE.name)
    if last + 1 >= len(parts):
        return None
    relative = Path(*parts[last + 1:])
    try:           # the same content as this package's own file, or not this package's
        same = Path(py_file).read_bytes() == (_PACKAGE / relative).read_bytes()
    except OSError:
        return None
    return relative if same else None


# public names since numba 0.59 or so, underscored before
_LOCATOR_BASE = getattr(caching, "UserProvidedCacheLocator", None) or getattr(
    caching, "_UserProvidedCacheLocator")
_CACHE_IMPL = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")


class _ContentCacheLocator(_LOCATOR_BASE):
    """numba cache locator for navcore's files: one folder per navcore content (any path)."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        relative = _in_package(py_file)
        self._cache_path = str(_ROOT / "_".join(relative.with_suffix("").parts))

    def get_source_stamp(self):
        return _ROOT.name        # the content key: the same navcore gives the same stamp

    @classmethod
    def from_function(cls, py_func, py_file):
        if _ROOT is None:
            return None
        if _in_package(py_file) is None:
            return None
        locator = cls(py_func, py_file)
        try:
            locator.ensure_cache_path()
        except OSError:
            return None
        return locator


if _ContentCacheLocator not in _CACHE_IMPL._locator_classes:
    _CACHE_IMPL._locator_classes.insert(0, _ContentCacheLocator)


def kernel(function):
    """Compile ``function`` as a navcore kernel (numba ``njit``, cached when a folder is)."""
    return numba.njit(cache=_ROOT is not None, nogil=True)(function)


def jitable(function):
    """Let kernels call ``function``, which stays the plain Python function for every other
    caller (numba's ``register_jitable``: compiled into each kernel that calls it).  It must
    then be written for numba too: floats, tuples and arrays, no lists it unpacks."""
    return register_jitable(function)


__all__ = ["CACHE_ENV", "jitable", "kernel"]
