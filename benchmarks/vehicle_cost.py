"""The closed-loop components against TrajectoryImu, through the FMUs, in one invocation.

Two measurements of this checkout, each in this one process, the runs alternating (the
machine may be shared: what holds is a ratio of runs taken back to back); the FMUs are built
once, untimed, before the first pair, and no run reads the ideal samples of another
(``single_run_costs``, as ``navfmu bench``):

* **Per base step** (default): each pair runs ``uav_mission`` (GuidedUav -> ImuSensor +
  GnssReceiver -> Kf -> GuidedUav's guidance) and each ``--reference`` scenario (default
  ``uav_maneuver``, which samples at the same 50 Hz, and ``aircraft_500s``, 100 Hz), the
  order swapping from pair to pair.  A run is the co-simulation loop through the FMUs
  (:meth:`Simulation.run`, backend ``fmu``, no output files) over ``--stop`` seconds, with
  the master's clock (``time.perf_counter_ns``) replaced by the process's CPU clock
  (``time.process_time_ns``), so each component's exchange (set inputs, ``fmi2DoStep``, get
  outputs) is timed in CPU time.  Printed: per component its CPU time per base step (time
  per call x calls per base step), medians over the pairs, and the medians of the per-pair
  ratios GuidedUav / TrajectoryImu and ImuSensor / TrajectoryImu::

      python benchmarks/vehicle_cost.py --pairs 5 --stop 100

* **Whole flights** (``--flights``): each pair runs a 600 s ``uav_mission`` (Kf) and a 500 s
  ``aircraft_500s`` through the FMUs (:meth:`Simulation.run` from instantiation to teardown,
  no output files, the real clock); printed per scenario the wall and the CPU time per
  simulated second (medians) and the medians of the per-pair ratios mission / aircraft::

      python benchmarks/vehicle_cost.py --flights --pairs 3
"""
from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

from checkouts import alternating, argument_parser

HERE = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(HERE / "fmus"), str(HERE)]
MISSION = "uav_mission"
#: the components compared and the one they are compared with (FMU model names)
VEHICLE, SENSOR, REFERENCE = "GuidedUav", "ImuSensor", "TrajectoryImu"
#: the whole flights of ``--flights``: scenario, stop time [s]
FLIGHTS = ((MISSION, 600.0), ("aircraft_500s", 500.0))


def _models(scenarios):
    """The scenarios' models, their FMUs built if missing or stale (untimed)."""
    from orchestrator.running.scenarios import ensure_fmus, load_scenario

    models = {name: load_scenario(HERE / "models" / name) for name in scenarios}
    for model in models.values():
        ensure_fmus(model, log=lambda *a: None)
    return models


def _run(model, stop: float) -> dict:
    """One run through the FMUs: per component (FMU model name) its time per base step [us]
    by the master's clock, the simulated time, and the run's wall and CPU time [s]."""
    from orchestrator.cli.bench import single_run_costs
    from orchestrator.cosim.master import Simulation

    with single_run_costs():
        wall, cpu = time.perf_counter(), time.process_time()
        res = Simulation(model, backend="fmu").run(stop_time=stop)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    meta = res.metadata
    n_steps = meta["n_steps"]
    per_step = {meta["model_names"][n]: 1e6 * res.exchange_step_time_s[n] * calls / n_steps
                for n, calls in meta["step_calls"].items()}
    return {"per_step_us": per_step, "simulated_s": meta["stop_time"] - meta["start_time"],
            "wall_s": wall, "cpu_s": cpu}


def _print_pair(i, pairs, runs, references) -> None:
    costs = (("vehicle", runs[MISSION][-1][VEHICLE]), ("sensor", runs[MISSION][-1][SENSOR]),
             *((f"trajectory in {r}", runs[r][-1][REFERENCE]) for r in references))
    print(f"pair {i + 1}/{pairs}: " + ", ".join(f"{s} {c:.1f}" for s, c in costs) + " us",
          flush=True)


def component_costs(references, pairs: int, stop: float) -> str:
    """The per-base-step measurement (module docstring); its text."""
    scenarios = (MISSION, *references)
    models = _models(scenarios)
    runs = {s: [] for s in scenarios}
    clock, time.perf_counter_ns = time.perf_counter_ns, time.process_time_ns
    try:
        for i, order in alternating(pairs, scenarios):
            for scenario in order:
                runs[scenario].append(_run(models[scenario], stop)["per_step_us"])
            _print_pair(i, pairs, runs, references)
    finally:
        time.perf_counter_ns = clock
    lines = [f"{stop:g} s through the FMUs, CPU us per base step of each component's exchange "
             f"(set inputs, do_step, get outputs), medians of {pairs} alternating pairs:"]
    for scenario in scenarios:
        costs = runs[scenario]
        lines.append(f"  {scenario}: " + ", ".join(
            f"{c} {statistics.median(r[c] for r in costs):.1f}" for c in costs[0]))
    for ref in references:
        for label, name in (("vehicle", VEHICLE), ("sensor", SENSOR)):
            ratios = [m[name] / r[REFERENCE] for m, r in zip(runs[MISSION], runs[ref])]
            lines.append(f"  {label} ({name}) / TrajectoryImu in {ref}: median ratio "
                         f"{statistics.median(ratios):.3f} (per pair "
                         f"{', '.join(f'{x:.3f}' for x in ratios)})")
    return "\n".join(lines)


def flights(pairs: int) -> str:
    """The whole-flight measurement (module docstring); its text."""
    models = _models(name for name, _ in FLIGHTS)
    runs = {name: [] for name, _ in FLIGHTS}
    for i, order in alternating(pairs, FLIGHTS):
        for name, stop in order:
            runs[name].append(_run(models[name], stop))
            r = runs[name][-1]
            print(f"pair {i + 1}/{pairs} {name} {r['simulated_s']:g} s: wall {r['wall_s']:.2f} s,"
                  f" CPU {r['cpu_s']:.2f} s", flush=True)
    (mission, _), (other, _) = FLIGHTS
    lines = [f"whole flights through the FMUs (Simulation.run, no output files), medians of "
             f"{pairs} alternating pairs, per simulated second:"]
    for what in ("wall", "cpu"):
        per = {n: [r[f"{what}_s"] / r["simulated_s"] for r in runs[n]] for n in runs}
        ratios = [a / b for a, b in zip(per[mission], per[other])]
        lines.append(f"  {what}: {mission} {1e3 * statistics.median(per[mission]):.2f} ms, "
                     f"{other} {1e3 * statistics.median(per[other]):.2f} ms; ratio "
                     f"{statistics.median(ratios):.3f} (per pair "
                     f"{', '.join(f'{x:.3f}' for x in ratios)})")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argument_parser(__doc__, pairs=5)
    parser.add_argument("--stop", type=float, default=100.0,
                        help="simulated time of each per-base-step run [s] (default 100)")
    parser.add_argument("--reference", default="uav_maneuver,aircraft_500s",
                        help="comma-separated scenarios whose TrajectoryImu is the reference")
    parser.add_argument("--flights", action="store_true",
                        help="instead: time per simulated second of whole flights")
    args = parser.parse_args(argv)
    if args.flights:
        print(flights(args.pairs))
    else:
        references = [r.strip() for r in args.reference.split(",") if r.strip()]
        print(component_costs(references, args.pairs, args.stop))


if __name__ == "__main__":
    main()
