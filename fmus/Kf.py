"""FMU slave 'Kf': a thin FMI shell over
navcore.components.kf_components.Kf (see fmushell)."""
from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import kf_components as components


class Kf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.Kf)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(Kf)
