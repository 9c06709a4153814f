"""What can be checked before a run starts (or a model is written for another master): its
stop time, the memory it will need, that the scenario's components are connected at all, and
that they accept their parameter values.

The master preallocates the recording (one float64 per recorded variable and row), and the
result files and metrics need copies of it; a run whose recording cannot fit is refused up
front with the numbers, instead of a MemoryError after instantiating the FMUs.  Whether the
stop time lies within what a component can simulate (the end of a motion profile) is the
component's own check at initialization (the experiment's stop time reaches it through
fmi2SetupExperiment), before any step.
"""
from __future__ import annotations

import math
import os
from typing import Optional

from ..errors import NavfmuError

#: bytes of memory needed per recorded value: the recording itself, the table the result
#: file is written from, and the metrics' working copies
BYTES_PER_RECORDED_VALUE = 3 * 8


def check_stop_time(stop_time: Optional[float], start_time: float) -> None:
    """A given ``--stop`` must be a finite number after the start time."""
    if stop_time is None:
        return
    if not math.isfinite(stop_time):
        raise NavfmuError(f"--stop: the stop time must be a finite number of seconds, got "
                          f"{stop_time}")
    if not stop_time > start_time:
        raise NavfmuError(f"--stop: the stop time {stop_time:g} s must be after the start "
                          f"time {start_time:g} s")


def check_connected(model) -> None:
    """A scenario run for its metrics needs connections: without any, the filter receives no
    sensor data and its "errors" would be measured on nothing (all zero, inside 3 sigma).
    Refused by the file's name."""
    if not model.connections:
        raise NavfmuError(f"{model.path}: the system structure has no <ssd:Connections>: no "
                          "component receives another's output, so a run would measure "
                          "nothing; connect the sensors to the filter")


def check_initializes(model, parameters=None) -> None:
    """Every component of ``model`` accepts the model's parameter values: the model is
    initialized and stepped once on its FMUs (each FMU's own checks, ours or not), so that a
    model written for another master (``navfmu package``, ``export``) does not carry a value
    its FMU refuses, e.g. a negative sigma.  ``parameters``: overrides
    (``component.name`` -> value).  The refusal comes as the run's error, naming the
    component and the parameter."""
    import warnings

    from ..cosim.master import simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # a one-step run's filter warnings say nothing here
        simulate(model, backend="fmu", stop_time=model.start_time + model.base_step,
                 parameters=parameters)


def available_memory() -> Optional[int]:
    """Bytes of memory available to a new allocation (Linux MemAvailable; None if unknown)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_memory(n_rows: int, n_columns: int, available: Optional[int] = None) -> None:
    """Refuse a recording of ``n_rows`` x ``n_columns`` values that would not fit into the
    available memory (``available`` bytes; default: :func:`available_memory`)."""
    needed = n_rows * n_columns * BYTES_PER_RECORDED_VALUE
    available = available_memory() if available is None else available
    if available is not None and needed > available:
        raise NavfmuError(
            f"--stop: the run would record {n_rows} rows x {n_columns} variables and need about "
            f"{needed / 1e9:.3g} GB of memory, more than the {available / 1e9:.3g} GB "
            "available; shorten the run (--stop)")


def check_simulation(sim, stop_time: Optional[float]) -> None:
    """Both checks for a :class:`~orchestrator.cosim.master.Simulation` about to run to
    ``stop_time`` (None: the model's)."""
    start = sim.model.start_time
    check_stop_time(stop_time, start)
    stop = sim.model.stop_time if stop_time is None else float(stop_time)
    n_steps = sim._n_steps(start, stop)
    n_rows = n_steps // sim.record_every + 1
    check_memory(n_rows, sum(len(v) for v in sim.recorded.values()))


__all__ = ["check_stop_time", "check_connected", "check_initializes", "check_memory",
           "check_simulation", "available_memory"]
