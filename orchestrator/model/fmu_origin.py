"""Whether an FMU was built by this installation (*ours*) or comes from anywhere else
(*foreign*).

An FMU is ours when it is, byte for byte, the FMU of the same model name that ``navfmu
build`` wrote into this installation's ``fmus/dist`` (``Kf.fmu`` for model ``Kf``): that file
itself, or an identical copy anywhere under any file name; or when it carries that FMU's
build (its ``navfmu_build.json`` names the same build hash) with its code unchanged since
(:mod:`orchestrator.building.private_names`): the copies ``navfmu package`` and ``export``
write, whose model descriptions carry a scenario's start values, run the same code.
Everything else is foreign: an FMU of another tool or another person, another build of one of
our models (another checkout, an older version, a rebuild after ``fmus/dist`` changed), a copy
whose code was altered.  The master runs a foreign FMU in a host process of its own
(:mod:`orchestrator.cosim.isolation`), because nothing vouches that it neither crashes nor
hangs its host.
"""
from __future__ import annotations

import filecmp
import functools
from pathlib import Path
from typing import Optional, Tuple

from ..building import private_names
from ..building.build import DIST as INSTALLED_FMUS


def installed_fmu(model_name: str) -> Optional[Path]:
    """This installation's built FMU of ``model_name``, if there is one."""
    candidate = INSTALLED_FMUS / f"{model_name}.fmu"
    return candidate.resolve() if candidate.is_file() else None


def _signature(path: Path) -> Tuple[str, int, int]:
    stat = path.stat()
    return str(path), stat.st_size, stat.st_mtime_ns


@functools.lru_cache(maxsize=256)
def _identical(a: Tuple[str, int, int], b: Tuple[str, int, int]) -> bool:
    """Whether two files (by their signature: path, size, modification time, so a file
    rewritten since is compared again) hold the same bytes."""
    if a[0] == b[0]:
        return True
    return a[1] == b[1] and filecmp.cmp(a[0], b[0], shallow=False)


@functools.lru_cache(maxsize=256)
def _same_build(a: Tuple[str, int, int], b: Tuple[str, int, int]) -> bool:
    """Whether the FMU ``a`` carries the build of FMU ``b`` with its code unchanged."""
    mine, ours = private_names.read_build(Path(a[0])), private_names.read_build(Path(b[0]))
    return (mine is not None and ours is not None and mine.get("build") == ours.get("build")
            and not private_names.archive_changed_since_build(Path(a[0])))


def is_foreign(path, model_name: str) -> bool:
    """Whether the FMU file ``path`` (of model ``model_name``, from its model description)
    is foreign: neither byte for byte this installation's built FMU of that model nor a copy
    of its build with the code unchanged."""
    ours = installed_fmu(model_name)
    if ours is None:
        return True
    mine, theirs = _signature(Path(path).resolve()), _signature(ours)
    return not (_identical(mine, theirs) or _same_build(mine, theirs))


__all__ = ["INSTALLED_FMUS", "installed_fmu", "is_foreign"]
