"""FMU slave 'GnssReceiver': a thin FMI shell over navcore.components.GnssReceiver (see fmushell.py)."""
from fmushell import ComponentSlave
from navcore import components


class GnssReceiver(ComponentSlave):
    component_class = components.GnssReceiver
