"""Build the FMUs of ``fmus/`` into ``fmus/dist/`` with pythonfmu, only when stale.

An FMU is stale when it is missing or when the hash of its inputs (its slave script,
``fmushell.py`` and every file of ``navcore``) differs from the one recorded beside it in
``fmus/dist/<Model>.fmu.sha256``.  Each FMU is written to a temporary name and renamed, so an
interrupted build never leaves a broken ``.fmu`` behind.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from .errors import NavfmuError

ROOT = Path(__file__).resolve().parent.parent
FMU_SOURCES = ROOT / "fmus"
DIST = FMU_SOURCES / "dist"
SHELL = "fmushell.py"
LIBRARY = "navcore"


def slave_scripts(src: Path = FMU_SOURCES):
    """The FMU scripts: every ``fmus/*.py`` except the shared shell."""
    if not src.is_dir():
        raise NavfmuError(f"FMU sources not found at {src} (navfmu build needs the source tree)")
    return sorted(p for p in src.glob("*.py") if p.name != SHELL)


def source_hash(script: Path) -> str:
    h = hashlib.sha256()
    files = [script, script.parent / SHELL]
    files += sorted((script.parent / LIBRARY).rglob("*.py"))
    for f in files:
        h.update(f.relative_to(script.parent).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def fmu_path(name: str, dist: Path = DIST) -> Path:
    return dist / f"{name}.fmu"


def is_stale(script: Path, dist: Path = DIST) -> bool:
    fmu = fmu_path(script.stem, dist)
    stamp = fmu.with_suffix(".fmu.sha256")
    if not fmu.exists() or not stamp.exists():
        return True
    return stamp.read_text().strip() != source_hash(script)


def build_one(script: Path, dist: Path = DIST) -> Path:
    """Build one FMU (always) and return its path."""
    from pythonfmu.builder import FmuBuilder

    dist.mkdir(parents=True, exist_ok=True)
    target = fmu_path(script.stem, dist)
    with tempfile.TemporaryDirectory(prefix="navfmu_build_") as tmp:
        built = FmuBuilder.build_FMU(
            script, dest=tmp,
            project_files=[script.parent / LIBRARY, script.parent / SHELL],
            canGetAndSetFMUstate=True, canSerializeFMUstate=True)
        built = Path(built)
        if built.stem != script.stem:
            raise NavfmuError(f"{script}: the FMU's model name '{built.stem}' differs from the "
                              f"script name '{script.stem}'")
        fd, partial = tempfile.mkstemp(dir=dist, prefix=f".{script.stem}.", suffix=".part")
        os.close(fd)
        shutil.copyfile(built, partial)
        os.replace(partial, target)
    target.with_suffix(".fmu.sha256").write_text(source_hash(script) + "\n")
    return target


def build(names=None, force=False, dist: Path = DIST, log=print):
    """Build the named FMUs (all by default) that are stale (all with ``force``)."""
    scripts = slave_scripts()
    if names:
        known = {s.stem: s for s in scripts}
        unknown = [n for n in names if n not in known]
        if unknown:
            raise NavfmuError(f"unknown FMU {', '.join(unknown)}; known: {', '.join(known)}")
        scripts = [known[n] for n in names]
    built = []
    for script in scripts:
        if force or is_stale(script, dist):
            if log:
                log(f"building {script.stem}.fmu")
            built.append(build_one(script, dist))
    return built
