"""navcore: the navigation algorithms of navfmu as plain numpy/scipy code (no FMI).

Modules are named for what they compute: ``constants`` (G0, WGS-84, unit factors), ``earth``
(WGS-84 earth model), ``rotations``, ``strapdown`` (mechanization), ``trajectory`` (truth and
ideal IMU from a motion profile; ``motion_profiles`` the profiles, ``profile_segments`` their
kinematics), ``imu_errors`` and ``gnss_errors`` (sensor error models), ``error_model``
(15-state INS error dynamics), ``ins_gnss_kf`` (error-state Kalman filter),
``innovation_stats`` (NIS, chi-square quantiles and gates), ``adaptive_laws`` (paper 001),
``robust_laws`` (paper 004), ``unscented``/``ctfa``/``imm`` (paper 000), the engines
``adaptive_filters``, ``ukf_filters`` and ``ahrs``, the step-wise models wrapped by the FMUs
(``component`` the contract, ``sensor_components``, ``replay``, ``filter_component``,
``kf_components``, ``ukf_components``, ``ahrs_components``, registered in ``components``),
``errors`` (the one error hierarchy), ``signals`` (the variable contracts), ``timing`` (sample
grids and the one time tolerance) and ``latency`` (the history that applies a late GNSS fix at its
time).
"""
