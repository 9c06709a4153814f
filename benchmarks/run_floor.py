"""Where the wall time of ``navfmu run`` goes, and what is left when the components compute nothing.

For one scenario of this checkout, alternating ``--pairs`` times, each in a fresh interpreter:

* **full**: ``navfmu run SCENARIO --no-plots`` (in-process through ``orchestrator.cli.main``),
  its wall time split into the co-simulation loop (``Simulation._loop``), the results CSV
  (``Results.to_csv``) and the rest (imports, loading and instantiating the FMUs, metrics,
  report);
* **held**: the same run with every component's ``advance`` replaced, after its first real
  step, by "keep the outputs of the previous step": the FMI calls (or the direct backend's
  calls), the master's exchange and recording, and the output files remain, the navigation is
  gone.  Its loop time is the floor of the co-simulation loop under the per-sample FMI
  contract: no speed-up of the components can bring the loop below it.

The difference of the two loop times, per base step, is what the components' own work costs.
Prints the medians::

    python benchmarks/run_floor.py aircraft_500s --pairs 3
    python benchmarks/run_floor.py uav_maneuver --pairs 2 --backend direct

The patch works because an FMU built by this checkout imports ``navcore`` from the interpreter
that loads it (pythonfmu runs every slave in the host's interpreter when the host is Python):
the child checks that the held ``advance`` was called and refuses to report otherwise.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from checkouts import alternating, argument_parser, build_fmus, last_json, run_python

HERE = Path(__file__).resolve().parents[1]


def child(scenario: str, held: bool, backend: str, out: str) -> None:
    """One run in this interpreter; prints its phases as one JSON line."""
    t_start = time.perf_counter()
    sys.path[:0] = [str(HERE / "fmus"), str(HERE)]
    import navcore.core.component as component
    import orchestrator.cosim.master as master
    import orchestrator.results.run_results as results
    from orchestrator.cli.commands import main

    phases = {"loop": 0.0, "csv": 0.0, "held_calls": 0, "n_steps": 0}
    if held:
        real_advance = component.Component.advance

        def advance(self, t, h, inputs):
            if "_held_outputs" not in self.__dict__:
                self._held_outputs = real_advance(self, t, h, inputs)
            else:
                self.communication_time = t + h
                phases["held_calls"] += 1
            return self._held_outputs

        component.Component.advance = advance

    real_loop, real_csv = master.Simulation._loop, results.Results.to_csv

    def loop(self, step, record, recording, n_steps, *args, **kwargs):
        ns = real_loop(self, step, record, recording, n_steps, *args, **kwargs)
        phases["loop"] += ns * 1e-9
        phases["n_steps"] += n_steps
        return ns

    def to_csv(self, *args, **kwargs):
        t0 = time.perf_counter()
        try:
            return real_csv(self, *args, **kwargs)
        finally:
            phases["csv"] += time.perf_counter() - t0

    master.Simulation._loop, results.Results.to_csv = loop, to_csv
    args = ["run", f"models/{scenario}", "--no-plots", "--out", out, "--backend", backend]
    try:
        main(args)
    except SystemExit as exc:
        if exc.code:
            raise
    phases["total"] = time.perf_counter() - t_start
    if held and not phases["held_calls"]:
        raise SystemExit("run_floor: the held advance was never called (the components did "
                         "not import this interpreter's navcore)")
    print(json.dumps(phases))


def _run_child(scenario, held, backend, out):
    args = [str(Path(__file__).resolve()), scenario, "--child", "--backend", backend, "--out",
            out] + (["--held"] if held else [])
    return last_json(run_python(HERE, args, scenario, "run_floor")[1])


def measure(scenario: str, pairs: int, backend: str):
    """{"full": [phases, ...], "held": [...]} over ``pairs`` alternating pairs."""
    runs = {"full": [], "held": []}
    with tempfile.TemporaryDirectory(prefix="navfmu-floor-") as tmp:
        for i, order in alternating(pairs, ("full", "held")):
            for kind in order:
                phases = _run_child(scenario, kind == "held", backend, str(Path(tmp) / kind))
                runs[kind].append(phases)
                print(f"pair {i + 1}/{pairs} {kind}: total {phases['total']:.2f} s, loop "
                      f"{phases['loop']:.2f} s, csv {phases['csv']:.2f} s", flush=True)
    return runs


def summary(scenario: str, backend: str, runs) -> str:
    med = {kind: {p: statistics.median(r[p] for r in runs[kind])
                  for p in ("total", "loop", "csv")} for kind in runs}
    for m in med.values():
        m["rest"] = m["total"] - m["loop"] - m["csv"]
    lines = [f"{scenario} ({backend}), medians of {len(runs['full'])} [s]:",
             f"{'phase':8s} {'full':>8s} {'held':>8s}"]
    for p in ("total", "loop", "csv", "rest"):
        lines.append(f"{p:8s} {med['full'][p]:8.2f} {med['held'][p]:8.2f}")
    n_steps = runs["full"][0]["n_steps"]
    per_step = 1e6 / n_steps
    lines.append(f"per base step: loop {med['full']['loop'] * per_step:.1f} us, floor "
                 f"{med['held']['loop'] * per_step:.1f} us, the components' own work "
                 f"{(med['full']['loop'] - med['held']['loop']) * per_step:.1f} us "
                 f"({n_steps} base steps)")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argument_parser(__doc__, pairs=3)
    parser.add_argument("scenario", help="a folder name under models/")
    parser.add_argument("--backend", choices=("fmu", "direct"), default="fmu")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--held", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.scenario, args.held, args.backend, args.out)
        return
    build_fmus(HERE, "run_floor")
    runs = measure(args.scenario, args.pairs, args.backend)
    print(summary(args.scenario, args.backend, runs))


if __name__ == "__main__":
    main()
