"""Run every packaged model through an installed OMSimulator and compare with our master.

Usage::

    python tools/omsimulator_check.py --bin /path/to/OMSimulator/bin/OMSimulator \
        [--python /path/to/OMSimulator/lib/x86_64-linux-gnu] [--stop 20] [--models models]

Install OMSimulator by its own project's instructions (its BUILD.md); this script only uses
it.  For each folder of ``models/`` it writes ``navfmu package --no-step-hints`` (OMSimulator
refuses annotations on a component; every component then steps at the base step), runs

* OMSimulator's command line on the archive (``--stopTime``, ``--stepSize`` = the base step,
  a CSV result file) with the environment ``navfmu env`` prints, when ``--bin`` is given;
* OMSimulator's Python API (``OMSimulator.capi``), when ``--python`` is given (the folder
  holding the ``OMSimulator`` package and ``libOMSimulator.so``), in a child process: a weakly
  coupled system with the archive's FMU copies added one by one, the archive's connections,
  its Real/Integer/Boolean bindings set (Strings come from the copies' start values);
* our master on the same archive, Jacobi exchange (OMSimulator's), at the same step,

and prints per model, for the filter component, each navigation output's final value and the
RMS of the position (or attitude) error against the truth, from our master and from each
OMSimulator run side by side, and the largest difference over the run.
"""
from __future__ import annotations

import argparse
import multiprocessing
import os
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import scipy.io

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "fmus")]

from orchestrator.building.hostenv import host_environment  # noqa: E402
from orchestrator.cosim.master import Simulation  # noqa: E402
from orchestrator.model.ssp_archive import load_model  # noqa: E402
from orchestrator.packaging.package import package  # noqa: E402
from orchestrator.results import metrics  # noqa: E402
from orchestrator.results.run_results import Results  # noqa: E402
from orchestrator.running import scenarios  # noqa: E402

#: the outputs compared (those of the filter component a model has)
COMPARED = ("nav_lat", "nav_lon", "nav_h", "nav_vn", "nav_ve", "nav_vd",
            "nav_roll", "nav_pitch", "nav_yaw")
#: OMSimulator's weakly coupled system (co-simulation), oms_system_wc
OMS_SYSTEM_WC = 1


def results_from_mat(path, model) -> Results:
    """An OMSimulator MAT (v4) result as our :class:`Results`, one row per communication
    point (the last row OMSimulator wrote at each time, after its input update): per component
    of ``model`` every column ``<model>.<system>.<component>.<variable>``."""
    mat = scipy.io.loadmat(path, chars_as_strings=False)
    chars = mat["name"]
    names = ["".join(chars[:, j]).rstrip(" \x00") for j in range(chars.shape[1])]
    info, signals, constants = mat["dataInfo"], mat["data_2"], mat["data_1"]
    time = signals[0]
    rows = np.r_[time[1:] != time[:-1], True]

    def values(j):
        matrix, index = info[0, j], abs(info[1, j]) - 1
        row = (signals[index] if matrix in (0, 2) else np.full(len(time), constants[index, 0]))
        return (np.sign(info[1, j]) * row)[rows]

    data, columns = {}, {}
    for c in model.components:
        picked = [(j, name.split(".")[-1]) for j, name in enumerate(names)
                  if name.split(".")[-2:-1] == [c.name]]
        data[c.name] = np.column_stack([values(j) for j, _ in picked])
        columns[c.name] = [v for _, v in picked]
    return Results(time=time[rows], data=data, columns=columns,
                   units={c: [""] * len(v) for c, v in columns.items()})


def host_env() -> dict:
    """This process's environment with what a native host needs to load our FMUs
    (``navfmu env``) put first."""
    env = dict(os.environ)
    for key, value in host_environment().items():
        sep = " " if key == "LD_PRELOAD" else os.pathsep
        env[key] = sep.join(v for v in (value, env.get(key)) if v)
    return env


def run_cli(binary, archive, model, stop, work) -> Results:
    result = work / "cli_res.mat"
    done = subprocess.run([str(binary), f"--stopTime={stop!r}", f"--stepSize={model.base_step!r}",
                           f"--resultFile={result}", f"--tempDir={work}", str(archive)],
                          cwd=work, capture_output=True, text=True, env=host_env())
    errors = [line for line in (done.stdout + done.stderr).splitlines()
              if line.startswith("error:")]
    if done.returncode != 0 or errors or not result.exists():
        raise RuntimeError(f"OMSimulator exited with {done.returncode}: "
                           + ("; ".join(errors[:3]) or (done.stdout + done.stderr)[-400:]))
    return results_from_mat(result, model)


def _checked(status, call):
    if status.name not in ("ok", "warning"):
        raise RuntimeError(f"OMSimulator API: {call} returned {status.name}")


def _api_simulate(package_dir, archive, stop, work, log):
    """Child process: the archive's FMU copies through OMSimulator's C API, result to
    ``work/api_res.mat``; its log goes to ``log``."""
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    sys.path.insert(0, str(package_dir))
    from OMSimulator.capi import Capi as oms  # an instance, not a class

    model = load_model(archive)
    folder = work / "unpacked"
    with zipfile.ZipFile(archive) as z:
        z.extractall(folder)
    calls = [("setTempDirectory", str(work)), ("newModel", "model"),
             ("addSystem", "model.root", OMS_SYSTEM_WC)]
    calls += [("addSubModel", f"model.root.{c.name}", str(folder / c.source_text))
              for c in model.components]
    calls += [("addConnection", f"model.root.{k.start_component}.{k.start_connector}",
               f"model.root.{k.end_component}.{k.end_connector}") for k in model.connections]
    calls += [("setResultFile", "model", str(work / "api_res.mat")),
              ("setFixedStepSize", "model.root", model.base_step),
              ("setStopTime", "model", stop), ("instantiate", "model")]
    setters = {"Real": "setReal", "Integer": "setInteger", "Boolean": "setBoolean"}
    calls += [(setters[typ], f"model.root.{c.name}.{name}", value)
              for c in model.components for name, (typ, value) in c.parameters.items()
              if typ in setters]
    calls += [("initialize", "model"), ("simulate", "model"), ("terminate", "model"),
               ("delete", "model")]
    for name, *args in calls:
        _checked(getattr(oms, name)(*args), f"{name}{tuple(args)}")


def run_python(package_dir, archive, model, stop, work) -> Results:
    """OMSimulator's Python API in a child process (a crash there ends only that run)."""
    log = work / "api.log"
    child = multiprocessing.get_context("spawn").Process(
        target=_api_simulate, args=(package_dir, archive, stop, work, log))
    child.start()
    child.join()
    result = work / "api_res.mat"
    if child.exitcode != 0 or not result.exists():
        lines = log.read_text(errors="replace").splitlines() if log.exists() else []
        said = [line for line in lines if "rror" in line] or lines[-3:]
        raise RuntimeError(f"exit code {child.exitcode}: {'; '.join(said[:3])}")
    return results_from_mat(result, model)


def summary(results, filt) -> dict:
    """Final value of each compared output and the filter's error RMS (3-D position [m],
    else attitude [deg]) over the run."""
    out = {v: float(results.column(filt, v)[-1]) for v in COMPARED if results.has(filt, v)}
    try:
        m = metrics.filter_metrics(results, filt)
    except Exception as exc:  # a model without the navigation contract's truth
        return {**out, "rms": f"n/a ({exc})"}
    key, unit = ("position_rms_m", "m") if "position_rms_m" in m else ("attitude_rms_deg", "deg")
    out[f"RMS {key.split('_')[0]} error [{unit}]"] = float(
        np.sqrt(sum(v * v for v in m[key].values())))
    return out


def first_rows(results, n) -> Results:
    """``results`` cut to its first ``n`` rows."""
    return Results(time=results.time[:n], data={c: d[:n] for c, d in results.data.items()},
                   columns=results.columns, units=results.units)


def largest_difference(ours, theirs, filt, rows):
    """Largest |ours - theirs| of the compared outputs over ``rows`` (same rows in both),
    and where."""
    worst, where = 0.0, "-"
    for v in COMPARED:
        if ours.has(filt, v) and theirs.has(filt, v):
            diff = np.abs(ours.column(filt, v)[rows] - theirs.column(filt, v)[rows])
            if diff.size and diff.max() > worst:
                k = int(diff.argmax())
                worst, where = float(diff.max()), f"{v} at t = {theirs.time[rows][k]:.10g} s"
    return worst, where


def compare(ours, theirs, filt, label, n_steps):
    """Print our master's summary beside OMSimulator's at the stop time (row ``n_steps``)
    and the largest difference of the compared outputs over the run, row for row.

    OMSimulator sums its time (``t += h``); when the sum falls short of the stop time it
    takes one more step of the remainder (about 1e-15 s), in which the components one step
    late in the Jacobi exchange (receiver, filter) take the sample due at the stop time.
    That last row is compared with our master's one base step later (``ours`` holds it
    when the model runs that long)."""
    n = n_steps + 1
    print(f"  {label}: {len(theirs.time)} communication points to t = {float(theirs.time[-1])!r} s")
    if len(theirs.time) < n:
        raise RuntimeError(f"OMSimulator stopped after {len(theirs.time) - 1} of {n_steps} steps")
    mine, other = summary(first_rows(ours, n), filt), summary(first_rows(theirs, n), filt)
    print(f"    {'at the stop time':28s} {'our master (Jacobi)':>24} {'OMSimulator':>24}")
    for key, value in mine.items():
        print(f"    {key:28s} {value!r:>24} {other.get(key, 'missing')!r:>24}")
    time_off = float(np.max(np.abs(theirs.time[:n] - ours.time[:n])))
    worst, where = largest_difference(ours, theirs, filt, slice(0, n))
    print(f"  {label}: largest difference over {n_steps} steps {worst:.3g} ({where}); "
          f"times differ by up to {time_off:.3g} s")
    if len(theirs.time) > n and len(ours.time) > n:
        extra = theirs.time[-1] - theirs.time[n - 1]
        worst, where = largest_difference(
            first_rows(ours, n + 1), theirs, filt, slice(n, n + 1))
        print(f"  {label}: OMSimulator's extra last step of {extra:.3g} s: its final row vs our "
              f"master's one base step later: largest difference {worst:.3g} ({where})")
    return worst


def check_model(folder, args):
    """Package ``folder``, run it through our master and each OMSimulator host given."""
    with tempfile.TemporaryDirectory(prefix="omsim-check-") as tmp:
        work = Path(tmp)
        archive = package(folder, work / f"{folder.name}.ssp", step_hints=False)
        model = load_model(archive)
        n_steps = round((min(args.stop, model.stop_time) - model.start_time) / model.base_step)
        stop = model.start_time + n_steps * model.base_step
        ours_stop = model.start_time + min(n_steps + 1, round(
            (model.stop_time - model.start_time) / model.base_step)) * model.base_step
        ours = Simulation(scenarios.load_scenario(archive), algorithm="jacobi").run(ours_stop)
        filt = "filter" if "filter" in ours.components else metrics.filters_of(ours)[0]
        for label, run, where in (("command line", run_cli, args.bin),
                                  ("Python API", run_python, args.python)):
            if where is None:
                continue
            host_work = work / label.replace(" ", "_")
            host_work.mkdir()
            try:
                compare(ours, run(where, archive, model, stop, host_work), filt, label, n_steps)
            except Exception as exc:  # report and go on with the next host/model
                print(f"  {label}: failed: {exc}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", type=Path, help="OMSimulator's executable")
    parser.add_argument("--python", type=Path,
                        help="the folder holding OMSimulator's Python package")
    parser.add_argument("--stop", type=float, default=20.0, help="stop time [s]")
    parser.add_argument("--models", type=Path, default=ROOT / "models")
    args = parser.parse_args(argv)
    if args.bin is None and args.python is None:
        parser.error("give --bin and/or --python")
    for folder in sorted(p for p in args.models.iterdir() if (p / "SystemStructure.ssd").is_file()):
        print(folder.name, flush=True)
        check_model(folder, args)
        sys.stdout.flush()


if __name__ == "__main__":
    main()
