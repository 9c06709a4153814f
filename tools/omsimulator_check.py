"""Run every packaged model through an installed OMSimulator and compare with our master.

Usage::

    python tools/omsimulator_check.py --bin /path/to/OMSimulator/bin/OMSimulator \
        [--python /path/to/OMSimulator/lib/OMSimulator/..] [--stop 20] [--models models]

Install OMSimulator by its own project's instructions (its BUILD.md); this script only uses
it.  For each folder of ``models/`` it writes ``navfmu package --no-step-hints`` (OMSimulator
refuses annotations on a component; every component then steps at the base step), runs

* OMSimulator's command line on the archive (``--stopTime``, ``--stepSize`` = the base step,
  a CSV result file), when ``--bin`` is given;
* OMSimulator's Python API (``OMSimulator.capi``), when ``--python`` is given: a weakly coupled
  system with the archive's FMU copies added one by one, the archive's connections, its
  Real/Integer/Boolean bindings set (Strings come from the copies' start values);
* our master on the same archive, Jacobi exchange (OMSimulator's),

and prints per model the final value of each filter output from each, and the largest
difference over the run.
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "fmus")]

from orchestrator.cosim.master import Simulation  # noqa: E402
from orchestrator.model.ssp_archive import load_model  # noqa: E402
from orchestrator.packaging.package import package  # noqa: E402
from orchestrator.running import scenarios  # noqa: E402

#: the outputs compared (those of the filter component a model has)
COMPARED = ("nav_lat", "nav_lon", "nav_h", "nav_vn", "nav_ve", "nav_vd",
            "nav_roll", "nav_pitch", "nav_yaw")


def _read_csv(path):
    """time (n,), {column name: values (n,)} of an OMSimulator CSV result."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], np.array(rows[1:], dtype=float)
    return body[:, 0], {name: body[:, j] for j, name in enumerate(header)}


def _column(columns, component, variable):
    """The result column of ``component.variable`` whatever root prefix OMSimulator gave."""
    for name, values in columns.items():
        if name.endswith(f".{component}.{variable}") or name == f"{component}.{variable}":
            return values
    return None


def run_cli(binary, archive, model, stop, work):
    result = work / "cli_res.csv"
    done = subprocess.run([str(binary), f"--stopTime={stop}", f"--stepSize={model.base_step}",
                           f"--resultFile={result}", f"--tempDir={work}", str(archive)],
                          cwd=work, capture_output=True, text=True)
    if done.returncode != 0 or not result.exists():
        raise RuntimeError(f"OMSimulator exited with {done.returncode}: "
                           f"{(done.stdout + done.stderr).strip()[-800:]}")
    return _read_csv(result)


def run_python(package_dir, archive, model, stop, work):
    sys.path.insert(0, str(package_dir))
    from OMSimulator.capi import Capi

    oms = Capi()
    folder = work / "unpacked"
    with zipfile.ZipFile(archive) as z:
        z.extractall(folder)
    oms.setTempDirectory(str(work))
    oms.newModel("model")
    oms.addSystem("model.root", 1)  # oms_system_wc: weakly coupled (co-simulation)
    for c in model.components:
        oms.addSubModel(f"model.root.{c.name}", str(folder / c.source_text))
    for k in model.connections:
        oms.addConnection(f"model.root.{k.start_component}.{k.start_connector}",
                          f"model.root.{k.end_component}.{k.end_connector}")
    setters = {"Real": oms.setReal, "Integer": oms.setInteger, "Boolean": oms.setBoolean}
    result = work / "api_res.csv"
    oms.setResultFile("model", str(result))
    oms.setFixedStepSize("model.root", model.base_step)
    oms.setStopTime("model", stop)
    oms.instantiate("model")
    for c in model.components:
        for name, (typ, value) in c.parameters.items():
            if typ in setters:
                setters[typ](f"model.root.{c.name}.{name}", value)
    oms.initialize("model")
    oms.simulate("model")
    oms.terminate("model")
    oms.delete("model")
    return _read_csv(result)


def compare(name, ours, theirs, label):
    time, columns = theirs
    filt = "filter" if "filter" in ours.components else ours.components[-1]
    worst = 0.0
    print(f"  {label}: {len(time)} rows to t = {time[-1]:g} s")
    for variable in COMPARED:
        if not ours.has(filt, variable):
            continue
        other = _column(columns, filt, variable)
        if other is None:
            print(f"    {variable:10s} not in OMSimulator's result")
            continue
        mine = np.interp(time, ours.time, ours.column(filt, variable))
        worst = max(worst, float(np.max(np.abs(mine - other))))
        print(f"    {variable:10s} ours {ours.column(filt, variable)[-1]!r:>24}   "
              f"OMSimulator {other[-1]!r:>24}")
    print(f"  {label}: largest difference over the run {worst:.3g}")


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
        print(folder.name)
        with tempfile.TemporaryDirectory(prefix="omsim-check-") as tmp:
            work = Path(tmp)
            archive = package(folder, work / f"{folder.name}.ssp", step_hints=False)
            model = load_model(archive)
            stop = min(args.stop, model.stop_time)
            ours = Simulation(scenarios.load_scenario(archive), algorithm="jacobi").run(stop)
            for label, run, where in (("command line", run_cli, args.bin),
                                      ("Python API", run_python, args.python)):
                if where is None:
                    continue
                try:
                    compare(folder.name, ours, run(where, archive, model, stop, work), label)
                except Exception as exc:  # report and go on with the next host/model
                    print(f"  {label}: failed: {exc}")


if __name__ == "__main__":
    main()
