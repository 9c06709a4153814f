"""The INS/GNSS filter cases of two error sources a third-party filter gets wrong and the
other cases do not show: the GNSS antenna's lever arm and the biases of a MEMS IMU.

* ``lever_arm`` (check ``filter.lever_arm``): the clean scenario of the consistency case
  with the antenna :data:`LEVER_ARM` (forward, right, down) from the IMU, on the receiver
  and on the filter (its ``lever_arm_x/y/z``), the receiver fed the truth attitude it needs
  (:func:`orchestrator.model.receiver_wiring.connect_receiver_attitude`), 120 s.  The
  filter's own runs without the arm (the consistency case's first 120 s, the same seeds)
  are the reference:
  a filter that handles the arm has the same errors with it, one that ignores it is off by
  |l| = 4.6 m, one with its sign flipped by 2 |l|.  The aircraft turns, climbs and
  accelerates, so the arm's NED offset changes and cannot hide in a constant position error.
  A filter without the three parameters (no declared lever arm), or a scenario whose truth
  source has no attitude outputs, skips the case.
* ``mems_imu`` (check ``robust.mems_imu``): the consistency case's scenario with the MEMS IMU
  of ``uav_mission`` (gyro turn-on bias 50 deg/h, ARW 0.3 deg/sqrt(h); accelerometer 2000 ug,
  VRW 100 ug/sqrt(Hz)), the filter told so where it has Kf's parameter names
  (:data:`MEMS_FILTER`), and a 30 s GNSS outage at 100-130 s after 100 s of takeoff, climb
  and acceleration that make the biases observable; the 3-D position RMS over the outage
  against Kf's on the same seeds, failing beyond 2 (no warn band).  The bias estimates carry
  the INS through the outage: a filter that never feeds its gyro-bias estimate back drifts
  about ten times Kf's there (31.3 m against 3.1 m, one seed).  ``uav_mission``'s bias
  instability (20 deg/h, 100 s) is left out: its unestimable part dominates the drift and
  hides the feedback (an outage at 140-170 s: 29.8 m against 17.5 m, 1.7 times).
"""
from __future__ import annotations

import math
from typing import List

from ..errors import NavfmuError
from ..model.receiver_wiring import ATTITUDE, truth_source
from ..results.metric_comparisons import pooled_rms, rms_3d
from .filter_cases import (CLEAN_GNSS, FIRST, SHORT_S, TAIL_S, Case, case_runs, failed_run,
                           first_window, not_judged)
from .setting import Setting
from .verdicts import Check

#: the antenna from the IMU, body forward / right / down [m]: distinct per axis, so a swapped
#: or sign-flipped component shows
LEVER_ARM = {"lever_arm_x": 4.0, "lever_arm_y": 1.0, "lever_arm_z": -2.0}
#: position RMS with the arm over that without: pass up to the first, warn up to the second
LEVER_RATIO_PASS, LEVER_RATIO_WARN = 1.25, 1.5
#: the MEMS IMU of uav_mission (turn-on biases, white noise), on the scenario's truth
MEMS_IMU = {"gyro_bias_dph": 50.0, "gyro_arw_dpsh": 0.3, "accel_bias_ug": 2000.0,
            "accel_vrw_ugpsHz": 100.0}
#: what the filter is told of it (the parameters of that name it has)
MEMS_FILTER = {"p0_gyro_bias_dph": 50.0, "p0_accel_bias_ug": 2000.0, "q_gyro_arw_dpsh": 0.3,
               "q_accel_vrw_ugpsHz": 100.0}
MEMS_OUTAGE = [100.0, 130.0]
#: position RMS over the outage over Kf's beyond which the case fails (no warn band: the
#: estimated biases are what a filter has to carry it through)
MEMS_RATIO_FAIL = 2.0
RECEIVER = "gnss"


def _lever_arm_case(setting: Setting, runs: int) -> Case:
    missing = [n for n in LEVER_ARM if n not in setting.facts.parameters()]
    skip = ""
    if missing:
        skip = (f"the FMU declares no GNSS lever arm (no parameter {', '.join(missing)}; "
                "docs/guide/lever_arm.md)")
    else:
        model = setting.model()
        try:
            source = model.component(truth_source(model, RECEIVER))
        except NavfmuError as exc:   # no receiver fed by a truth: nothing to put the arm on
            source, skip = None, str(exc)
        if source is not None and not all(source.connectors.get(n, ("",))[0] == "output"
                                          for n in ATTITUDE):
            skip = (f"the scenario's truth source '{source.name}' outputs no attitude for the "
                    "receiver's lever arm")
    params = {**CLEAN_GNSS, **{f"{RECEIVER}.{k}": v for k, v in LEVER_ARM.items()}}
    return Case("lever_arm", "GNSS antenna lever arm 4/1/-2 m", str(setting.scenario), params,
                "lever_arm", stop=SHORT_S, seeds=runs, references=(),
                windows=first_window(setting.model()),
                extra={"receiver_attitude": RECEIVER}, skip=skip,
                filter_parameters={f"{setting.component}.{k}": v
                                   for k, v in LEVER_ARM.items()})


def _mems_case(setting: Setting, runs: int) -> Case:
    told = {f"{setting.component}.{k}": v for k, v in MEMS_FILTER.items()
            if k in setting.facts.parameters()}
    params = {**CLEAN_GNSS, "gnss.outages": f"{MEMS_OUTAGE[0]:g},{MEMS_OUTAGE[1]:g}",
              **{f"trajectory.{k}": v for k, v in MEMS_IMU.items()}}
    return Case("mems_imu", "MEMS IMU (turn-on biases) through a 30 s GNSS outage",
                str(setting.scenario), params, "position", list(MEMS_OUTAGE),
                stop=MEMS_OUTAGE[1] + TAIL_S, seeds=runs, filter_parameters=told,
                ratio_warn=MEMS_RATIO_FAIL)


def error_source_cases(setting: Setting, runs: int) -> List[Case]:
    """The lever-arm and MEMS-IMU cases of ``setting`` (see the module docstring)."""
    return [_lever_arm_case(setting, runs), _mems_case(setting, runs)]


def judge_lever_arm(case: Case, results, without: Case) -> Check:
    """``case`` (with the arm) against ``without`` (the consistency case: no arm, the same
    seeds and length) of the same filter."""
    arm = math.sqrt(sum(v * v for v in LEVER_ARM.values()))
    crit = (f"3-D position RMS with the antenna {arm:.1f} m off the IMU (on receiver and "
            f"filter) over the filter's own without it, same {case.seeds} seeds: pass <= "
            f"{LEVER_RATIO_PASS:g}, warn <= {LEVER_RATIO_WARN:g}")
    cid = "filter.lever_arm"
    runs = case_runs(results, case, "filter") if not case.skip else []
    unrun = not_judged(cid, case, crit, runs)
    if unrun:
        return unrun
    # the same seeds: the first of the consistency runs (all of them but with --quick)
    base = (case_runs(results, without, "filter")[:case.seeds] if without is not None
            else None)
    if base is None or failed_run(base):
        return Check(cid, case.title, crit, "no reference", "skip",
                     "the runs without the lever arm (filter.consistency) failed")
    mine = [rms_3d(r["windows"][FIRST], "position") for r in runs]
    ref = [rms_3d(r["windows"][FIRST], "position") for r in base]
    value, reference = pooled_rms(mine), pooled_rms(ref)
    ratio = value / reference if reference > 0 else math.inf
    details = {"filter": mine, "without_lever_arm": ref, "ratio": ratio}
    nees = [(r["windows"][FIRST].get("nees") or {}).get("position") for r in runs]
    measured = f"{value:.3g} m vs {reference:.3g} m without: ratio {ratio:.2f}"
    if all(v is not None for v in nees):
        details["nees_position"] = sum(nees) / len(nees)
        measured += f"; position NEES {details['nees_position']:.1f}"
    verdict = ("pass" if ratio <= LEVER_RATIO_PASS else
               "warn" if ratio <= LEVER_RATIO_WARN else "fail")
    reason = "" if verdict == "pass" else (
        f"the lever arm makes the position RMS {ratio:.2f} times larger (an ignored arm: about "
        f"{arm:.1f} m of error, a sign flipped: twice that)")
    return Check(cid, case.title, crit, measured, verdict, reason, details)


__all__ = ["error_source_cases", "judge_lever_arm", "LEVER_ARM", "MEMS_IMU", "MEMS_OUTAGE"]
