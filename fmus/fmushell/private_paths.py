"""Keep the packages of this FMU build importable, and never shared with other code.

A built FMU ships its packages under names private to its build (``navcore_<hash>``, ...:
``orchestrator.building.private_names``), so FMUs of other builds never share them.  The FMUs of
one build do share them: the first one imported them from its own unpacked folder, which its
host may delete when that FMU is freed, and a module imported later (another FMU's component)
is looked up through the packages' ``__path__`` in that folder.  :func:`adopt_folder` puts the
current FMU's folder first on the ``__path__`` of every package of the build already imported
(and drops folders that are gone); the slave script calls it before its imports and
:func:`fmushell.setup` at every instantiation.

It first checks that the current FMU's copy of the code is the one already imported: an FMU
whose Python files were changed after its build keeps its build's names, and would otherwise
run the other FMU's code without a word.  Such an FMU is refused (:class:`CodeConflict`, which
its host reports as a failed instantiation); navfmu's own master gives a changed FMU names of
its own before it loads it.  Outside a built FMU (the shell run from the source tree) nothing
is done.
"""
from __future__ import annotations

import hashlib
import os
import sys

from navcore.core.state_format import packed_content_hash

_SHELL = __name__.split(".")[0]                  # "fmushell" or "fmushell_<suffix>"
_SUFFIX = _SHELL[len("fmushell"):]               # "" outside a built FMU
_PACKAGES = tuple(f"{p}{_SUFFIX}" for p in ("fmushell", "navcore", "pythonfmu"))
#: the resources folder this build's packages were imported from
_FOLDER = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_CONTENTS = {}                                   # folder -> packed_content_hash of its packages
#: the script's global recording the hash of the script file its module was imported from
SCRIPT_HASH = "_navfmu_script_sha256"


class CodeConflict(ImportError):
    """This FMU's Python code differs from the code of the same names already imported."""


def packages_content(folder: str) -> str:
    """packed_content_hash of the build's packages in the resources ``folder`` (cached)."""
    content = _CONTENTS.get(folder)
    if content is None:
        files = []
        for package in _PACKAGES:
            root = os.path.join(folder, package)
            for directory, subdirs, names in os.walk(root):
                subdirs[:] = [d for d in subdirs if d != "__pycache__"]
                for name in names:
                    if name.endswith(".py"):
                        path = os.path.join(directory, name)
                        with open(path, "rb") as f:
                            files.append((os.path.relpath(path, folder).replace(os.sep, "/"),
                                          f.read()))
        content = _CONTENTS[folder] = packed_content_hash(files)
    return content


def _conflict(what: str, folder: str, other: str) -> CodeConflict:
    return CodeConflict(
        f"the Python code of this FMU ({what} in {folder}) differs from the code of the same "
        f"build already loaded in this process (from {other}): the FMU was changed after it "
        f"was built, and two FMUs cannot share one module name with different code; run it in "
        f"a process of its own, rebuild it, or run it with navfmu, which gives a changed FMU "
        f"names of its own")


def adopt_folder(folder: str, script_globals=None) -> None:
    """Check that the FMU unpacked in the resources ``folder`` carries the imported code (its
    packages, and the script of ``script_globals`` when given), then make ``folder`` the first
    place the build's imported packages are searched."""
    if not _SUFFIX:
        return
    folder = os.path.abspath(folder)
    if packages_content(folder) != packages_content(_FOLDER):
        raise _conflict("its packages", folder, _FOLDER)
    if script_globals is not None:
        script = os.path.join(folder, f"{script_globals['__name__']}.py")
        with open(script, "rb") as f:
            digest = hashlib.sha256(f.read()).hexdigest()
        if script_globals.setdefault(SCRIPT_HASH, digest) != digest:
            raise _conflict("its script", folder, os.path.dirname(script_globals["__file__"]))
    for name, module in list(sys.modules.items()):
        search = getattr(module, "__path__", None)
        if search is None or name.split(".")[0] not in _PACKAGES:
            continue
        own = os.path.join(folder, *name.split("."))
        kept = [p for p in search if p != own and os.path.isdir(p)]
        search[:] = [own, *kept] if os.path.isdir(own) else kept


if _SUFFIX:
    packages_content(_FOLDER)      # now, while the folder exists (a host may delete it later)
