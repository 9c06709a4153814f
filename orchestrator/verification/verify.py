"""``navfmu verify FMU``: detect the FMU's role, run the FMI checks and its role's checks,
write the report and return the exit status (0 every required check passes, 1 one fails;
usage errors raise :class:`~orchestrator.errors.NavfmuError`, status 2).

The runs of a role's checks are tasks of the campaign executor (serial, process pool or
Dask, :mod:`orchestrator.executor`); each run of the FMU under test happens in a child
process of its worker (:mod:`.scenario_run`), so an FMU that crashes its host gets the
verdict ``crash`` on the checks that needed it (retried once) and the report is still
written; the exit status is 1 on a fail or a crash.
"""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Sequence

from fmpy import read_model_description

from ..building import build as fmu_build
from ..cosim import fmu_builds
from ..results import outputs
from ..running import scenarios
from ..running.prechecks import check_initializes
from ..errors import NavfmuError
from ..campaigns.executor import Executor, Task
from . import attitude_checks, filter_checks, sensor_checks, vehicle_checks
from .fmi_checks import run_fmi_checks
from .report_writing import counts, failing, write_report
from .roles import detect_role, read_fmu
from .scenario_run import run_job
from .setting import make_setting
from ..campaigns.defaults import DEFAULT_RUNS, DEFAULT_WORKERS

#: our FMUs the checks run as references or sources
REFERENCE_FMUS = ("Kf", "InsOnly", "UkfAhrs", "TrajectoryImu", "GnssReceiver")


def _role_checks(setting, runs, executor, progress, workdir, quick=False):
    """The checks of the role: plan the runs, run them on ``executor`` (then the runs that
    depend on their results, for a role that has them), judge them."""
    module = {"ins_gnss_filter": filter_checks, "attitude_filter": attitude_checks,
              "imu_sensor": sensor_checks, "gnss_receiver": sensor_checks,
              "vehicle": vehicle_checks}[setting.role]
    plan = module.plan(setting, runs, quick=quick)

    def run(jobs):
        return executor.run([Task(key=key, func=run_job, args=(job, isolated))
                             for key, job, isolated in jobs], progress=progress)

    results = dict(run(plan.jobs))
    if hasattr(module, "next_jobs"):
        results.update(run(module.next_jobs(setting, plan, results)))
    return module.judge_plan(setting, plan, results, workdir)


def _check_given_values(setting) -> None:
    """Parameter values given with --set/--ssv that the FMU refuses (``init_lat=nan``) are
    the user's error, said before the checks run: the scenario is initialized and stepped
    once with them; when it fails, and succeeds without them, the values are refused with
    the FMU's own message.  (An FMU that fails either way is the checks' to judge.)"""
    if not setting.user_sets:
        return
    model = setting.swapped()
    try:
        check_initializes(model, setting.component_parameters())
    except NavfmuError as exc:
        try:
            check_initializes(model)
        except NavfmuError:
            return
        given = ", ".join(f"{k}={v}" for k, v in setting.user_sets.items())
        raise NavfmuError(f"{setting.facts.path.name} refuses the parameter values given "
                          f"({given}): {exc}") from None


def verify(fmu, role: Optional[str] = None, scenario_names: Sequence[str] = (),
           runs: Optional[int] = None, sets: Optional[Dict[str, Any]] = None, out=None,
           junit=None, workers: int = DEFAULT_WORKERS, scheduler: Optional[str] = None,
           local_cluster: bool = False, progress=None,
           log: Callable[[str], None] = print, default_root=Path("."),
           quick: bool = False) -> Dict[str, Any]:
    """Verify ``fmu``; returns the summary with ``checks``, ``counts``, ``report`` and
    ``exit_status``.  Without ``out`` the report goes to ``default_root/verify-<model>``;
    ``quick``: a filter's cases on one seed, but its consistency runs."""
    runs = DEFAULT_RUNS if runs is None else runs
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise NavfmuError(f"--runs: expected a whole number >= 1, got {runs!r}")
    facts = read_fmu(fmu)
    found_role = detect_role(facts, role)
    setting = make_setting(facts, found_role, scenario_names, sets)
    out = Path(out) if out else Path(default_root) / f"verify-{facts.model_name}"
    outputs.check_target(out)
    if junit is not None:
        outputs.check_writable(junit, "--junit")     # before the checks, not after them
    executor = Executor(workers=workers, scheduler=scheduler, local_cluster=local_cluster)
    fmu_build.build([n for n in REFERENCE_FMUS if (fmu_build.FMU_SOURCES / f"{n}.py").is_file()],
                    log=log)
    for path in setting.scenario_paths:
        scenarios.ensure_fmus(scenarios.load_scenario(path), log=log)
    _check_given_values(setting)
    log(f"verifying {facts.path.name} as {found_role}")
    checks = run_fmi_checks(setting)
    with executor, tempfile.TemporaryDirectory(prefix="navfmu_verify_figures_") as tmp:
        role_checks, figures = _role_checks(setting, runs, executor, progress, Path(tmp),
                                            quick)
        checks += role_checks
        summary = {"fmu": str(facts.path), "model_name": facts.model_name,
                   "role": found_role, "role_forced": role is not None,
                   "scenarios": [p.parent.name for p in setting.scenario_paths],
                   "runs": runs, "quick": quick, "parameters": setting.user_sets,
                   "datasheet": setting.datasheet, "executor": executor.mode,
                   "build": fmu_builds.build_info(facts.path, read_model_description(
                       str(facts.path), validate=False))}
        report = write_report(out, summary, checks, figures, junit)
    n = counts(checks)
    summary.update(checks=checks, counts=n, report=report,
                   exit_status=1 if failing(checks) else 0)
    return summary


__all__ = ["verify", "DEFAULT_RUNS"]
