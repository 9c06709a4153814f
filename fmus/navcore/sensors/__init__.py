"""Sensor error models and sensor data: the IMU error model (``imu_errors``), the GNSS
receiver's noise, steps, outliers and outages (``gnss_errors``), the magnetometer and the
vibration disturbance (``magnetometer``), the sensor-log format (``sensorlog``) and readers of
other tools' data (``log_converters``).

Wing order: imports ``core`` and ``ins``; imported by ``filters`` and ``components``.
"""
