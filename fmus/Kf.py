"""FMU slave 'Kf': a thin FMI shell over navcore.components.Kf (see fmushell.py)."""
from fmushell import ComponentSlave
from navcore import components


class Kf(ComponentSlave):
    component_class = components.Kf
