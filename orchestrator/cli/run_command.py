"""``navfmu run`` and ``compare``: simulate the scenario once per filter, print the RMS table
with the paper's rows, the per-filter consistency line and the paper comparison, and write
the output folder."""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Optional, Sequence

from ..results import mission_metrics, outputs
from ..running import prechecks, scenarios, shared_replay, smoothing
from .cli_options import DEFAULT_OUT, parse_sets, parse_window
from ..running.comparison import paper_comparison, report_table
from ..running.comparison_text import format_comparison
from ..errors import NavfmuError
from .progress import progress_bars
from ..running.run_outputs import write_outputs
from ..running.ssv_bindings import overrides


def _consistency_line(run, m) -> str:
    extra = []
    if "nis" in m:
        extra.append(f"mean NIS {m['nis']['mean']:.2f} (dof {m['nis']['dof']}, 95 % band "
                     f"{m['nis']['band95'][0]:.2f}-{m['nis']['band95'][1]:.2f})")
    if "nees" in m:
        extra.append("NEES pos/vel/att " + "/".join(f"{m['nees'][g]:.2f}" for g in
                                                    ("position", "velocity", "attitude")))
    if "inside_3sigma_pct" in m:
        inside = m["inside_3sigma_pct"]
        extra.append("inside 3 sigma [%] pos/vel/att " + " / ".join(
            ",".join(f"{v:.0f}" for v in inside[g].values())
            for g in ("position", "velocity", "attitude")))
    if "time_per_step_ms" in m:
        extra.append(f"{m['time_per_step_ms'] * 1e3:.0f} us per filter step")
    return f"  {run.label}: " + "; ".join(extra)


def _comparable_reference(model, stop, replay, echo):
    """paper.json's numbers where the run is the paper's scenario over its span (paper.json's
    ``span_s``; without it, the model's experiment), else None (a shorter run, one started
    later or a replayed log does not compare with the paper's table): said once."""
    reference = scenarios.paper_reference(model)
    if reference is None:
        return None
    run_span = [model.start_time, model.stop_time if stop is None else stop]
    paper_span = reference.get("span_s") or [model.start_time, model.stop_time]
    why = None
    if replay:
        why = "the sensors are a replayed log"
    elif run_span != paper_span:
        why = (f"the run spans {run_span[0]:g}-{run_span[1]:g} s, the paper's scenario "
               f"{paper_span[0]:g}-{paper_span[1]:g} s")
    if why:
        echo(f"(the paper's numbers are left out: {why})")
        return None
    return reference


#: replay_model's keyword arguments -> the command-line options that set them
_REPLAY_OPTIONS = {"start_time": "--start", "max_dt_jitter": "--max-dt-jitter"}


def _time_origin_note(run) -> str:
    """Where the run's times start in a replayed log's time scale (when not at 0)."""
    return f"; times after the log's {run.time_origin:.10g} s" if run.time_origin else ""


def _simulate_all(model, filters, out, stop, backend, window, parameters, fmt, replay,
                  log_sensors, algorithm, echo, replay_options=None, isolation=None):
    stream_dir = None
    if fmt == "parquet":
        if log_sensors:
            raise NavfmuError("--log-sensors needs the run's rows in memory: use --format csv "
                              "or npz with it")
        stream_dir = outputs.stream_folder(out)
    try:
        if shared_replay.shareable(model, filters, replay, fmt):
            with progress_bars() as progress_bar:
                return shared_replay.simulate_filters(
                    model, filters, backend, stop, parameters, window,
                    progress_bar(",".join(filters)), algorithm, lambda m: echo(m, err=True),
                    replay, replay_options, isolation)
    except NavfmuError:
        pass                # one by one: the first failing filter's own error
    runs = []
    with progress_bars() as progress_bar:
        for f in filters:
            stream_to = None
            if stream_dir is not None:
                stream_to = stream_dir / ("results.parquet" if len(filters) == 1 else
                                          f"results_{scenarios.filter_label(model, f)}.parquet")
            runs.append(scenarios.simulate_scenario(
                model, filter=f, backend=backend, stop_time=stop, parameters=parameters,
                window=window, progress=progress_bar(f or "scenario"), algorithm=algorithm,
                log=lambda m: echo(m, err=True), replay=replay, stream_to=stream_to,
                replay_options=replay_options, isolation=isolation))
    return runs


def _smoothed_run(model, filter, stop, window, parameters, replay, replay_options, algorithm):
    """The smoothed run of ``filter`` (``--smooth``, :mod:`orchestrator.running.smoothing`)."""
    with progress_bars() as progress_bar:
        return smoothing.smoothed_run(
            model, filter=filter, stop_time=stop, parameters=parameters, window=window,
            progress=progress_bar("smoother"), algorithm=algorithm, log=None, replay=replay,
            replay_options=replay_options)


def _baseline_run(model, baseline, stop, backend, window, parameters, algorithm, echo,
                  isolation=None):
    """The mission's baseline run (its ``mission.json``), reported under its label (kept in
    memory, also under ``--format parquet``)."""
    with progress_bars() as progress_bar:
        run = scenarios.simulate_scenario(
            model, backend=backend, stop_time=stop,
            parameters={**baseline["parameters"], **(parameters or {})}, window=window,
            progress=progress_bar(baseline["label"]), algorithm=algorithm,
            log=lambda m: echo(m, err=True), isolation=isolation)
    run.label = baseline["label"]
    return run


def run_scenarios(scenario, filters: Sequence[Optional[str]], out, stop, backend, window, sets,
                  fmt, no_plots, echo: Callable, algorithm="gauss-seidel",
                  replay=None, log_sensors=None, replay_options=None, isolation=None,
                  ssv=(), smooth=False) -> None:
    """Run ``scenario`` once per entry of ``filters`` (None: the scenario's own filter), print
    the report with ``echo(text, err=False)`` and write the output folder ``out`` (default
    ``navfmu-results/<model>``), each run with its progress bar; the figures are titled from
    the runs (:func:`orchestrator.results.plot_style.figure_title`).  ``replay_options``: the
    keyword arguments of :func:`orchestrator.running.replay.replay_model` (``--start``,
    ``--max-dt-jitter``), only with ``replay``.  ``isolation``: which FMUs run in a host
    process of their own (``--isolate``, ``--call-timeout``; default: the foreign ones).
    ``ssv``: the ``--ssv`` items (:mod:`orchestrator.running.ssv_bindings`), under ``sets``.
    ``smooth``: also the smoothed run of the (single) filter, after the real-time one."""
    replay_options = {k: v for k, v in (replay_options or {}).items() if v is not None}
    model, window, parameters, out = _checked_inputs(scenario, filters, out, stop, window, sets,
                                                     ssv, fmt, replay, replay_options, smooth)
    runs = _simulate_all(model, filters, out, stop, backend, window, parameters, fmt, replay,
                         log_sensors, algorithm, echo, replay_options, isolation)
    if smooth:
        runs.append(_smoothed_run(model, filters[0], stop, window, parameters, replay,
                                  replay_options, algorithm))
    baseline = scenarios.mission_baseline(model) if replay is None else None
    if baseline is not None:
        runs.append(_baseline_run(model, baseline, stop, backend, window, parameters,
                                  algorithm, echo, isolation))
    if log_sensors:
        from ..running.replay import write_sensor_log

        echo(f"sensor log written to {write_sensor_log(runs[0].results, log_sensors)}/")
    if not runs[0].metrics:
        echo(f"\n{model.name}: no truth in the run (a sensor log without truth.csv): no "
             "metrics")
        written = write_outputs(runs, out, fmt=fmt, plots_on=False)
        echo(f"wrote {len(written)} files to {out}/: " + ", ".join(p.name for p in written))
        return
    reference = _comparable_reference(model, stop, replay, echo)
    comparison = _print_report(scenario, model, filters, runs, reference, echo)
    with progress_bars() as progress_bar:   # a long CSV takes seconds: show the writing
        written = write_outputs(runs, out, fmt=fmt, plots_on=not no_plots,
                                reference=reference, comparison=comparison,
                                progress=progress_bar("writing", unit="part"))
    echo(f"\nwrote {len(written)} files to {out}/: " + ", ".join(p.name for p in written))


def _checked_inputs(scenario, filters, out, stop, window, sets, ssv, fmt, replay,
                    replay_options, smooth):
    """The scenario's model, the metric window, the parameter overrides and the output folder,
    every option checked before anything runs."""
    if replay_options and replay is None:
        raise NavfmuError(f"{_REPLAY_OPTIONS[next(iter(replay_options))]} needs --replay (it "
                          "applies to a sensor log)")
    model = scenarios.load_scenario(scenario)
    scenarios.paper_reference(model)       # a malformed paper.json is refused before the run
    prechecks.check_connected(model)
    window = parse_window(window)
    parameters = overrides(ssv, model, parse_sets(sets))
    prechecks.check_stop_time(stop, model.start_time)
    out = outputs.check_target(Path(out) if out else DEFAULT_OUT / model.name)
    if smooth:
        if fmt == "parquet":
            raise NavfmuError("--smooth keeps the run's rows in memory: use --format csv or npz "
                              "with it")
        smoothing.check_smoothable(model, filters[0])
    return model, window, parameters, out


def _print_report(scenario, model, filters, runs, reference, echo):
    """Print the runs' RMS table, consistency lines, mission table and the comparison with
    the paper; return that comparison (written with the outputs)."""
    first = next(iter(runs[0].metrics.values()))
    echo(f"\n{model.name}: RMS errors over {first['window_s']} s (the truth spans "
         f"{first['truth_span_s']} s)" + _time_origin_note(runs[0]))
    echo(report_table(runs, reference))
    for run in runs:
        for m in run.metrics.values():
            echo(_consistency_line(run, m))
    missions = [(run.label, run.metrics[scenarios.FILTER_COMPONENT]["mission"]) for run in runs
                if "mission" in run.metrics.get(scenarios.FILTER_COMPONENT, {})]
    if missions:
        echo(f"\n{model.name}: the true path against the route (outage: no valid GNSS fix)")
        echo(mission_metrics.mission_table(missions))
    names = [f for f in filters if f]
    if len(names) < 2:  # a single run: suggest timing the paper's filters against each other
        names = list((reference or {}).get("time_per_cycle_ms") or {}) or names
    comparison = paper_comparison(runs, reference)
    text = format_comparison(
        comparison,
        bench_command=(f"`navfmu bench {scenario} --filters {','.join(names)}`" if names else ""),
        show_missing=len(filters) > 1)
    if text:
        echo(text)
    return comparison


__all__ = ["run_scenarios"]
