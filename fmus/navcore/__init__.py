"""navcore: the navigation algorithms of navfmu as plain numpy/scipy code (no FMI).

Wings, lowest first; a wing imports only the ones before it (``tests/test_layout.py``):

* ``core``: the step-wise ``Component`` contract, declared state and its byte format, the
  signal contracts, limits, times on a sample grid and the compiled kernels' decorator;
* ``ins``: constants, the WGS-84 earth model, rotations and MRP, the strapdown mechanization and
  its exact inverse, the 15-state error model, motion profiles, the truth trajectory, the lever
  arm;
* ``sensors``: IMU, GNSS (white and time-correlated) and magnetometer error models, the
  sensor-log format, its times and the converters of other tools' data;
* ``filters``: innovation statistics, the adaptive and robust laws of papers 001 and 004, the
  Kalman, unscented, IMM, CTFA and AHRS engines, the recovery guards, the initial state from
  the data, the NIS monitor and the late-fix history;
* ``vehicles``: the guided UAV's point-mass dynamics, route guidance and turbulence;
* ``components``: the components the FMUs wrap, and their registry
  (``navcore.components.registry``).

``errors`` is the one error hierarchy, for navcore and the master.
"""

#: navfmu's version: the one definition (``pyproject.toml`` reads it, ``navfmu --version``
#: prints it)
__version__ = "0.1.0"
#: the FMI standard every navfmu FMU implements
FMI_VERSION = "2.0"
