"""Test FMU: Kf that applies every new fix, gnss_valid or not; caught by the outage case
(whose invalid fixes carry gross errors)."""
from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components


class IgnoresValidKfModel(components.Kf):
    model_name = "IgnoresValidKf"

    def step(self, t, h, inputs):
        return super().step(t, h, {**inputs, "gnss_valid": True})


class IgnoresValidKf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, IgnoresValidKfModel)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(IgnoresValidKf)
