"""Reading a system model from a folder, its .ssd, or one ``.ssp`` archive.

An ``.ssp`` archive is a zip holding ``SystemStructure.ssd`` at its root (with its ``.ssv``
files and the FMUs its sources name, e.g. under ``resources/``), as ``navfmu package``
writes it.  It is extracted once per process into a temporary folder that is removed at
interpreter exit, and loaded from there by :func:`orchestrator.model.ssp.load_ssd`; the model's
``archive`` then names the ``.ssp`` file (libcosim is given the archive itself).  An archive
is read as data: at most :data:`MAX_MEMBERS` members and :data:`MAX_ARCHIVE_BYTES`
uncompressed (checked from the zip directory before anything is written), no member outside
the folder; the .ssd/.ssv inside are then bounded by :mod:`orchestrator.model.ssp`.
"""
from __future__ import annotations

import atexit
import dataclasses
import shutil
import tempfile
import zipfile
from pathlib import Path
from typing import Dict, Tuple

from ..errors import SspError
from .ssp import SystemModel, load_ssd
from .suggestions import did_you_mean

#: bounds of an archive (ours: 4-7 members, 20-40 MB uncompressed)
MAX_MEMBERS = 1000
MAX_ARCHIVE_BYTES = 1024 * 1024 * 1024
_EXTRACTED: Dict[Tuple[str, int, int], Path] = {}


def _check_members(archive: Path, zf: zipfile.ZipFile, target: Path) -> None:
    infos = zf.infolist()
    if len(infos) > MAX_MEMBERS:
        raise SspError(f"{archive}: {len(infos)} members, more than the {MAX_MEMBERS} an SSP "
                       f"archive may hold")
    total = sum(i.file_size for i in infos)
    if total > MAX_ARCHIVE_BYTES:
        raise SspError(f"{archive}: {total} bytes uncompressed, more than the "
                       f"{MAX_ARCHIVE_BYTES} an SSP archive may hold")
    for info in infos:
        if target not in (target / info.filename).resolve().parents:
            raise SspError(f"{archive}: member '{info.filename}' lies outside the archive")


def _extract(archive: Path) -> Path:
    """Extract ``archive`` once per process into a temporary folder removed at exit."""
    stat = archive.stat()
    key = (str(archive), stat.st_mtime_ns, stat.st_size)
    if key in _EXTRACTED:
        return _EXTRACTED[key]
    target = Path(tempfile.mkdtemp(prefix=f"navfmu-{archive.stem}-")).resolve()
    atexit.register(shutil.rmtree, target, True)
    try:
        with zipfile.ZipFile(archive) as zf:
            _check_members(archive, zf, target)
            zf.extractall(target)
    except zipfile.BadZipFile as exc:
        raise SspError(f"{archive}: not an SSP archive (zip): {exc}") from None
    if not (target / "SystemStructure.ssd").is_file():
        raise SspError(f"{archive}: the archive has no SystemStructure.ssd at its root")
    _EXTRACTED[key] = target
    return target


def _models_beside(path: Path):
    """The names of the models in ``path``'s folder (folders with a ``SystemStructure.ssd``,
    ``.ssd`` and ``.ssp`` files): what a mistyped model name may have meant."""
    folder = path.parent
    if not folder.is_dir():
        return []
    return [p.name for p in folder.iterdir()
            if (p.is_dir() and (p / "SystemStructure.ssd").is_file())
            or p.suffix.lower() in (".ssd", ".ssp")]


def load_model(path) -> SystemModel:
    """Load a model folder, its ``.ssd`` file or an ``.ssp`` archive."""
    path = Path(path).expanduser()
    if not path.exists():
        raise SspError(f"{path}: no such model folder, .ssd or .ssp file"
                       + did_you_mean(path.name, _models_beside(path)))
    if path.suffix.lower() == ".ssp" and not path.is_dir():
        if not path.is_file():
            raise SspError(f"{path}: file not found")
        model = load_ssd(_extract(path.resolve()))
        return dataclasses.replace(model, archive=path.resolve())
    return load_ssd(path)


__all__ = ["load_model"]
