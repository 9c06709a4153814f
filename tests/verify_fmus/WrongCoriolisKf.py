"""Test FMU: Kf whose mechanization adds the Coriolis acceleration with the wrong sign
(+2 omega_ie x v instead of -2 omega_ie x v); caught by the noiseless closure."""
import math

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components
from navcore.ins.strapdown import Strapdown

EARTH_RATE = 7.292115e-5


class WrongCoriolisStrapdown(Strapdown):
    def update(self, dtheta, dvel, dt):
        v = self.v_ned.tolist()
        wn, wd = EARTH_RATE * math.cos(self.lat), -EARTH_RATE * math.sin(self.lat)
        super().update(dtheta, dvel, dt)
        w_x_v = (-wd * v[1], wd * v[0] - wn * v[2], wn * v[1])
        # the update adds -2 omega_ie x v dt; adding 4 omega_ie x v dt leaves +2 omega_ie x v dt
        self.v_ned = self.v_ned + [4.0 * dt * c for c in w_x_v]


class WrongCoriolisKfModel(components.Kf):
    model_name = "WrongCoriolisKf"

    def make_engine(self, config, nav):
        nav.__class__ = WrongCoriolisStrapdown
        return super().make_engine(config, nav)


class WrongCoriolisKf(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, WrongCoriolisKfModel)

    def do_step(self, current_time, step_size):
        return fmushell.do_step(self, current_time, step_size)


fmushell.bind_methods(WrongCoriolisKf)
