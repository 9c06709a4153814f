"""FMU slave 'InsOnly': a thin FMI shell over navcore.components.InsOnly (see fmushell.py)."""
from pythonfmu import Fmi2Slave

import fmushell
from navcore import components


class InsOnly(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fmushell.setup(self, components.InsOnly)

    setup_experiment = fmushell.setup_experiment
    exit_initialization_mode = fmushell.exit_initialization_mode
    do_step = fmushell.do_step
    _get_fmu_state = fmushell.get_fmu_state
    _set_fmu_state = fmushell.set_fmu_state
    to_xml = fmushell.to_xml
