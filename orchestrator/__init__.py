"""navfmu's co-simulation master: SSP loading, fixed-step multirate stepping, recording.

The master is generic: it knows FMUs, connections and steps, nothing about navigation.
See :mod:`orchestrator.master` for the exact stepping semantics.
"""
from .errors import NavfmuError, SimulationError, SspError, WiringError
from .ssp import ComponentSpec, Connection, SystemModel, load_ssd
from .results import Results
from .backends import DirectInstance, FmuInstance, Instance, VarInfo
from .master import Simulation, simulate

__all__ = [
    "NavfmuError", "SspError", "WiringError", "SimulationError",
    "SystemModel", "ComponentSpec", "Connection", "load_ssd",
    "Results", "Instance", "FmuInstance", "DirectInstance", "VarInfo",
    "Simulation", "simulate",
]
