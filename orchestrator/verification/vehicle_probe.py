"""The recording of a vehicle FMU under test: its outputs in initialization mode (the
parameters set before it, as fmpy and our master set them), after
``fmi2ExitInitializationMode`` (before any ``doStep``) and along a flight at two
communication steps, ``h`` and ``h / refine``, through raw fmpy calls on fresh instances.

A vehicle with inputs of the guided vehicle's contract (``nav_lat``, ...) is guided on its
own truth: before each step every input ``nav_X`` gets the vehicle's last ``truth_X``
output (``nav_time`` its ``truth_time``), as a perfect navigation solution would give it.
The recording runs in the child process of a verification run
(:func:`.scenario_run.summarize_run`, ``kind = "vehicle_trajectory"``); nothing here imports
navcore: the kinematics are judged by the parent (:mod:`.vehicle_checks`).
"""
from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any, Dict

import numpy as np

from .fmi_probe import Instance
from ..cosim.source_fmus import ensure_binary


def _feeds(instance: Instance):
    """input name -> output name of the guidance on the vehicle's own truth."""
    outputs = set(instance.output_names())
    feeds = {}
    for name, v in instance.vars.items():
        if v.causality == "input" and name.startswith("nav_"):
            source = "truth_" + name[len("nav_"):]
            if source in outputs:
                feeds[name] = source
    return feeds


def _fly(path, md, unzip, parameters, h, steps, label):
    """Rows of every output at the end of initialization and after each of ``steps`` steps."""
    in_mode = []
    inst = Instance(path, md, unzip, label, parameters, parameters_first=True,
                    in_initialization=lambda i: in_mode.append(i.read()))
    names = inst.output_names()
    feeds = {i: names.index(o) for i, o in _feeds(inst).items()}
    rows = [inst.read()]
    for k in range(steps):
        for name, column in feeds.items():
            inst.set(name, rows[-1][column])
        try:
            inst.fmu.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        except Exception as exc:     # an FMI error status: where, and what the FMU said
            raise RuntimeError(f"t = {k * h:g} s, fmi2DoStep with step {h:g} s: {exc}") from None
        rows.append(inst.read())
    inst.free()
    return names, in_mode[0], np.array(rows)


def record(job: Dict[str, Any]) -> Dict[str, Any]:
    """``{"names", "in_initialization", "initial", "coarse", "fine"}``: the outputs in
    initialization mode and after it (NaN as None), the flight at ``h`` and the one at
    ``h / refine`` at the instants of the first (rows k * h)."""
    from fmpy import extract, read_model_description

    md = read_model_description(job["fmu"], validate=False)
    unzip = extract(job["fmu"])
    h, refine = float(job["h"]), int(job["refine"])
    steps = int(round(job["duration"] / h))
    try:
        ensure_binary(Path(job["fmu"]), md, Path(unzip), "vehicle")
        names, in_mode, coarse = _fly(job["fmu"], md, unzip, job["parameters"], h, steps,
                                      "coarse")
        _, _, fine = _fly(job["fmu"], md, unzip, job["parameters"], h / refine, steps * refine,
                       "fine")
    except Exception as exc:     # a refused step, or an instance that would not load
        return {"error": str(exc)}
    finally:
        shutil.rmtree(unzip, ignore_errors=True)

    def plain(rows):
        return [[None if not math.isfinite(x) else float(x) for x in row] for row in rows]

    return {"names": names, "h": h, "refine": refine, "in_initialization": plain([in_mode])[0],
            "initial": plain(coarse[:1])[0],
            "coarse": plain(coarse), "fine": plain(fine[::refine])}


__all__ = ["record"]
