"""Outage recovery of every INS/GNSS filter on models/mems_outages, measured against the Kf.

A test helper (and, run as a script, the table of docs/guide/real_sensors.md)::

    python tests/outage_recovery.py [--stop 450] [--filters Kf,Iakf] [--set param=value ...]

The sensors of the scenario run once (:mod:`direct_replay`); each filter is replayed over
them.  Per filter and outage: the 3-D position error ``RECOVERY_EPOCHS`` fixes after the
outage ends and the largest error over the run, both also as a ratio to the Kf's; the RMS
true error over the RMS reported sigma (the norm of std_pn/pe/pd) after the first 60 s, at
the epochs with a fix and at those without; and when the NIS warning came.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from direct_replay import MODELS, SensorRecord, run_filter, simulate_sensors  # noqa: E402

from navcore.sensors.gnss_errors import parse_records  # noqa: E402
from orchestrator.cli.cli_options import parse_sets  # noqa: E402
from orchestrator.running.scenarios import registry  # noqa: E402

SCENARIO = MODELS / "mems_outages"
#: the filters compared (Kf is the reference)
FILTERS = ("Kf", "SageHusaFading", "Iakf", "NewtonRobustKf", "Igg3RobustKf", "Ukf", "CtfaUkf",
           "ImmUkf")
#: "a few epochs after the outage": the error this many fixes after the first fix back
RECOVERY_EPOCHS = 5


@dataclass
class FilterRecovery:
    model: str
    after: List[float]           # error RECOVERY_EPOCHS fixes after each outage [m]
    max_error: float             # largest 3-D position error over the run [m]
    error_to_sigma_gnss: float   # RMS true error / RMS reported sigma, epochs with a fix
    error_to_sigma_outage: float  # the same over the epochs without a fix
    warnings: List[str] = None     # the notices the component gave (the NIS warning)
    r_scale_max: float = 1.0       # largest adaptive R scale (trace R / trace R0) reported
    rows: np.ndarray = None
    error: np.ndarray = None


def outages(sensors: SensorRecord):
    return [(t0, t1) for t0, t1 in parse_records(sensors.parameters["gnss"]["outages"],
                                                  "outages", (("t0", float), ("t1", float)))]


def recovery(sensors: SensorRecord, model: str, overrides: Optional[Dict] = None
             ) -> FilterRecovery:
    run = run_filter(sensors, registry()[model], overrides=overrides)
    t = sensors.time[run.rows]
    error = np.linalg.norm(run.position_error_ned(), axis=1)
    sigma = np.sqrt(sum(run.outputs[f"std_p{a}"] ** 2 for a in "ned"))
    after = []
    for _, t1 in outages(sensors):
        k = int(np.searchsorted(t, t1 - 1e-6)) + RECOVERY_EPOCHS - 1
        after.append(float(error[min(k, len(error) - 1)]))
    settled = t > 60.0
    with_gnss = settled & run.outputs["updated"].astype(bool)
    rms = lambda a: float(np.sqrt(np.mean(a ** 2)))
    return FilterRecovery(model, after, float(error.max()),
                          rms(error[with_gnss]) / rms(sigma[with_gnss]),
                          rms(error[settled & ~with_gnss]) / rms(sigma[settled & ~with_gnss]),
                          run.component.take_notices(), float(run.outputs["r_scale"].max()),
                          run.rows, error)


def table(sensors: SensorRecord, models: Sequence[str] = FILTERS,
          overrides: Optional[Dict[str, Dict]] = None) -> Dict[str, FilterRecovery]:
    return {m: recovery(sensors, m, (overrides or {}).get(m)) for m in models}


def format_table(results: Dict[str, FilterRecovery], sensors: SensorRecord) -> str:
    kf = results["Kf"]
    spans = [f"{t1 - t0:.0f} s" for t0, t1 in outages(sensors)]
    head = ("| filter | " + " | ".join(f"after {s} [m] (x Kf)" for s in spans)
            + " | max [m] (x Kf) | RMS error / RMS sigma: with fixes, in outages"
            + " | NIS warning at |")
    lines = [head, "|" + "---|" * (len(spans) + 4)]
    for name, r in results.items():
        cells = [f"{a:.2f} ({a / k:.2f})" for a, k in zip(r.after, kf.after)]
        cells.append(f"{r.max_error:.2f} ({r.max_error / kf.max_error:.2f})")
        cells.append(f"{r.error_to_sigma_gnss:.1f}, {r.error_to_sigma_outage:.1f}")
        cells.append(", ".join(w.split("at t = ")[1].split(" s ")[0] + " s" for w in r.warnings
                               if "chi-square band" in w) or "-")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None):
    import argparse

    parser = argparse.ArgumentParser()
    parser.add_argument("--stop", type=float, default=None)
    parser.add_argument("--filters", default=",".join(FILTERS))
    parser.add_argument("--set", action="append", default=[])
    args = parser.parse_args(argv)
    sensors = simulate_sensors(SCENARIO, stop_time=args.stop)
    sets = {key.split(".", 1)[1]: value for key, value in
            parse_sets([f"filter.{item}" for item in args.set]).items()}
    models = args.filters.split(",")
    print(format_table(table(sensors, models, {m: sets for m in models}), sensors))


if __name__ == "__main__":
    main()
