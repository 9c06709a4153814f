"""FMU slave 'GuidedUav': a thin FMI shell over
navcore.components.guided_uav.GuidedUav (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import guided_uav as components


class GuidedUav(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.GuidedUav)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(GuidedUav)
