"""Test FMU: Kf whose mechanization adds the Coriolis acceleration with the wrong sign
(+2 omega_ie x v instead of -2 omega_ie x v); caught by the noiseless closure."""
import math

from pythonfmu import Fmi2Slave

import fmushell
from navcore.components import registry as components
from navcore.ins.strapdown import Strapdown

EARTH_RATE = 7.292115e-5


class WrongCoriolisStrapdown(Strapdown):
    def _nav_terms(self, v, dt):
        zeta, g_cor = super()._nav_terms(v, dt)
        wn, wd = EARTH_RATE * math.cos(self.lat), -EARTH_RATE * math.sin(self.lat)
        w_x_v = (-wd * v[1], wd * v[0] - wn * v[2], wn * v[1])
        # g_cor holds -2 omega_ie x v; adding 4 omega_ie x v leaves +2 omega_ie x v
        return zeta, tuple(g + 4.0 * c for g, c in zip(g_cor, w_x_v))


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
