"""Test FMU: TrajectoryImu whose gyro white noise is 3 times the gyro_arw_dpsh it declares;
caught by the Allan-deviation ARW check."""
from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components

ARW_FACTOR = 3.0


class NoisyImuModel(components.TrajectoryImu):
    model_name = "NoisyImu"

    def initialize(self, start_time):
        declared = self.params["gyro_arw_dpsh"]
        self.params["gyro_arw_dpsh"] = ARW_FACTOR * declared
        try:
            return super().initialize(start_time)
        finally:
            self.params["gyro_arw_dpsh"] = declared


class NoisyImu(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, NoisyImuModel)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(NoisyImu)
