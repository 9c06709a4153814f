"""A/B wall-time measurement of this checkout against another checkout of navfmu.

Runs, alternating in one invocation (the machine may be shared: a ratio taken from pairs run
back to back is what holds; absolute times do not), for every pair:

* ``navfmu run SCENARIO --no-plots`` through the FMUs (``python -m orchestrator.cli run``
  of each checkout, in its own folder, on its own FMUs in ``fmus/dist``) for each of the
  paper scenarios ``aircraft_500s``, ``aircraft_outliers`` and ``uav_maneuver``;
* a campaign of ``--runs`` seeds (default 10) of ``--campaign-scenario`` through the direct
  backend, in one process per checkout: for seed ``s = 1..runs`` the scenario with
  ``trajectory.seed = gnss.seed = s``, through ``orchestrator.running.scenarios.simulate_scenario``
  (the same work in any checkout, also in those that predate ``navfmu montecarlo``).

Each task runs once in each checkout per pair, the order of the two checkouts swapping from
pair to pair; the printed ratio is the median over the pairs of (this / other) wall time.
The FMUs of both checkouts are built once before the first pair (untimed).

    python benchmarks/ab_speed.py --other /path/to/other/checkout
    python benchmarks/ab_speed.py --other ../ref --pairs 5 --stop 100 --campaign-stop 100

``--stop`` shortens every run (default: each scenario's own stop time); ``--tasks`` selects
tasks (``run:aircraft_500s,campaign``).  ``--json FILE`` also writes every time measured.

``--flat SCENARIO`` measures instead, in this checkout only, whether the per-step cost is
flat in the flight length: the co-simulation loop's wall time per base step of a ``--short``
(default 600 s) and a ``--long`` (default 3600 s) run, alternating ``--pairs`` times::

    python benchmarks/ab_speed.py --flat uav_maneuver --pairs 3
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from checkouts import alternating, argument_parser, build_fmus, layout_module, run_python

HERE = Path(__file__).resolve().parents[1]
SCENARIOS = ("aircraft_500s", "aircraft_outliers", "uav_maneuver")


def _call(checkout: Path, args, what: str) -> float:
    """Wall time [s] of ``python ARGS`` run in ``checkout`` on its own sources."""
    return run_python(checkout, args, what, "ab_speed")[0]


def _task_args(task: str, out: Path, stop, campaign_stop, runs: int, scenario: str):
    if task == "campaign":
        args = [str(Path(__file__).resolve()), "--seed-loop", scenario, "--runs", str(runs)]
        return args + (["--campaign-stop", str(campaign_stop)] if campaign_stop else [])
    name = task.split(":", 1)[1]
    args = ["-m", "orchestrator.cli", "run", f"models/{name}", "--no-plots", "--out", str(out)]
    return args + (["--stop", str(stop)] if stop else [])


def seed_loop(scenario: str, runs: int, stop) -> None:
    """The campaign task, run inside a checkout: ``runs`` seeds through the direct backend."""
    scenarios = layout_module("orchestrator.running.scenarios")
    model = scenarios.load_scenario(Path("models") / scenario)
    for seed in range(1, runs + 1):
        scenarios.simulate_scenario(model, backend="direct", stop_time=stop, build=False,
                          parameters={"trajectory.seed": seed, "gnss.seed": seed},
                          log=lambda *a, **k: None)


def flat(scenario: str, short: float, long: float, pairs: int, backend: str) -> str:
    """Per-step cost of a ``short`` and a ``long`` run of ``scenario`` in this checkout,
    alternating ``pairs`` times in this process: wall and CPU time of :meth:`Simulation.run`
    (instantiation to teardown, no output files) per base step, medians and their ratios (the
    CPU time of this process is the steadier one on a loaded machine).  The runs alternate in
    one process, so none may read the ideal samples of another (``single_run_costs``)."""
    sys.path[:0] = [str(HERE / "fmus"), str(HERE)]
    from orchestrator.cli.bench import single_run_costs
    from orchestrator.cosim.master import Simulation
    from orchestrator.building.build import ensure_fmus
    from orchestrator.running.scenarios import load_scenario, registry

    model = load_scenario(HERE / "models" / scenario)
    if backend == "fmu":
        ensure_fmus(model, log=lambda *a: None)
    cost = {short: [], long: []}
    cpu = {short: [], long: []}
    for i, order in alternating(pairs, (short, long)):
        for stop in order:
            sim = Simulation(model, backend=backend,
                             registry=registry() if backend == "direct" else None)
            t0, c0 = time.perf_counter(), time.process_time()
            with single_run_costs():
                res = sim.run(stop_time=stop)
            steps = res.metadata["n_steps"]
            cost[stop].append((time.perf_counter() - t0) / steps)
            cpu[stop].append((time.process_time() - c0) / steps)
            print(f"pair {i + 1}/{pairs} {scenario} {stop:g} s ({backend}): "
                  f"{1e6 * cost[stop][-1]:.1f} us wall, {1e6 * cpu[stop][-1]:.1f} us CPU per "
                  "base step", flush=True)
    lines = []
    for what, values in (("wall", cost), ("CPU", cpu)):
        a, b = statistics.median(values[short]), statistics.median(values[long])
        lines.append(f"{scenario} ({backend}), {what}: {1e6 * a:.1f} us per base step over "
                     f"{short:g} s, {1e6 * b:.1f} us over {long:g} s; long / short = "
                     f"{b / a:.3f} (medians of {pairs})")
    return "\n".join(lines)


def measure(other: Path, tasks, pairs: int, stop, campaign_stop, runs: int, scenario: str):
    """{task: [(this_s, other_s), ...]} over ``pairs`` alternating pairs."""
    checkouts = {"this": HERE, "other": other}
    for checkout in checkouts.values():
        build_fmus(checkout, "ab_speed")
    times = {t: [] for t in tasks}
    with tempfile.TemporaryDirectory(prefix="navfmu-ab-") as tmp:
        for i, order in alternating(pairs, ("this", "other")):
            for task in tasks:
                wall = {}
                for label in order:
                    out = Path(tmp) / label / task.replace(":", "-")
                    args = _task_args(task, out, stop, campaign_stop, runs, scenario)
                    wall[label] = _call(checkouts[label], args, task)
                times[task].append((wall["this"], wall["other"]))
                print(f"pair {i + 1}/{pairs} {task:26s} this {wall['this']:8.2f} s  other "
                      f"{wall['other']:8.2f} s  ratio {wall['this'] / wall['other']:.3f}",
                      flush=True)
    return times


def summary(times) -> str:
    lines = [f"{'task':26s} {'median this [s]':>16s} {'median other [s]':>17s} "
             f"{'median ratio':>13s}  (this / other, per pair)"]
    for task, pairs in times.items():
        ratios = [a / b for a, b in pairs]
        lines.append(f"{task:26s} {statistics.median(a for a, _ in pairs):16.2f} "
                     f"{statistics.median(b for _, b in pairs):17.2f} "
                     f"{statistics.median(ratios):13.3f}  "
                     f"({', '.join(f'{r:.3f}' for r in ratios)})")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argument_parser(__doc__, pairs=5)
    parser.add_argument("--other", type=Path, help="the other checkout (its root folder)")
    parser.add_argument("--stop", type=float, help="stop time of the scenario runs [s] "
                        "(default: each scenario's own)")
    parser.add_argument("--campaign-stop", type=float,
                        help="stop time of each campaign run [s] (default: the scenario's)")
    parser.add_argument("--runs", type=int, default=10, help="seeds of the campaign task")
    parser.add_argument("--campaign-scenario", default="aircraft_500s")
    parser.add_argument("--tasks", default=",".join([f"run:{s}" for s in SCENARIOS]
                                                    + ["campaign"]))
    parser.add_argument("--json", type=Path, help="also write the times to this file")
    parser.add_argument("--flat", metavar="SCENARIO", help="instead: per-step cost of a "
                        "--short and a --long run of SCENARIO in this checkout (alternating "
                        "--pairs times, one process)")
    parser.add_argument("--short", type=float, default=600.0)
    parser.add_argument("--long", type=float, default=3600.0)
    parser.add_argument("--backend", choices=("fmu", "direct"), default="fmu",
                        help="backend of --flat")
    parser.add_argument("--seed-loop", metavar="SCENARIO", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.seed_loop:
        seed_loop(args.seed_loop, args.runs, args.campaign_stop)
        return
    if args.flat:
        print(flat(args.flat, args.short, args.long, args.pairs, args.backend))
        return
    if args.other is None or not (args.other / "orchestrator").is_dir():
        parser.error("--other: give the root folder of another navfmu checkout")
    tasks = [t.strip() for t in args.tasks.split(",") if t.strip()]
    times = measure(args.other.resolve(), tasks, args.pairs, args.stop, args.campaign_stop,
                    args.runs, args.campaign_scenario)
    print(summary(times))
    if args.json:
        args.json.write_text(json.dumps({"other": str(args.other), "pairs": args.pairs,
                                         "stop": args.stop, "campaign_stop": args.campaign_stop,
                                         "runs": args.runs, "times": times}, indent=2))


if __name__ == "__main__":
    main()
