"""What a case of the INS/GNSS filter checks is (:class:`Case`: a scenario with parameter
overrides, its seeds, its references and how it is judged), the values the cases share (run
lengths, the clean receiver, the references), and :func:`failed_run`, which every judge asks
first."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

from .run_failures import full_text, hint, one_line
from .verdicts import Check

#: length of the consistency runs [s]; the other cases end :data:`TAIL_S` after their
#: disturbance (or at :data:`SHORT_S`)
STOP_S = 200.0
TAIL_S = 10.0
SHORT_S = 120.0
REFERENCE, FREE_INERTIAL = "Kf", "InsOnly"
#: the window of the first SHORT_S seconds every consistency run also reports: the
#: cases of that length compare with it (the lever arm)
FIRST = "first"
#: a receiver with white noise only (no noise steps, outlier patches or periodic outliers)
CLEAN_GNSS = {"gnss.noise_steps": "", "gnss.outlier_patches": "", "gnss.outlier_period": 0.0}


@dataclass
class Case:
    """One case: ``metric`` says how it is judged; ``skip`` (a reason) when the FMU or the
    scenario lacks what the case needs (no runs then); ``extra`` goes into every job."""

    name: str
    title: str
    ssd: str
    parameters: Dict[str, Any]
    metric: str
    window: Optional[List[float]] = None
    stop: float = SHORT_S
    seeds: int = 1
    references: tuple = (REFERENCE,)
    extra: Dict[str, Any] = field(default_factory=dict)
    skip: str = ""
    #: parameters only the filter under test and the references get (not the scenario's)
    filter_parameters: Dict[str, Any] = field(default_factory=dict)
    #: a robustness ratio above this warns, above it fails (None: the common bounds)
    ratio_warn: Optional[float] = None
    #: more named windows [start, end] [s] whose metrics every run reports
    windows: Dict[str, List[float]] = field(default_factory=dict)


def _failure(run) -> Optional[Dict[str, Any]]:
    """The failure of one run (:mod:`.run_failures`), or None when it finished finite."""
    if "error" in run:
        return run.get("failure") or {"error": run["error"], "crashed": run.get("crashed"),
                                      "hint": hint(run)}
    if run.get("nonfinite"):
        failure = {"error": f"non-finite outputs {', '.join(run['nonfinite'][:6])}",
                   "time": run.get("nonfinite_time"), "nonfinite": run["nonfinite"]}
        failure["hint"] = hint(failure)
        return failure
    return None


def failed_run(runs) -> Optional[str]:
    """Why the first of ``runs`` that failed did so, on one line (where, why, what to try),
    or None when every run finished with finite outputs."""
    for i, r in enumerate(runs):
        failure = _failure(r)
        if failure:
            return f"seed {i}: {one_line(failure)}"
    return None


def failure_check(cid: str, title: str, criterion: str, runs) -> Optional[Check]:
    """The check's verdict when one of ``runs`` failed: ``crash`` when its host process died
    (twice), else ``fail``; the whole failure in ``details["failure"]``.  None when every
    run finished."""
    for i, r in enumerate(runs):
        failure = _failure(r)
        if failure:
            verdict = "crash" if failure.get("crashed") else "fail"
            return Check(cid, title, criterion, "host crashed" if verdict == "crash" else
                         "run failed", verdict, f"seed {i}: {one_line(failure)}",
                         {"failure": dict(failure, seed=i),
                          "failure_text": full_text(failure)})
    return None


def not_judged(cid: str, case: Case, criterion: str, runs) -> Optional[Check]:
    """The check of ``case`` when it cannot be judged on its merits: ``skip`` (the case's
    reason) or the failure of one of the filter's ``runs`` (:func:`failure_check`)."""
    if case.skip:
        return Check(cid, case.title, criterion, "not run", "skip", case.skip)
    return failure_check(cid, case.title, criterion, runs)


def first_window(model) -> Dict[str, List[float]]:
    """The :data:`FIRST` window of a run of ``model``: its first :data:`SHORT_S` seconds."""
    return {FIRST: [model.start_time, model.start_time + SHORT_S]}


def case_runs(results, case, who):
    """The results of ``who`` ("filter" or a reference) on every seed of ``case``."""
    return [results[(case.name, who, i)] for i in range(case.seeds)]


__all__ = ["Case", "failed_run", "failure_check", "not_judged", "case_runs", "first_window",
           "STOP_S", "TAIL_S", "SHORT_S", "REFERENCE", "FREE_INERTIAL", "CLEAN_GNSS", "FIRST"]
