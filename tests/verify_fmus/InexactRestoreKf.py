"""Test FMU: Kf whose state restore keeps the covariance in single precision only (a
restored state continues close to, not exactly as, the saved one); caught by fmi.state."""
import numpy as np
from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components


class InexactRestoreKfModel(components.Kf):
    model_name = "InexactRestoreKf"

    @classmethod
    def from_state(cls, state):
        component = super().from_state(state)
        component.engine.P = component.engine.P.astype(np.float32).astype(np.float64)
        return component


class InexactRestoreKf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, InexactRestoreKfModel)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(InexactRestoreKf)
