"""The checks of an attitude (AHRS) filter on its role's scenario (``ahrs_turntable``: a
static turntable, random vibration from :data:`DISTURBANCE_S`), each against ``UkfAhrs`` on
the same seeds:

* ``consistency``: before the disturbance, the normalized RMS sqrt(mean((e / std)^2)) of
  roll, pitch and yaw (:mod:`orchestrator.metrics`), mean over the seeds, within
  :data:`NORMALIZED_BAND`;
* ``disturbance``: after it, the RMS of roll and pitch over UkfAhrs's (pass up to
  :data:`~.filter_checks.RATIO_PASS`, warn up to :data:`~.filter_checks.RATIO_WARN`), and a
  warning when the filter's sigma falls far below its error there (normalized RMS above
  :data:`OVERCONFIDENT`) without the filter saying so;
* ``timing``: time per step through the FMU against UkfAhrs's.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import List

from ..campaigns import campaign
from ..campaigns import seeds as campaign_seeds
from ..running import scenarios
from ..results.metric_comparisons import pooled_rms
from .filter_cases import failed_run
from .filter_checks import RATIO_PASS, RATIO_WARN, TIME_RATIO_WARN
from .setting import Setting
from .verdicts import Check

REFERENCE = "UkfAhrs"
DISTURBANCE_S = 121.0
NORMALIZED_BAND = (0.5, 1.5)
OVERCONFIDENT = 3.0
LEVEL = ("roll", "pitch")


@dataclass
class Plan:
    seeds: int
    jobs: list


def plan(setting: Setting, runs: int, quick: bool = False) -> Plan:
    """The runs of the attitude checks (one case: ``quick`` changes nothing)."""
    model = setting.model()
    spec = campaign.CampaignSpec(scenario=str(setting.scenario), filters=(REFERENCE,),
                                 runs=runs)
    offsets = campaign_seeds.seed_offsets(spec, campaign_seeds.random_components(model, "direct"))
    reference = str(scenarios.resolve_filter(REFERENCE))
    windows = {"before": [0.0, DISTURBANCE_S - 1.0], "after": [DISTURBANCE_S, 1e9]}
    jobs = []
    for i in range(runs):
        seeds = {f"{c}.seed": s for c, s in campaign_seeds.run_seeds(spec, offsets, i).items()}
        base = {"ssd": str(setting.scenario), "component": setting.component,
                "parameters": seeds, "windows": windows}
        jobs.append((("ahrs", "filter", i), dict(base, fmu=str(setting.facts.path),
                     parameters={**seeds, **setting.component_parameters()}), True))
        jobs.append((("ahrs", REFERENCE, i), dict(base, fmu=reference,
                     backend="fmu" if i == 0 else "direct"), i == 0))
    return Plan(runs, jobs)


def _consistency(mine) -> Check:
    crit = (f"before the disturbance, normalized RMS of roll, pitch, yaw in "
            f"{NORMALIZED_BAND[0]:g}-{NORMALIZED_BAND[1]:g} (mean over the seeds)")
    per = [r["windows"]["before"].get("attitude_normalized_rms") for r in mine]
    if any(p is None for p in per):
        return Check("ahrs.consistency", "attitude consistency", crit, "no std_* outputs",
                     "skip", "the FMU outputs no std_roll/std_pitch/std_yaw")
    means = {a: sum(p[a] for p in per) / len(per) for a in per[0]}
    bad = [f"{a} {v:.2f}" for a, v in means.items()
           if not NORMALIZED_BAND[0] <= v <= NORMALIZED_BAND[1]]
    return Check("ahrs.consistency", "attitude consistency", crit,
                 ", ".join(f"{a} {v:.2f}" for a, v in means.items()),
                 "fail" if bad else "pass", ("outside the band: " + ", ".join(bad)) if bad
                 else "", {"normalized_rms": means})


def _disturbance(mine, theirs) -> Check:
    crit = (f"after the disturbance, RMS of roll and pitch over {REFERENCE}'s on the same "
            f"seeds: pass <= {RATIO_PASS:g}, warn <= {RATIO_WARN:g}; warn when the "
            f"normalized RMS exceeds {OVERCONFIDENT:g}")
    value = {a: pooled_rms([r["windows"]["after"]["attitude_rms_deg"][a] for r in mine])
             for a in LEVEL}
    ref = {a: pooled_rms([r["windows"]["after"]["attitude_rms_deg"][a] for r in theirs])
           for a in LEVEL}
    ratio = max(value[a] / ref[a] for a in LEVEL)
    verdict = "pass" if ratio <= RATIO_PASS else ("warn" if ratio <= RATIO_WARN else "fail")
    reasons = [] if verdict == "pass" else [f"{ratio:.2f} times {REFERENCE}'s error"]
    normalized = [r["windows"]["after"].get("attitude_normalized_rms") for r in mine]
    if all(n is not None for n in normalized):
        worst = max(sum(n[a] for n in normalized) / len(normalized) for a in LEVEL)
        if worst > OVERCONFIDENT:
            verdict = "fail" if verdict == "fail" else "warn"
            reasons.append(f"its sigma is far below its error after the disturbance "
                           f"(normalized RMS {worst:.1f})")
    measured = ", ".join(f"{a} {value[a]:.3f} deg (ref {ref[a]:.3f})" for a in LEVEL)
    return Check("ahrs.disturbance", "attitude error after the disturbance", crit, measured,
                 verdict, "; ".join(reasons), {"rms_deg": value, "reference_rms_deg": ref})


def _timing(mine, theirs) -> Check:
    crit = f"mean wall time of one do_step through the FMU, over {REFERENCE}'s"
    t_mine = mine[0]["metrics"].get("time_per_step_ms")
    t_ref = theirs[0]["metrics"].get("time_per_step_ms")
    if not t_mine or not t_ref:
        return Check("ahrs.timing", "time per step", crit, "not measured", "skip",
                     "no step time recorded")
    ratio = t_mine / t_ref
    verdict = "warn" if ratio > TIME_RATIO_WARN else "pass"
    return Check("ahrs.timing", "time per step", crit,
                 f"{t_mine * 1e3:.0f} us per step, {REFERENCE} {t_ref * 1e3:.0f} us: ratio "
                 f"{ratio:.2f}", verdict, f"{ratio:.0f} times" if verdict == "warn" else "")


def judge_plan(setting: Setting, planned: Plan, results, workdir):
    mine = [results[("ahrs", "filter", i)] for i in range(planned.seeds)]
    theirs = [results[("ahrs", REFERENCE, i)] for i in range(planned.seeds)]
    failed = failed_run(mine)
    checks: List[Check]
    if failed:
        checks = [Check(f"ahrs.{n}", n, "the runs finish with finite outputs", "run failed",
                        "fail", failed) for n in ("consistency", "disturbance", "timing")]
    elif failed_run(theirs):
        checks = [Check("ahrs.reference", "reference", f"{REFERENCE} runs", "run failed",
                        "fail", failed_run(theirs))]
    else:
        checks = [_consistency(mine), _disturbance(mine, theirs), _timing(mine, theirs)]
    return checks, {}


__all__ = ["plan", "judge_plan"]
