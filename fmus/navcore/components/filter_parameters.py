"""The parameters every INS/GNSS filter declares (:class:`navcore.components.filter_component.
InsGnssFilter`): initial state and covariance, the process and measurement noise assumed, the
latency bound, and those of the start, alignment, biases, lever arm, correlated fixes, noise
factor and land aids, each defined in its own module and gathered here in the order the
FMUs list them."""
from __future__ import annotations

import math

from ..core import signals
from ..core.component import Limits, boolean, real, string
from ..filters.correlated_gnss import CORRELATION_PARAMETERS
from ..filters.initial_biases import INITIAL_BIAS_PARAMETERS
from ..filters.initial_state import INIT_PARAMETERS
from ..filters.land_aids import LAND_AID_PARAMETERS
from ..filters.process_noise_factor import IMU_NOISE_PARAMETERS
from ..filters.static_alignment import STATIC_PARAMETERS
from ..ins.lever_arm import LEVER_ARM_PARAMETERS
from ..sensors.gnss_errors import POS_SIGMA_LIMITS, VEL_SIGMA_LIMITS
from ..sensors.imu_errors import (ACCEL_BIAS_LIMITS, ACCEL_VRW_LIMITS, GYRO_ARW_LIMITS,
                                  GYRO_BIAS_LIMITS)

#: default latency bound of the filters (parameter ``max_fix_age``) [s]: a 1 Hz receiver
#: under a Jacobi master (libcosim) reaches the filter one receiver period (1 s) after the
#: fix was taken; the extra half period covers a receiver's own output latency up to 0.5 s
#: on top (or a 2 Hz receiver with a 1 s delay)
DEFAULT_MAX_FIX_AGE = 1.5
#: accepted ranges of the filters' parameters: the initial state within the ranges of the
#: signals (navcore.core.signals); an assumed GNSS sigma positive and at most the receiver model's
_ANGLE = signals.EULER_ANGLE
_R_POS = Limits(0.0, POS_SIGMA_LIMITS.high, low_open=True)
_R_VEL = Limits(0.0, VEL_SIGMA_LIMITS.high, low_open=True)
_TAU = Limits(0.0, 1e9)


def _gauss_markov_parameters(sensor, suffix, unit, limits):
    """The assumed first-order Gauss-Markov bias of one sensor triad: sigma and time constant."""
    return (real(f"q_{sensor}_bias_instability_{suffix}", unit,
                 f"Gauss-Markov {sensor} bias sigma assumed", 0.0, limits),
            real(f"q_{sensor}_bias_tau_s", "s",
                 f"Gauss-Markov {sensor} bias correlation time (0 = constant)", 0.0, _TAU))


FILTER_PARAMETERS = (
    *signals.state_ports("init", "initial"),
    real("init_roll", "rad", "initial roll", 0.0, _ANGLE),
    real("init_pitch", "rad", "initial pitch", 0.0, _ANGLE),
    real("init_yaw", "rad", "initial yaw", 0.0, _ANGLE),
    real("p0_pos", "m", "initial 1-sigma position error, each axis", 5.0, Limits(0.0, 1e5)),
    real("p0_vel", "m/s", "initial 1-sigma velocity error, each axis", 0.3, Limits(0.0, 1e3)),
    real("p0_att_level", "rad", "initial 1-sigma roll/pitch (north/east tilt) error",
         math.radians(1.0), Limits(0.0, math.pi)),
    real("p0_att_yaw", "rad", "initial 1-sigma heading error", math.radians(1.0),
         Limits(0.0, math.pi)),
    real("p0_gyro_bias_dph", "deg/h", "initial 1-sigma gyro bias", 0.1, GYRO_BIAS_LIMITS),
    real("p0_accel_bias_ug", "ug", "initial 1-sigma accelerometer bias", 100.0,
         ACCEL_BIAS_LIMITS),
    real("q_gyro_arw_dpsh", "deg/sqrt(h)", "gyro angle random walk assumed by the filter", 0.001,
         GYRO_ARW_LIMITS),
    real("q_accel_vrw_ugpsHz", "ug/sqrt(Hz)", "accel velocity random walk assumed by the filter",
         5.0, ACCEL_VRW_LIMITS),
    *_gauss_markov_parameters("gyro", "dph", "deg/h", GYRO_BIAS_LIMITS),
    *_gauss_markov_parameters("accel", "ug", "ug", ACCEL_BIAS_LIMITS),
    real("r_pos_n", "m", "GNSS position 1-sigma assumed, north", 5.0, _R_POS),
    real("r_pos_e", "m", "GNSS position 1-sigma assumed, east", 5.0, _R_POS),
    real("r_pos_d", "m", "GNSS position 1-sigma assumed, down", 5.0, _R_POS),
    real("r_vel_n", "m/s", "GNSS velocity 1-sigma assumed, north", 0.3, _R_VEL),
    real("r_vel_e", "m/s", "GNSS velocity 1-sigma assumed, east", 0.3, _R_VEL),
    real("r_vel_d", "m/s", "GNSS velocity 1-sigma assumed, down", 0.3, _R_VEL),
    string("measurement", "GNSS measurement used: 'position' or 'position_velocity'",
           "position_velocity"),
    real("max_fix_age", "s", "latency bound: a fix whose gnss_time is more than this from the "
         "filter's nav_time is not applied (counted in n_stale_fixes); a later one is applied "
         "at its gnss_time by re-propagation", DEFAULT_MAX_FIX_AGE, Limits(0.0, 3600.0)),
    *INIT_PARAMETERS,
    *STATIC_PARAMETERS,
    *INITIAL_BIAS_PARAMETERS,
    *LEVER_ARM_PARAMETERS,
    boolean("r_from_receiver", "take the receiver's own per-fix position sigmas (inputs "
            "gnss_std_n/e/d, a replayed log's std_n/e/d) as the position part of R instead "
            "of r_pos_*", False),
    *CORRELATION_PARAMETERS,
    *IMU_NOISE_PARAMETERS,
    *LAND_AID_PARAMETERS,
)
