"""The gnss-ins-sim run of this folder: motion_def-attitude.csv, 100 Hz IMU, 1 Hz GPS,
mid-accuracy, ref_frame=0, one run, numpy's legacy generator seeded with 28.

    PYTHONPATH=<gnss-ins-sim checkout> python run_gnss_ins_sim.py <output folder>
"""
import sys

import numpy as np
from gnss_ins_sim.sim import imu_model, ins_sim

np.random.seed(28)
imu = imu_model.IMU(accuracy='mid-accuracy', axis=6, gps=True)
sim = ins_sim.Sim([100, 1, 100], 'motion_def-attitude.csv', ref_frame=0, imu=imu,
                  mode=None, env=None, algorithm=None)
sim.run(1)
sim.results(sys.argv[1])
