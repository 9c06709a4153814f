"""navfmu's co-simulation master: SSP loading, fixed-step multirate stepping, recording.

The master is generic: it knows FMUs, connections and steps, nothing about navigation.
See :mod:`orchestrator.cosim.master` for the exact stepping semantics.

The names below are imported on first use, so that ``navfmu`` starts (and installs its
Ctrl-C handling, :mod:`orchestrator.cosim.interrupts`) before numpy, fmpy and scipy load.
"""
import importlib

_EXPORTS = {
    "NavfmuError": "errors",
    "SspError": "errors",
    "WiringError": "errors",
    "SimulationError": "errors",
    "SystemModel": "model.ssp",
    "ComponentSpec": "model.ssp",
    "Connection": "model.ssp",
    "load_ssd": "model.ssp",
    "Results": "results.run_results",
    "Instance": "cosim.backends",
    "FmuInstance": "cosim.fmu_instance",
    "DirectInstance": "cosim.direct_instance",
    "VarInfo": "cosim.backends",
    "Simulation": "cosim.master",
    "simulate": "cosim.master",
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'orchestrator' has no attribute '{name}'")
    return getattr(importlib.import_module(f".{module}", __name__), name)
