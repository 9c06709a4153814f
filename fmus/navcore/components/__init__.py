"""The components the FMUs wrap, navcore's highest wing: the sensor components
(``sensor_components``: TrajectoryImu, GnssReceiver; ``imu_sensor``: ImuSensor, on a vehicle's
truth; ``imu_measurement`` the IMU outputs both share), the guided UAV (``guided_uav``), the
sensor-log replay (``replay``), the
shell every INS/GNSS filter shares (``filter_component``), the filter families
(``kf_components``, ``ukf_components``, ``ahrs_components``) and the registry of model names
(``registry``: ``from navcore.components.registry import Kf``).

Wing order: imports every other wing; nothing in navcore imports it.
"""
