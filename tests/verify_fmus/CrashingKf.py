"""Test FMU: Kf that aborts its host process (SIGABRT) once the simulation passes 5 s."""
import os

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components

CRASH_AFTER_S = 5.0


class CrashingKfModel(components.Kf):
    model_name = "CrashingKf"

    def step(self, t, h, inputs):
        if t >= CRASH_AFTER_S:
            os.abort()
        return super().step(t, h, inputs)


class CrashingKf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, CrashingKfModel)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(CrashingKf)
