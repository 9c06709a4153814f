"""Compiling the native FMI test hosts of tests/chost/ (C programs without Python)."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import fmpy
import pytest


def compile_c_host(source: Path, folder: Path) -> Path:
    """The executable of ``source``, compiled into ``folder`` with the system ``cc`` (warnings
    are errors) against the FMI 2 headers fmpy ships; skips the test when either is missing."""
    cc = shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler 'cc' on PATH: cannot build the native FMI host")
    include = Path(fmpy.__file__).parent / "c-code"
    if not (include / "fmi2Functions.h").is_file():
        pytest.skip(f"the installed fmpy ships no FMI 2 headers in {include}")
    exe = folder / source.stem
    r = subprocess.run([cc, "-O1", "-Wall", "-Wextra", "-Werror", "-I", str(include), "-o",
                        str(exe), str(source), "-ldl"], capture_output=True, text=True)
    assert r.returncode == 0, f"compiling {source} failed:\n{r.stderr}"
    return exe
