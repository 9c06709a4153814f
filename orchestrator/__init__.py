"""navfmu's co-simulation master: SSP loading, fixed-step multirate stepping, recording.

The master is generic: it knows FMUs, connections and steps, nothing about navigation.
See :mod:`orchestrator.master` for the exact stepping semantics.

The names below are imported on first use, so that ``navfmu`` starts (and installs its
Ctrl-C handling, :mod:`orchestrator.interrupts`) before numpy, fmpy and scipy load.
"""
import importlib

_EXPORTS = {
    "NavfmuError": "errors", "SspError": "errors", "WiringError": "errors",
    "SimulationError": "errors",
    "SystemModel": "ssp", "ComponentSpec": "ssp", "Connection": "ssp", "load_ssd": "ssp",
    "Results": "results",
    "Instance": "backends", "FmuInstance": "fmu_instance", "DirectInstance": "direct_instance",
    "VarInfo": "backends",
    "Simulation": "master", "simulate": "master",
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'orchestrator' has no attribute '{name}'")
    return getattr(importlib.import_module(f".{module}", __name__), name)
