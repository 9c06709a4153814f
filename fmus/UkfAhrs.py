"""FMU slave 'UkfAhrs': a thin FMI shell over
navcore.components.ahrs_components.UkfAhrs (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import ahrs_components


class UkfAhrs(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, ahrs_components.UkfAhrs)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(UkfAhrs)
