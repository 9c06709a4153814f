"""``navfmu validate``: FMUs checked with fmpy's validation (by default every FMU of
``fmus/dist``, built first), each file's problems listed, an error when any has one."""
from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Callable, Sequence

from . import build as fmu_build
from ..errors import NavfmuError


def validate_fmus(fmus: Sequence[str] = (), echo: Callable[[str], None] = print) -> None:
    """Validate ``fmus`` (default: build and take every FMU of fmus/dist), printing each
    file's result with ``echo``; raise a NavfmuError naming the count of failed FMUs."""
    from fmpy.validation import validate_fmu

    if not fmus:
        fmu_build.build()
        fmus = [str(fmu_build.fmu_path(s.stem)) for s in fmu_build.slave_scripts()]
    bad = 0
    for f in fmus:
        if not Path(f).is_file():
            raise NavfmuError(f"FMU file not found: {f}")
        if not zipfile.is_zipfile(f):
            raise NavfmuError(f"{f}: not an FMU (an FMU is a zip archive)")
        try:
            problems = validate_fmu(f)
        except Exception as exc:  # fmpy raises plain exceptions for broken archives
            raise NavfmuError(f"{f}: cannot read the FMU: {exc}") from None
        if problems:
            bad += 1
            echo(f"{f}: {len(problems)} problem(s)")
            for p in problems:
                echo(f"  {p}")
        else:
            echo(f"{f}: no problems found")
    if bad:
        raise NavfmuError(f"{bad} FMU(s) failed validation")


__all__ = ["validate_fmus"]
