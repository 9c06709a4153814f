"""Calls out of FMI 2.0's call sequence on one built FMU, through fmpy's raw FMI functions.

``python tests/fmi_state_probe.py FMU OUT.jsonl`` runs every case of :data:`CASES` on fresh
instances and appends one JSON line per case to OUT as soon as it ran: its name, the status of
the call out of sequence (0 = fmi2OK, 2 = fmi2Discard, 3 = fmi2Error, 4 = fmi2Fatal, None for a
void function or a NULL instance), the messages logged by that call, and what the case checks
after it.  Run in a subprocess by tests/test_fmi_state_machine.py: a crash (double free,
use after free) ends this process, and the cases after it are missing from OUT, which the test
reports as the crashing case.
"""
from __future__ import annotations

import ctypes
import json
import sys
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2FMUstate, calloc, free)

#: the parameters an FMU needs to initialize, and its Real input a NaN is given to
SETUP = {
    "ImuSensor": ({}, "truth_time"),
    "GnssReceiver": ({}, "truth_lat"),
    "Kf": ({"init_lat": 0.7, "init_h": 100.0}, "imu_dvel_z"),
    "Ukf": ({"init_lat": 0.7, "init_h": 100.0}, "imu_dvel_z"),
    "ImuGnssReplay": ({"log": str(Path(__file__).resolve().parents[1] / "models"
                                  / "replay_gnss_ins_sim" / "log")}, None),
}


class Probe:
    """One FMU, unpacked once; :meth:`fresh` makes an instance with a logger of its own."""

    def __init__(self, fmu):
        self.md = read_model_description(str(fmu))
        self.dir = extract(str(fmu))
        self.name = self.md.modelName
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.type = {v.name: v.type for v in self.md.modelVariables}
        self.logs = []

        def logger(env, inst, status, category, message):
            self.logs.append([status, message.decode(errors="replace")])

        self._logger = fmi2CallbackLoggerTYPE(logger)
        cb = fmi2CallbackFunctions()
        cb.logger = self._logger
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.callbacks = cb
        self.slaves = []

    def slave(self, guid=None):
        s = FMU2Slave(guid=self.md.guid if guid is None else guid, unzipDirectory=self.dir,
                      modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="probe")
        self.slaves.append(s)   # fmpy unloads the library when a slave is collected
        return s

    def fresh(self, phase="stepComplete"):
        """A slave in ``phase``: instantiated, initializationMode or stepComplete."""
        s = self.slave()
        s.instantiate(callbacks=self.callbacks, loggingOn=False)
        if phase == "instantiated":
            return s
        params, _ = SETUP[self.name]
        s.setupExperiment(startTime=0.0)
        for k, v in params.items():
            self.set(s, k, v)
        s.enterInitializationMode()
        if phase == "initializationMode":
            return s
        s.exitInitializationMode()
        return s

    def set(self, s, name, value):
        setter = getattr(s.dll, f"fmi2Set{self.type[name]}")
        ctype = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_int,
                 "String": ctypes.c_char_p}[self.type[name]]
        value = value.encode() if isinstance(value, str) else value
        return setter(s.component, (ctypes.c_uint * 1)(self.vr[name]), 1, (ctype * 1)(value))

    def raw(self, s, function, *args):
        """The status of the raw FMI function (fmpy's wrappers raise on a bad status)."""
        return getattr(s.dll, function)(s.component, *args)

    def get_real(self, s, component=None):
        out = (ctypes.c_double * 1)()
        first = next(v for v in self.md.modelVariables if v.type == "Real")
        return s.dll.fmi2GetReal(s.component if component is None else component,
                                 (ctypes.c_uint * 1)(first.valueReference), 1, out)


def _step(p, s):
    return p.raw(s, "fmi2DoStep", ctypes.c_double(0.0),
                 ctypes.c_double(float(p.md.defaultExperiment.stepSize)), 1)


# -- the cases: each returns (status, what it checks after the call) ----------------------
def case_free_instance_twice(p):
    s = p.fresh()
    c = s.component
    s.dll.fmi2FreeInstance(c)
    s.dll.fmi2FreeInstance(c)
    return None, {"get_after": p.get_real(s, c)}


def case_get_real_after_free_instance(p):
    s = p.fresh()
    c = s.component
    s.dll.fmi2FreeInstance(c)
    return p.get_real(s, c), {}


def case_set_state_after_free_state(p):
    s = p.fresh()
    state = fmi2FMUstate()
    s.dll.fmi2GetFMUstate(s.component, ctypes.byref(state))
    freed = fmi2FMUstate(state.value)
    s.dll.fmi2FreeFMUstate(s.component, ctypes.byref(state))
    status = s.dll.fmi2SetFMUstate(s.component, freed)
    size = ctypes.c_size_t()
    return status, {"serialize_size": s.dll.fmi2SerializedFMUstateSize(s.component, freed,
                                                                        ctypes.byref(size)),
                    "free_again": s.dll.fmi2FreeFMUstate(s.component, ctypes.byref(freed)),
                    "step_after": _step(p, s)}


def case_state_of_a_freed_instance(p):
    a, b = p.fresh(), p.fresh()
    state = fmi2FMUstate()
    a.dll.fmi2GetFMUstate(a.component, ctypes.byref(state))
    a.dll.fmi2FreeInstance(a.component)
    return b.dll.fmi2SetFMUstate(b.component, state), {"step_after": _step(p, b)}


def case_do_step_before_exit_initialization(p):
    s = p.fresh("initializationMode")
    return _step(p, s), {"exit_after": p.raw(s, "fmi2ExitInitializationMode")}


def case_do_step_after_terminate(p):
    s = p.fresh()
    s.dll.fmi2Terminate(s.component)
    return _step(p, s), {"get_after": p.get_real(s)}


def case_enter_initialization_twice(p):
    s = p.fresh("initializationMode")
    return p.raw(s, "fmi2EnterInitializationMode"), {
        "exit_after": p.raw(s, "fmi2ExitInitializationMode"), "step_after": _step(p, s)}


def case_setup_experiment_after_initialization(p):
    s = p.fresh()
    return p.raw(s, "fmi2SetupExperiment", 0, ctypes.c_double(0.0), ctypes.c_double(1.0), 0,
                 ctypes.c_double(0.0)), {"step_after": _step(p, s)}


def case_get_real_when_instantiated(p):
    return p.get_real(p.fresh("instantiated")), {}


def case_set_real_after_terminate(p):
    s = p.fresh()
    s.dll.fmi2Terminate(s.component)
    name = next(v.name for v in p.md.modelVariables
                if v.causality == "parameter" and v.type == "Real")
    return p.set(s, name, 1.0), {}


def case_terminate_twice(p):
    s = p.fresh()
    s.dll.fmi2Terminate(s.component)
    return p.raw(s, "fmi2Terminate"), {}


def case_reset_returns_to_instantiated(p):
    s = p.fresh()
    s.dll.fmi2Terminate(s.component)
    reset = p.raw(s, "fmi2Reset")
    params, _ = SETUP[p.name]
    step_early = _step(p, s)              # instantiated again: doStep is out of sequence
    setup = p.raw(s, "fmi2SetupExperiment", 0, ctypes.c_double(0.0), 0, 0, ctypes.c_double(0.0))
    for k, v in params.items():
        p.set(s, k, v)
    enter, exit_ = p.raw(s, "fmi2EnterInitializationMode"), p.raw(s, "fmi2ExitInitializationMode")
    return reset, {"step_early": step_early, "setup": setup, "enter": enter, "exit": exit_,
                   "step_after": _step(p, s)}


def case_wrong_guid(p):
    s = p.slave(guid="{00000000-0000-0000-0000-000000000000}")
    try:
        s.instantiate(callbacks=p.callbacks, loggingOn=False)
        made = s.component is not None
    except Exception:
        made = False
    return None, {"instantiated": made}


def case_nan_input(p):
    _, name = SETUP[p.name]
    if name is None:
        return None, {"skipped": True}
    s = p.fresh()
    p.set(s, name, float("nan"))
    status = _step(p, s)
    n = len(p.logs)
    return status, {"step_again": _step(p, s), "again_logs": p.logs[n:],
                    "get_after": p.get_real(s), "reset": p.raw(s, "fmi2Reset")}


CASES = {name[5:]: fn for name, fn in globals().items() if name.startswith("case_")}


def main(fmu, out):
    p = Probe(Path(fmu))
    with open(out, "a") as f:
        for name, fn in CASES.items():
            p.logs.clear()
            f.write(json.dumps({"case": name, "started": True}) + "\n")
            f.flush()
            status, after = fn(p)
            f.write(json.dumps({"case": name, "status": status, "logs": p.logs,
                                "after": after}) + "\n")
            f.flush()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
