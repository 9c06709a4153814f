"""``navfmu package``: a model folder as one self-contained SSP archive (``.ssp``).

The archive is a zip with, at its root, ``SystemStructure.ssd`` (the model's, comments kept)
and every other file of the model folder at its relative path (``.ssv`` parameter files,
``paper.json``, data such as the replay's sensor ``log/``; hidden files left out), and every
component's FMU under ``resources/<file name>``: a copy whose model description carries the
scenario's parameter values as start values, with the files a String parameter names
(:mod:`orchestrator.packaging.fmu_copies`).  Each Component's ``source`` is rewritten to
``resources/<file name>`` (two different copies with the same file name get ``_2``,
``_3``... suffixes), and every Component carries ``type``.  String parameter values are
left out of the archive's parameter sets (the FMU copies start from them) and, with
``step_hints=False``, the Components' step hints too, so strict SSP readers (OMSimulator)
import it (:mod:`orchestrator.packaging.strict_ssp`); the System carries OMSimulator's
annotation naming its co-simulation master, without which OMSimulator imports no System
(:mod:`orchestrator.packaging.oms_annotation`).  libcosim and our
:func:`orchestrator.model.ssp.load_model` read it unchanged, with the folder's numbers (with
the step hints).  The archive is written to a temporary name and renamed.
"""
from __future__ import annotations

import re
import zipfile
from pathlib import Path
from typing import Dict

from ..cosim.fmi3_variables import refuse_fmi3
from ..errors import NavfmuError
from ..results.outputs import check_writable
from ..results.run_results import atomic_write
from ..model.ssp import FMU_TYPE
from ..model.ssp_archive import load_model
from .fmu_copies import FmuCopy, component_copies, fmu_bytes
from .oms_annotation import with_oms_system_annotation
from .strict_ssp import without_component_annotations, without_string_values

RESOURCES = "resources"


def _resource_names(copies: Dict[str, FmuCopy]) -> Dict[str, str]:
    """component name -> archive path of its FMU copy (one entry per distinct copy)."""
    by_copy: Dict[tuple, str] = {}
    taken = set()
    names = {}
    for component, copy in copies.items():
        if copy.key() not in by_copy:
            stem, suffix, n = copy.source.stem, copy.source.suffix, 1
            candidate = f"{RESOURCES}/{copy.source.name}"
            while candidate in taken:
                n += 1
                candidate = f"{RESOURCES}/{stem}_{n}{suffix}"
            taken.add(candidate)
            by_copy[copy.key()] = candidate
        names[component] = by_copy[copy.key()]
    return names


def _rewrite_ssd(text: str, sources: Dict[str, str]) -> str:
    """Set ``source`` (and ``type``) of every ``<ssd:Component>`` start tag."""
    def fix(match):
        tag = match.group(0)
        name = re.search(r'\bname="([^"]*)"', tag).group(1)
        tag = re.sub(r'\bsource="[^"]*"', f'source="{sources[name]}"', tag)
        if not re.search(r'\btype="', tag):
            tag = tag.replace("<ssd:Component", f'<ssd:Component type="{FMU_TYPE}"', 1)
        return tag

    return re.sub(r"<ssd:Component\b[^>]*>", fix, text)


def _folder_files(ssd: Path):
    """(archive name, path) of every file of the model folder but the .ssd; refuses a
    parameter binding to a file outside the folder (it would not be in the archive)."""
    folder = ssd.parent.resolve()
    text = ssd.read_text(encoding="utf-8")
    for source in re.findall(r'<ssd:ParameterBinding\b[^>]*\bsource="([^"]*)"', text):
        if folder not in (folder / source).resolve().parents:
            raise NavfmuError(f"{ssd}: parameter file '{source}' lies outside the model folder; "
                              f"move it next to the .ssd to package the model")
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if path.is_file() and path != ssd and not any(p.startswith(".") for p in rel.parts):
            if rel.parts[0] == RESOURCES:
                raise NavfmuError(f"{folder}: the folder has a '{RESOURCES}' entry, where the "
                                  f"archive puts the FMUs")
            yield rel.as_posix(), path


def package(model_dir, out, step_hints: bool = True) -> Path:
    """Write ``model_dir`` (a model folder or its .ssd) as the archive ``out``; returns it.
    ``step_hints=False`` leaves the Components' ``osp:StepSizeHint`` out (module docstring)."""
    model = load_model(model_dir)
    if model.archive is not None:
        raise NavfmuError(f"{model_dir} is already an SSP archive")
    refuse_fmi3(model.components, "libcosim, for which the archive is written,")
    out = Path(out)
    if out.suffix.lower() != ".ssp":
        raise NavfmuError(f"--out {out}: an SSP archive needs the extension .ssp")
    check_writable(out, "--out")
    copies = component_copies(model)
    sources = _resource_names(copies)
    ssd = model.path
    ssd_text = without_string_values(_rewrite_ssd(ssd.read_text(encoding="utf-8"), sources))
    ssd_text = with_oms_system_annotation(ssd_text, model.base_step)
    if not step_hints:
        ssd_text = without_component_annotations(ssd_text)
    files = list(_folder_files(ssd))
    fmus = {sources[name]: fmu_bytes(copy, name) for name, copy in copies.items()}

    def write(f):
        with zipfile.ZipFile(f, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("SystemStructure.ssd", ssd_text)
            for arcname, path in files:
                if path.suffix == ".ssv":
                    zf.writestr(arcname, without_string_values(path.read_text(encoding="utf-8")))
                else:
                    zf.write(path, arcname)
            for arcname, data in fmus.items():
                zf.writestr(arcname, data)

    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise NavfmuError(f"--out {out}: cannot make its folder: {exc.strerror or exc}") from None
    return atomic_write(out, write, binary=True)


__all__ = ["package"]
