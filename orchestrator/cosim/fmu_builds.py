"""Which build of an FMU runs: what a run's results and verify's report say of each FMU.

The FMU given is the code that runs.  A navfmu FMU imports its Python code under names private
to its build (:mod:`orchestrator.building.private_names`); one whose code was changed after its
build still carries its build's names, so it is given names of its own here, in its unpacked
folder, before it is loaded (else it would run the code of an unchanged FMU of its build loaded
in the same process, or be refused by it).
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Dict, Optional, Tuple

from ..building import private_names

_FILE_HASHES: Dict[Tuple[str, int, int], str] = {}


def file_sha256(path: Path) -> str:
    """SHA-256 of the file ``path`` (cached on its path, size and modification time)."""
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns)
    digest = _FILE_HASHES.get(key)
    if digest is None:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        digest = _FILE_HASHES[key] = h.hexdigest()
    return digest


def build_info(path: Path, model_description, unzipdir: Optional[Path] = None) -> dict:
    """What runs for the FMU ``path``: its file and content hash, its model name, GUID and
    generating tool, and for a navfmu FMU its build (version, build hash) and whether its code
    was changed after that build.  Given the folder ``unzipdir`` it is unpacked in, such a
    changed FMU is given names of its own there (it then runs its own code)."""
    md = model_description
    info = {"fmu": str(path), "fmu_sha256": file_sha256(path), "model": md.modelName,
            "guid": md.guid, "fmi_version": md.fmiVersion,
            "generation_tool": md.generationTool or ""}
    build = private_names.read_build(path)
    if build is not None:
        info["navfmu_version"] = build.get("version", "")
        info["navfmu_build"] = build.get("build", "")
        info["changed_after_build"] = (
            private_names.repack_if_changed(unzipdir) if unzipdir is not None
            else private_names.archive_changed_since_build(path))
    return info


__all__ = ["build_info", "file_sha256"]
