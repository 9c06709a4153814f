"""FMU slave 'FuzzyUkfAhrs': a thin FMI shell over
navcore.components.ahrs_components.FuzzyUkfAhrs (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import ahrs_components


class FuzzyUkfAhrs(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, ahrs_components.FuzzyUkfAhrs)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(FuzzyUkfAhrs)
