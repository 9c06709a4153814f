"""The checks of a vehicle FMU: the vehicle contract of docs/guide/vehicle_in_the_loop.md
on a recording of the vehicle alone (:mod:`.vehicle_probe`), then a flight through
``ImuSensor -> GnssReceiver -> Kf`` (the role's scenario, ``uav_mission``, with the vehicle
swapped in and the filter started at the vehicle's initial outputs).

* ``vehicle.initial_outputs``: every output finite in initialization mode (the parameters
  set before it) and after ``fmi2ExitInitializationMode``, before the first ``doStep``, the same in
  both (a master hands them on to ``ImuSensor`` from initialization mode), ``truth_time`` =
  the start time.
* ``vehicle.velocity``: per step, the velocity the change of geodetic position makes against
  the trapezoid of the velocity outputs (:mod:`navcore.ins.truth_consistency`): at most the
  allowance of a rectangle rule (half the velocity change) + :data:`VELOCITY_TOL`.
* ``vehicle.body_rates``: the body rate the attitude change makes (earth and transport rate
  taken off, as the contract's inertial body rates include them) against the trapezoid of
  ``body_rate_*``: at most half their change + :data:`RATE_TOL`; the attitude integrated from
  the body rates alone over the recording is reported beside.
* ``vehicle.specific_force``: the velocity change, Coriolis and WGS-84 normal gravity against
  the trapezoid of ``C_bn specific_force_*``: at most half its change + :data:`FORCE_TOL`
  (a constant 9.81 m/s2 gravity passes; a missing or flipped one does not).
* ``vehicle.step_size``: the recording at ``h`` and at ``h / 2`` agree at the instants of the
  first within :data:`STEP_TOL` (position, velocity, attitude).
* ``vehicle.flight``: the flight finishes (``ImuSensor`` takes the vehicle's truth) and the
  filter's errors are reported; a 3-D position RMS above :data:`FLIGHT_WARN_M` warns.

Units are ``fmi.ports``'s (the role's contract), state save and restore ``fmi.state``'s.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np

from navcore.ins import truth_consistency as tc
from navcore.ins.earth import lla_delta_to_ned

from ..results.metric_comparisons import rms_3d
from .filter_cases import failure_check
from .setting import Setting
from .verdicts import Check

#: length of the recording [s] (``quick``: half)
RECORD_S = 60.0
#: length of the flight through sensors and filter [s] (``quick``: half)
FLIGHT_S = 120.0
#: step refinement of the step-size check
REFINE = 2
VELOCITY_TOL = 0.01      # m/s
RATE_TOL = 1e-4          # rad/s
FORCE_TOL = 0.05         # m/s2
#: position [m], velocity [m/s], attitude [rad] differences the step-size check accepts
STEP_TOL = {"position": 0.05, "velocity": 0.01, "attitude": 1e-3}
FLIGHT_WARN_M = 10.0
STATE = ("lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw")
RATE_NAMES = tuple(f"body_rate_{a}" for a in "xyz")
FORCE_NAMES = tuple(f"specific_force_{a}" for a in "xyz")


@dataclass
class Plan:
    jobs: list
    quick: bool = False
    flight: Dict = field(default_factory=dict)


def plan(setting: Setting, runs: int, quick: bool = False) -> Plan:
    """The recording of the vehicle alone (its flight follows it: :func:`next_jobs`)."""
    scale = 0.5 if quick else 1.0
    job = {"kind": "vehicle_trajectory", "fmu": str(setting.facts.path),
           "parameters": setting.parameters, "h": setting.model().base_step,
           "refine": REFINE, "duration": RECORD_S * scale}
    flight = {"ssd": str(setting.scenario), "component": "filter", "swap": setting.component,
              "fmu": str(setting.facts.path), "prune_inputs": True, "stop": FLIGHT_S * scale,
              "parameters": dict(setting.component_parameters())}
    return Plan([(("trajectory", "vehicle", 0), job, True)], quick, flight)


def next_jobs(setting: Setting, planned: Plan, results):
    """The flight, the filter started at the vehicle's initial outputs (those it has)."""
    record = results[("trajectory", "vehicle", 0)]
    job = dict(planned.flight, parameters=dict(planned.flight["parameters"]))
    initial = dict(zip(record.get("names", ()), record.get("initial", ())))
    for name in STATE:
        value = initial.get("truth_" + name)
        if value is not None:
            job["parameters"][f"filter.init_{name}"] = value
    return [(("flight", "filter", 0), job, True)]


def _columns(record, rows):
    table = np.array(rows, dtype=float)
    return {n: table[:, i] for i, n in enumerate(record["names"])}


def _initial_check(record) -> Check:
    crit = ("every output finite in initialization mode and after fmi2ExitInitializationMode "
            "(before the first doStep), the same in both; truth_time = the start time")
    names = record["names"]
    during, after = record["in_initialization"], record["initial"]
    bad = [n for n, v in zip(names, after) if v is None]
    bad_during = [n for n, v in zip(names, during) if v is None]
    changed = [n for n, a, b in zip(names, during, after)
               if a is not None and b is not None and a != b]
    t0 = dict(zip(names, after)).get("truth_time")
    reasons = ([f"non-finite until the first step: {', '.join(bad[:8])}"] if bad else []) + (
        [f"non-finite in initialization mode: {', '.join(bad_during[:8])}"]
        if bad_during and not bad else []) + (
        [f"in initialization mode not yet the start state: {', '.join(changed[:8])} change "
         "at fmi2ExitInitializationMode"] if changed else []) + (
        [f"truth_time = {t0!r} at the start time 0"] if t0 is not None and t0 != 0.0 else [])
    measured = (f"{len(bad)} non-finite after, {len(bad_during)} non-finite in, "
                f"{len(changed)} changed at the end of initialization mode")
    return Check("vehicle.initial_outputs", "outputs defined from initialization", crit,
                 measured, "fail" if reasons else "pass",
                 "; ".join(reasons) + ("; a master hands them on from initialization mode "
                                       "(docs/guide/authoring_fmus.md)" if reasons else ""),
                 {"nonfinite": bad, "nonfinite_in_initialization": bad_during,
                  "changed": changed})


def _worst(cid, title, crit, mismatch, allowance, tol, unit, t) -> Check:
    excess = mismatch - allowance
    k = int(np.nanargmax(excess))
    measured = (f"worst step (to t = {t[k + 1]:g} s): mismatch {mismatch[k]:.3g} {unit}, "
                f"allowance {allowance[k]:.3g} {unit}")
    ok = bool(np.all(excess <= tol))
    return Check(cid, title, crit, measured, "pass" if ok else "fail",
                 "" if ok else f"{int(np.sum(excess > tol))} of {len(excess)} steps beyond "
                 f"{tol:g} {unit}", {"worst_excess": float(excess[k]), "time": float(t[k + 1]),
                                     "max_mismatch": float(np.nanmax(mismatch))})


def _kinematic_checks(c) -> List[Check]:
    t = c["truth_time"]
    v = np.stack([c["truth_vn"], c["truth_ve"], c["truth_vd"]], axis=-1)
    att = (c["truth_roll"], c["truth_pitch"], c["truth_yaw"])
    checks = [_worst("vehicle.velocity", "velocity against the change of position",
                     f"|position chord / dt - velocity trapezoid| <= |dv|/2 + {VELOCITY_TOL:g} "
                     "m/s every step (WGS-84 radii)",
                     *tc.velocity_mismatch(t, c["truth_lat"], c["truth_lon"], c["truth_h"], v),
                     VELOCITY_TOL, "m/s", t)]
    crit = f"attitude change against the body rates' trapezoid: <= |dw|/2 + {RATE_TOL:g} rad/s"
    if all(n in c for n in RATE_NAMES):
        rates = np.stack([c[n] for n in RATE_NAMES], axis=-1)
        check = _worst("vehicle.body_rates", "attitude against the body rates", crit,
                       *tc.body_rate_mismatch(t, c["truth_lat"], c["truth_h"], v, *att, rates),
                       RATE_TOL, "rad/s", t)
        drift = float(np.max(tc.integrated_attitude_error(t, c["truth_lat"], c["truth_h"], v,
                                                          *att, rates)))
        check.measured += f"; attitude integrated from the rates off by {np.degrees(drift):.3g} deg"
        check.details["integrated_attitude_error_deg"] = float(np.degrees(drift))
        checks.append(check)
    else:
        checks.append(Check("vehicle.body_rates", "attitude against the body rates", crit,
                            "no body rates", "skip", "the FMU outputs no body_rate_x/y/z"))
    crit = (f"dv/dt + Coriolis - normal gravity against C_bn f^b's trapezoid: <= |df|/2 + "
            f"{FORCE_TOL:g} m/s2")
    if all(n in c for n in FORCE_NAMES):
        force = np.stack([c[n] for n in FORCE_NAMES], axis=-1)
        checks.append(_worst("vehicle.specific_force", "specific force against acceleration "
                             "and gravity", crit, *tc.specific_force_mismatch(
                                 t, c["truth_lat"], c["truth_h"], v, *att, force),
                             FORCE_TOL, "m/s2", t))
    else:
        checks.append(Check("vehicle.specific_force", "specific force against acceleration "
                            "and gravity", crit, "no specific force", "skip",
                            "the FMU outputs no specific_force_x/y/z"))
    return checks


def _step_check(record, coarse, fine) -> Check:
    h = record["h"]
    crit = (f"steps of {h:g} s and {h / record['refine']:g} s agree at the common instants: "
            + ", ".join(f"{k} within {v:g}" for k, v in STEP_TOL.items()))
    lat = coarse["truth_lat"]
    d_pos = lla_delta_to_ned(lat, coarse["truth_h"], fine["truth_lat"] - lat,
                             fine["truth_lon"] - coarse["truth_lon"],
                             fine["truth_h"] - coarse["truth_h"])
    diffs = {"position": np.linalg.norm(d_pos, axis=-1),
             "velocity": np.linalg.norm(np.stack([fine[n] - coarse[n] for n in
                                                  ("truth_vn", "truth_ve", "truth_vd")]), axis=0),
             "attitude": np.max(np.abs(np.angle(np.exp(1j * np.stack(
                 [fine[n] - coarse[n] for n in ("truth_roll", "truth_pitch", "truth_yaw")])))),
                 axis=0)}
    worst = {k: float(np.nanmax(d)) for k, d in diffs.items()}
    bad = [k for k, w in worst.items() if not w <= STEP_TOL[k]]
    measured = "largest difference: " + ", ".join(f"{k} {w:.3g}" for k, w in worst.items())
    return Check("vehicle.step_size", "step-size independence", crit, measured,
                 "fail" if bad else "pass",
                 (f"{', '.join(bad)} depend on the communication step (an integrator stepping "
                  "with it; integrate on a grid of the vehicle's own)") if bad else "",
                 {"largest": worst})


def _flight_check(setting, run) -> Check:
    crit = (f"the flight through ImuSensor -> GnssReceiver -> Kf on {setting.scenario.parent.name}"
            f" finishes; 3-D position RMS of Kf <= {FLIGHT_WARN_M:g} m (else warn)")
    title = "flight through sensors and filter"
    broken = failure_check("vehicle.flight", title, crit, [run])
    if broken is not None:
        return broken
    m = run["metrics"]
    rms = {g: rms_3d(m, g) for g in ("position", "velocity", "attitude")}
    measured = (f"Kf RMS: position {rms['position']:.3g} m, velocity {rms['velocity']:.3g} m/s, "
                f"attitude {rms['attitude']:.3g} deg")
    warn = not rms["position"] <= FLIGHT_WARN_M
    return Check("vehicle.flight", title, crit, measured, "warn" if warn else "pass",
                 "the filter's error is large for this receiver: the truth may be "
                 "inconsistent in a way the checks above do not see" if warn else "",
                 {"rms": rms, "metrics": m})


def judge_plan(setting: Setting, planned: Plan, results, workdir):
    record = results[("trajectory", "vehicle", 0)]
    title = "recording of the vehicle alone"
    broken = failure_check("vehicle.recording", title, "the vehicle steps through the "
                           "recording", [record])
    checks = [broken] if broken is not None else []
    if broken is None:      # the kinematics from the first finite row on
        start = 1 if None in record["initial"] else 0
        coarse = _columns(record, record["coarse"][start:])
        fine = _columns(record, record["fine"][start:])
        checks += [_initial_check(record), *_kinematic_checks(coarse),
                   _step_check(record, coarse, fine)]
    checks.append(_flight_check(setting, results[("flight", "filter", 0)]))
    return checks, {}


__all__ = ["plan", "next_jobs", "judge_plan", "RECORD_S", "FLIGHT_S"]
