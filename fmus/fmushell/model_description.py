"""The FMU's model description: SI units with their UnitDefinitions, legal attributes, the
model structure's dependencies and the FMI 2.0 order of the elements (pythonfmu's default
fails ``fmpy validate`` and declares no dependency, which an importer reads as "every output
depends on every input": an algebraic loop through every closed loop of components).

Dependencies, as the shell behaves (``tests/test_model_structure.py`` checks them against it):

* ``Outputs``: none.  An output changes only in doStep (the component computes it there from
  the inputs set before the step), never because an input was set after the step, so no
  output depends on an input at a communication point: every output declares
  ``dependencies=""``.
* ``InitialUnknowns`` (every output): the knowns of initialization mode its value at the end
  of it may depend on: every parameter (a component computes its start outputs from its
  parameters; declared for all of them, not traced one by one) and the inputs its component
  class names in ``initial_dependencies`` (those :meth:`Component.initial_inputs` reads).

``dependenciesKind`` is not written: every dependence is nonlinear ("dependent", the default
when the attribute is absent)."""
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
    for sv in root.find("ModelVariables"):
        name = sv.get("name")
        child = sv[0] if len(sv) else None
        unit = slave._units.get(name, "")
        if child is not None and "start" in child.attrib and name in slave._values:
            child.set("start", start_text(child.tag, slave._values[name]))  # exact
        if child is not None and child.tag == "Real" and unit:
            child.set("unit", unit)
            if unit not in used_units:
                used_units.append(unit)
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
    _model_structure(root.find("ModelStructure"), root.find("ModelVariables"),
                     slave.component_class)
    # put the children in the order the FMI 2.0 schema prescribes
    children = list(root)
    for c in children:
        root.remove(c)
    children.sort(key=lambda e: _MD_ORDER.index(e.tag))
    root.extend(children)
    return root


def _model_structure(structure, variables, component_class):
    """Write the Outputs' and the InitialUnknowns' dependencies (module docstring) into
    ``structure``, replacing what pythonfmu wrote."""
    index = {sv.get("name"): i for i, sv in enumerate(variables, start=1)}
    declared = component_class.initial_dependencies
    inputs = {p.name for p in component_class.inputs}
    outputs = sorted(index[p.name] for p in component_class.outputs)
    if not (set(declared) <= {p.name for p in component_class.outputs}
            and all(set(names) <= inputs for names in declared.values())):
        raise ValueError(f"{component_class.model_name}: initial_dependencies names an "
                         "output or an input the component does not declare")
    parameters = [index[p.name] for p in component_class.parameters]
    initial = {index[name]: [index[n] for n in names] for name, names in declared.items()}
    for child in list(structure):
        structure.remove(child)
    if not outputs:
        return
    listed = SubElement(structure, "Outputs")
    for i in outputs:
        SubElement(listed, "Unknown", index=str(i), dependencies="")
    listed = SubElement(structure, "InitialUnknowns")
    for i in outputs:
        knowns = sorted(parameters + initial.get(i, []))
        SubElement(listed, "Unknown", index=str(i), dependencies=" ".join(map(str, knowns)))
