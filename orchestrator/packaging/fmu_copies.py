"""Packaged FMU copies that run their scenario in a host that applies no parameter binding.

``navfmu package`` and ``navfmu export`` put into the archive, for each component, a copy of
its FMU whose model description carries the scenario's parameter values (every binding of
the .ssd and its .ssv files, Strings included) as start values: OMSimulator applies no String
from an ``.ssv`` and fmpy's SSP runner no binding at all, and our FMUs start from the start
values of their own model description (``fmushell.start_values``).  A String parameter whose
value, taken relative to the .ssd, names a file or folder inside the model folder (the
replay's ``log``) has that file copied into the copy's ``resources/`` under the same relative
path, where the FMU looks first (``fmushell.resource_files``): the archive then runs from any
working directory.  Components with the same FMU and the same values share one copy.
"""
from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Tuple
from xml.etree import ElementTree as ET

from defusedxml.ElementTree import fromstring as parse_xml

from navcore.core.start_text import start_text

from ..errors import NavfmuError
from ..model.ssp import SystemModel

MODEL_DESCRIPTION = "modelDescription.xml"


@dataclass
class FmuCopy:
    """One FMU copy: the FMU it is made from, its start values and the files it carries."""

    source: Path
    #: the scenario's (start time, stop time, the component's step) as DefaultExperiment
    experiment: Tuple[float, float, float]
    starts: Dict[str, str] = field(default_factory=dict)
    files: Dict[str, Path] = field(default_factory=dict)  # path under resources/ -> file

    def key(self) -> Tuple:
        return (self.source, self.experiment, tuple(sorted(self.starts.items())),
                tuple(sorted((k, str(v)) for k, v in self.files.items())))


def _carried_files(folder: Path, component, name: str, value: str) -> Dict[str, Path]:
    """The files a String value names inside the model ``folder`` (relative path -> file)."""
    if not value or Path(value).is_absolute():
        return {}
    target = (folder / value).resolve()
    if folder not in target.parents or not target.exists():
        return {}
    if target.is_file():
        return {Path(value).as_posix(): target}
    files = {}
    for path in sorted(target.rglob("*")):
        rel = path.relative_to(target)
        if path.is_file() and not any(part.startswith(".") for part in rel.parts):
            files[(Path(value) / rel).as_posix()] = path
    if not files:
        raise NavfmuError(f"component '{component}': parameter '{name}' names the folder "
                          f"{target}, which holds no file")
    return files


def component_copies(model: SystemModel) -> Dict[str, FmuCopy]:
    """component name -> the FMU copy it runs in the archive."""
    folder = Path(model.path).parent.resolve()
    copies = {}
    for c in model.components:
        src = Path(c.source).resolve()
        if not src.is_file():
            raise NavfmuError(f"component '{c.name}': FMU file not found: {src} (navfmu build?)")
        step = c.step_hint if c.step_hint is not None else model.base_step
        copy = FmuCopy(src, (model.start_time, model.stop_time, step))
        for pname, (type_name, value) in c.parameters.items():
            copy.starts[pname] = start_text(type_name, value)
            if type_name == "String":
                copy.files.update(_carried_files(folder, c.name, pname, value))
        copies[c.name] = copy
    return copies


def _fmi3_starts(root, starts: Dict[str, str]) -> set:
    """Set the start values of an FMI 3.0 model description: an attribute of the variable's
    element, a ``<Start value>`` child for a String; returns the names set."""
    found = set()
    variables = root.find("ModelVariables")
    for v in (variables if variables is not None else ()):
        name = v.get("name")
        if name not in starts:
            continue
        if v.tag == "String":
            for old in v.findall("Start"):
                v.remove(old)
            ET.SubElement(v, "Start", {"value": starts[name]})
        else:
            v.set("start", starts[name])
        found.add(name)
    return found


def _model_description(xml: bytes, copy: FmuCopy, where: str) -> bytes:
    """The model description with the copy's start values and DefaultExperiment."""
    root = parse_xml(xml, forbid_dtd=True)
    experiment = root.find("DefaultExperiment")
    if experiment is not None:
        for attr, value in zip(("startTime", "stopTime", "stepSize"), copy.experiment):
            experiment.set(attr, repr(float(value)))
    starts = copy.starts
    found = set()
    if root.get("fmiVersion") == "3.0":
        found = _fmi3_starts(root, starts)
    for sv in root.iter("ScalarVariable"):
        name = sv.get("name")
        if name in starts and len(sv):
            sv[0].set("start", starts[name])
            found.add(name)
    missing = sorted(set(starts) - found)
    if missing:
        raise NavfmuError(f"{where}: the FMU has no variable {', '.join(missing)} to bind")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def fmu_bytes(copy: FmuCopy, component: str) -> bytes:
    """The FMU copy as the bytes of an .fmu file."""
    out = io.BytesIO()
    where = f"component '{component}' ({copy.source.name})"
    with zipfile.ZipFile(copy.source) as src, \
            zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as dst:
        names = set(src.namelist())
        for info in src.infolist():
            data = src.read(info)
            if info.filename == MODEL_DESCRIPTION:
                data = _model_description(data, copy, where)
            dst.writestr(info, data)
        for rel, path in copy.files.items():
            arcname = f"resources/{rel}"
            if arcname in names:
                raise NavfmuError(f"{where}: cannot carry {path}: the FMU has its own "
                                  f"{arcname}")
            dst.write(path, arcname)
    return out.getvalue()


__all__ = ["FmuCopy", "component_copies", "fmu_bytes"]
