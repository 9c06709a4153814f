"""Test FMU: Kf whose measurement covariance is a tenth of the R its r_* parameters declare
(overconfident); caught by the consistency check."""
import dataclasses

import numpy as np
from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components


class OverconfidentKfModel(components.Kf):
    model_name = "OverconfidentKf"

    def make_config(self):
        config = super().make_config()
        return dataclasses.replace(config, r_sigma=config.r_sigma / np.sqrt(10.0))


class OverconfidentKf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, OverconfidentKfModel)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(OverconfidentKf)
