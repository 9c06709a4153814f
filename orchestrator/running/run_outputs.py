"""The files of ``navfmu run`` / ``compare``: results (one file per run), metrics.json,
report.json and the plots, written together into one output folder
(:func:`orchestrator.results.outputs.staged`)."""
from __future__ import annotations

import json
from pathlib import Path
from typing import List, Sequence

from ..cosim import interrupts
from ..results import metrics as nav_metrics
from ..results import mission_metrics
from ..results import outputs
from ..results import phases as scenario_phases
from ..results import recorder
from .comparison import paper_comparison
from ..results.jsonsafe import jsonable
from ..results.run_results import atomic_write
from .scenarios import FILTER_COMPONENT, Run, has_truth

#: adaptive diagnostics plotted when a filter has them
ADAPTIVE_OUTPUTS = ("q_scale", "r_scale", "fading_factor", "outlier", "compression", "chi2",
                    "model_prob_1", "model_prob_2", "model_prob_3")
#: R scale factors of the attitude filters (paper 003 eq. 25) and the fuzzy inputs (eq. 19)
R_SCALE_OUTPUTS = ("r_scale_accel", "r_scale_mag")
FUZZY_INPUT_OUTPUTS = ("fuzzy_e_accel", "fuzzy_de_accel", "fuzzy_e_mag", "fuzzy_de_mag")


def write_outputs(runs: Sequence[Run], out: Path, fmt="csv", plots_on=True, title="",
                  reference=None, comparison=None, progress=None) -> List[Path]:
    """Results (one file per run), metrics.json, report.json (the paper comparison with
    ``reference``, when it has anything; ``comparison``: that comparison when the caller has
    already computed it) and plots, replacing the folder ``out`` as a whole
    (:func:`orchestrator.results.outputs.staged`: all of them appear together or none does).
    ``progress(done, total)`` is told of every part written: each results file, the JSON
    files, the plots as one part.  Returns the paths the files have in ``out``."""
    out = Path(out)
    if comparison is None:
        comparison = paper_comparison(runs, reference)
    with outputs.staged(out) as stage:
        written = _Written(progress, len(runs) + 1 + bool(comparison) + bool(plots_on))
        names = [p.name for p in _write_files(runs, stage, fmt, plots_on, title, reference,
                                              comparison, written)]
    return [out / n for n in names]


class _Written(list):
    """The paths written so far; a pending Ctrl-C or SIGTERM stops between files;
    ``progress`` hears of each of the ``parts`` done (:meth:`part_done`)."""

    def __init__(self, progress=None, parts=0):
        super().__init__()
        self.progress, self.parts, self.done = progress, parts, 0
        if progress is not None:
            progress(0, parts)

    def add(self, path, part=False):
        if path:
            self.append(path)
        if part:
            self.part_done()
        interrupts.safe_point("writing")

    def part_done(self):
        self.done += 1
        if self.progress is not None:
            self.progress(min(self.done, self.parts), self.parts)


def _write_files(runs, out: Path, fmt, plots_on, title, reference, comparison,
                 written: "_Written") -> List[Path]:
    """Write every output file into the folder ``out``.  A run streamed to a Parquet file
    (:attr:`Run.series_file`) has its file moved in."""
    streamed = {}
    for run in runs:
        stem = "results" if len(runs) == 1 else f"results_{run.label}"
        if run.series_file is not None:     # streamed while it ran: move it into place
            streamed[id(run)] = outputs.move_into(run.series_file, out)
            written.add(streamed[id(run)], part=True)
        elif fmt == "npz":
            written.add(run.results.to_npz(out / f"{stem}.npz"), part=True)
        else:
            written.add(run.results.to_csv(out / f"{stem}.csv"), part=True)
    summary = {run.label: {"metrics": run.metrics,
                           "step_time_s": run.results.step_time_s,
                           "exchange_step_time_s": run.results.exchange_step_time_s,
                           "metadata": jsonable(run.results.metadata)} for run in runs}
    written.add(atomic_write(out / "metrics.json", lambda f: f.write(
        json.dumps(summary, indent=2, sort_keys=True))), part=True)
    if comparison:
        written.add(atomic_write(out / "report.json", lambda f: f.write(
            json.dumps(jsonable(comparison), indent=2, sort_keys=True))), part=True)
    if plots_on and all(has_truth(run.results) for run in runs):
        _write_plots(runs, streamed, out, title, reference, written)
        written.part_done()
    return written


def _write_plots(runs, streamed, out: Path, title, reference, written: _Written) -> None:
    # matplotlib only where plots are drawn (not in executor workers)
    from ..results import plots
    from ..results.plot_style import figure_title

    entries = []
    for run in runs:
        results = (run.results if run.series_file is None
                   else recorder.plot_view(streamed[id(run)]))
        for f in nav_metrics.filters_of(results):
            label = run.label if f == FILTER_COMPONENT else f"{run.label}:{f}"
            entries.append((label, results, f, nav_metrics.navigation_errors(results, f)))
    navigation = [en for en in entries if "pos_n" in en[3]]
    attitude = [en for en in entries if "pos_n" not in en[3]]
    if attitude:
        for path in _attitude_plots(attitude, out, title or figure_title(attitude)):
            written.add(path)
    if navigation:
        _navigation_plots(navigation, out, title, reference, written)
    shown = navigation or attitude   # a streamed run's rows are in its plot view only
    first = shown[0][1] if shown else runs[0].results
    truth = nav_metrics.find_component(first, "truth_", ("time", "lat", "lon", "h"))
    written.add(plots.plot_trajectory(first, truth, out / "trajectory.png", title))
    missions = [(run.label, run.results, FILTER_COMPONENT) for run in runs
                if run.series_file is None and FILTER_COMPONENT in run.results.components]
    vehicle = mission_metrics.find_vehicle(runs[0].results) if missions else None
    if vehicle is not None:
        from ..results.mission_plots import plot_mission

        written.add(plot_mission(missions, vehicle, out / "mission.png",
                                 title or (figure_title(shown) if shown else "")))


def _navigation_plots(entries, out: Path, title, reference, written: _Written) -> None:
    """Plots of INS/GNSS filters: errors (and each filter's +-3 sigma apart when several),
    NIS, the adaptive diagnostics, the R estimate, chi-square and the outliers.  ``title``:
    the caller's, else each figure's from the run (:func:`~orchestrator.results.plot_style.
    figure_title`: the model, the filters it shows, the profile and the span)."""
    from ..results import filter_plots, plots
    from ..results.plot_style import figure_title

    if len(entries) > 1:  # errors.png compares RMS; each filter's +-3 sigma apart
        for entry in entries:
            safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in entry[0])
            written.add(plots.plot_errors([entry], out / f"errors_{safe}.png",
                                          f"{entry[0]} ({title})" if title
                                          else figure_title([entry])))
    title = title or figure_title(entries)
    written.add(plots.plot_errors(entries, out / "errors.png", title))
    written.add(filter_plots.plot_nis(entries, out / "nis.png", title))
    windows = scenario_phases.phase_windows(reference)
    written.add(filter_plots.plot_series(entries, ADAPTIVE_OUTPUTS, out / "adaptive.png",
                                         title, phases=windows))
    written.add(filter_plots.plot_r_estimate(entries, out / "r_estimate.png", title))
    written.add(filter_plots.plot_chi2(entries, out / "chi2.png", title, phases=windows))
    written.add(filter_plots.plot_outliers(entries, out / "outliers.png", title))


def _attitude_plots(entries, out: Path, title: str) -> List[Path]:
    """Plots of attitude-only filters: Euler errors with +-3 sigma, the pitch error alone
    (paper 003's Fig. 3), NIS, the R scale factors and the fuzzy inputs when present."""
    from ..results import filter_plots, plots

    written = [plots.plot_attitude_errors(entries, out / "attitude_errors.png", title),
               plots.plot_attitude_errors(entries, out / "pitch_error.png",
                                          f"{title}: pitch error (paper 003 Fig. 3)",
                                          angles=("pitch",)),
               filter_plots.plot_nis(entries, out / "nis.png", title)]
    for p in (filter_plots.plot_series(entries, R_SCALE_OUTPUTS, out / "r_scale.png", title,
                                       log_variables=R_SCALE_OUTPUTS),
              filter_plots.plot_series(entries, FUZZY_INPUT_OUTPUTS, out / "fuzzy_inputs.png",
                                       title)):
        if p:
            written.append(p)
    return written


__all__ = ["write_outputs", "ADAPTIVE_OUTPUTS"]
