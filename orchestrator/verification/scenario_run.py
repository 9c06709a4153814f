"""One scenario run of a verification, as a task: the scenario with one component swapped
for the FMU under test (or a reference FMU of ours), with parameter overrides, summarized
into plain numbers (metrics over the whole run and over named windows, the growth of the
position error over a window, the GNSS fix errors, whether every output stayed finite).

:func:`run_isolated` runs the task in a child process (``python -m
orchestrator.verification.scenario_run JOB.json``): an FMU that crashes its host ends that
child and the run reports the crash as its error; a refused step (an FMI error status) is
reported the same way.  :func:`summarize_run` is what the child computes.
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
import warnings
from typing import Any, Dict

import numpy as np

from navcore.ins.earth import radii

from ..cosim.isolation import ISOLATE_MODES, Isolation
from ..errors import NavfmuError
from ..model.receiver_wiring import connect_receiver_attitude
from ..results import metrics
from ..results.jsonsafe import jsonable
from ..running import scenarios
from .run_failures import crash_failure, failure_of
from .sensor_checks import allan_curves
from .verdicts import run_child
from . import vehicle_probe

MODULE = "orchestrator.verification.scenario_run"


def run_isolated(job: Dict[str, Any]) -> Dict[str, Any]:
    """The summary of ``job`` computed in a child process (``{"error": ..., "failure": ...}``
    on a failure); that child is the FMU's host already, so it runs every FMU in its own
    process.  A child that dies (a crash, not a refused step) is run once more; a second
    death is the run's ``failure`` with ``crashed`` set."""
    job = dict(job, isolation="never")
    result = run_child(MODULE, job)
    if result.get("crashed"):
        result = run_child(MODULE, job)
        if result.get("crashed"):
            result["failure"] = crash_failure(result["error"] + " (twice: retried once)")
    return result


def run_job(job: Dict[str, Any], isolated: bool) -> Dict[str, Any]:
    """One run of a check (an executor task): in a child process when ``isolated``, else
    here (a reference of ours), a user error then becoming the run's ``error``."""
    if isolated:
        return run_isolated(job)
    try:
        return summarize_run(job)
    except NavfmuError as exc:
        return {"error": str(exc).splitlines()[0], "failure": failure_of(exc)}


def _position_error_norm(errors):
    return np.sqrt(errors["pos_n"] ** 2 + errors["pos_e"] ** 2 + errors["pos_d"] ** 2)


def _growth(results, component, window):
    """3-D position error at the window's start and its largest value inside it [m]."""
    e = metrics.navigation_errors(results, component)
    if "pos_n" not in e:
        return None
    norm = _position_error_norm(e)
    t = e["time"]
    inside = e["valid"] & metrics.time_mask(t, window)
    if not inside.any():
        return None
    start = float(norm[inside][0])
    return {"start_m": start, "max_m": float(np.max(norm[inside])),
            "growth_m": float(np.max(norm[inside]) - start)}


def _fix_errors(results, receiver):
    """NED errors of every new fix of ``receiver`` against the truth at its gnss_time."""
    truth = metrics.find_component(results, "truth_", ("time", "lat", "lon", "h"))
    col = results.column
    epoch = col(receiver, "gnss_epoch")
    rows = np.nonzero(np.diff(epoch) != 0)[0] + 1
    t_fix = col(receiver, "gnss_time")[rows]
    t_truth = col(truth, "truth_time")
    keep = np.concatenate([[True], np.diff(t_truth) > 0])

    def at_fix(name):
        return np.interp(t_fix, t_truth[keep], col(truth, name)[keep])

    lat, lon, h = at_fix("truth_lat"), at_fix("truth_lon"), at_fix("truth_h")
    rn, re = radii(lat)
    out = {"time": t_fix,
           "pos_n": (col(receiver, "gnss_lat")[rows] - lat) * (rn + h),
           "pos_e": (col(receiver, "gnss_lon")[rows] - lon) * (re + h) * np.cos(lat),
           "pos_d": -(col(receiver, "gnss_h")[rows] - h),
           "valid": col(receiver, "gnss_valid")[rows] > 0.5}
    for a in "ned":
        out["vel_" + a] = col(receiver, f"gnss_v{a}")[rows] - at_fix(f"truth_v{a}")
    if results.has(receiver, "gnss_outlier"):
        out["outlier"] = col(receiver, "gnss_outlier")[rows] > 0.5
    return {k: np.asarray(v).tolist() for k, v in out.items()}


#: the pose a static IMU with truth inputs is held at (the static profile's start)
STATIC_POSE = {"truth_lat": math.radians(40.1), "truth_lon": math.radians(118.6),
               "truth_h": 100.0}
_INCREMENTS = tuple(f"imu_{q}_{a}" for q in ("dtheta", "dvel") for a in "xyz")


def imu_static(job: Dict[str, Any]) -> Dict[str, Any]:
    """The IMU FMU alone, standing still, for ``job["stop"]`` s: the Allan deviation of its
    rates (:func:`.sensor_checks.allan_curves`)."""
    from fmpy import read_model_description, simulate_fmu

    md = read_model_description(job["fmu"], validate=False)
    params = job["parameters"]
    h = float(params.get("imu_period") or md.defaultExperiment.stepSize)
    names = {v.name: v for v in md.modelVariables}
    inputs = [n for n, v in names.items() if v.causality == "input"]
    signal = None
    if inputs:
        t = np.array([0.0, job["stop"]])
        columns = [("time", float)] + [(n, float) for n in inputs]
        signal = np.zeros(2, dtype=columns)
        signal["time"] = t
        for n in inputs:
            signal[n] = t if n == "truth_time" else STATIC_POSE.get(n, 0.0)
    rows = simulate_fmu(job["fmu"], validate=False, stop_time=job["stop"], step_size=h,
                        output_interval=h, start_values=params, input=signal,
                        output=["imu_time", "imu_dt", *_INCREMENTS])
    new = np.concatenate([[False], np.diff(rows["imu_time"]) > 0])
    dt = rows["imu_dt"][new]
    rates = {n: (rows[n][new] / dt).tolist() for n in _INCREMENTS}
    return {"samples": int(new.sum()), "allan": allan_curves(rates, float(np.median(dt)))}


def without_absent_inputs(model, component):
    """``model`` without the connections into inputs ``component``'s FMU does not have (a
    vehicle flying on its own, without the guided vehicle's ``nav_*`` inputs)."""
    from fmpy import read_model_description

    names = {v.name for v in read_model_description(
        str(model.component(component).source), validate=False).modelVariables}
    kept = [c for c in model.connections
            if c.end_component != component or c.end_connector in names]
    return dataclasses.replace(model, connections=kept)


def summarize_run(job: Dict[str, Any]) -> Dict[str, Any]:
    """Run ``job`` in this process and summarize it (see the module docstring)."""
    if job.get("kind") == "imu_static":
        return imu_static(job)
    if job.get("kind") == "vehicle_trajectory":
        return vehicle_probe.record(job)
    model = scenarios.load_scenario(job["ssd"])
    if job.get("fmu"):
        swapped = job.get("swap", job["component"])
        model = model.replace_source(swapped, job["fmu"])
        if job.get("prune_inputs"):
            model = without_absent_inputs(model, swapped)
    if job.get("receiver_attitude"):
        model = connect_receiver_attitude(model, job["receiver_attitude"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            run = scenarios.simulate_scenario(model, backend=job.get("backend", "fmu"),
                                              stop_time=job.get("stop"),
                                              parameters=job.get("parameters") or {},
                                              build=False, log=lambda m: None,
                                              isolation=Isolation(job.get("isolation",
                                                                          ISOLATE_MODES[0])))
        except NavfmuError as exc:
            return {"error": str(exc).splitlines()[0], "failure": failure_of(exc)}
    results = run.results
    component = job["component"]
    out: Dict[str, Any] = {}
    data = results.data[component]
    bad = [n for n, ok in zip(results.columns[component], np.isfinite(data).all(axis=0))
           if not ok]
    out["nonfinite"] = bad
    if bad:
        rows = np.nonzero(~np.isfinite(data).all(axis=1))[0]
        out["nonfinite_time"] = float(results.time[rows[0]])
    if job.get("kind") == "receiver":
        out["fixes"] = _fix_errors(results, component)
        return out
    if bad:
        return out
    out["metrics"] = metrics.filter_metrics(results, component)
    out["windows"] = {name: metrics.filter_metrics(results, component, window=tuple(w))
                      for name, w in (job.get("windows") or {}).items()}
    if job.get("growth"):
        out["growth"] = _growth(results, component, tuple(job["growth"]))
    return out


def main(job_file):
    with open(job_file, encoding="utf-8") as f:
        job = json.load(f)
    print(json.dumps(jsonable(summarize_run(job))), flush=True)
    sys.stderr.flush()
    # the answer is out: end here, without the interpreter's finalization, which a failed
    # pythonfmu instance's leftover objects can crash (SIGSEGV after a Python exception in
    # its do_step), turning a reported failure into a host crash
    os._exit(0)


if __name__ == "__main__":
    main(sys.argv[1])
