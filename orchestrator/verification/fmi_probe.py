"""The FMI probes that load the FMU under test, run in a child process of their own
(``python -m orchestrator.verification.fmi_probe JOB.json``) so that an FMU which crashes
its host ends that child, not the verification: the parent reads the child's last stdout
line (JSON) or, when there is none, reports how the child ended.

Probes, each on fresh instances driven through raw fmpy calls:

* ``state``: step through the input table; at its middle get the FMU state (and serialize
  it); continue to the end (run A); set the state back and run the second half again (B);
  deserialize the bytes into a new instance and run it (C).  B and C must equal A bit for bit.
* ``variable_step``: the table coarsened ``k`` times (increments summed over ``k`` rows,
  other inputs sampled at the end of each coarse interval); ``k`` steps of one period on the
  held coarse inputs (the last one seeing the new sample, as Gauss-Seidel delivers it) against
  one step of ``k`` periods; outputs compared bit for bit at the coarse instants.
* ``hostile``: an unknown value reference read, an output set, a step back in time; each
  must return an error status (fmi2Discard or worse), and the child must live on.

Nothing here imports navcore's algorithms: the probes need nothing of navfmu inside the
FMU.  FMI 3.0 FMUs are probed through fmpy's ``FMU3Slave`` with the same calls.
"""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np

from ..cosim.fmi3_variables import FMI3_TYPES
from ..cosim.source_fmus import ensure_binary

INCREMENTS = ("imu_dtheta_x", "imu_dtheta_y", "imu_dtheta_z", "imu_dvel_x", "imu_dvel_y",
              "imu_dvel_z")
RATES = {"imu_gyro_x": "imu_dtheta_x", "imu_gyro_y": "imu_dtheta_y",
         "imu_gyro_z": "imu_dtheta_z", "imu_accel_x": "imu_dvel_x",
         "imu_accel_y": "imu_dvel_y", "imu_accel_z": "imu_dvel_z"}
ERROR_STATUS = 2  # Discard or worse (fmi2 and fmi3 alike) counts as a refusal


AUTHORING = "docs/guide/authoring_fmus.md#packaging-the-slaves-own-code-a-second-instance-must-work"


class SecondInstanceError(RuntimeError):
    """The second instance of the FMU in this process failed where the first did not."""


def second_instance_message(model: str, exc) -> str:
    """What a failed instantiation after a successful one in the same process means."""
    return (f"the second instance of {model} in one process failed to instantiate, the first "
            f"did not ({exc}): the FMU's code shares state between its instances, typically a "
            "pythonfmu slave importing a module of its own project, which lives in the "
            "process's one sys.modules; package the module in the FMU's resources under a name "
            f"private to the FMU, or keep the slave's code in its one script (see {AUTHORING})")


class Instance:
    """One initialized instance of the FMU (FMI 2.0 or 3.0), with its variables grouped by
    their connector type (:mod:`orchestrator.cosim.fmi3_variables` maps FMI 3.0's).  A failed
    instantiation after a successful one in this process says what that means
    (:func:`second_instance_message`)."""

    #: instances created in this process so far
    created = 0

    def __init__(self, path, md, unzip, name, parameters, in_initialization=None,
                 parameters_first=False):
        """``in_initialization(self)``: called in initialization mode, the parameters set;
        ``parameters_first``: set them before entering initialization mode (as fmpy's
        simulate_fmu and our master do), else in initialization mode."""
        self.md = md
        self.fmi3 = md.fmiVersion == "3.0"
        self.vars = {v.name: v for v in md.modelVariables}
        if self.fmi3:
            from fmpy.fmi3 import FMU3Slave as Slave
        else:
            from fmpy.fmi2 import FMU2Slave as Slave
        self.fmu = Slave(guid=md.guid, unzipDirectory=unzip, instanceName=name,
                         modelIdentifier=md.coSimulation.modelIdentifier)
        try:
            self.fmu.instantiate()
        except Exception as exc:
            if Instance.created:
                raise SecondInstanceError(second_instance_message(md.modelName, exc)) from None
            raise
        Instance.created += 1
        if not self.fmi3:
            self.fmu.setupExperiment(startTime=0.0)
        if parameters_first:
            for key, value in parameters.items():
                self.set(key, value)
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.enterInitializationMode()
        if not parameters_first:
            for key, value in parameters.items():
                self.set(key, value)
        # the outputs by connector type, within one by FMI type (fmpy's get<type> for each)
        self.groups = []
        for kind in ("Real", "Integer", "Boolean"):
            by_type = {}
            for v in md.modelVariables:
                if v.causality == "output" and self.kind(v) == kind:
                    by_type.setdefault(v.type, []).append(v)
            self.groups += list(by_type.items())
        if in_initialization is not None:
            in_initialization(self)
        self.fmu.exitInitializationMode()

    def kind(self, v) -> str:
        """The connector type of ``v``."""
        return FMI3_TYPES.get(v.type, v.type) if self.fmi3 else v.type

    def set(self, name, value):
        v = self.vars[name]
        cast = {"Real": float, "Integer": int, "Boolean": bool, "String": str}[self.kind(v)]
        getattr(self.fmu, "set" + v.type)([v.valueReference], [cast(value)])

    def read(self):
        """All outputs as one float64 vector (Integers and Booleans as numbers)."""
        parts = [np.asarray(getattr(self.fmu, "get" + typ)([v.valueReference for v in vs]),
                            dtype=float) for typ, vs in self.groups]
        return np.concatenate(parts) if parts else np.zeros(0)

    def output_names(self):
        return [v.name for _, vs in self.groups for v in vs]

    def state(self, verb, *args):
        """fmpy's ``<verb>FMUstate`` (FMI 2.0) or ``<verb>FMUState`` (FMI 3.0) call."""
        if verb == "deserialize" and not self.fmi3:
            verb = "deSerialize"
        return getattr(self.fmu, f"{verb}FMU{'S' if self.fmi3 else 's'}tate")(*args)

    def run(self, table, k0, k1, h):
        rows = []
        names = [n for n in table if n in self.vars and self.vars[n].causality == "input"]
        for k in range(k0, k1):
            for n in names:
                self.set(n, table[n][k])
            self.fmu.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            rows.append(self.read())
        return np.array(rows)

    def free(self):
        try:
            self.fmu.terminate()
            self.fmu.freeInstance()
        except Exception:
            pass


def _difference(a, b, names, h, k0):
    """None when a and b are equal bit for bit, else where they first differ."""
    if a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64)):
        return None
    if a.shape != b.shape:
        return {"what": f"{len(a)} rows against {len(b)}"}
    rows, cols = np.nonzero(a.view(np.uint64) != b.view(np.uint64))
    r, c = int(rows[0]), int(cols[0])
    with np.errstate(invalid="ignore"):
        worst = float(np.nanmax(np.abs(a - b)))
    return {"what": f"{names[c]} at t = {(k0 + r + 1) * h:.6g} s: {float(a[r, c])!r} "
                    f"against {float(b[r, c])!r}", "max_abs_difference": worst}


def probe_state(path, md, unzip, parameters, table, h):
    n = len(next(iter(table.values())))
    k0 = n // 2
    first = Instance(path, md, unzip, "state_a", parameters)
    names = first.output_names()
    first.run(table, 0, k0, h)
    state = first.state("get")
    result = {"steps": n, "restored_at_s": k0 * h}
    blob = first.state("serialize", state) if md.coSimulation.canSerializeFMUstate else None
    a = first.run(table, k0, n, h)
    first.state("set", state)
    b = first.run(table, k0, n, h)
    result["set_state"] = _difference(a, b, names, h, k0)
    first.free()
    if blob is not None:
        second = Instance(path, md, unzip, "state_c", parameters)
        restored = second.state("deserialize", blob)
        second.state("set", restored)
        c = second.run(table, k0, n, h)
        result["serialized_bytes"] = len(blob)
        result["deserialize"] = _difference(a, c, names, h, k0)
        second.free()
    return result


def coarsen(table, k):
    """The input table with ``k`` rows merged into one (see the module docstring)."""
    n = len(next(iter(table.values()))) // k
    out = {}
    for name, values in table.items():
        x = np.asarray(values, dtype=float)[:n * k].reshape(n, k)
        if name in INCREMENTS:
            out[name] = x.sum(axis=1)
        elif name == "imu_dt":
            out[name] = x.sum(axis=1)
        else:
            out[name] = x[:, -1]
    if "imu_dt" in out:
        for rate, increment in RATES.items():
            if rate in out and increment in out:
                out[rate] = out[increment] / out["imu_dt"]
    return out


def probe_variable_step(path, md, unzip, parameters, table, h, k):
    coarse = coarsen(table, k)
    n = len(next(iter(coarse.values())))
    held = {name: np.repeat(np.concatenate([[v[0]], v[:-1]]), k) for name, v in coarse.items()}
    for name in held:            # the last fine step of each interval sees the new sample
        held[name][k - 1::k] = coarse[name]
    fine = Instance(path, md, unzip, "fine", parameters)
    a = fine.run(held, 0, n * k, h)[k - 1::k]
    big = Instance(path, md, unzip, "coarse", parameters)
    b = big.run(coarse, 0, n, h * k)
    names = fine.output_names()
    fine.free()
    big.free()
    diff = _difference(a, b, names, h * k, 0)
    return {"k": k, "coarse_steps": n, "difference": diff}


def _status(call):
    from fmpy.fmi1 import FMICallException

    try:
        call()
    except FMICallException as exc:
        return int(exc.status)
    return 0


def probe_hostile(path, md, unzip, parameters, table, h):
    cases = {}
    real = "Float64" if md.fmiVersion == "3.0" else "Real"
    outputs = [v for v in md.modelVariables if v.causality == "output" and v.type == real]
    top = max(v.valueReference for v in md.modelVariables) + 1000
    inst = Instance(path, md, unzip, "hostile_vr", parameters)
    cases["unknown value reference"] = _status(lambda: getattr(inst.fmu, "get" + real)([top]))
    inst.free()
    if outputs:
        inst = Instance(path, md, unzip, "hostile_set", parameters)
        cases["set of an output"] = _status(
            lambda: getattr(inst.fmu, "set" + real)([outputs[0].valueReference], [0.5]))
        inst.free()
    inst = Instance(path, md, unzip, "hostile_back", parameters)
    inst.run(table, 0, 2, h)
    cases["step back in time"] = _status(
        lambda: inst.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=h))
    inst.free()
    return {"statuses": cases, "error_status_from": ERROR_STATUS}


def main(job_file):
    from fmpy import extract, read_model_description

    with open(job_file, encoding="utf-8") as f:
        job = json.load(f)
    data = np.load(job["table"])
    table = {name: data[name] for name in data.files}
    md = read_model_description(job["fmu"], validate=False)
    unzip = extract(job["fmu"])
    probe = {"state": probe_state, "variable_step": probe_variable_step,
             "hostile": probe_hostile}[job["probe"]]
    extra = {"k": job["k"]} if job["probe"] == "variable_step" else {}
    try:
        ensure_binary(Path(job["fmu"]), md, Path(unzip), job["probe"])
        result = probe(job["fmu"], md, unzip, job["parameters"], table, job["h"], **extra)
    except Exception as exc:   # an FMI error status on a legal call, or a broken FMU
        result = {"error": str(exc) if isinstance(exc, SecondInstanceError)
                  else f"{type(exc).__name__}: {exc}"}
    print(json.dumps(result), flush=True)
    # the instances' shared libraries stay loaded; leave their files to the OS at exit
    shutil.rmtree(unzip, ignore_errors=True)


if __name__ == "__main__":
    main(sys.argv[1])
