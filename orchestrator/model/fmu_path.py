"""Where a system model's FMUs are found: a component's ``source``, then a search path.

A component's ``source`` is searched, first hit wins:

1. relative to the .ssd file, as SSP prescribes (inside an ``.ssp`` archive:
   ``resources/X.fmu``);
2. by its file name in each directory of the environment variable ``NAVFMU_FMU_PATH``
   (separated by ``os.pathsep``), for a model folder used away from its FMUs;
3. by its file name in this installation's ``fmus/dist`` (where ``navfmu build`` puts them).

If none exists, the source is the one of rule 3 when navfmu can build that FMU (a fresh
checkout before ``navfmu build``), else the relative one; the master then reports it missing
with the places searched.  libcosim and other SSP tools know rule 1 only: to run a copied
model there, write it as one archive (``navfmu package``).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import List

from ..building.build import DIST as INSTALLED_FMUS
from ..building.build import FMU_SOURCES

#: the environment variable of rule 2
FMU_PATH_VARIABLE = "NAVFMU_FMU_PATH"


def fmu_search_path() -> List[Path]:
    """The directories of rules 2 and 3, in search order."""
    dirs = [Path(p).expanduser() for p in os.environ.get(FMU_PATH_VARIABLE, "").split(os.pathsep)
            if p.strip()]
    return dirs + [INSTALLED_FMUS]


def resolve_source(base: Path, source: str) -> Path:
    """The FMU file a component's ``source`` (relative to the folder ``base``) names."""
    relative = (base / source).resolve()
    if relative.is_file():
        return relative
    name = Path(source).name
    for directory in fmu_search_path():
        candidate = (directory / name).resolve()
        if candidate.is_file():
            return candidate
    buildable = FMU_SOURCES / (Path(name).stem + ".py")
    return (INSTALLED_FMUS / name).resolve() if buildable.is_file() else relative


def searched_places() -> str:
    """The search path in words, for a "not found" message."""
    return (f"relative to the .ssd, in ${FMU_PATH_VARIABLE} "
            f"({os.environ.get(FMU_PATH_VARIABLE, 'unset')}) and in {INSTALLED_FMUS}")


__all__ = ["FMU_PATH_VARIABLE", "INSTALLED_FMUS", "fmu_search_path", "resolve_source",
           "searched_places"]
