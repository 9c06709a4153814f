"""The FMU's model description: SI units with their UnitDefinitions, legal attributes and the
FMI 2.0 order of the elements (pythonfmu's default fails ``fmpy validate``)."""
from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Slave

from navcore.ins.constants import DEG as _DEG, G0 as _G0

from navcore.core.start_text import start_text

#: every unit symbol used on our interfaces: (FMI 2.0 BaseUnit exponents, factor to SI).
#: Datasheet units (only in parameters whose name says so) carry their factor; those with a
#: fractional exponent (deg/sqrt(h), ug/sqrt(Hz)) are declared without a BaseUnit.
UNITS = {
    "1": ({}, 1.0),
    "s": ({"s": 1}, 1.0),
    "m": ({"m": 1}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "m/s": ({"m": 1, "s": -1}, 1.0),
    "m/s2": ({"m": 1, "s": -2}, 1.0),
    "rad/s": ({"rad": 1, "s": -1}, 1.0),
    "T": ({"kg": 1, "s": -2, "A": -1}, 1.0),
    "Hz": ({"s": -1}, 1.0),
    "deg/h": ({"rad": 1, "s": -1}, _DEG / 3600.0),
    "ug": ({"m": 1, "s": -2}, 1e-6 * _G0),
    "ppm": ({}, 1e-6),
    "urad": ({"rad": 1}, 1e-6),
    "deg/h/g": ({"rad": 1, "s": 1, "m": -1}, _DEG / 3600.0 / _G0),
    "deg/sqrt(h)": (None, 1.0),
    "deg/h/sqrt(h)": (None, 1.0),
    "ug/sqrt(Hz)": (None, 1.0),
}

# FMI 2.0 order of the children of fmiModelDescription
_MD_ORDER = ["ModelExchange", "CoSimulation", "UnitDefinitions", "TypeDefinitions",
             "LogCategories", "DefaultExperiment", "VendorAnnotations", "ModelVariables",
             "ModelStructure"]

def to_xml(slave, model_options=None):
    options = dict(model_options or {})
    options.setdefault("canGetAndSetFMUstate", True)
    options.setdefault("canSerializeFMUstate", True)
    root = Fmi2Slave.to_xml(slave, options)
    cosim = root.find("CoSimulation")
    cosim.set("canGetAndSetFMUstate", "true")
    cosim.set("canSerializeFMUstate", "true")
    used_units = []
    output_indices = []
    for index, sv in enumerate(root.find("ModelVariables"), start=1):
        name = sv.get("name")
        child = sv[0] if len(sv) else None
        unit = slave._units.get(name, "")
        if child is not None and "start" in child.attrib and name in slave._values:
            child.set("start", start_text(child.tag, slave._values[name]))  # exact
        if child is not None and child.tag == "Real" and unit:
            child.set("unit", unit)
            if unit not in used_units:
                used_units.append(unit)
        if sv.get("causality") == "output":
            output_indices.append(index)
    if used_units:
        unit_defs = Element("UnitDefinitions")
        for unit in used_units:
            u = SubElement(unit_defs, "Unit", name=unit)
            exponents, factor = UNITS[unit]
            if exponents is not None:
                attrib = {k: str(v) for k, v in exponents.items()}
                if factor != 1.0:
                    attrib["factor"] = repr(factor)
                SubElement(u, "BaseUnit", attrib)
        root.append(unit_defs)
    structure = root.find("ModelStructure")
    if not getattr(slave.component_class, "outputs_depend_on_inputs", True):
        # outputs at t computed from inputs at earlier times only: no direct feedthrough
        for unknown in structure.iter("Unknown"):
            unknown.set("dependencies", "")
    if output_indices and structure.find("InitialUnknowns") is None:
        initial = SubElement(structure, "InitialUnknowns")
        for index in output_indices:
            SubElement(initial, "Unknown", index=str(index))
    # put the children in the order the FMI 2.0 schema prescribes
    children = list(root)
    for c in children:
        root.remove(c)
    children.sort(key=lambda e: _MD_ORDER.index(e.tag))
    root.extend(children)
    return root
