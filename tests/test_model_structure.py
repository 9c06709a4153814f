"""Every built FMU's declared dependencies (ModelStructure) against its behaviour.

An importer orders its initialization and detects algebraic loops from the Outputs' and the
InitialUnknowns' ``dependencies``; a declared independence that is false makes it read a stale
value.  For each FMU (its default parameters) and each input, one at a time, perturbed from
two baselines (the inputs' start values, and plausible non-zero values with the time tags at
the start time):

* InitialUnknowns: the input set in initialization mode; an output that differs from the
  baseline's, read in initialization mode or after fmi2ExitInitializationMode, must declare
  the input; an exit the FMU refuses for that value shows that it reads the input there, so
  some output must declare it;
* Outputs: after fmi2ExitInitializationMode (a communication point), the input set without a
  doStep; an output that changes must declare it.

Declared dependencies that the perturbations do not show are allowed where the component
reads the input: ImuSensor's magnetometer outputs declare every truth input (any non-zero one
makes the inputs a start sample), but from the plausible baseline only the attitude changes
them.  ImuSensor runs with its magnetometer on (off by default: then nothing would show).
"""
from __future__ import annotations

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from test_fmus import FMU_NAMES, dist  # noqa: F401  (dist: the built FMUs, once a session)

#: parameters other than the defaults, so that a dependence can show
PARAMETERS = {"ImuSensor": {"mag_field_T": 5e-5}}


def _plausible(variable):
    """A non-zero input value inside every component's accepted range (time tags: 0)."""
    name = variable.name
    if variable.type == "Boolean":
        return True
    if variable.type == "Integer":
        return 1
    if name.endswith("_time"):
        return 0.0
    if name.endswith("_dt"):
        return 0.01
    if name.endswith("_lat"):
        return 0.7
    if name.endswith("_lon"):
        return 2.0
    if name.endswith("_h"):
        return 100.0
    return 0.05


_TYPES = {"Real": float, "Integer": int, "Boolean": lambda text: text in (True, "true")}


def _perturbed(variable, value):
    if variable.type == "Boolean":
        return not value
    if variable.type == "Integer":
        return value + 1
    return value + 1e-3 * (1.0 + abs(value))


class _Probe:
    """One instance of an FMU, reset before each initialization."""

    def __init__(self, path, tmp_path, parameters):
        self.md = read_model_description(str(path))
        self.parameters = [(v, parameters[v.name]) for v in self.md.modelVariables
                           if v.name in parameters]
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=extract(str(path), tmp_path),
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName="probe")
        self.fmu.instantiate()
        self.inputs = [v for v in self.md.modelVariables if v.causality == "input"]
        self.outputs = [v for v in self.md.modelVariables if v.causality == "output"]

    def set(self, variable, value):
        getattr(self.fmu, f"set{variable.type}")([variable.valueReference], [value])

    def read(self):
        return {v.name: getattr(self.fmu, f"get{v.type}")([v.valueReference])[0]
                for v in self.outputs}

    def initialize(self, values):
        """(outputs in initialization mode, outputs after exit or None if it was refused)
        with the inputs ``values`` (name -> value) set in initialization mode."""
        self.fmu.reset()
        self.fmu.setupExperiment(startTime=0.0)
        for v, value in self.parameters:
            self.set(v, value)
        self.fmu.enterInitializationMode()
        for v in self.inputs:
            self.set(v, values[v.name])
        during = self.read()
        try:
            self.fmu.exitInitializationMode()
        except FMICallException:
            return during, None
        return during, self.read()


def _changed(before, after):
    """The outputs whose values differ (NaN equals NaN)."""
    return {n for n, x in after.items() if not (x == before[n] or x != x and before[n] != x)}


def _declared(unknowns, causality):
    """Unknown name -> the names of its declared dependencies of ``causality``."""
    return {u.variable.name: {v.name for v in u.dependencies if v.causality == causality}
            for u in unknowns}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_declared_dependencies_hold(dist, name, tmp_path):
    probe = _Probe(dist / f"{name}.fmu", tmp_path, PARAMETERS.get(name, {}))
    initial = _declared(probe.md.initialUnknowns, "input")
    outputs = _declared(probe.md.outputs, "input")
    assert set(initial) == set(outputs) == {v.name for v in probe.outputs}
    # the start outputs are computed from the parameters: every one is declared, and nothing
    # but inputs and parameters (the knowns of initialization mode)
    parameters = {v.name for v in probe.md.modelVariables if v.causality == "parameter"}
    assert all({v.name for v in u.dependencies} - initial[u.variable.name] == parameters
               for u in probe.md.initialUnknowns)
    assert all(u.dependencies == [] for u in probe.md.outputs)
    read_at_exit = set().union(*initial.values())
    if not probe.inputs:   # a source (TrajectoryImu, ImuGnssReplay): nothing to perturb
        assert not read_at_exit
        return
    shown = {}   # input -> outputs it changed in initialization
    for baseline in ({v.name: v.start if v.start is not None else 0 for v in probe.inputs},
                     {v.name: _plausible(v) for v in probe.inputs}):
        typed = {v.name: _TYPES[v.type](baseline[v.name]) for v in probe.inputs}
        during0, exit0 = probe.initialize(typed)
        assert exit0 is not None, f"{name}: the baseline {typed} is refused"
        for v in probe.inputs:
            during, after = probe.initialize({**typed, v.name: _perturbed(v, typed[v.name])})
            if after is None:
                assert v.name in read_at_exit, (
                    f"{name}: a refused exit shows that '{v.name}' is read in initialization, "
                    "but no InitialUnknown declares it")
                continue
            for out in _changed(during0, during) | _changed(exit0, after):
                shown.setdefault(v.name, set()).add(out)
                assert v.name in initial[out], (
                    f"{name}: InitialUnknown '{out}' changes with input '{v.name}' but does "
                    "not declare it")
        # Outputs: an input set at a communication point, without a doStep
        probe.initialize(typed)
        before = probe.read()
        for v in probe.inputs:
            probe.set(v, _perturbed(v, typed[v.name]))
            for out in _changed(before, probe.read()):
                assert v.name in outputs[out], (
                    f"{name}: output '{out}' changes with input '{v.name}' between steps but "
                    "does not declare it")
            probe.set(v, typed[v.name])
    probe.fmu.terminate()
    probe.fmu.freeInstance()
