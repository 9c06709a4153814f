"""The ``navfmu`` command line: build, validate, env, run, compare, bench, convert,
montecarlo, report, tune, verify, package, export (``convert`` is
:mod:`.convert_commands`, ``package`` and ``export`` :mod:`.package_commands`, the options
several commands share :mod:`.option_groups`).

User errors (:class:`~orchestrator.errors.NavfmuError`, and click's usage errors) print one
first line ``navfmu: error: ...`` (on its own line: progress bars are cleared first) and exit
with status 2; no traceback.  ``--debug`` shows tracebacks of internal errors and the log of
a failed component.  Ctrl-C ends every command with ``navfmu: interrupted`` and status 130,
SIGTERM with ``navfmu: terminated`` and status 143 (:mod:`orchestrator.cosim.interrupts`).
Warnings for the user print once each as ``navfmu: warning: ...``
(:mod:`orchestrator.cli.user_warnings`).
"""
from __future__ import annotations

import errno
import signal
import sys
from pathlib import Path

import click

from ..cosim import interrupts
from ..campaigns.defaults import (BENCH_RUNS, BENCH_WORKERS, DEFAULT_RUNS, DEFAULT_SEED,
                                  DEFAULT_WORKERS)
from .cli_options import (DEFAULT_OUT, filter_names, nonempty_name, nonempty_path,
                          parse_named_sets, parse_sets, parse_train_seeds, parse_window,
                          version_text)
from ..errors import NavfmuError, SimulationError
from ..cosim.exchange import ALGORITHMS
from .convert_commands import convert
from .option_groups import (BATCH_HELP, SSV_HELP, common_run_options, isolation,
                            isolation_options)
from .package_commands import export, package
from .progress import progress_bars
from .user_warnings import in_cli_voice


class _Group(click.Group):
    """Lists each command with its whole first sentence (click's default cuts it with
    "..." at the terminal width)."""

    def format_commands(self, ctx, formatter):
        rows = []
        for name in self.list_commands(ctx):
            cmd = self.get_command(ctx, name)
            if cmd is not None and not cmd.hidden:
                rows.append((name, cmd.get_short_help_str(limit=10_000)))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


#: the errors of a disk that cannot take the output (full, over quota, read-only): the
#: user's to act on, not a bug
DISK_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS)

#: every command: -h as well as --help, and each option's default in its help
CONTEXT_SETTINGS = {"help_option_names": ["-h", "--help"], "show_default": True}


@click.group(cls=_Group, context_settings=CONTEXT_SETTINGS)
@click.version_option(message="%(version)s", version=version_text(),
                      help="Print navfmu's version, the FMI version of its FMUs and Python's.")
@click.option("--debug", is_flag=True, help="Show tracebacks of internal errors.")
@click.pass_context
def cli(ctx, debug):
    """navfmu: INS/GNSS co-simulation with adaptive Kalman filter FMUs."""
    ctx.obj = {"debug": debug}


@cli.command()
@click.argument("names", nargs=-1)
@click.option("--force", is_flag=True, help="Rebuild even if up to date.")
def build(names, force):
    """Build the FMUs (all, or NAMES) into fmus/dist/ when missing or stale."""
    from ..building import build as fmu_build

    built = fmu_build.build(list(names) or None, force=force)
    for p in built:
        click.echo(f"built {p}")
    if not built:
        click.echo(f"FMUs in {fmu_build.DIST} are up to date")


@cli.command()
@click.argument("fmus", nargs=-1, type=click.Path(), callback=nonempty_path)
def validate(fmus):
    """Validate FMUs with fmpy (default: every FMU in fmus/dist, built first)."""
    from ..building.validation import validate_fmus

    validate_fmus(fmus, echo=click.echo)


@cli.command("env")
@click.option("--format", "fmt", type=click.Choice(["sh", "json"]), default="sh",
              show_default=True, help="Shell 'export' lines or a JSON object.")
def env_(fmt):
    """Print the environment a native (non-Python) FMI host needs to load the FMUs."""
    from ..building import hostenv

    click.echo(hostenv.render(hostenv.host_environment(), fmt))


def _execute(scenario, filters, out, stop, backend, window, sets, ssv, fmt, no_plots,
             replay=None, log_sensors=None, smooth=False):
    from .run_command import run_scenarios

    meta = click.get_current_context().meta
    run_scenarios(scenario, filters, out, stop, backend, window, sets, fmt, no_plots,
                  echo=click.echo, ssv=ssv, smooth=smooth,
                  algorithm=meta.get("algorithm", ALGORITHMS[0]),
                  replay=replay, log_sensors=log_sensors,
                  replay_options={k: meta.get(k) for k in ("start_time", "max_dt_jitter")},
                  isolation=isolation())


@cli.command()
@click.argument("scenario", type=click.Path(), callback=nonempty_path)
@click.option("--filter", "filter_", callback=nonempty_name,
              help="Swap the 'filter' component: an FMU name (Kf, SageHusaFading, ...) or the "
              "path of an .fmu file (default: the scenario's own filter).")
@click.option("--log-sensors", "log_sensors", type=click.Path(file_okay=False),
              callback=nonempty_path,
              help="Also write the run's IMU, GNSS and truth signals as a sensor log to this "
              "folder (replay it with --replay).")
@click.option("--smooth", is_flag=True,
              help="Also write the filter's smoothed solution (Rauch-Tung-Striebel over the "
              "recorded run; Kf) with its own metrics, as the run '<filter>-smoothed'.")
@common_run_options
def run(scenario, filter_, log_sensors, smooth, out, stop, backend, window, sets, ssv, fmt,
        no_plots, replay):
    """Co-simulate SCENARIO (a models/ folder or .ssd file) and report its metrics."""
    _execute(scenario, [filter_], out, stop, backend, window, sets, ssv, fmt, no_plots,
             replay=replay, log_sensors=log_sensors, smooth=smooth)


@cli.command()
@click.argument("scenario", type=click.Path(), callback=nonempty_path)
@click.option("--filters", required=True, help="Comma-separated filter FMUs, e.g. Kf,Iakf.")
@common_run_options
def compare(scenario, filters, out, stop, backend, window, sets, ssv, fmt, no_plots, replay):
    """Run SCENARIO once per filter (same truth and sensor seeds) and compare them."""
    names = filter_names(filters)
    _execute(scenario, names, out, stop, backend, window, sets, ssv, fmt, no_plots,
             replay=replay)


cli.add_command(convert)
cli.add_command(package)
cli.add_command(export)


@cli.command(short_help="Time SCENARIO through the FMUs against navcore directly (or, with "
             "--filters, several filters against each other), in one process.")
@click.argument("scenario", type=click.Path(), callback=nonempty_path, required=False)
@click.option("--stop", type=float, default=100.0, show_default=True,
              help="Simulated time of each run [s].")
@click.option("--repeat", type=int, default=3, show_default=True,
              help="Alternate the runs this many times and keep each one's fastest.")
@click.option("--filters", help="Comma-separated filter FMUs (e.g. Ukf,CtfaUkf,ImmUkf): time "
              "each one swapped into the scenario, through the FMUs, instead of comparing the "
              "FMU and direct paths.")
@click.option("--libcosim", "against_libcosim", is_flag=True, help="Time our master (Jacobi) "
              "against libcosim on the same SSP and base step instead.")
@click.option("--executors", is_flag=True, help="Time a small campaign (--runs runs of the "
              "filters, default Kf) serially, on --workers pool processes and on a Dask "
              "LocalCluster: speed-up and Dask's per-run overhead.")
@click.option("--runs", type=int, default=None, help="Runs per filter (only with --executors; "
              f"default {BENCH_RUNS}).")
@click.option("--workers", type=int, default=None, help="Pool processes timed against the "
              f"serial campaign (only with --executors; default {BENCH_WORKERS}: a pool of one "
              "measures no speed-up).")
@click.option("--json", "as_json", is_flag=True, help="Print the measurements as JSON.")
def bench(scenario, stop, repeat, filters, against_libcosim, executors, runs, workers, as_json):
    """Run SCENARIO through the FMUs and through navcore directly, in one process; print the
    time ratio and the per-step cost of each component.  With --filters: run it through the
    FMUs once per filter instead and print each filter's time per cycle and the ratios to the
    first filter (next to the paper's, from paper.json).  SCENARIO defaults to navfmu's own
    models/aircraft_500s."""
    from .bench import bench_command, check_bench_options

    check_bench_options(filters=filters, against_libcosim=against_libcosim,
                        executors=executors, runs=runs, workers=workers)
    runs = BENCH_RUNS if runs is None else runs
    workers = BENCH_WORKERS if workers is None else workers
    click.echo(bench_command(scenario, stop=stop, repeat=repeat, filters=filters,
                             against_libcosim=against_libcosim, executors=executors, runs=runs,
                             workers=workers, as_json=as_json,
                             log=lambda m: click.echo(m, err=True)))



@cli.command()
@click.argument("scenario", type=click.Path(), callback=nonempty_path)
@click.option("--runs", type=int, required=True, help="Number of seeds (runs per filter).")
@click.option("--filters", required=True, help="Comma-separated filter FMUs, e.g. Kf,Iakf.")
@click.option("--workers", type=int, default=DEFAULT_WORKERS,
              help="Local worker processes (1: in this process).")
@click.option("--out", "out", type=click.Path(file_okay=False), callback=nonempty_path,
              help="Campaign folder (default: navfmu-results/<scenario>-montecarlo).")
@click.option("--scheduler", metavar="tcp://HOST:PORT", help="Run on this Dask scheduler.")
@click.option("--local-cluster", is_flag=True, help="Start a Dask LocalCluster of --workers.")
@click.option("--seed", type=int, default=DEFAULT_SEED,
              help="Campaign seed: run i uses seed + i (+ each random component's offset).")
@click.option("--seed-offset", "seed_offsets", multiple=True, metavar="COMP=K",
              help="Seed offset of a random component (default 1000 x its position).")
@click.option("--backend", type=click.Choice(["direct", "fmu"]), default="direct",
              show_default=True, help="navcore objects directly (same numbers), or the FMUs.")
@click.option("--stop", type=float, help="Stop time [s] (default: the SSD's).")
@click.option("--window", help="Metric window t0:t1 [s] (default: the whole run).")
@click.option("--samples", type=click.Choice(["all", "fixes"]), default="all",
              show_default=True, help="Metric samples: every row, or the GNSS fix epochs.")
@click.option("--set", "sets", multiple=True, metavar="COMP.VAR=VALUE",
              help="Override a parameter (repeatable; not a random component's seed: see "
              "--seed).")
@click.option("--ssv", "ssv", multiple=True, metavar="[COMPONENT=]FILE", help=SSV_HELP)
@click.option("--series", type=click.Choice(["parquet", "csv"]),
              help="Also keep every run's time series in this format.")
@click.option("--batch", type=int, default=None, help=BATCH_HELP)
@isolation_options
def montecarlo(scenario, runs, filters, workers, out, scheduler, local_cluster, seed,
               seed_offsets, backend, stop, window, samples, sets, ssv, series, batch):
    """Monte Carlo campaign: RUNS seeds x FILTERS on SCENARIO; resumable (run the same
    command again to finish a killed campaign)."""
    from ..campaigns import campaign, campaign_summary
    from ..campaigns import seeds as campaign_seeds
    from ..running import scenarios
    from ..running.ssv_bindings import overrides

    names = tuple(filter_names(filters))
    model = scenarios.load_scenario(scenario)
    spec = campaign.CampaignSpec(
        scenario=scenario, filters=names, runs=runs, seed=seed, backend=backend,
        stop_time=stop, window=parse_window(window), samples=samples,
        seed_offsets=campaign_seeds.parse_seed_offsets(seed_offsets),
        parameters=tuple(overrides(ssv, model, parse_sets(sets)).items()), series=series,
        batch=batch, isolation=isolation())
    out = Path(out) if out else DEFAULT_OUT / f"{model.name}-montecarlo"
    with progress_bars() as progress_bar:
        summary = campaign.run_campaign(spec, out, workers=workers, scheduler=scheduler,
                                        local_cluster=local_cluster,
                                        progress=progress_bar("runs", unit="run"),
                                        log=lambda m: click.echo(m, err=True))
    counts = summary["counts"]
    click.echo(f"{summary['runs']} runs x {len(names)} filters = {counts['total']} filter "
               f"runs: {counts['ran']} now, {counts['done_before']} done before; results in "
               f"{out}/")
    click.echo(campaign_summary.format_summary(summary))


@cli.command()
@click.option("--out", "out", type=click.Path(file_okay=False), callback=nonempty_path,
              default=str(DEFAULT_OUT / "report"),
              help="Report folder (report.md, figures/, campaigns/).")
@click.option("--scenario", "scenario_names", multiple=True, metavar="NAME",
              help="Report this scenario only: a name of models/ or a scenario folder "
              "(repeatable; default: every scenario of models/).")
@click.option("--runs", type=int, default=DEFAULT_RUNS,
              help="Runs per filter and scenario (more: narrower intervals).")
@click.option("--workers", type=int, default=DEFAULT_WORKERS,
              help="Local worker processes (1: in this process).")
@click.option("--scheduler", metavar="tcp://HOST:PORT", help="Run on this Dask scheduler.")
@click.option("--local-cluster", is_flag=True, help="Start a Dask LocalCluster of --workers.")
@click.option("--stop", type=float, help="Stop time of every run [s] (default: each SSD's; "
              "shorter for a quick look, the papers' tables need the full runs).")
@click.option("--only-finished", is_flag=True, help="Run nothing: report the runs the "
              "campaigns in --out have finished (the first runs every filter has).")
@click.option("--batch", type=int, default=None, help=BATCH_HELP)
def report(out, scenario_names, runs, workers, scheduler, local_cluster, stop, only_finished,
           batch):
    """Campaigns of every scenario of models/ with every filter that fits it, and one
    Markdown report: the papers' tables with our numbers and intervals, figures,
    NEES/NIS consistency, the cross matrix.  Resumes the campaigns it finds in --out."""
    from ..reporting import report as report_module

    with progress_bars() as progress_bar:
        path = report_module.build_report(
            out, runs=runs, workers=workers, scenarios=scenario_names, scheduler=scheduler,
            local_cluster=local_cluster, stop_time=stop,
            progress_factory=lambda name: progress_bar(name, unit="run"),
            log=lambda m: click.echo(m, err=True), only_finished=only_finished, batch=batch)
    click.echo(f"wrote {path}")


@cli.command()
@click.argument("scenario", type=click.Path(), callback=nonempty_path)
@click.option("--component", default="filter", show_default=True,
              help="Component whose parameters are tuned.")
@click.option("--params", "params", required=True, help="Comma-separated parameter names.")
@click.option("--range", "ranges", multiple=True, metavar="NAME=LO:HI",
              help="Search range of a parameter (default: its declared min/max; repeatable).")
@click.option("--generations", type=int, default=5, show_default=True,
              help="Generations (paper 003: 500).")
@click.option("--population", type=int, default=10, show_default=True,
              help="Individuals per generation (paper 003: 100).")
@click.option("--workers", type=int, default=DEFAULT_WORKERS,
              help="Local processes evaluating candidates (1: in this process).")
@click.option("--scheduler", help="Dask scheduler address tcp://HOST:PORT (instead of a "
              "local pool).")
@click.option("--seed", type=int, default=DEFAULT_SEED, help="Seed of the GA.")
@click.option("--train-seeds", default=None, help="Comma-separated values given to every "
              "component's 'seed' parameter; the cost is the mean over them (default: the "
              "model's own seeds).")
@click.option("--backend", type=click.Choice(["fmu", "direct"]), default="direct",
              show_default=True, help="Evaluate through the FMUs or the navcore objects "
              "(same numbers).")
@click.option("--stop", type=float, help="Stop time of each run [s] (default: the SSD's).")
@click.option("--window", help="Fitness window t0:t1 [s] (default: the whole run).")
@click.option("--out", type=click.Path(file_okay=False), callback=nonempty_path,
              help="Output folder, the only place written: <component>_tuned.ssv, tune.json, "
              "fitness.png (default: navfmu-results/<scenario>-tune).")
@click.option("--ssv", "ssv", multiple=True, metavar="[COMPONENT=]FILE", help=SSV_HELP)
@click.option("--batch", type=int, default=None, help=BATCH_HELP.replace(
    "Runs of one filter", "Candidates of a generation (all their training runs)"))
@click.option("--replay", "replay", type=click.Path(), callback=nonempty_path,
              help="Every run replays this sensor-log folder in place of the scenario's "
              "sensor components (--stop is then in the log's time).")
def tune(scenario, component, params, ranges, generations, population, workers, scheduler,
         seed, train_seeds, backend, stop, window, out, ssv, batch, replay):
    """Tune numeric parameters of a component of SCENARIO with paper 003's genetic
    algorithm; each cost evaluation is a co-simulation (attitude RMS, eq. 20).  Writes
    only into --out and prints the --ssv option that applies the result."""
    from ..campaigns import tune as tuner

    from ..campaigns.batching import check_batch

    check_batch(batch, backend)
    names = [p.strip() for p in params.split(",") if p.strip()]
    seeds = parse_train_seeds(train_seeds)
    from ..running import scenarios
    from ..running.ssv_bindings import overrides
    from ..results.outputs import check_writable

    model = scenarios.load_scenario(scenario)
    fixed = overrides(ssv, model)
    out = Path(out) if out else DEFAULT_OUT / f"{model.name}-tune"
    check_writable(out, "--out", folder=True)
    with progress_bars() as progress_bar:
        summary = tuner.run_tune(scenario, component, names, generations=generations,
                                 population=population, workers=workers, seed=seed,
                                 ranges=tuner.parse_ranges(ranges), train_seeds=seeds,
                                 backend=backend, stop_time=stop, window=parse_window(window),
                                 scheduler=scheduler, batch=batch, parameters=fixed,
                                 replay=replay,
                                 progress=progress_bar("tune", unit="individual"),
                                 log=lambda m: click.echo(m, err=True))
    click.echo(f"best cost {summary['best_cost']:.5f} deg after {summary['evaluations']} "
               f"evaluations; tuned values:")
    for k, v in summary["best_values"].items():
        click.echo(f"  {component}.{k} = {v!r}")
    written = tuner.write_tune_outputs(summary, out)
    click.echo(f"wrote {', '.join(str(p) for p in written)}")
    click.echo(f"apply it with: navfmu run {scenario} --ssv {component}={written[0]}")


@cli.command()
@click.argument("fmu", type=click.Path())
@click.option("--role", type=click.Choice(["ins_gnss_filter", "attitude_filter", "imu_sensor",
                                           "gnss_receiver", "vehicle"]),
              help="Force the role (default: detected from the FMU's variables).")
@click.option("--scenario", "scenario_names", multiple=True, help="Scenario of the "
              "consistency runs (a models/ name or .ssd; repeatable; default: the role's).")
@click.option("--runs", type=int, default=DEFAULT_RUNS, help="Seeds per case.")
@click.option("--quick", is_flag=True, help="A filter's cases on one seed, but its "
              "consistency runs (about half the time).")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="A parameter of "
              "the FMU, or datasheet.NAME=VALUE: a declared value the FMU does not carry.")
@click.option("--ssv", "ssv", multiple=True, metavar="FILE", help="A parameter set (.ssv) of "
              "the FMU's parameters (repeatable, later over earlier, --set over all).")
@click.option("--out", type=click.Path(file_okay=False),
              help="Report folder (default: navfmu-results/verify-<model>).")
@click.option("--junit", type=click.Path(dir_okay=False), help="Also write JUnit XML here.")
@click.option("--workers", type=int, default=DEFAULT_WORKERS,
              help="Local worker processes (1: in this process).")
@click.option("--scheduler", metavar="tcp://HOST:PORT", help="Run on this Dask scheduler.")
@click.option("--local-cluster", is_flag=True, help="Start a Dask LocalCluster of --workers.")
@click.pass_context
def verify(ctx, fmu, role, scenario_names, runs, sets, ssv, out, junit, workers, scheduler,
           local_cluster, quick):
    """Verify a filter, sensor or vehicle FMU (ours or not): FMI, contract, consistency and
    robustness checks of its role; writes verify.md and verify.json; exit 0 all pass, 1 one
    fails."""
    from ..running.ssv_bindings import read_fmu_bindings
    from ..verification.verify import verify as verify_fmu

    bound = {**read_fmu_bindings(ssv), **parse_named_sets(sets)}
    with progress_bars() as progress_bar:
        summary = verify_fmu(fmu, role=role, scenario_names=scenario_names, runs=runs,
                             sets=bound, out=out, junit=junit,
                             workers=workers, scheduler=scheduler, local_cluster=local_cluster,
                             progress=progress_bar("runs", unit="run"), quick=quick,
                             log=lambda m: click.echo(m, err=True), default_root=DEFAULT_OUT)
    for check in summary["checks"]:
        click.echo(f"  {check.verdict:5s} {check.id}: {check.measured}"
                   + (f" ({check.reason})" if check.reason and check.verdict != "pass" else ""))
    n = summary["counts"]
    click.echo(f"{n['pass']} pass, {n['fail']} fail, {n['warn']} warn, {n['skip']} skip"
               + (f", {n['crash']} crash" if n["crash"] else "") + f"; wrote {summary['report']}")
    ctx.exit(summary["exit_status"])


def main(argv=None):
    debug = "--debug" in (argv if argv is not None else sys.argv[1:])
    try:
        with in_cli_voice(lambda m: click.echo(m, err=True), debug=debug), \
                interrupts.deferred():
            status = cli.main(args=argv, prog_name="navfmu", standalone_mode=False)
    except NavfmuError as exc:
        click.echo(f"navfmu: error: {exc}", err=True)
        if debug and isinstance(exc, SimulationError) and exc.log:
            click.echo("component log:\n  " + "\n  ".join(exc.log), err=True)
        sys.exit(2)
    except (click.exceptions.Abort, KeyboardInterrupt) as exc:
        # a second Ctrl-C (a terminal sends it to the whole group) must not kill the teardown
        # that follows (Dask's cluster closing at exit) with a traceback or a signal status
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        # click turns a KeyboardInterrupt (and so Terminated) into Abort, the cause kept
        if isinstance(exc, interrupts.Terminated) or isinstance(exc.__cause__,
                                                                 interrupts.Terminated):
            click.echo("navfmu: terminated", err=True)
            sys.exit(128 + signal.SIGTERM)
        click.echo("navfmu: interrupted", err=True)
        sys.exit(130)
    except click.exceptions.Exit as exc:  # --help
        sys.exit(exc.exit_code)
    except click.UsageError as exc:
        hint = (f"\n  (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else "")
        click.echo(f"navfmu: error: {exc.format_message()}{hint}", err=True)
        sys.exit(2)
    except click.ClickException as exc:
        click.echo(f"navfmu: error: {exc.format_message()}", err=True)
        sys.exit(exc.exit_code)
    except Exception as exc:  # a bug: say so in one line unless --debug
        if debug:
            raise
        if isinstance(exc, OSError) and exc.errno in DISK_ERRNOS:
            # a full disk where no caller named the file: the file the system names, if any
            where = f"{exc.filename}: " if exc.filename else ""
            click.echo(f"navfmu: error: {where}cannot write: {exc.strerror}", err=True)
            sys.exit(2)
        click.echo(f"navfmu: internal error: {exc!r} (run with --debug for the traceback)",
                   err=True)
        sys.exit(3)
    # a command's ctx.exit(n) comes back as its return value (verify: 1 when a check fails)
    sys.exit(status if isinstance(status, int) else 0)


if __name__ == "__main__":
    main()
