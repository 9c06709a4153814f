"""FMU slave 'TrajectoryImu': a thin FMI shell over navcore.components.TrajectoryImu (see fmushell.py)."""
from fmushell import ComponentSlave
from navcore import components


class TrajectoryImu(ComponentSlave):
    component_class = components.TrajectoryImu
