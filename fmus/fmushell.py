"""Thin pythonfmu shell around a navcore :class:`~navcore.component.Component`.

Each FMU script in ``fmus/`` is a few lines: a subclass of :class:`ComponentSlave` naming the
navcore component it wraps.  This module does the FMI side once for all of them:

* registers every declared parameter, input and output with legal causality, variability and
  initial (Integer/Boolean ``discrete``; parameters ``fixed`` with ``initial="exact"``;
  outputs ``calculated`` and listed as InitialUnknowns);
* writes SI units and their UnitDefinitions into the model description (pythonfmu does not);
* saves the full internal state (the component object, not only the registered variables)
  behind ``canGetAndSetFMUstate`` / ``canSerializeFMUstate``;
* never lets a Python exception escape an FMI call: a user error (bad parameter, NaN input)
  is logged through the FMI logger and reported as fmi2Discard from ``do_step`` (the master
  stops with that message); after such an error every further ``do_step`` is refused too.
"""
from __future__ import annotations

import base64
import pickle
import traceback
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status

from navcore.component import NavcoreError

_DEG = 0.017453292519943295
_G0 = 9.80665
#: every unit symbol used on our interfaces: (FMI 2.0 BaseUnit exponents, factor to SI).
#: Datasheet units (only in parameters whose name says so) carry their factor; those with a
#: fractional exponent (deg/sqrt(h), ug/sqrt(Hz)) are declared without a BaseUnit.
UNITS = {
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
    "ug/sqrt(Hz)": (None, 1.0),
}

_VAR_CLASSES = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}

# FMI 2.0 order of the children of fmiModelDescription
_MD_ORDER = ["ModelExchange", "CoSimulation", "UnitDefinitions", "TypeDefinitions",
             "LogCategories", "DefaultExperiment", "VendorAnnotations", "ModelVariables",
             "ModelStructure"]


class ComponentSlave(Fmi2Slave):
    """Base of the FMU slaves; subclasses set ``component_class``."""

    component_class = None  # a navcore Component subclass, set by each FMU script

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        cls = self.component_class
        self.modelName = cls.model_name
        self.description = cls.description
        start, stop, step = cls.default_experiment
        self.default_experiment = DefaultExperiment(start_time=start, stop_time=stop, step_size=step)
        self.author = "navfmu"
        self.version = "0.1.0"
        self._values = {}
        self._units = {}
        self._input_names = tuple(p.name for p in cls.inputs)
        self._component = None
        self._start_time = 0.0
        self._failed = None
        for port in cls.parameters:
            self._register(port, Fmi2Causality.parameter, Fmi2Variability.fixed, Fmi2Initial.exact)
        for port in cls.inputs:
            variability = Fmi2Variability.continuous if port.type == "Real" else Fmi2Variability.discrete
            self._register(port, Fmi2Causality.input, variability, None)
        for port in cls.outputs:
            variability = Fmi2Variability.continuous if port.type == "Real" else Fmi2Variability.discrete
            self._register(port, Fmi2Causality.output, variability, None)

    def _register(self, port, causality, variability, initial):
        name = port.name
        self._values[name] = port.default()
        self._units[name] = port.unit
        values = self._values
        var = _VAR_CLASSES[port.type](
            name,
            causality=causality,
            variability=variability,
            initial=initial,
            description=port.description or None,
            getter=lambda: values[name],
            setter=lambda v: values.__setitem__(name, v),
        )
        self.register_variable(var, nested=False)

    # -- life cycle -----------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time, tolerance):
        self._start_time = float(start_time)

    def exit_initialization_mode(self):
        params = {p.name: self._values[p.name] for p in self.component_class.parameters}
        try:
            self._component = self.component_class(**params)
            self._values.update(self._component.initialize(self._start_time))
        except NavcoreError as exc:
            self._fail(str(exc))
        except Exception as exc:  # a bug, not a user error: still never crash the host
            self._fail(f"internal error during initialization: {exc!r}\n{traceback.format_exc()}")

    def do_step(self, current_time, step_size):
        if self._failed is not None:
            self.log(f"{self.instance_name}: refusing to step after an earlier error: {self._failed}",
                     Fmi2Status.error)
            return False
        values = self._values
        try:
            inputs = {n: values[n] for n in self._input_names}
            values.update(self._component.step(current_time, step_size, inputs))
        except NavcoreError as exc:
            self._fail(f"t={current_time:.6g} s: {exc}")
            return False
        except Exception as exc:
            self._fail(f"t={current_time:.6g} s: internal error: {exc!r}\n{traceback.format_exc()}")
            return False
        return True

    def _fail(self, message):
        self._failed = message
        self.log(f"{self.instance_name}: {message}", Fmi2Status.error)

    # -- FMU state: the registered values plus the whole component ----------------------
    def _get_fmu_state(self):
        blob = pickle.dumps((self._component, self._failed, self._start_time), protocol=4)
        return {"values": dict(self._values), "component": base64.b64encode(blob).decode("ascii")}

    def _set_fmu_state(self, state):
        self._values.clear()
        self._values.update(state["values"])
        self._component, self._failed, self._start_time = pickle.loads(
            base64.b64decode(state["component"]))

    # -- model description: units, legal attributes -------------------------------------
    def to_xml(self, model_options=dict()):
        options = dict(model_options)
        options.setdefault("canGetAndSetFMUstate", True)
        options.setdefault("canSerializeFMUstate", True)
        root = super().to_xml(options)
        cosim = root.find("CoSimulation")
        cosim.set("canGetAndSetFMUstate", "true")
        cosim.set("canSerializeFMUstate", "true")
        used_units = []
        output_indices = []
        for index, sv in enumerate(root.find("ModelVariables"), start=1):
            name = sv.get("name")
            child = sv[0] if len(sv) else None
            unit = self._units.get(name, "")
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
