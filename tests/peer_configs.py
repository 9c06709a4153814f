"""The peer's configuration files (rtklibexplorer/GNSS_IMU's drive_config.py and
walk_config.py) as text in their form, with their values from its public repository, for
the tests of benchmarks/gnss_imu_config.py and benchmarks/real_drive.py --config."""
from __future__ import annotations

import re

DRIVE_CONFIG = '''from imu_math import Init
import numpy as np
imu_sample_rate = 100
imu_offset   = [0., 0., -0.65]  # forward, right, down
gyro_noise_PSD =  0.0038
accel_noise_PSD = 70
accel_bias_PSD = 7
gyro_bias_PSD = 3.8e-5
imu_misalign = np.array([180.0, 0.0, 180.0])
imu_misalign += np.array([0, -6.79, 5.35])
gnss_offset = [0, -0.05, -0.65]
imu_noise_factors = [1, 2, 4, 2, 0.25, 0.25]
init =Init()
init.att_unc = [10, 10, 100]
init.bias_acc_unc = 0.2
init.bias_gyro_unc = 0.2
imu_t_off = -0.125
float_err_gain = 2
single_err_gain = 5
zupt_epcoh_count = 50
zupt_accel_thresh = 0.25
zupt_gyro_thresh = 0.25
zupt_vel_SD = 0.01
zaru_gyro_SD = 0.01
yaw_align_min_vel = 1.0
nhc_min_vel = 1.0
nhc_gyro_thesh = 20
nhc_vel_SD = .25
nhc_vel_SD_coast = 0.05
start_coast = 40
end_coast = 30
coast_len = 15
'''

#: what walk_config.py sets otherwise (Python literals, one assignment each)
WALK_VALUES = {"imu_offset": "[0, 0.05, 0]", "imu_misalign": "np.array([180.0, 0.0, -90.0])",
               "gnss_offset": "[0, 0, 0]", "imu_noise_factors": "[4, 4, 4, 4, 1, 0.25]",
               "imu_t_off": "0", "start_coast": "25", "end_coast": "45"}


def config_text(values=None) -> str:
    """DRIVE_CONFIG with each ``name = value`` of ``values`` instead of the drive's (its
    ``+=`` lines of those names dropped)."""
    text = DRIVE_CONFIG
    for name, value in (values or {}).items():
        text = re.sub(rf"^{name} \+=.*\n", "", text, flags=re.M)
        text = re.sub(rf"^{name}( *)=.*$", f"{name} = {value}", text, flags=re.M)
    return text
