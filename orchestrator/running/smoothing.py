"""A smoothed solution beside the real-time one (``navfmu run ... --smooth``).

The smoothing itself lives in navcore (:mod:`navcore.components.smoothing`): the scenario is
run once more under the direct backend with the filter's recording class from the navcore
facade, which then gives the smoothed solution at every IMU epoch.  Here that solution is
laid on the run's rows (the row whose filter ``nav_time`` is the epoch) as the outputs of a
filter component of the same name, so the metrics, files and plots treat it as one more
filter, labelled ``<filter>-smoothed``.  To synchronize the IMU's clock with the GNSS
clock, the session may ask for more runs with the fixes on the IMU's clock (the course
estimate, the likelihood search); the smoothed solution of the run whose fixes fit best is
laid on its rows.
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from navcore.core import signals
from navcore.filters.time_offset_search import OffsetSearch

from ..results.run_results import Results
from . import scenarios

#: the suffix of a smoothed run's label
SMOOTHED_SUFFIX = "-smoothed"
_STD_NAMES = [p.name for p in signals.FILTER_OUTPUTS if p.name.startswith("std_")]


def check_smoothable(model, filter=None) -> None:
    """Refuse (one error naming the filter and the supported ones) a filter the smoother
    does not support, before anything runs."""
    from navcore.components.smoothing import SmoothingSession

    SmoothingSession(scenarios.filter_label(model, filter))


def synchronized_run(model, filter=None, synchronize=True, search=OffsetSearch(),
                     **simulate):
    """(session, run, its warnings held back): the recorded run of ``model`` with ``filter``
    (None: the model's own; the keyword arguments of
    :func:`orchestrator.running.scenarios.simulate_scenario` but the backend, which is the
    direct one), refused before running for a filter the smoother does not support.

    ``synchronize``: synchronize the IMU's clock with the GNSS clock after the first run
    (:meth:`navcore.components.smoothing.SmoothingSession.synchronize`: the course
    estimate, else the likelihood search, each offset one more run with the fixes on the
    IMU's clock); the run returned is the one whose fixes fit best (the session's
    ``time_offset``).  ``search``: the likelihood search's bounds and budget
    (:class:`navcore.filters.time_offset_search.OffsetSearch`; None: the course estimate
    only).  The smoother and the offline calibration of a log's IMU clock
    (:mod:`orchestrator.running.clock_calibration`) share it."""
    from navcore.components.smoothing import SmoothingSession

    label = scenarios.filter_label(model, filter)
    session = SmoothingSession(label, search)

    def recorded_run():
        return scenarios.simulate_scenario(model, filter=filter, backend="direct",
                                           components={label: session.component_class},
                                           **simulate)

    run, said = _quietly(recorded_run)
    if synchronize:
        run, said = session.synchronize(lambda: _quietly(recorded_run), first=(run, said))
    return session, run, said


def smoothed_run(model, filter=None, synchronize=True, search=OffsetSearch(),
                 **simulate) -> scenarios.Run:
    """The smoothed run of ``model`` with ``filter``: :func:`synchronized_run`'s run
    smoothed (only its warnings are raised, as they are for the real-time run), on the GNSS
    clock when synchronized."""
    window = simulate.pop("window", None)
    session, run, said = synchronized_run(model, filter, synchronize, search, **simulate)
    label = scenarios.filter_label(model, filter)
    raise_held(said)
    solution = session.solution()
    results = smoothed_results(run.results, solution)
    smoothed = scenarios.measured_run(label + SMOOTHED_SUFFIX, run.model, results, window,
                                      time_origin=run.time_origin)
    smoothed.results.metadata["smoother"] = {
        "method": "Rauch-Tung-Striebel (error state, closed-loop corrections)",
        "epochs": int(len(solution["time"])),
        "recording_mb": round(solution["recording_bytes"] / 1e6, 2),
        **clock_metadata(session)}
    return scenarios.report_inconsistency(smoothed)


def raise_held(said) -> None:
    """Raise the warnings ``said`` a run held back (:func:`synchronized_run`), as they were."""
    for w in said:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def _quietly(run):
    """(``run()``, the warnings it raised, held back)."""
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        return run(), list(said)


def clock_metadata(session) -> dict:
    """The synchronization's entries of the smoothed run's metadata (``session`` a
    synchronized :class:`navcore.components.smoothing.SmoothingSession`): the IMU time offset
    applied [s], the course estimate, its correlation, epochs and reason it was not taken,
    and every offset run with its fixes' fit (mean negative log-likelihood per fix), the
    search's bounds when it ran."""
    clock = session.clock
    if clock is None:
        return {}
    out = {"imu_time_offset_s": round(float(session.time_offset), 4),
           "imu_time_offset_estimate_s": round(float(clock.tau), 4),
           "imu_time_offset_correlation": (None if clock.correlation != clock.correlation
                                           else round(float(clock.correlation), 4)),
           "imu_time_offset_epochs": int(clock.epochs)}
    if clock.reason:
        out["imu_time_offset_not_estimated"] = clock.reason
    out["imu_time_offset_runs"] = len(session.fits)
    out["imu_time_offset_fit_per_fix"] = {f"{k:+.3f}": round(float(v), 4)
                                          for k, v in sorted(session.fits.items())}
    if session.searched:
        out["imu_time_offset_search"] = dataclasses.asdict(session.search)
    return out


def smoothed_results(results: Results, solution) -> Results:
    """``results`` with the filter component's columns replaced by the smoothed solution at
    the rows whose ``nav_time`` is one of its epochs (``aligned`` false on the others)."""
    f = scenarios.FILTER_COMPONENT
    nav_time = results.column(f, "nav_time")
    t = solution["time"]
    k = np.clip(np.searchsorted(t, nav_time), 0, len(t) - 1)
    km = np.clip(k - 1, 0, len(t) - 1)
    k = np.where(np.abs(t[km] - nav_time) < np.abs(t[k] - nav_time), km, k)
    found = np.abs(t[k] - nav_time) <= 1e-6 * np.maximum(1.0, np.abs(nav_time))
    found &= results.column(f, "aligned") > 0.5
    columns = {"nav_time": nav_time, "aligned": found.astype(float)}
    for name, key in zip(signals.NAV_SOLUTION_NAMES, ("lat", "lon", "h", "vn", "ve", "vd",
                                                      "roll", "pitch", "yaw")):
        columns[name] = solution[key][k]
    for i, name in enumerate(signals.NAV_BG_NAMES):
        columns[name] = solution["gyro_bias"][k, i]
    for i, name in enumerate(signals.NAV_BA_NAMES):
        columns[name] = solution["accel_bias"][k, i]
    for i, name in enumerate(_STD_NAMES):
        columns[name] = solution["std"][k, i]
    units = dict(zip(results.columns[f], results.units[f]))
    data = {c: results.data[c] for c in results.components if c != f}
    cols = {c: results.columns[c] for c in data}
    unit_map = {c: results.units[c] for c in data}
    data[f] = np.column_stack(list(columns.values()))
    cols[f] = list(columns)
    unit_map[f] = [units.get(name, "") for name in columns]
    return Results(results.time, data, cols, unit_map, metadata=dict(results.metadata))


__all__ = ["SMOOTHED_SUFFIX", "check_smoothable", "clock_metadata", "smoothed_results",
           "raise_held", "smoothed_run", "synchronized_run"]
