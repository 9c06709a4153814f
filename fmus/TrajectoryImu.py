"""FMU slave 'TrajectoryImu': a thin FMI shell over
navcore.components.sensor_components.TrajectoryImu (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import sensor_components as components


class TrajectoryImu(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.TrajectoryImu)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(TrajectoryImu)
