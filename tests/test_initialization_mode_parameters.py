"""A parameter set in initialization mode (FMI 2.0 allows it for fixed parameters, and a
host such as a C master may set them there) counts for the outputs a host reads in
initialization mode, as one set before it does: the outputs read then are those of the
parameters set so far, never those of the ones the component was first started with."""
from __future__ import annotations

import shutil

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from orchestrator.building import build as fmu_build

CASES = [("GuidedUav", "airspeed", 31.0), ("Kf", "init_lat", 0.61)]


def _outputs_in_initialization(unzip, md, name, value, before):
    """The Real outputs read in initialization mode with ``name`` set to ``value`` before
    entering it (``before``) or inside it, and again after exitInitializationMode."""
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, instanceName=f"i{before}",
                    modelIdentifier=md.coSimulation.modelIdentifier)
    variables = {v.name: v for v in md.modelVariables}
    outputs = [v.valueReference for v in md.modelVariables
               if v.causality == "output" and v.type == "Real"]
    fmu.instantiate()
    try:
        fmu.setupExperiment(startTime=0.0)
        if value is not None and before:
            fmu.setReal([variables[name].valueReference], [value])
        fmu.enterInitializationMode()
        default = np.array(fmu.getReal(outputs))
        if value is not None and not before:
            fmu.setReal([variables[name].valueReference], [value])
        during = np.array(fmu.getReal(outputs))
        fmu.exitInitializationMode()
        after = np.array(fmu.getReal(outputs))
        return default, during, after
    finally:
        fmu.terminate()
        fmu.freeInstance()


@pytest.mark.parametrize("model,name,value", CASES)
def test_a_parameter_set_in_initialization_mode_counts_for_its_outputs(tmp_path, model, name,
                                                                       value):
    fmu_build.build(log=None)
    path = fmu_build.fmu_path(model)
    md = read_model_description(str(path))
    unzip = extract(str(path), str(tmp_path / "unzip"))
    try:
        _, plain, _ = _outputs_in_initialization(unzip, md, name, None, True)
        _, set_before, after_before = _outputs_in_initialization(unzip, md, name, value, True)
        stale, set_inside, after_inside = _outputs_in_initialization(unzip, md, name, value,
                                                                      False)
    finally:
        shutil.rmtree(unzip, ignore_errors=True)
    assert not np.array_equal(set_before, plain, equal_nan=True), "pick a parameter that " \
        "changes an output in initialization mode"
    assert np.array_equal(stale, plain, equal_nan=True)
    # read after the set, in initialization mode: the new parameter's outputs, bit for bit
    assert np.array_equal(set_inside, set_before, equal_nan=True)
    assert np.array_equal(after_inside, after_before, equal_nan=True)
