"""FMU slave 'ImuGnssReplay': a thin FMI shell over
navcore.components.replay.ImuGnssReplay (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import replay as components


class ImuGnssReplay(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.ImuGnssReplay)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(ImuGnssReplay)
