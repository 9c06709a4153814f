"""Reading system structure descriptions (SSP 1.0, the subset libcosim also reads).

A system model is a folder with ``SystemStructure.ssd`` (and optionally ``.ssv`` parameter
files next to it).  The subset:

* literal namespace prefixes ``ssd:``, ``ssc:``, ``ssv:`` (and ``osp:`` for the OSP
  annotations), because libcosim matches tag names literally;
* one flat ``ssd:System`` with ``ssd:Elements/ssd:Component`` (``name``, ``source``, ``type``
  ``application/x-fmu-sharedlibrary``: SSP 1.0's default when absent, but OMSimulator skips a
  component without it, so our models write it and any other value is an error), each with
  typed ``ssd:Connectors/ssd:Connector``
  (``name``, ``kind`` input/output/parameter/calculatedParameter, one child ``ssc:Real``
  (optional ``unit``) / ``ssc:Integer`` / ``ssc:Boolean`` / ``ssc:String``);
* ``ssd:ParameterBindings/ssd:ParameterBinding`` inline
  (``ssd:ParameterValues/ssv:ParameterSet/ssv:Parameters/ssv:Parameter``) or by
  ``source="file.ssv"`` (relative to the .ssd);
* swap variants (ours, outside SSP): when a component's FMU is replaced
  (:meth:`SystemModel.replace_source`) by one whose file is ``MODEL.fmu``, a file
  ``file.MODEL.ssv`` next to a bound ``file.ssv`` is applied on top of that binding, so a
  scenario can carry settings for the FMUs it may be swapped to.  The .ssd does not reference
  it, so libcosim and other SSP hosts, which run the .ssd's own FMU, never read it;
* ``ssd:Connections/ssd:Connection`` from a component's output to a component's input,
  without transformation;
* ``ssd:DefaultExperiment startTime stopTime`` with the base step in
  ``ssd:Annotations/ssc:Annotation[@type="com.opensimulationplatform"]/osp:Algorithm/
  osp:FixedStepAlgorithm@baseStepSize``; a component's own step as
  ``ssd:Annotations/ssc:Annotation[@type="com.opensimulationplatform"]/osp:StepSizeHint@value``
  inside the ``ssd:Component``.

A component's ``source`` is resolved by :func:`orchestrator.model.fmu_path.resolve_source`
(relative to the .ssd first, then a search path); :mod:`orchestrator.model.ssp_archive` reads a
model packed as one ``.ssp`` archive.

Anything outside the subset, or inconsistent, raises :class:`~orchestrator.errors.SspError`
naming the file and the element/attribute.  Files are read as data only: with defusedxml,
refusing any DTD (so no entity expansion and no external reference), and up to
:data:`~orchestrator.model.ssp_xml.MAX_FILE_BYTES`.
"""
from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple

from navcore.core.timing import TIME_TOLERANCE

from ..errors import SspError
from .fmu_path import resolve_source
from .ssp_xml import OSP_ANNOTATION_TYPE, OSP_NS, SSC_NS, SSD_NS, SSV_NS, TYPES
from .ssp_xml import tag as _tag
from .ssp_xml import pretty as _pretty
from .ssp_xml import parse as _parse
from .ssp_xml import attr as _attr
from .ssp_xml import float_attr as _float_attr
from .ssp_xml import only_children as _only_children
from .ssp_xml import osp_annotation as _osp_annotation
from .ssp_xml import typed_value as _typed_value

#: the one component type of the subset (SSP 1.0's default)
FMU_TYPE = "application/x-fmu-sharedlibrary"
KINDS = ("input", "output", "parameter", "calculatedParameter")


@dataclass
class ComponentSpec:
    """One ``ssd:Component``: its FMU, declared connectors, bound parameters and step hint."""

    name: str
    source: Path
    connectors: Dict[str, Tuple[str, str]] = field(default_factory=dict)  # name -> (kind, type)
    parameters: Dict[str, Tuple[str, object]] = field(default_factory=dict)  # name -> (type, value)
    step_hint: Optional[float] = None
    units: Dict[str, str] = field(default_factory=dict)  # connector name -> unit (Real only)
    type: str = FMU_TYPE
    #: the ``source`` attribute as written in the .ssd
    source_text: str = ""
    #: the ``.ssv`` files bound by ``source=`` (for the swap variants, module docstring)
    parameter_files: List[Path] = field(default_factory=list)
    #: names set by a swap variant file: meant for this FMU, so never skipped as absent
    variant_parameters: Tuple[str, ...] = ()
    #: parameter name -> the unit its bound Real value is given in (``<ssv:Real unit=..>``),
    #: converted to the FMU variable's unit when the master sets it
    parameter_units: Dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Connection:
    """Output ``start_component.start_connector`` drives input ``end_component.end_connector``."""

    start_component: str
    start_connector: str
    end_component: str
    end_connector: str

    def __str__(self) -> str:
        return (f"{self.start_component}.{self.start_connector} -> "
                f"{self.end_component}.{self.end_connector}")


@dataclass
class SystemModel:
    """A loaded system structure.  ``path`` is the .ssd file."""

    name: str
    path: Path
    base_step: float
    start_time: float
    stop_time: float
    components: List[ComponentSpec]
    connections: List[Connection]
    #: component name -> source it had before :meth:`replace_source` (swaps)
    replaced_sources: Dict[str, Path] = field(default_factory=dict)
    #: the ``.ssp`` archive the model was read from (None for a folder)
    archive: Optional[Path] = None

    def component(self, name: str) -> ComponentSpec:
        for c in self.components:
            if c.name == name:
                return c
        from ..errors import WiringError

        raise WiringError(
            f"{self.path}: no component named '{name}' "
            f"(components: {', '.join(c.name for c in self.components)})"
        )

    def replace_source(self, component_name: str, new_source) -> "SystemModel":
        """Return a copy in which ``component_name`` runs ``new_source`` (a filter swap).

        A relative ``new_source`` is taken relative to the current directory.  Whether the new
        FMU has every connected variable is checked when a :class:`Simulation` is built.
        The swap variants for the new FMU's model name are applied (module docstring).
        """
        old = self.component(component_name)
        new_path = Path(new_source).expanduser().resolve()
        units = dict(old.parameter_units)
        variant = _swap_variant(old, new_path.stem, units)
        components = [
            dataclasses.replace(c, source=new_path,
                                connectors=dict(c.connectors),
                                parameters={**c.parameters, **variant},
                                units=dict(c.units), parameter_files=list(c.parameter_files),
                                variant_parameters=tuple(variant), parameter_units=units)
            if c.name == component_name else c
            for c in self.components
        ]
        replaced = dict(self.replaced_sources)
        replaced.setdefault(component_name, old.source)
        return dataclasses.replace(self, components=components,
                                   connections=list(self.connections),
                                   replaced_sources=replaced)


def _swap_variant(comp: ComponentSpec, model_name: str,
                  units: Dict[str, str]) -> Dict[str, Tuple[str, object]]:
    """Values of ``file.MODEL.ssv`` next to each ``file.ssv`` bound to ``comp`` (in order);
    their units replace those of the names in ``units``."""
    values: Dict[str, Tuple[str, object]] = {}
    for ssv in comp.parameter_files:
        variant = ssv.with_name(f"{ssv.stem}.{model_name}{ssv.suffix}")
        if variant.is_file():
            values.update(read_ssv(variant, units))
    return values


def _read_parameter_set(path: Path, parameter_set: ET.Element, where: str,
                        units: Optional[Dict[str, str]] = None) -> Dict[str, Tuple[str, object]]:
    """name -> (type, value) of a parameter set; ``units`` receives, per Real given with a
    ``unit`` attribute, that unit (and loses any earlier unit of a name given without)."""
    result: Dict[str, Tuple[str, object]] = {}
    parameters = parameter_set.find(_tag(SSV_NS, "Parameters"))
    if parameters is None:
        return result
    for p in parameters.findall(_tag(SSV_NS, "Parameter")):
        name = _attr(path, p, "name", f"{where} <ssv:Parameter>")
        pwhere = f"{where} <ssv:Parameter name=\"{name}\">"
        if name in result:
            raise SspError(f"{path}: {pwhere} is given twice")
        result[name] = _typed_value(path, p, pwhere)
        if units is not None:
            units.pop(name, None)
            unit = _value_unit(p)
            if unit:
                units[name] = unit
    return result


def _value_unit(parameter: ET.Element) -> str:
    """The ``unit`` attribute of a parameter's ``<ssv:Real>`` ('' when none)."""
    real = parameter.find(_tag(SSV_NS, "Real"))
    return (real.get("unit") or "").strip() if real is not None else ""


def read_ssv(path: Path, units: Optional[Dict[str, str]] = None
             ) -> Dict[str, Tuple[str, object]]:
    """A ``.ssv`` parameter set: name -> (type, value), each error naming the file;
    ``units``: as in :func:`_read_parameter_set`."""
    root = _parse(path)
    if root.tag != _tag(SSV_NS, "ParameterSet"):
        raise SspError(
            f"{path}: root element is <{_pretty(root.tag)}>, expected <ssv:ParameterSet>"
        )
    return _read_parameter_set(path, root, "<ssv:ParameterSet>", units)


def _read_bindings(path: Path, comp_elem: ET.Element, cwhere: str, files: List[Path],
                   units: Dict[str, str]) -> Dict[str, Tuple[str, object]]:
    """The bound parameters; the ``.ssv`` files bound by ``source=`` are appended to ``files``,
    the units of the values given with one go into ``units``."""
    params: Dict[str, Tuple[str, object]] = {}
    bindings = comp_elem.find(_tag(SSD_NS, "ParameterBindings"))
    if bindings is None:
        return params
    for binding in bindings.findall(_tag(SSD_NS, "ParameterBinding")):
        bwhere = f"{cwhere} <ssd:ParameterBinding>"
        if binding.get("prefix"):
            raise SspError(f"{path}: {bwhere} attribute 'prefix' is not supported")
        if binding.find(_tag(SSD_NS, "ParameterMapping")) is not None:
            raise SspError(f"{path}: {bwhere} <ssd:ParameterMapping> is not supported")
        source = binding.get("source")
        if source:
            ssv_path = (path.parent / source).resolve()
            if not ssv_path.is_file():
                raise SspError(f"{path}: {bwhere} source=\"{source}\": file not found ({ssv_path})")
            values = read_ssv(ssv_path, units)
            files.append(ssv_path)
        else:
            pv = binding.find(_tag(SSD_NS, "ParameterValues"))
            if pv is None:
                raise SspError(f"{path}: {bwhere} has neither a 'source' attribute nor "
                               f"<ssd:ParameterValues>")
            pset = pv.find(_tag(SSV_NS, "ParameterSet"))
            if pset is None:
                raise SspError(f"{path}: {bwhere} <ssd:ParameterValues> lacks <ssv:ParameterSet>")
            values = _read_parameter_set(path, pset, bwhere, units)
        # later bindings override earlier ones, as in SSP
        params.update(values)
    return params


def _read_component(path: Path, elem: ET.Element) -> ComponentSpec:
    name = _attr(path, elem, "name", "<ssd:Component>")
    cwhere = f"<ssd:Component name=\"{name}\">"
    source = _attr(path, elem, "source", cwhere)
    ctype = elem.get("type", FMU_TYPE)
    if ctype != FMU_TYPE:
        raise SspError(f"{path}: {cwhere} type=\"{ctype}\" is not supported (only FMUs: "
                       f"type=\"{FMU_TYPE}\")")
    comp = ComponentSpec(name=name, source=resolve_source(path.parent, source), type=ctype,
                         source_text=source)
    connectors = elem.find(_tag(SSD_NS, "Connectors"))
    if connectors is not None:
        for con in connectors.findall(_tag(SSD_NS, "Connector")):
            cname = _attr(path, con, "name", f"{cwhere} <ssd:Connector>")
            kwhere = f"{cwhere} <ssd:Connector name=\"{cname}\">"
            kind = _attr(path, con, "kind", kwhere)
            if kind not in KINDS:
                raise SspError(f"{path}: {kwhere} kind=\"{kind}\" is not one of {', '.join(KINDS)}")
            typed = [c for c in con if c.tag in {_tag(SSC_NS, t) for t in TYPES}]
            if len(typed) != 1:
                raise SspError(f"{path}: {kwhere} needs exactly one type child <ssc:Real>, "
                               f"<ssc:Integer>, <ssc:Boolean> or <ssc:String> (found {len(typed)})")
            typ = typed[0].tag.split("}", 1)[1]
            if cname in comp.connectors:
                raise SspError(f"{path}: {kwhere} is declared twice")
            comp.connectors[cname] = (kind, typ)
            if typ == "Real" and typed[0].get("unit"):
                comp.units[cname] = typed[0].get("unit")
    comp.parameters = _read_bindings(path, elem, cwhere, comp.parameter_files,
                                     comp.parameter_units)
    osp = _osp_annotation(elem)
    if osp is not None:
        hint = osp.find(_tag(OSP_NS, "StepSizeHint"))
        if hint is not None:
            comp.step_hint = _float_attr(path, hint, "value", f"{cwhere} <osp:StepSizeHint>")
    return comp


def _read_components(path: Path, system: ET.Element, system_name: str) -> List[ComponentSpec]:
    elements = system.find(_tag(SSD_NS, "Elements"))
    if elements is None:
        raise SspError(f"{path}: <ssd:System name=\"{system_name}\"> has no <ssd:Elements>")
    _only_children(path, elements, (_tag(SSD_NS, "Component"),),
                   "<ssd:Elements> (only a flat system of components is supported)")
    components: List[ComponentSpec] = []
    names = set()
    for elem in elements.findall(_tag(SSD_NS, "Component")):
        comp = _read_component(path, elem)
        if comp.name in names:
            raise SspError(f"{path}: <ssd:Component name=\"{comp.name}\"> is declared twice "
                           f"(component names must be unique)")
        components.append(comp)
        names.add(comp.name)
    if not components:
        raise SspError(f"{path}: <ssd:Elements> contains no <ssd:Component>")
    return components


def _read_connection(path: Path, ce: ET.Element,
                     by_name: Dict[str, ComponentSpec]) -> Tuple[Connection, str]:
    """One ``ssd:Connection`` (checked against the components' connectors) and its text."""
    where = "<ssd:Connection>"
    attrs = {}
    for a in ("startElement", "startConnector", "endElement", "endConnector"):
        value = ce.get(a)
        if a.endswith("Element") and (value is None or value.strip() == ""):
            attrs[a] = ""
        else:
            attrs[a] = _attr(path, ce, a, where)
    where = (f"<ssd:Connection startElement=\"{attrs['startElement']}\" "
             f"startConnector=\"{attrs['startConnector']}\" "
             f"endElement=\"{attrs['endElement']}\" "
             f"endConnector=\"{attrs['endConnector']}\">")
    if len(ce):
        raise SspError(f"{path}: {where} has a <{_pretty(ce[0].tag)}> child: connection "
                       f"transformations are not supported")
    if not attrs["startElement"] or not attrs["endElement"]:
        raise SspError(f"{path}: {where}: connections to the system itself are not "
                       f"supported (component to component only)")
    conn = Connection(attrs["startElement"], attrs["startConnector"],
                      attrs["endElement"], attrs["endConnector"])
    kinds = []
    for role, cname, vname in (("start", conn.start_component, conn.start_connector),
                               ("end", conn.end_component, conn.end_connector)):
        comp = by_name.get(cname)
        if comp is None:
            raise SspError(f"{path}: {where}: {role}Element \"{cname}\" is not a component "
                           f"of the system (components: {', '.join(by_name)})")
        if vname not in comp.connectors:
            raise SspError(f"{path}: {where}: {role}Connector \"{vname}\" is not declared "
                           f"as an <ssd:Connector> of component \"{cname}\"")
        kinds.append(comp.connectors[vname])
    (skind, stype), (ekind, etype) = kinds
    if skind != "output":
        raise SspError(f"{path}: {where}: the start connector has kind \"{skind}\"; only "
                       f"output -> input connections are supported")
    if ekind != "input":
        raise SspError(f"{path}: {where}: the end connector has kind \"{ekind}\"; only "
                       f"output -> input connections are supported")
    if stype != etype:
        raise SspError(f"{path}: {where}: type mismatch, {stype} output connected to "
                       f"{etype} input")
    return conn, where


def _read_connections(path: Path, system: ET.Element,
                      components: List[ComponentSpec]) -> List[Connection]:
    by_name = {c.name: c for c in components}
    connections: List[Connection] = []
    driven: Dict[Tuple[str, str], Connection] = {}
    conns_elem = system.find(_tag(SSD_NS, "Connections"))
    if conns_elem is None:
        return connections
    for ce in conns_elem.findall(_tag(SSD_NS, "Connection")):
        conn, where = _read_connection(path, ce, by_name)
        key = (conn.end_component, conn.end_connector)
        if key in driven:
            raise SspError(f"{path}: {where}: input {conn.end_component}.{conn.end_connector} "
                           f"is already connected ({driven[key]}); an input takes one source")
        driven[key] = conn
        connections.append(conn)
    return connections


def _read_experiment(path: Path, root: ET.Element) -> Tuple[float, float, float]:
    """Start time, stop time and base step of ``ssd:DefaultExperiment``."""
    experiment = root.find(_tag(SSD_NS, "DefaultExperiment"))
    if experiment is None:
        raise SspError(f"{path}: <ssd:DefaultExperiment> is missing (it carries the base step)")
    start = _float_attr(path, experiment, "startTime", "<ssd:DefaultExperiment>",
                        required=False, default=0.0)
    stop = _float_attr(path, experiment, "stopTime", "<ssd:DefaultExperiment>")
    if stop <= start:
        raise SspError(f"{path}: <ssd:DefaultExperiment> stopTime={stop} must be greater than "
                       f"startTime={start}")
    base_step = None
    osp = _osp_annotation(experiment)
    if osp is not None:
        algorithm = osp.find(_tag(OSP_NS, "Algorithm"))
        if algorithm is not None:
            fixed = algorithm.find(_tag(OSP_NS, "FixedStepAlgorithm"))
            if fixed is None:
                raise SspError(f"{path}: <osp:Algorithm> must contain <osp:FixedStepAlgorithm> "
                               f"(only fixed-step co-simulation is supported)")
            base_step = _float_attr(path, fixed, "baseStepSize", "<osp:FixedStepAlgorithm>")
    if base_step is None:
        raise SspError(
            f"{path}: <ssd:DefaultExperiment> has no base step: add "
            f"<ssd:Annotations><ssc:Annotation "
            f"type=\"{OSP_ANNOTATION_TYPE}\"><osp:Algorithm><osp:FixedStepAlgorithm "
            f"baseStepSize=\"...\"/>"
        )
    if base_step <= 0:
        raise SspError(f"{path}: <osp:FixedStepAlgorithm> baseStepSize={base_step} must be > 0")
    return start, stop, base_step


def _check_step_hints(path: Path, components: List[ComponentSpec], base_step: float) -> None:
    for comp in components:
        if comp.step_hint is None:
            continue
        where = (
            f"<ssd:Component name=\"{comp.name}\"> <osp:StepSizeHint value=\"{comp.step_hint}\">"
        )
        if comp.step_hint <= 0:
            raise SspError(f"{path}: {where}: the step must be > 0")
        ratio = comp.step_hint / base_step
        if round(ratio) < 1 or abs(ratio - round(ratio)) > TIME_TOLERANCE * ratio:
            raise SspError(f"{path}: {where}: the step must be an integer multiple of the base "
                           f"step {base_step}")


def load_ssd(path) -> SystemModel:
    """Load ``SystemStructure.ssd`` (``path`` is the file or the folder holding it)."""
    path = Path(path).expanduser()
    if path.is_dir():
        path = path / "SystemStructure.ssd"
    path = path.resolve()
    root = _parse(path)
    if root.tag != _tag(SSD_NS, "SystemStructureDescription"):
        raise SspError(f"{path}: root element is <{_pretty(root.tag)}>, expected "
                       f"<ssd:SystemStructureDescription>")
    systems = root.findall(_tag(SSD_NS, "System"))
    if len(systems) != 1:
        raise SspError(f"{path}: <ssd:SystemStructureDescription> needs exactly one <ssd:System> "
                       f"(found {len(systems)})")
    system = systems[0]
    system_name = _attr(path, system, "name", "<ssd:System>")
    model_name = root.get("name") or system_name
    components = _read_components(path, system, system_name)
    connections = _read_connections(path, system, components)
    start, stop, base_step = _read_experiment(path, root)
    _check_step_hints(path, components, base_step)
    return SystemModel(name=model_name, path=path, base_step=base_step, start_time=start,
                       stop_time=stop, components=components, connections=connections)


__all__ = ["SystemModel", "ComponentSpec", "Connection", "load_ssd", "read_ssv", "FMU_TYPE",
           "SSD_NS", "SSC_NS", "SSV_NS", "OSP_NS"]
