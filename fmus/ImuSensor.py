"""FMU slave 'ImuSensor': a thin FMI shell over
navcore.components.imu_sensor.ImuSensor (see fmushell)."""

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import imu_sensor as components


class ImuSensor(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.ImuSensor)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(ImuSensor)
