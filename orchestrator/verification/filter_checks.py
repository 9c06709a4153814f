"""The checks of an INS/GNSS filter, on its role's scenario: noiseless closure, consistency
over N seeds, robustness against ``Kf`` on the same seeds, time per step against ``Kf``.

Every case is the scenario with overrides of its sensor components (``gnss``,
``trajectory``), run to the end of its window plus :data:`TAIL_S` (the closure and the
cases judged over the whole run to :data:`SHORT_S`, the consistency runs to
:data:`STOP_S`); the consistency and robustness cases start from a clean receiver (no
noise steps, outlier patches or periodic outliers), so each case adds
exactly one disturbance:

* ``closure``: IMU and GNSS without any error, one run;
* ``consistency``: the clean scenario, N seeds (:data:`NEES_BAND`, NIS band of
  :func:`orchestrator.metrics.nis_band95`);
* ``noise_step``: GNSS velocity sigma 3 m/s at 60-120 s (judged over 60-130 s);
* ``outlier_patch``: 15 m/s outliers on the east and north velocity at 120-130 s (judged
  over 120-140 s);
* ``outage``: fixes invalid (``gnss_valid`` false) at 140-170 s, and those invalid fixes
  carry gross errors (200 m, 20 m/s), as a receiver's last guesses do: a filter must not use
  them.  The growth of the 3-D position error over the outage is judged against ``Kf``'s
  and ``InsOnly``'s on the same seeds;
* ``late_fixes``: every fix published 0.5 s after it was taken (``output_delay``), with its
  ``gnss_time``;
* ``stationary_start``: the vehicle stands still the whole run (profile ``static``);
* ``high_dynamics``: the scenario ``uav_maneuver`` (its strong manoeuvres), when it fits;
* ``lever_arm`` and ``mems_imu``: an antenna lever arm, a MEMS IMU through an outage
  (:mod:`.error_source_cases`).

The random components get the campaign seeds
(:func:`orchestrator.campaigns.seeds.run_seeds`):
run i of every filter sees the same truth, IMU and GNSS noise.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, List

from ..campaigns import campaign
from ..campaigns import seeds as campaign_seeds
from ..running import scenarios
from ..results.metric_comparisons import pooled_rms, rms_3d
from ..results.metrics import nis_band95
from .setting import MODELS, Setting
from .error_source_cases import error_source_cases, judge_lever_arm
from .filter_cases import (CLEAN_GNSS, FREE_INERTIAL, REFERENCE, SHORT_S, STOP_S, TAIL_S, Case,
                           case_runs, failed_run, failure_check, first_window, not_judged)
from .verdicts import Check

#: noiseless closure bounds: position [m], velocity [m/s], attitude [deg] (largest |error|)
CLOSURE_BOUNDS = {"position_max_m": 0.1, "velocity_max_mps": 0.01, "attitude_max_deg": 0.01}
_UNITS = {"position_max_m": "m", "velocity_max_mps": "m/s", "attitude_max_deg": "deg"}
#: mean NEES of a 3-state group over the seeds: RMS(error / sigma) between 0.5 and 1.5,
#: as the consistency test of Kf judges it (tests/test_kf_consistency.py)
NEES_BAND = (3 * 0.5 ** 2, 3 * 1.5 ** 2)
#: robustness: the filter's error over Kf's on the same seeds; pass up to the first, warn up
#: to the second, fail beyond
RATIO_PASS, RATIO_WARN = 2.0, 5.0
#: outage: growth <= OUTAGE_FACTOR * max(Kf's, InsOnly's) + OUTAGE_SLACK_M
OUTAGE_FACTOR, OUTAGE_SLACK_M = 2.0, 1.0
#: time per step over Kf's above which the timing check warns
TIME_RATIO_WARN = 20.0
#: trajectory parameters a noiseless IMU keeps (everything else bound is an error term)
_KEPT = ("profile", "imu_period", "seed", "extend_profile", "level_reference_g")


def _noiseless(model) -> Dict[str, Any]:
    values = dict(CLEAN_GNSS)
    values.update({f"gnss.{q}_sigma_{a}": 0.0 for q in ("pos", "vel") for a in "ned"})
    for name, (typ, _) in model.component("trajectory").parameters.items():
        if name not in _KEPT and typ == "Real":
            values[f"trajectory.{name}"] = 0.0
    return values


def cases(setting: Setting, runs: int) -> List[Case]:
    """The cases of ``setting`` (see the module docstring)."""
    ssd = str(setting.scenario)
    model = setting.model()
    found = [Case("closure", "noiseless closure", ssd, _noiseless(model), "closure")]
    for path in setting.scenario_paths:
        found.append(Case("consistency" if path == setting.scenario else
                          f"consistency_{path.parent.name}",
                          f"consistency on {path.parent.name}", str(path), dict(CLEAN_GNSS),
                          "consistency", seeds=runs, references=(), stop=STOP_S,
                          windows=first_window(model)))
    robust = [
        ("noise_step", "GNSS velocity-noise step", {"gnss.noise_steps": "60,120,vel,3,3,3"},
         "velocity", [60.0, 130.0]),
        ("outlier_patch", "GNSS outlier patch",
         {"gnss.outlier_patches": "120,130,vel,ne,15"}, "velocity", [120.0, 140.0]),
        ("outage", "30 s GNSS outage", {"gnss.outages": "140,170", "gnss.outlier_patches":
                                        "140,170,pos,ned,200; 140,170,vel,ned,20"},
         "growth", [140.0, 170.0]),
        ("late_fixes", "fixes 0.5 s late", {"gnss.output_delay": 0.5}, "position", None),
        ("stationary_start", "stationary vehicle", {"trajectory.profile": "static"},
         "position", None)]
    for name, title, extra, metric, window in robust:
        refs = (REFERENCE, FREE_INERTIAL) if metric == "growth" else (REFERENCE,)
        found.append(Case(name, title, ssd, {**CLEAN_GNSS, **extra}, metric, window,
                          seeds=runs, references=refs,
                          stop=window[1] + TAIL_S if window else SHORT_S))
    dynamic = MODELS / "uav_maneuver" / "SystemStructure.ssd"
    if dynamic.is_file() and setting.scenario != dynamic.resolve():
        found.append(Case("high_dynamics", "high-dynamics profile (uav_maneuver)",
                          str(dynamic), {}, "position", seeds=runs))
    return found + error_source_cases(setting, runs)


def jobs(setting: Setting, case_list: List[Case], seed: int = 1):
    """``(key, job, isolated)`` for every run: the filter under test in a child process
    (isolated), the references of ours in the worker itself (direct backend, except the
    closure's Kf, which runs through its FMU for the timing check)."""
    out = []
    for case in case_list:
        if case.skip:
            continue
        model = scenarios.load_scenario(case.ssd)
        spec = campaign.CampaignSpec(scenario=case.ssd, filters=(REFERENCE,), runs=case.seeds,
                                     seed=seed)
        offsets = campaign_seeds.seed_offsets(
            spec, campaign_seeds.random_components(model, "direct"))
        for i in range(case.seeds):
            seeds = {f"{c}.seed": s
                     for c, s in campaign_seeds.run_seeds(spec, offsets, i).items()}
            base = {"ssd": case.ssd, "component": setting.component, "stop": case.stop,
                    "parameters": {**case.parameters, **case.filter_parameters, **seeds},
                    "windows": {**({"case": case.window} if case.window else {}),
                                **case.windows},
                    "growth": case.window if case.metric == "growth" else None,
                    **case.extra}
            mine = dict(base, fmu=str(setting.facts.path), parameters={
                **base["parameters"], **setting.component_parameters()})
            out.append(((case.name, "filter", i), mine, True))
            for ref in case.references:
                backend = "fmu" if case.name == "closure" else "direct"
                fmu = str(scenarios.resolve_filter(ref))
                out.append(((case.name, ref, i), dict(base, fmu=fmu, backend=backend),
                            backend == "fmu"))
    return out


# -- judging -----------------------------------------------------------------------------------
def _judge_closure(case, results) -> Check:
    crit = ("perfect IMU and GNSS, filter started at the truth: largest |error| <= "
            + ", ".join(f"{v:g} {_UNITS[k]} ({k.split('_')[0]})"
                        for k, v in CLOSURE_BOUNDS.items()))
    run = case_runs(results, case, "filter")[0]
    broken = failure_check("filter.closure", case.title, crit, [run])
    if broken:
        return broken
    m = run["metrics"]
    worst = {k: max(m[k].values()) for k in CLOSURE_BOUNDS if k in m}
    over = [f"{k.split('_')[0]} {worst[k]:.3g} > {CLOSURE_BOUNDS[k]:g}" for k in worst
            if not worst[k] <= CLOSURE_BOUNDS[k]]
    measured = ", ".join(f"{k.split('_')[0]} {v:.3g}" for k, v in worst.items())
    return Check("filter.closure", case.title, crit, measured, "fail" if over else "pass",
                 "; ".join(over), {"largest_errors": worst})


def _judge_consistency(case, results) -> Check:
    crit = (f"mean NEES per 3-state group in [{NEES_BAND[0]:.2f}, {NEES_BAND[1]:.2f}] over "
            f"{case.seeds} seeds; pooled mean NIS in its chi-square 95 % band")
    cid = "filter." + case.name
    runs = case_runs(results, case, "filter")
    broken = failure_check(cid, case.title, crit, runs)
    if broken:
        return broken
    ms = [r["metrics"] for r in runs]
    parts, problems, details = [], [], {}
    if all("nees" in m for m in ms):
        for g in ms[0]["nees"]:
            values = [m["nees"][g] for m in ms]
            if any(v is None for v in values):
                continue
            mean = sum(values) / len(values)
            details[f"nees_{g}"] = mean
            parts.append(f"NEES {g} {mean:.2f}")
            if not NEES_BAND[0] <= mean <= NEES_BAND[1]:
                problems.append(f"NEES {g} {mean:.2f} "
                                + ("above: overconfident" if mean > NEES_BAND[1]
                                   else "below: pessimistic"))
    if all("nis" in m for m in ms):
        n = sum(m["nis"]["updates"] for m in ms)
        mean = sum(m["nis"]["mean"] * m["nis"]["updates"] for m in ms) / n
        lo, hi = nis_band95(n, ms[0]["nis"]["dof"])
        details.update(nis=mean, nis_band=[lo, hi], nis_dof=ms[0]["nis"]["dof"], updates=n)
        parts.append(f"NIS {mean:.2f} (band {lo:.2f}-{hi:.2f}, dof {ms[0]['nis']['dof']})")
        if not lo <= mean <= hi:
            problems.append(f"NIS {mean:.2f} outside {lo:.2f}-{hi:.2f}")
    if not parts:
        return Check(cid, case.title, crit, "no std_* / nis outputs", "skip",
                     "the FMU outputs neither its covariance (std_*) nor nis/nis_dof/updated")
    return Check(cid, case.title, crit, "; ".join(parts), "fail" if problems else "pass",
                 "; ".join(problems), details)


def _case_value(run, metric):
    if metric == "growth":
        return (run.get("growth") or {}).get("growth_m", math.nan)
    m = run["windows"]["case"] if run.get("windows") else run["metrics"]
    group = "velocity" if metric == "velocity" else "position"
    return rms_3d(m, group)


def _judge_robustness(case, results) -> Check:
    cid = "robust." + case.name
    unit = {"velocity": "m/s", "position": "m", "growth": "m"}[case.metric]
    what = {"velocity": "3-D velocity RMS", "position": "3-D position RMS",
            "growth": "growth of the 3-D position error"}[case.metric]
    where = f" over {case.window[0]:g}-{case.window[1]:g} s" if case.window else ""
    warn_up_to = RATIO_WARN if case.ratio_warn is None else case.ratio_warn
    if case.metric == "growth":
        crit = (f"{what}{where} <= {OUTAGE_FACTOR:g} x max(Kf's, InsOnly's) + "
                f"{OUTAGE_SLACK_M:g} m (means over {case.seeds} seeds); finite outputs")
    else:
        crit = (f"{what}{where} over Kf's on the same {case.seeds} seeds: pass <= "
                f"{RATIO_PASS:g}, " + (f"warn <= {warn_up_to:g}; " if warn_up_to > RATIO_PASS
                                       else "fail beyond; ")
                + "finite outputs, no refused step")
    runs = case_runs(results, case, "filter") if not case.skip else []
    unrun = not_judged(cid, case, crit, runs)
    if unrun:
        return unrun
    refs = {ref: case_runs(results, case, ref) for ref in case.references}
    broken = [f"{ref}: {why}" for ref, rr in refs.items() if (why := failed_run(rr))]
    if broken:
        return Check(cid, case.title, crit, "reference failed", "fail",
                     "reference run failed: " + "; ".join(broken))
    mine = [_case_value(r, case.metric) for r in runs]
    theirs = {ref: [_case_value(r, case.metric) for r in rr] for ref, rr in refs.items()}
    details = {"filter": mine, **theirs}
    if case.metric == "growth":
        value = sum(mine) / len(mine)
        ref_means = {ref: sum(v) / len(v) for ref, v in theirs.items()}
        bound = OUTAGE_FACTOR * max(ref_means.values()) + OUTAGE_SLACK_M
        measured = (f"{value:.2f} {unit} (Kf {ref_means[REFERENCE]:.2f}, InsOnly "
                    f"{ref_means[FREE_INERTIAL]:.2f}; bound {bound:.2f})")
        ok = value <= bound
        return Check(cid, case.title, crit, measured, "pass" if ok else "fail",
                     "" if ok else f"the error grew {value:.1f} m over the outage, bound "
                     f"{bound:.1f} m", details)
    value, ref = pooled_rms(mine), pooled_rms(theirs[REFERENCE])
    ratio = value / ref if ref > 0 else math.inf
    measured = f"{value:.3g} {unit} vs Kf {ref:.3g} {unit}: ratio {ratio:.2f}"
    verdict = "pass" if ratio <= RATIO_PASS else ("warn" if ratio <= warn_up_to else "fail")
    reason = "" if verdict == "pass" else f"{ratio:.2f} times Kf's {what}"
    return Check(cid, case.title, crit, measured, verdict, reason, details)


def _judge_timing(results) -> Check:
    crit = (f"mean wall time of one do_step through the FMU, over Kf's (warn above "
            f"{TIME_RATIO_WARN:g})")
    mine = results.get(("closure", "filter", 0), {})
    ref = results.get(("closure", REFERENCE, 0), {})
    t_mine = (mine.get("metrics") or {}).get("time_per_step_ms")
    t_ref = (ref.get("metrics") or {}).get("time_per_step_ms")
    if not t_mine or not t_ref:
        return Check("filter.timing", "time per step", crit, "not measured", "skip",
                     "the closure run did not finish")
    ratio = t_mine / t_ref
    measured = f"{t_mine * 1e3:.0f} us per step, Kf {t_ref * 1e3:.0f} us: ratio {ratio:.2f}"
    verdict = "warn" if ratio > TIME_RATIO_WARN else "pass"
    return Check("filter.timing", "time per step", crit, measured, verdict,
                 f"{ratio:.0f} times Kf's time per step" if verdict == "warn" else "",
                 {"time_per_step_ms": t_mine, "kf_time_per_step_ms": t_ref})


@dataclass
class Plan:
    cases: List[Case]
    jobs: list


def plan(setting: Setting, runs: int, quick: bool = False) -> Plan:
    """The cases of ``setting`` and the runs they need; ``quick``: every case but the
    consistency runs on one seed (``navfmu verify --quick``)."""
    found = cases(setting, runs)
    if quick:
        for case in found:
            if case.metric != "consistency":
                case.seeds = 1
    return Plan(found, jobs(setting, found))


def judge_plan(setting: Setting, planned: Plan, results, workdir):
    """``(checks, figures)`` of the finished runs (figures: file name -> path)."""
    checks = judge(planned.cases, results)
    robust = [c for c in checks if c.id.startswith("robust.") and "filter" in c.details]
    if not robust:
        return checks, {}
    path = workdir / "robustness.png"
    _robustness_figure(robust, path)
    for c in robust:
        c.figure = path.name
    return checks, {path.name: path}


def _robustness_figure(checks, path):
    """Write :func:`robustness_plot` of ``checks`` to ``path``."""
    import matplotlib.pyplot as plt

    fig = robustness_plot(checks)
    fig.savefig(path, dpi=80)
    plt.close(fig)


def robustness_plot(checks):
    """Per robustness case, the filter's value of every seed next to the references': the
    bars of one seed grouped around its whole-number tick (seed 0, 1, ... of the case)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(checks), figsize=(2.6 * len(checks), 3.2), squeeze=False)
    for ax, c in zip(axes[0], checks):
        series = {k: v for k, v in c.details.items() if isinstance(v, list)}
        width = 0.8 / max(1, len(series))
        for j, (who, values) in enumerate(series.items()):
            x = [i + width * (j - (len(series) - 1) / 2) for i in range(len(values))]
            ax.bar(x, values, width=width, label=who)
        seeds = max((len(v) for v in series.values()), default=0)
        ax.set_xticks(range(seeds))
        ax.set_xlim(-0.5, seeds - 0.5)
        ax.set_title(c.id.split(".", 1)[1], fontsize=9)
        ax.set_xlabel("seed")
        ax.tick_params(labelsize=8)
    axes[0][0].set_ylabel("m or m/s (see the check)")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def judge(case_list: List[Case], results) -> List[Check]:
    checks = []
    for case in case_list:
        if case.metric == "closure":
            checks.append(_judge_closure(case, results))
        elif case.metric == "consistency":
            checks.append(_judge_consistency(case, results))
        elif case.metric == "lever_arm":
            without = next((c for c in case_list if c.name == "consistency"), None)
            checks.append(judge_lever_arm(case, results, without))
        else:
            checks.append(_judge_robustness(case, results))
    checks.append(_judge_timing(results))
    return checks


__all__ = ["plan", "judge_plan", "cases", "jobs", "judge", "Case", "STOP_S", "NEES_BAND",
           "CLOSURE_BOUNDS"]
