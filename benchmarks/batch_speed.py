"""Runs per core-second of Monte Carlo campaigns: this checkout against another, alternating.

For every scenario x filter of ``--cases`` (default: the acceptance list of the batch work,
:data:`CASES`) and every pair, ``navfmu montecarlo SCENARIO --runs R --filters F --stop T``
runs once in each checkout (``python -m orchestrator.cli`` on the checkout's own sources, in
its own temporary folder, direct backend, one worker), the order of the two checkouts
swapping from pair to pair.  A campaign's cost is the CPU time of its process (user + system,
``resource.getrusage`` of the children: the core-seconds it took, steadier than wall time on
a shared machine); the printed number per case is the median over the pairs of
``(R / cost this) / (R / cost other)``, the ratio of runs per core-second.  Each campaign
includes its process start and imports, as a user's command does.  Before the first pair
each checkout runs a two-run campaign of every case, 2 s long, untimed: the compiled kernels
a case uses are then in the disk cache, as on any machine after its first campaign (a first
campaign after a change to navcore compiles them, several seconds).

    python benchmarks/batch_speed.py --other /path/to/other/checkout --pairs 3 --stop 60
    python benchmarks/batch_speed.py --other ../ref --cases aircraft_500s:Kf --batch 1

``--batch B`` passes ``--batch B`` to this checkout's campaigns (default: its own choice);
``--json FILE`` also writes every time measured.
"""
from __future__ import annotations

import json
import resource
import statistics
import tempfile
import time
from pathlib import Path

from checkouts import alternating, argument_parser, other_checkout, run_python

HERE = Path(__file__).resolve().parents[1]
#: (scenario, filter) of the acceptance list
CASES = (("aircraft_500s", "Kf"), ("aircraft_500s", "SageHusaFading"),
         ("aircraft_500s", "Iakf"), ("aircraft_outliers", "Kf"),
         ("aircraft_outliers", "NewtonRobustKf"), ("uav_maneuver", "Ukf"),
         ("uav_maneuver", "CtfaUkf"), ("uav_maneuver", "ImmUkf"),
         ("ahrs_turntable", "UkfAhrs"), ("ahrs_turntable", "FuzzyUkfAhrs"))


#: stop time [s] of the untimed two-run campaign of each case and checkout before the pairs
WARM_UP_STOP = 2.0


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def campaign_cost(checkout: Path, scenario: str, filter_name: str, runs: int, stop, out: Path,
                  batch=None):
    """(CPU seconds, wall seconds) of one campaign in ``checkout``."""
    args = ["-m", "orchestrator.cli", "montecarlo", f"models/{scenario}", "--runs", str(runs),
            "--filters", filter_name, "--out", str(out)]
    if stop:
        args += ["--stop", str(stop)]
    if batch is not None:
        args += ["--batch", str(batch)]
    cpu0 = _children_cpu()
    wall = run_python(checkout, args, f"the campaign {scenario} x {filter_name}",
                      "batch_speed")[0]
    return _children_cpu() - cpu0, wall


def measure(other: Path, cases, pairs: int, runs: int, stop, batch):
    checkouts = {"this": HERE, "other": other}
    costs = {f"{s}:{f}": [] for s, f in cases}
    with tempfile.TemporaryDirectory(prefix="navfmu-batch-") as tmp:
        for scenario, filter_name in cases:      # untimed: the kernels compile once per machine
            for label, checkout in checkouts.items():
                campaign_cost(checkout, scenario, filter_name, 2, WARM_UP_STOP,
                              Path(tmp) / f"warm-{label}-{scenario}-{filter_name}")
        for i, order in alternating(pairs, ("this", "other")):
            for scenario, filter_name in cases:
                key = f"{scenario}:{filter_name}"
                cost = {}
                for label in order:
                    out = Path(tmp) / f"{label}-{i}-{scenario}-{filter_name}"
                    cost[label] = campaign_cost(checkouts[label], scenario, filter_name, runs,
                                                stop, out, batch if label == "this" else None)
                costs[key].append((cost["this"], cost["other"]))
                ratio = cost["other"][0] / cost["this"][0]
                print(f"pair {i + 1}/{pairs} {key:34s} CPU this {cost['this'][0]:7.2f} s  "
                      f"other {cost['other'][0]:7.2f} s  runs per core-second x{ratio:.2f}",
                      flush=True)
    return costs


def summary(costs, runs: int) -> str:
    lines = [f"{'case':34s} {'this [runs/core-s]':>19s} {'other':>8s} {'ratio':>7s}  "
             "(median over pairs; per pair)"]
    for key, pairs in costs.items():
        ratios = [b[0] / a[0] for a, b in pairs]
        this = statistics.median(runs / a[0] for a, _ in pairs)
        other = statistics.median(runs / b[0] for _, b in pairs)
        lines.append(f"{key:34s} {this:19.3f} {other:8.3f} {statistics.median(ratios):7.2f}  "
                     f"({', '.join(f'{r:.2f}' for r in ratios)})")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argument_parser(__doc__, pairs=3, other=True)
    parser.add_argument("--runs", type=int, default=20, help="seeds per campaign")
    parser.add_argument("--stop", type=float, help="stop time of every run [s] (default: "
                        "each scenario's own)")
    parser.add_argument("--batch", type=int, help="--batch of this checkout's campaigns")
    parser.add_argument("--cases", help="comma-separated SCENARIO:FILTER (default: CASES)")
    parser.add_argument("--json", type=Path, help="also write the costs to this file")
    args = parser.parse_args(argv)
    other = other_checkout(parser, args)
    cases = CASES if not args.cases else tuple(
        tuple(c.split(":", 1)) for c in args.cases.split(",") if c.strip())
    t0 = time.perf_counter()
    costs = measure(other, cases, args.pairs, args.runs, args.stop, args.batch)
    print(summary(costs, args.runs))
    print(f"({time.perf_counter() - t0:.0f} s in all)")
    if args.json:
        args.json.write_text(json.dumps({"other": str(args.other), "pairs": args.pairs,
                                         "runs": args.runs, "stop": args.stop,
                                         "costs": costs}, indent=2))


if __name__ == "__main__":
    main()
