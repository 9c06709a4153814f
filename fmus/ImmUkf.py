"""FMU slave 'ImmUkf': a thin FMI shell over
navcore.components.ukf_components.ImmUkf (see fmushell)."""
from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import ukf_components as components


class ImmUkf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.ImmUkf)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(ImmUkf)
