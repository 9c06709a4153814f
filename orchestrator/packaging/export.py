"""``navfmu export``: a whole system model as one co-simulation FMU (fmpy's container FMU).

The exported FMU holds every component's FMU under ``resources/`` and fmpy's native container
(``fmpy.container_fmu``), which steps them itself.  Its rules (fmpy's ``container-fmu``
sources, ``doFixedStep``/``exitInitializationMode``):

* one fixed internal step ``h`` = the model's base step; a host step must be an integer
  multiple of ``h``;
* every internal step, every component steps over ``[t, t + h]`` (declaration order), then
  every connection is transferred: a Jacobi exchange, each component one step late on its
  sources (rule 3J of :mod:`orchestrator.cosim.master` without decimation);
* the connections are transferred once before initialization mode is left (not after it).

The container has no decimation: a component's ``osp:StepSizeHint`` cannot be honoured, so
the export steps every component at the base step.  That is legal for our components whose
period is not tied to the step (the GNSS receiver fixes at its own ``fix_interval`` from
``truth_time`` whatever the step); a component that only accepts its own period (the IMU, the
filters) must have the base step as its period, which is what our models do.  So the export
reproduces our master's ``--algorithm jacobi`` run of the model *with the hints removed*
(:func:`without_step_hints`).

Container variables: every output of every component as ``component.variable`` (unit kept),
and every parameter the system structure binds as a fixed parameter of that name whose start
is the bound value (so the FMU runs the scenario as it is, and a host may change it).  The
components are the packaged copies of :mod:`orchestrator.fmu_copies` (the scenario's values
as their start values, the files their Strings name inside), and the archive claims only the
platforms every component has a binary for.
"""
from __future__ import annotations

import dataclasses
import shutil
import tempfile
import uuid
import zipfile
from pathlib import Path
from typing import Dict, List, Set

from navcore.core.start_text import start_text

from ..cosim.fmi3_variables import FMI3_TYPES, check_version
from ..building.build import binary_platforms
from ..errors import NavfmuError
from ..model.ssp import SystemModel
from ..model.ssp_archive import load_model
from ..results.outputs import check_writable
from ..results.run_results import atomic_write
from .fmu_copies import component_copies, fmu_bytes

_FMI_TYPES = {"Real": "Real", "Integer": "Integer", "Boolean": "Boolean", "String": "String"}
#: the container's own type names for a connection (its configuration reader knows no FMI 2
#: names, and fmpy's writer passes a connection's type through unconverted)
_CONTAINER_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean"}
#: FMI 3.0 platform tuple -> the FMI 2.0 platform name of the container's binary for it
_FMI2_PLATFORMS = {"x86_64-linux": "linux64", "x86_64-windows": "win64",
                   "x86_64-darwin": "darwin64"}


def _container_type(spec, variable) -> str:
    """The exported FMU's (FMI 2.0) type of a component's ``variable``: its own for an FMI 2.0
    component, the connector type of an FMI 3.0 one (:mod:`orchestrator.cosim.fmi3_variables`);
    what the container cannot pass is refused by name (it reads and writes an Integer as
    Int32, so an FMI 3.0 Int64 cannot go through it)."""
    typ = _FMI_TYPES.get(variable.type) or (
        FMI3_TYPES.get(variable.type) if variable.type != "Int64" and not variable.dimensions
        else None)
    if typ is None:
        raise NavfmuError(f"component '{spec.name}' ({spec.source.name}): {variable.causality} "
                          f"'{variable.name}' has type {variable.type}"
                          f"{' (an array)' if variable.dimensions else ''}, which the exported FMU "
                          f"cannot pass (fmpy's container reads Float64, Int32 and Boolean)")
    return typ


def _as_connector(spec, variable):
    """A connection end as the container names its type (FMI 3.0 names for FMI 2.0 types)."""
    import attrs

    return attrs.evolve(variable,
                        type=_CONTAINER_TYPES[_container_type(spec, variable)])


def without_step_hints(model: SystemModel) -> SystemModel:
    """``model`` with every component stepping at the base step (the exported FMU's rule)."""
    return dataclasses.replace(
        model, components=[dataclasses.replace(c, step_hint=None) for c in model.components])


def _read_components(model: SystemModel, copies: Dict[str, Path]):
    """Every component of the container (its FMU copy's model description read and its FMI
    version checked), every component's variables by name, and the unit definitions of all."""
    from fmpy import read_model_description
    from fmpy.container_fmu.config import Component

    components, variables, units = {}, {}, {}
    for spec in model.components:
        md = read_model_description(str(copies[spec.name]))
        check_version(md, spec.name, spec.source)
        components[spec.name] = Component(name=spec.name, filename=copies[spec.name],
                                          modelDescription=md)
        variables[spec.name] = {v.name: v for v in md.modelVariables}
        for u in md.unitDefinitions:
            units.setdefault(u.name, u)
    return components, variables, units


def _container_variables(model: SystemModel, components, variables):
    """The container's variables (time, every component's parameters and non-String,
    non-Enumeration outputs as ``Component.variable``) and each one's mapping onto its
    component's variable."""
    from fmpy.model_description import ModelVariable

    container_vars: List = [ModelVariable(name="time", type="Real", causality="independent",
                                          variability="continuous")]
    mappings: Dict = {}
    for spec in model.components:
        comp, own = components[spec.name], variables[spec.name]
        for pname, (type_name, value) in spec.parameters.items():
            v = own[pname]
            cv = ModelVariable(name=f"{spec.name}.{pname}", type=_container_type(spec, v),
                               causality="parameter", variability="fixed", initial="exact",
                               start=start_text(type_name, value), unit=v.unit,
                               description=v.description)
            container_vars.append(cv)
            mappings[cv] = [(comp, v)]
        for v in own.values():
            if v.causality != "output" or v.type in ("String", "Enumeration"):
                continue
            cv = ModelVariable(name=f"{spec.name}.{v.name}", type=_container_type(spec, v),
                               causality="output",
                               variability=v.variability, initial="calculated", unit=v.unit,
                               description=v.description)
            container_vars.append(cv)
            mappings[cv] = [(comp, v)]
    return container_vars, mappings


def _configuration(model: SystemModel, copies: Dict[str, Path]):
    from fmpy.container_fmu.config import Configuration, Connection
    from fmpy.model_description import (CoSimulation, DefaultExperiment, ModelDescription,
                                        Unknown)

    components, variables, units = _read_components(model, copies)
    container_vars, mappings = _container_variables(model, components, variables)
    specs = {spec.name: spec for spec in model.components}
    connections = [Connection(components[c.start_component],
                              [_as_connector(specs[c.start_component],
                                             variables[c.start_component][c.start_connector])],
                              components[c.end_component],
                              [_as_connector(specs[c.end_component],
                                             variables[c.end_component][c.end_connector])])
                   for c in model.connections]
    outputs = [Unknown(index=i, variable=v) for i, v in enumerate(container_vars, start=1)
               if v.causality == "output"]
    md = ModelDescription(
        fmiVersion="2.0", modelName=model.name, instantiationToken="{%s}" % uuid.uuid4(),
        description=f"system model {model.name} as one FMU (fmpy container, Jacobi exchange "
                    f"at the base step {model.base_step} s)",
        generationTool="navfmu export",
        unitDefinitions=list(units.values()),
        defaultExperiment=DefaultExperiment(startTime=str(model.start_time),
                                            stopTime=str(model.stop_time),
                                            stepSize=str(model.base_step)),
        coSimulation=CoSimulation(modelIdentifier="container_fmu",
                                  fixedInternalStepSize=model.base_step),
        modelVariables=container_vars, outputs=outputs, initialUnknowns=list(outputs))
    return Configuration(parallelDoStep=False, modelDescription=md,
                         components=list(components.values()), connections=connections,
                         variableMappings=mappings)


def export(model_dir, out) -> Path:
    """Write the system ``model_dir`` (folder, .ssd or .ssp) as the FMU ``out``; returns it."""
    from fmpy.container_fmu.cli import create_container_fmu

    model = load_model(model_dir)
    out = Path(out)
    if out.suffix.lower() != ".fmu":
        raise NavfmuError(f"--out {out}: an FMU needs the extension .fmu")
    if not out.parent.is_dir():
        raise NavfmuError(f"cannot write {out}: the folder {out.parent} does not exist")
    check_writable(out, "--out")
    work = Path(tempfile.mkdtemp(prefix="navfmu-export-"))
    try:
        copies = _write_copies(model, work / "fmus")
        (work / "unzipped").mkdir()
        create_container_fmu(_configuration(model, copies), work / "unzipped",
                             work / "container.fmu")
        platforms = _common_platforms(copies.values())
        atomic_write(out, lambda f: _repack(work / "container.fmu", f, platforms), binary=True)
    except OSError as exc:
        raise NavfmuError(f"--out {out}: cannot write the FMU: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return out


def _write_copies(model: SystemModel, folder: Path) -> Dict[str, Path]:
    """component name -> its FMU copy with the scenario's start values (and files), written
    as ``folder/<component>.fmu`` (the container extracts each under its file's stem)."""
    folder.mkdir()
    paths = {}
    for name, copy in component_copies(model).items():
        paths[name] = folder / f"{name}.fmu"
        paths[name].write_bytes(fmu_bytes(copy, name))
    return paths


def _common_platforms(fmus) -> Set[str]:
    """The FMI 2.0 platforms (``binaries/<platform>``) every one of ``fmus`` has a binary for
    (an FMI 3.0 component's platform tuples by their FMI 2.0 names)."""
    common = None
    for fmu in fmus:
        with zipfile.ZipFile(fmu) as z:
            have = binary_platforms(z.namelist())
        have = {_FMI2_PLATFORMS.get(p, p) for p in have}
        common = have if common is None else common & have
    return common or set()


def _repack(container: Path, f, platforms: Set[str]) -> None:
    """fmpy's container archive without what it cannot keep: the binaries of platforms the
    components have none for (fmpy adds darwin64, win64 and linux64 whatever they carry), and
    the partial copy of itself (``Container.zip``) that fmpy's make_archive puts into it."""
    with zipfile.ZipFile(container) as src, \
            zipfile.ZipFile(f, "w", compression=zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            parts = info.filename.split("/")
            if info.filename == "Container.zip":
                continue
            if parts[0] == "binaries" and len(parts) > 1 and parts[1] not in platforms:
                continue
            dst.writestr(info, src.read(info))


__all__ = ["export", "without_step_hints"]
