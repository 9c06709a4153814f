"""CPU time per base step of every component: this checkout against another one, alternating.

For each scenario, each pair runs the co-simulation loop (:meth:`Simulation.run`, direct
backend, no output files) once in each checkout, in a fresh process on that checkout's own
sources, the order of the two swapping from pair to pair.  Inside a run the master's clock
(``time.perf_counter_ns``) is replaced by the process's CPU clock (``time.process_time_ns``),
so each component's exchange (set inputs, step, get outputs) is timed in CPU time, which
the other processes of a shared machine disturb much less than wall time.  Printed per
component: the median over the pairs of its CPU time per base step (its time per call times
its calls per base step), in each checkout, and the ratio; *rest* is the master's loop and
recording::

    python benchmarks/step_cpu.py --other /path/to/other/checkout
    python benchmarks/step_cpu.py --other ../ref --pairs 5 --stop 100 aircraft_500s:Kf

A scenario argument is ``NAME`` or ``NAME:FILTER`` (the filter swapped in); default
``aircraft_500s`` and ``uav_maneuver``.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from checkouts import alternating, last_json, layout_module, run_python

HERE = Path(__file__).resolve().parents[1]


def child(scenario: str, stop: float) -> None:
    """One timed run inside a checkout (the current folder); prints the costs as JSON."""
    time.perf_counter_ns = time.process_time_ns      # before the master reads its clock
    Simulation = layout_module("orchestrator.cosim.master").Simulation
    scenarios = layout_module("orchestrator.running.scenarios")

    name, _, filter_name = scenario.partition(":")
    model = scenarios.load_scenario(Path("models") / name)
    if filter_name:
        model = scenarios.swap_filter(model, filter_name)
    res = Simulation(model, backend="direct", registry=scenarios.registry()).run(stop_time=stop)
    meta = res.metadata
    n_steps = meta["n_steps"]
    cost = {n: 1e6 * res.exchange_step_time_s[n] * calls / n_steps
            for n, calls in meta["step_calls"].items()}
    cost["total"] = 1e6 * meta["wall_time_s"] / n_steps
    cost["rest"] = cost["total"] - sum(v for k, v in cost.items() if k != "total")
    print(json.dumps(cost))


def _run(checkout: Path, scenario: str, stop: float) -> dict:
    args = [str(Path(__file__).resolve()), "--child", scenario, "--stop", str(stop)]
    return last_json(run_python(checkout, args, scenario, "step_cpu")[1])


def compare(other: Path, scenarios, pairs: int, stop: float) -> None:
    checkouts = {"this": HERE, "other": other.resolve()}
    for scenario in scenarios:
        costs = {"this": [], "other": []}
        for _, order in alternating(pairs, ("this", "other")):
            for label in order:
                costs[label].append(_run(checkouts[label], scenario, stop))
        print(f"\n{scenario}, {stop:g} s, CPU us per base step, medians of {pairs} pairs")
        print(f"{'component':16s} {'this':>8s} {'other':>8s} {'ratio':>6s}")
        for name in costs["this"][0]:
            a = statistics.median(c[name] for c in costs["this"])
            b = statistics.median(c[name] for c in costs["other"])
            print(f"{name:16s} {a:8.1f} {b:8.1f} {a / b:6.3f}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("scenarios", nargs="*", default=["aircraft_500s", "uav_maneuver"])
    ap.add_argument("--other", type=Path, help="the other checkout")
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--stop", type=float, default=100.0)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child, args.stop)
    elif args.other is None:
        ap.error("--other CHECKOUT is required")
    else:
        compare(args.other, args.scenarios, args.pairs, args.stop)


if __name__ == "__main__":
    main()
