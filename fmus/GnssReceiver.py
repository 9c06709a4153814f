"""FMU slave 'GnssReceiver': a thin FMI shell over
navcore.components.sensor_components.GnssReceiver (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import sensor_components as components


class GnssReceiver(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.GnssReceiver)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(GnssReceiver)
