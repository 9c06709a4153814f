"""One facade function per task: run a scenario, compare filters, benchmark the paths.

A *scenario* is a folder of ``models/`` with a ``SystemStructure.ssd`` (and optional
``paper.json`` with the paper's reference numbers).  Filters are found in the results by the
signal contract: every recorded component with a ``nav_time`` output is a filter, the one with
``truth_time`` is the truth source.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from . import build as fmu_build
from . import interrupts
from . import metrics as nav_metrics
from . import outputs
from . import phases as scenario_phases
from . import prechecks
from . import recorder
from . import windows as paper_windows
from .errors import NavfmuError
from .master import Simulation
from .results import Results, atomic_write
from .ssp import SystemModel
from .ssp_archive import load_model

#: name of the component a ``--filter`` swap replaces
FILTER_COMPONENT = "filter"
#: adaptive diagnostics plotted when a filter has them
ADAPTIVE_OUTPUTS = ("q_scale", "r_scale", "fading_factor", "outlier", "compression", "chi2",
                    "model_prob_1", "model_prob_2", "model_prob_3")
#: R scale factors of the attitude filters (paper 003 eq. 25) and the fuzzy inputs (eq. 19)
R_SCALE_OUTPUTS = ("r_scale_accel", "r_scale_mag")
FUZZY_INPUT_OUTPUTS = ("fuzzy_e_accel", "fuzzy_de_accel", "fuzzy_e_mag", "fuzzy_de_mag")


def registry():
    """Model name -> navcore component class, for the direct backend."""
    from navcore.components import REGISTRY

    return REGISTRY


def _fmu_sources(model: SystemModel) -> List[Path]:
    return [c.source for c in model.components]


def ensure_fmus(model: SystemModel, log=print) -> None:
    """Build the FMUs the model uses that come from ``fmus/dist`` and are missing or stale."""
    names = []
    for src in _fmu_sources(model):
        src = Path(src).resolve()
        if src.parent == fmu_build.DIST.resolve():
            if (fmu_build.FMU_SOURCES / f"{src.stem}.py").is_file():
                names.append(src.stem)
    scripts = [fmu_build.FMU_SOURCES / f"{n}.py" for n in names]
    stale = [s.stem for s in scripts if fmu_build.is_stale(s)]
    if stale:
        fmu_build.build(stale, log=log)


def resolve_filter(name_or_path: str) -> Path:
    """``Kf`` -> ``fmus/dist/Kf.fmu``; a path to an ``.fmu`` is taken as it is."""
    p = Path(name_or_path)
    if p.suffix == ".fmu" or "/" in name_or_path:
        if not p.is_file():
            raise NavfmuError(f"--filter: FMU file not found: {p}")
        return p.resolve()
    if not (fmu_build.FMU_SOURCES / f"{name_or_path}.py").is_file():
        known = ", ".join(s.stem for s in fmu_build.slave_scripts())
        raise NavfmuError(f"--filter: unknown filter '{name_or_path}' (known FMUs: {known}; or "
                          "give the path of an .fmu file)")
    return fmu_build.fmu_path(name_or_path)


def swap_filter(model: SystemModel, filter: str) -> SystemModel:
    """``model`` with its ``filter`` component's FMU replaced (see :func:`resolve_filter`)."""
    if FILTER_COMPONENT not in [c.name for c in model.components]:
        raise NavfmuError(f"{model.path}: no component named '{FILTER_COMPONENT}' to swap")
    return model.replace_source(FILTER_COMPONENT, resolve_filter(filter))


def load_scenario(path) -> SystemModel:
    from .replay import resolve_log_parameters

    return resolve_log_parameters(load_model(Path(path)))


def paper_reference(model: SystemModel) -> Optional[Dict[str, Any]]:
    ref = Path(model.path).parent / "paper.json"
    if not ref.is_file():
        return None
    try:
        return json.loads(ref.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise NavfmuError(f"{ref}: cannot read the paper's reference numbers: {exc}") from None


filters_in = nav_metrics.filters_of


def has_truth(results: Results) -> bool:
    return any(results.has(c, "truth_time") for c in results.components)


@dataclass
class Run:
    """One co-simulation and its metrics."""

    label: str
    model: SystemModel
    results: Results
    metrics: Dict[str, Dict[str, Any]] = field(default_factory=dict)
    #: the Parquet file the run was streamed to (then ``results`` has no rows)
    series_file: Optional[Path] = None
    #: of a streamed run: paper.json window name -> filter component -> metrics
    window_metrics: Dict[str, Dict[str, Dict[str, Any]]] = field(default_factory=dict)


def filter_label(model: SystemModel, filter: Optional[str] = None) -> str:
    """The name a run of ``model`` (with ``filter`` swapped in) is reported under: the
    filter FMU's name, or the model's name when it has no ``filter`` component."""
    if FILTER_COMPONENT not in [c.name for c in model.components]:
        return model.name
    return Path(resolve_filter(filter) if filter
                else model.component(FILTER_COMPONENT).source).stem


def simulate_scenario(model: SystemModel, filter: Optional[str] = None, backend: str = "fmu",
                      stop_time: Optional[float] = None, parameters=None, window=None,
                      progress=None, build=True, log=print, replay=None,
                      algorithm="gauss-seidel", stream_to=None) -> Run:
    """Run one scenario (optionally with the filter component swapped, and with its sensor
    components replaced by a replay of the sensor log in folder ``replay``, see
    :func:`orchestrator.replay.replay_model`) and compute metrics (not without a truth).

    ``stream_to``: a ``.parquet`` path; the rows then go to that file and to the metrics in
    chunks (memory flat in the flight length) instead of staying in ``results``."""
    label = filter_label(model, filter)
    if filter:
        model = swap_filter(model, filter)
    record = None
    if replay is not None:
        from . import replay as log_replay

        model, notes = log_replay.replay_model(model, replay, stop_time=stop_time)
        stop_time = None
        parameters = {**log_replay.parameter_overrides(model, notes), **(parameters or {})}
        record = log_replay.recorded_signals(model, notes)
    if backend == "fmu" and build:
        ensure_fmus(model, log=log)
    sim = Simulation(model, backend=backend, registry=registry() if backend == "direct" else None,
                     parameters=parameters, record=record, algorithm=algorithm)
    prechecks.check_simulation(sim, stop_time)
    if stream_to is not None:
        overlap = max(sim.decimation.values()) + 1
        sink = recorder.MetricsSink(window=window, overlap=overlap)
        end = model.stop_time if stop_time is None else stop_time
        # the paper's windows the run reaches (a shorter run: the others are left out)
        windowed = {name: recorder.MetricsSink(window=(float(w["t0"]), float(w["t1"])),
                                               overlap=overlap)
                    for name, w in paper_windows.paper_windows(paper_reference(model)).items()
                    if end is None or float(w["t0"]) < end}
        header = sim.run(stop_time=stop_time, progress=progress, sink=recorder.Tee(
            [sink, *windowed.values(), recorder.ParquetSink(stream_to)]))
        return Run(label, model, header, dict(sink.metrics), Path(stream_to),
                   {name: dict(s.metrics) for name, s in windowed.items()})
    results = sim.run(stop_time=stop_time, progress=progress)
    run = Run(label, model, results)
    if not has_truth(results):
        return run
    for f in filters_in(results):
        run.metrics[f] = nav_metrics.filter_metrics(results, f, window=window)
    return run


def _row_label(run: Run, component: str) -> str:
    return run.label if component == FILTER_COMPONENT else f"{run.label}:{component}"


def report_table(runs: Sequence[Run], reference=None) -> str:
    """RMS table of every filter of ``runs``, each followed by the row of the paper's
    ``table`` (paper.json) whose ``filter`` it is, then the paper's rows of filters not run.
    Missing numbers of the paper (null) print '-'."""
    ref_rows = []
    for r in (reference or {}).get("table", ()):
        values = (r.get("position_enu_m"), r.get("velocity_enu_mps"), r.get("attitude_deg"))
        if all(v is None for v in values):
            continue  # the paper gives no number for this row (e.g. only in a figure)
        ref_rows.append((r.get("filter"), f"paper: {r['label']}",
                         nav_metrics.reference_metrics(*values)))
    used = set()
    rows = []
    for run in runs:
        for f, m in run.metrics.items():
            rows.append((_row_label(run, f), m))
            if f != FILTER_COMPONENT:
                continue
            for i, (name, label, ref) in enumerate(ref_rows):
                if name == run.label and i not in used:
                    rows.append((label, ref))
                    used.add(i)
    rows += [(label, ref) for i, (_, label, ref) in enumerate(ref_rows) if i not in used]
    return nav_metrics.rms_table(rows)


def _by_filter(runs: Sequence[Run]) -> Dict[str, Dict[str, Any]]:
    """Filter label (the FMU's name) -> metrics of the swapped ``filter`` component."""
    return {run.label: run.metrics[FILTER_COMPONENT] for run in runs
            if FILTER_COMPONENT in run.metrics}


def paper_comparison(runs: Sequence[Run], reference=None) -> Dict[str, Any]:
    """Our numbers next to the paper's, for the blocks ``reference`` (paper.json) has:

    * ``improvement_percent`` (baseline and filter names): per-axis entries (``position_enu``,
      ``velocity_enu`` [%], ``position_ratio_enu``, ``velocity_ratio_enu`` [baseline RMS /
      filter RMS], east/north/up) and 3-D entries (``position``, ``velocity`` [%], of the 3-D
      RMS, see :func:`metrics.rms_3d`);
    * ``time_per_cycle_ms`` (filter -> ms; the first listed is the baseline of the ratios):
      our filter's mean do_step time per call next to it;

    and, from the filters' outputs alone, the outlier detection of every filter that reports
    it (``metrics.outlier_detection``).  A block whose filters were not run says which are
    missing.  JSON-ready dict; :func:`format_comparison` prints it."""
    reference = reference or {}
    ours = _by_filter(runs)
    out: Dict[str, Any] = {}
    imp = reference.get("improvement_percent")
    if isinstance(imp, dict) and imp.get("baseline") and imp.get("filter"):
        base, filt = imp["baseline"], imp["filter"]
        block: Dict[str, Any] = {"baseline": base, "filter": filt, "note": imp.get("note", "")}
        missing = [f for f in (base, filt) if f not in ours]
        if missing:
            block["missing"] = missing
        else:
            items = []
            for group in ("position", "velocity", "attitude"):
                b, f = ours[base], ours[filt]
                if group in imp:
                    b3, f3 = nav_metrics.rms_3d(b, group), nav_metrics.rms_3d(f, group)
                    items.append({"key": group, "kind": "percent_3d", "baseline_rms": b3,
                                  "filter_rms": f3,
                                  "ours": nav_metrics.improvement_percent(b3, f3),
                                  "paper": imp[group]})
                for suffix, kind in (("_enu", "percent_axes"), ("_ratio_enu", "ratio_axes")):
                    key = group + suffix
                    if key not in imp:
                        continue
                    bs, fs = nav_metrics.per_axis_enu(b, group), nav_metrics.per_axis_enu(f, group)
                    fn = (nav_metrics.improvement_percent if kind == "percent_axes"
                          else nav_metrics.rms_ratio)
                    items.append({"key": key, "kind": kind, "baseline_rms": bs,
                                  "filter_rms": fs,
                                  "ours": [fn(x, y) for x, y in zip(bs, fs)],
                                  "paper": imp[key]})
            block["items"] = items
        out["improvement"] = block
    times = reference.get("time_per_cycle_ms")
    if isinstance(times, dict) and times:
        base = next(iter(times))
        rows = []
        base_ms = ours.get(base, {}).get("time_per_step_ms")
        for name, m in ours.items():
            ms = m.get("time_per_step_ms")
            if ms is None:
                continue
            paper_ms = times.get(name)
            rows.append({"filter": name, "ours_ms": ms,
                         "ours_ratio": ms / base_ms if base_ms else None,
                         "paper_ms": paper_ms,
                         "paper_ratio": paper_ms / times[base] if paper_ms is not None else None})
        run0 = runs[0].results.metadata if runs else {}
        out["time_per_cycle"] = {
            "baseline": base, "rows": rows,
            "filter_step_s": (run0.get("base_step", float("nan"))
                              * (run0.get("decimation") or {}).get(FILTER_COMPONENT, 1)),
            "missing": [f for f in times if f not in ours]}
    phase_stats = scenario_phases.phase_statistics(runs, reference, filters_in)
    if phase_stats and phase_stats["rows"]:
        out["phases"] = phase_stats
    detection = {name: m["outlier_detection"] for name, m in ours.items()
                 if "outlier_detection" in m}
    if detection:
        out["outlier_detection"] = detection
    windowed = paper_windows.window_comparison(runs, FILTER_COMPONENT, reference)
    if windowed:
        out["windows"] = windowed
    return out


_UNITS = {"position": "m", "velocity": "m/s", "attitude": "deg"}


def _num(value, fmt="8.3f"):
    if value is None or (isinstance(value, float) and value != value):
        return f"{'-':>{len(format(0.0, fmt))}s}"
    return format(value, fmt)


def _pct(value):
    return "-" if value != value else f"{100 * value:.1f} %"


def format_comparison(comparison: Dict[str, Any], bench_command: str = "",
                      show_missing: bool = True) -> str:
    """Text of :func:`paper_comparison` (empty if it has nothing); ``show_missing=False``
    leaves out the blocks that lack a filter (a single-filter ``navfmu run``)."""
    lines = [paper_windows.format_windows(comparison.get("windows") or {})]
    imp = comparison.get("improvement")
    if imp and ("missing" not in imp or show_missing):
        base, filt = imp["baseline"], imp["filter"]
        lines.append(f"\npaper's improvement of {filt} over {base}:")
        if "missing" in imp:
            lines.append(f"  not compared: add {', '.join(imp['missing'])} to --filters")
        for item in imp.get("items", ()):
            key = item["key"]
            if item["kind"] == "percent_3d":
                unit = _UNITS.get(key, "")
                lines.append(f"  {key} 3-D RMS: {base} {item['baseline_rms']:.4f} {unit}, {filt} "
                             f"{item['filter_rms']:.4f} {unit}: ours "
                             f"{_num(item['ours'], '.1f').strip()} % lower, paper "
                             f"{_num(item['paper'], '.1f').strip()} %")
                continue
            what = (f"{key.split('_')[0]} RMS ratio {base}/{filt}" if item["kind"] == "ratio_axes"
                    else f"{key.split('_')[0]} RMS reduction [%]")
            lines.append(f"  {what:40s} {'E':>8s} {'N':>8s} {'U':>8s}")
            fmt = "8.2f" if item["kind"] == "ratio_axes" else "8.1f"
            lines.append(f"  {'    ours':40s} " + " ".join(_num(v, fmt) for v in item["ours"]))
            lines.append(f"  {'    paper':40s} " + " ".join(_num(v, fmt) for v in item["paper"]))
        if imp.get("items") and any(i["kind"] == "percent_3d" for i in imp["items"]):
            lines.append("  (3-D RMS: root of the sum of the per-axis mean squares)")
    tpc = comparison.get("time_per_cycle")
    if tpc:
        base = tpc["baseline"]
        lines.append(f"\nmean time per filter cycle (the filter's do_step, one cycle = "
                     f"{tpc['filter_step_s']:g} s), ratios to {base}:")
        lines.append(f"  {'filter':14s} {'ours [ms]':>10s} {'ours ratio':>11s} "
                     f"{'paper [ms]':>11s} {'paper ratio':>12s}")
        for r in tpc["rows"]:
            lines.append(f"  {r['filter']:14s} {_num(r['ours_ms'], '10.4f')} "
                         f"{_num(r['ours_ratio'], '11.2f')} {_num(r['paper_ms'], '11.3f')} "
                         f"{_num(r['paper_ratio'], '12.2f')}")
        if tpc["missing"] and show_missing:
            lines.append(f"  (paper lists {', '.join(tpc['missing'])}: not run here)")
        lines.append("  ours: separate runs one after the other on a shared machine; for the "
                     "ratios measured in one process, alternating the filters, run "
                     + (bench_command or "`navfmu bench SCENARIO --filters A,B,C`"))
    phase_text = scenario_phases.format_phase_statistics(comparison.get("phases"))
    if phase_text:
        lines.append(phase_text)
    det = comparison.get("outlier_detection")
    if det:
        lines.append("\noutlier detection at the update epochs (injected = the receiver's "
                     "gnss_outlier of the fix used):")
        for name, d in det.items():
            gate = d.get("chi2_threshold")
            gate_text = (f"; gate {gate['value']:g} ({gate['source']}), expected "
                         f"{100 * d['expected_false_alarm_rate_chi2_1']:.1f} % per clean "
                         "observation" if gate else "")
            lines.append(f"  {name}: detected {d['detected_epochs']}/{d['injected_epochs']} "
                         f"injected epochs ({_pct(d['detection_rate'])}); false alarms on "
                         f"{d['false_alarm_epochs']}/{d['clean_epochs']} clean epochs "
                         f"({_pct(d['false_alarm_rate'])}), "
                         f"{d['false_alarm_observations']}/{d['clean_observations']} clean "
                         f"observations ({_pct(d['false_alarm_rate_per_observation'])})"
                         + gate_text)
    return "\n".join(line for line in lines if line)


def write_outputs(runs: Sequence[Run], out: Path, fmt="csv", plots_on=True, title="",
                  reference=None) -> List[Path]:
    """Results (one file per run), metrics.json, report.json (:func:`paper_comparison` with
    ``reference``, when it has anything) and plots, replacing the folder ``out`` as a whole
    (:func:`orchestrator.outputs.staged`: all of them appear together or none does).
    Returns the paths the files have in ``out``."""
    out = Path(out)
    with outputs.staged(out) as stage:
        names = [p.name for p in _write_files(runs, stage, fmt, plots_on, title, reference)]
    return [out / n for n in names]


def _write_files(runs, out: Path, fmt, plots_on, title, reference) -> List[Path]:
    """Write every output file into the folder ``out``; a pending Ctrl-C stops between files.
    A run streamed to a Parquet file (:attr:`Run.series_file`) has its file moved in."""
    written = []
    streamed = {}

    def add(path):
        if path:
            written.append(path)
        interrupts.check()

    for run in runs:
        stem = "results" if len(runs) == 1 else f"results_{run.label}"
        if run.series_file is not None:     # streamed while it ran: move it into place
            streamed[id(run)] = outputs.move_into(run.series_file, out)
            add(streamed[id(run)])
        elif fmt == "npz":
            add(run.results.to_npz(out / f"{stem}.npz"))
        else:
            add(run.results.to_csv(out / f"{stem}.csv"))
    summary = {run.label: {"metrics": run.metrics,
                           "step_time_s": run.results.step_time_s,
                           "exchange_step_time_s": run.results.exchange_step_time_s,
                           "metadata": _jsonable(run.results.metadata)} for run in runs}
    add(atomic_write(out / "metrics.json",
                     lambda f: f.write(json.dumps(summary, indent=2, sort_keys=True))))
    comparison = paper_comparison(runs, reference)
    if comparison:
        add(atomic_write(out / "report.json", lambda f: f.write(
            json.dumps(_jsonable(comparison), indent=2, sort_keys=True))))
    if plots_on and all(has_truth(run.results) for run in runs):
        from . import plots  # matplotlib only where plots are drawn (not in executor workers)

        entries = []
        for run in runs:
            results = (run.results if run.series_file is None
                       else recorder.plot_view(streamed[id(run)]))
            for f in filters_in(results):
                label = run.label if f == FILTER_COMPONENT else f"{run.label}:{f}"
                entries.append((label, results, f, nav_metrics.navigation_errors(results, f)))
        navigation = [en for en in entries if "pos_n" in en[3]]
        attitude = [en for en in entries if "pos_n" not in en[3]]
        if attitude:
            for path in _attitude_plots(attitude, out, title):
                add(path)
        entries = navigation
        if entries:
            add(plots.plot_errors(entries, out / "errors.png", title))
            if len(entries) > 1:  # errors.png compares RMS; each filter's +-3 sigma apart
                for entry in entries:
                    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in entry[0])
                    add(plots.plot_errors([entry], out / f"errors_{safe}.png",
                                          f"{entry[0]} ({title})" if title else entry[0]))
            add(plots.plot_nis(entries, out / "nis.png", title))
            windows = scenario_phases.phase_windows(reference)
            add(plots.plot_series(entries, ADAPTIVE_OUTPUTS, out / "adaptive.png", title,
                                  phases=windows))
            add(plots.plot_r_estimate(entries, out / "r_estimate.png", title))
            add(plots.plot_chi2(entries, out / "chi2.png", title, phases=windows))
            add(plots.plot_outliers(entries, out / "outliers.png", title))
        shown = entries or attitude   # a streamed run's rows are in its plot view only
        first = shown[0][1] if shown else runs[0].results
        truth = nav_metrics.find_component(first, "truth_", ("time", "lat", "lon", "h"))
        add(plots.plot_trajectory(first, truth, out / "trajectory.png", title))
    return written


def _attitude_plots(entries, out: Path, title: str) -> List[Path]:
    """Plots of attitude-only filters: Euler errors with +-3 sigma, the pitch error alone
    (paper 003's Fig. 3), NIS, the R scale factors and the fuzzy inputs when present."""
    from . import plots

    written = [plots.plot_attitude_errors(entries, out / "attitude_errors.png", title),
               plots.plot_attitude_errors(entries, out / "pitch_error.png",
                                          f"{title}: pitch error (paper 003 Fig. 3)",
                                          angles=("pitch",)),
               plots.plot_nis(entries, out / "nis.png", title)]
    for p in (plots.plot_series(entries, R_SCALE_OUTPUTS, out / "r_scale.png", title,
                                log_variables=R_SCALE_OUTPUTS),
              plots.plot_series(entries, FUZZY_INPUT_OUTPUTS, out / "fuzzy_inputs.png", title)):
        if p:
            written.append(p)
    return written


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and value != value:
        return None  # NaN is not JSON
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


def _check_bench_run(model: SystemModel, stop_time, repeat) -> int:
    """The checked ``repeat`` count of a benchmark (at least one run) and its stop time."""
    if int(repeat) != repeat or repeat < 1:
        raise NavfmuError(f"--repeat: the number of runs per path must be a positive integer, "
                          f"got {repeat}")
    prechecks.check_stop_time(stop_time, model.start_time)
    return int(repeat)


def bench(model: SystemModel, stop_time: Optional[float] = None, repeat: int = 2,
          progress_factory=None, log=print) -> Dict[str, Any]:
    """Run the same system through the navcore objects directly and through the FMUs, in one
    process, alternating ``repeat`` times; keep each path's fastest run (the machine is shared,
    the minimum is the least disturbed) and return wall times, their ratio and the
    per-component costs of those runs."""
    repeat = _check_bench_run(model, stop_time, repeat)
    ensure_fmus(model, log=log)
    out: Dict[str, Any] = {}
    best: Dict[str, Any] = {}
    for _ in range(repeat):
        for backend in ("direct", "fmu"):
            sim = Simulation(model, backend=backend,
                             registry=registry() if backend == "direct" else None)
            progress = progress_factory(backend) if progress_factory else None
            t0 = time.perf_counter()
            res = sim.run(stop_time=stop_time, progress=progress)
            wall = time.perf_counter() - t0
            if backend not in best or wall < best[backend][0]:
                best[backend] = (wall, res)
    for backend, (wall, res) in best.items():
        out[backend] = {"wall_s": wall, "steps": len(res.time) - 1,
                        "do_step_us": {c: 1e6 * v for c, v in res.step_time_s.items()},
                        "exchange_us": {c: 1e6 * v for c, v in res.exchange_step_time_s.items()},
                        "master_overhead_us": 1e6 * res.metadata.get("master_overhead_s_per_step",
                                                                     float("nan"))}
    out["repeat"] = repeat
    out["ratio"] = out["fmu"]["wall_s"] / out["direct"]["wall_s"]
    a, b = best["fmu"][1], best["direct"][1]
    out["identical"] = all(
        a.columns[c] == b.columns[c] and (a.data[c] == b.data[c]).all() for c in a.components)
    return out


def bench_filters(model: SystemModel, filters: Sequence[str], stop_time: Optional[float] = None,
                  repeat: int = 3, progress_factory=None, reference=None,
                  log=print) -> Dict[str, Any]:
    """Run ``model`` through the FMUs once per filter of ``filters`` (swapped into the
    ``filter`` component), alternating the filters ``repeat`` times in this process, and keep
    each filter's fastest run (smallest mean do_step time of the filter: the machine is
    shared, the minimum is the least disturbed).  Returns per filter the filter's mean FMU
    do_step time per call (one filter cycle) in ms, the run's wall time, and the ratios to the
    first filter, next to the paper's ``time_per_cycle_ms`` (``reference``, paper.json) when it
    lists the filter; JSON-ready."""
    filters = list(filters)
    if not filters:
        raise NavfmuError("--filters: give at least one filter")
    if len(set(filters)) != len(filters):
        raise NavfmuError(f"--filters: a filter is listed twice: {', '.join(filters)}")
    repeat = _check_bench_run(model, stop_time, repeat)
    models = {f: swap_filter(model, f) for f in filters}
    for m in models.values():
        ensure_fmus(m, log=log)
    best: Dict[str, Dict[str, Any]] = {}
    for _ in range(repeat):
        for f in filters:
            sim = Simulation(models[f], backend="fmu")
            progress = progress_factory(f) if progress_factory else None
            t0 = time.perf_counter()
            res = sim.run(stop_time=stop_time, progress=progress)
            wall = time.perf_counter() - t0
            step = float(res.step_time_s[FILTER_COMPONENT])
            if f not in best or step < best[f]["do_step_s"]:
                best[f] = {"do_step_s": step, "wall_s": wall,
                           "calls": int(res.metadata["step_calls"][FILTER_COMPONENT]),
                           "steps": int(res.metadata["n_steps"]),
                           "stop_time": float(res.metadata["stop_time"]),
                           "cycle_s": float(res.metadata["base_step"])
                           * int(res.metadata["decimation"][FILTER_COMPONENT])}
    paper = (reference or {}).get("time_per_cycle_ms") or {}
    base, paper_base = filters[0], paper.get(filters[0])
    rows = {}
    for f in filters:
        b = best[f]
        ms = 1e3 * b["do_step_s"]
        paper_ms = paper.get(f)
        rows[f] = {"time_per_cycle_ms": ms, "ratio": ms / (1e3 * best[base]["do_step_s"]),
                   "wall_s": b["wall_s"], "filter_calls": b["calls"], "base_steps": b["steps"],
                   "cycle_s": b["cycle_s"], "paper_time_per_cycle_ms": paper_ms,
                   "paper_ratio": (paper_ms / paper_base
                                   if paper_ms is not None and paper_base else None)}
    return {"model": model.name, "backend": "fmu", "stop_time": best[base]["stop_time"],
            "repeat": repeat,
            "baseline": base, "filters": rows}
