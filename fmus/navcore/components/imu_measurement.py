"""The IMU and magnetometer outputs of a sensor component, from ideal increments: one
implementation for :class:`~navcore.components.sensor_components.TrajectoryImu` (increments
from its motion profile) and :class:`~navcore.components.imu_sensor.ImuSensor` (increments from
a vehicle's truth inputs).

:class:`ImuMeasurement` is a mixin of those components: it declares the parameters of the
error models (``seed``, every :class:`~navcore.sensors.imu_errors.ImuErrorModel` and
:class:`~navcore.sensors.magnetometer.MagnetometerModel` parameter), builds the two models and turns
one interval's ideal increments into the ``imu_*`` and ``mag_*`` outputs.  It adds no state
field of its own: the components declare ``errors`` and ``magnetometer`` (their state) and
``mag_on``/``_no_mag`` (derived) themselves, so their saved states keep their shape.
"""
from __future__ import annotations

import numpy as np

from ..core import signals
from ..core.component import Limits, integer, real, string
from ..ins.rotations import _euler_rows
from ..sensors.imu_errors import INTENSITY_REFERENCE_RATE, ImuErrorModel
from ..sensors.magnetometer import MagnetometerModel

#: accepted seeds (numpy's generators take non-negative integers; FMI Integers are 32 bit)
SEED_LIMITS = Limits(0, 2**31 - 1)

_UNIT_OF_DATASHEET = {"deg/h": "deg/h", "deg/sqrt(h)": "deg/sqrt(h)", "ug": "ug",
                      "ug/sqrt(Hz)": "ug/sqrt(Hz)", "ppm": "ppm", "urad": "urad",
                      "deg/h/g": "deg/h/g", "s": "s", "m": "m", "m/s": "m/s", "rad/s": "rad/s",
                      "m/s2": "m/s2", "T": "T", "rad": "rad", "Hz": "Hz", "": ""}


def ports_from_table(table):
    """Ports for a ``{name: (default, unit, description, limits)}`` parameter table of a
    navcore model (``limits`` None for a string)."""
    ports = []
    for name, (default, unit, description, limits) in table.items():
        if isinstance(default, str):
            ports.append(string(name, description, default))
        else:
            ports.append(real(name, _UNIT_OF_DATASHEET[unit], description, default, limits))
    return tuple(ports)


#: the parameters of the IMU's and the magnetometer's errors, and their seed
ERROR_PARAMETERS = (
    integer("seed", "seed of every random error of the IMU and the magnetometer", 1,
            SEED_LIMITS),
    *ports_from_table(ImuErrorModel.PARAMETERS),
    *ports_from_table(MagnetometerModel.PARAMETERS),
)


class ImuMeasurement:
    """Mixin of the IMU components (module docstring): ``self.params`` holds the
    :data:`ERROR_PARAMETERS`; the component calls :meth:`build_error_models` in its
    ``initialize`` and :meth:`measure` once per IMU interval."""

    def build_error_models(self):
        """The IMU and magnetometer error models of the parameters, seeded by ``seed``."""
        p = self.params
        self.errors = ImuErrorModel({k: p[k] for k in ImuErrorModel.PARAMETERS}, p["seed"])
        self.magnetometer = MagnetometerModel(
            {k: p[k] for k in MagnetometerModel.PARAMETERS}, p["seed"])
        mag = self.magnetometer
        # the magnetometer/vibration model runs (and draws) only when it is switched on, so a
        # scenario without it keeps its numbers and its speed
        self.mag_on = bool(mag.field_ned.any() or mag.vibration_on)

    def start_outputs(self, out, start_time, attitude):
        """Write the IMU and magnetometer outputs at the start (no interval yet) into ``out``;
        ``attitude`` is the true (roll, pitch, yaw) at the start, or None when it is not
        known yet (:meth:`start_magnetometer` then writes the magnetometer later)."""
        out.update({p.name: 0.0 for p in signals.IMU + signals.MAG})
        out["imu_time"] = out["mag_time"] = start_time
        self._no_mag = {p.name: out[p.name] for p in signals.MAG}
        if attitude is not None:
            self.start_magnetometer(out, start_time, attitude)

    def start_magnetometer(self, out, t, attitude):
        """The magnetometer sample at the start time (when it is switched on)."""
        if self.mag_on:
            self._write_mag(out, t, attitude)

    def _write_mag(self, out, t, attitude):
        C_bn = np.array(_euler_rows(*attitude))
        m = self.magnetometer.measure(t, C_bn)
        out["mag_time"] = t
        out["mag_x"], out["mag_y"], out["mag_z"] = (float(v) for v in m)

    def measure(self, out, t_end, dt, dtheta, dvel, rate_norm, attitude):
        """Write the measured increments of the interval ``[t_end - dt, t_end]`` into ``out``.

        ``dtheta``, ``dvel``: the ideal body-axis increments (3-arrays); ``rate_norm``
        [rad/s]: ``|dtheta| / dt``, the manoeuvre measure of the error model; ``attitude``:
        the true (roll, pitch, yaw) at ``t_end``, for the magnetometer."""
        intensity = rate_norm / INTENSITY_REFERENCE_RATE
        dtheta, dvel = self.errors.apply(t_end, dt, dtheta, dvel, intensity)
        if self.mag_on:
            self._write_mag(out, t_end, attitude)
            if self.magnetometer.vibrating(t_end):
                dvel = dvel + self.magnetometer.accel_disturbance(t_end) * dt
        else:
            out.update(self._no_mag)
        out["imu_time"] = t_end
        out["imu_dt"] = dt
        dth, dv = dtheta.tolist(), dvel.tolist()   # plain floats: the outputs are state
        update = out.update
        update(zip(signals.IMU_DTHETA_NAMES, dth))
        update(zip(signals.IMU_DVEL_NAMES, dv))
        update(zip(signals.IMU_GYRO_NAMES, [x / dt for x in dth]))
        update(zip(signals.IMU_ACCEL_NAMES, [x / dt for x in dv]))
        return out
