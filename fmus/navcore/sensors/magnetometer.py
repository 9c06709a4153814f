"""Three-axis magnetometer and the vibration disturbance of paper 003's turntable test.

Magnetometer (paper 003 sec. 4: the earth field in NED is ``M = [H cos I, 0, H sin I]``, with
``H`` the total intensity and ``I`` the inclination; no declination, so north is magnetic
north)::

    m_meas = S (C_bn^T M) + b_hi + k(t) w,     w ~ N(0, sigma_m^2 I)

with ``S`` the soft-iron matrix (identity by default), ``b_hi`` the hard-iron offset [T] and
``k(t)`` the vibration factor of the noise.  The defaults of ``H`` and ``I`` for a scenario
come from a geomagnetic model when the scenario is written (see
``models/ahrs_turntable/make_field.py``), never inside the FMU.

Vibration disturbance (paper 003: ideal for the first 100 s, random vibration from 121 s):
from ``vibration_start_s`` on, the accelerometer's specific force gets extra white noise of
1-sigma ``vibration_accel_noise_mps2`` per sample and a sinusoid of amplitude
``vibration_accel_amplitude_mps2`` at ``vibration_frequency_hz`` (axes x, y, z with phases
0, 2 pi/3, 4 pi/3), and the magnetometer noise is multiplied by ``vibration_mag_factor``.

Random numbers: one generator ``default_rng([seed, 3003])`` draws 3 magnetometer normals
and 3 vibration normals per sample, always (so switching one source on never changes the
other's realisation), independent of the IMU error model's generator: a scenario without a
magnetometer or vibration keeps its IMU numbers bit for bit.
"""
from __future__ import annotations

import math
from typing import Any, Dict, Tuple

import numpy as np

from ..core.kernels import jitable
from ..core.limits import FINITE, Limits
from ..errors import ParameterError
from .gnss_errors import check_known, read_declared


def _soft_iron(text: Any) -> np.ndarray:
    if text in ("", None):
        return np.eye(3)
    try:
        values = [float(v) for v in str(text).replace(";", ",").split(",") if v.strip()]
    except ValueError:
        values = []
    if len(values) != 9 or not all(math.isfinite(v) for v in values):
        raise ParameterError(f"parameter 'mag_soft_iron' must be 9 comma-separated finite "
                             f"numbers (the 3x3 matrix, row by row), got {text!r}")
    return np.array(values).reshape(3, 3)


#: phases of the vibration on the three axes [rad]
_AXIS_PHASES = (0.0, 2.0 * math.pi / 3, 4.0 * math.pi / 3)

class MagnetometerModel:
    """Magnetometer and vibration disturbance of the module docstring."""

    #: samples whose normals are drawn in one call
    NORMALS_BLOCK = 256

    state_fields = ("rng", "_normals", "_n_used")
    derived_fields = ("field_ned", "noise", "hard_iron", "soft_iron", "vibration_start",
                      "vibration_noise", "vibration_amplitude", "vibration_frequency",
                      "vibration_mag_factor", "vibration_on", "field_key")

    #: name -> (default, unit, description) of every parameter
    PARAMETERS: Dict[str, Tuple[Any, str, str, Any]] = {
        "mag_field_T": (0.0, "T", "total intensity H of the earth field (0 = no "
                                     "magnetometer: mag_* outputs stay 0)", Limits(0.0, 1e-3)),
        "mag_inclination": (math.radians(60.0), "rad", "inclination I of the earth field "
                                                        "(positive down)",
                            Limits(-math.pi / 2, math.pi / 2)),
        "mag_noise_T": (0.0, "T", "1-sigma white noise of each magnetometer axis per sample",
                        Limits(0.0, 1e-3)),
        "mag_hard_iron_x": (0.0, "T", "hard-iron offset, body x", Limits(-1e-3, 1e-3)),
        "mag_hard_iron_y": (0.0, "T", "hard-iron offset, body y", Limits(-1e-3, 1e-3)),
        "mag_hard_iron_z": (0.0, "T", "hard-iron offset, body z", Limits(-1e-3, 1e-3)),
        "mag_soft_iron": ("", "", "soft-iron matrix S, 9 numbers row by row ('' = identity)",
                          None),
        "vibration_start_s": (0.0, "s", "time the vibration disturbance starts", FINITE),
        "vibration_accel_noise_mps2": (0.0, "m/s2", "1-sigma extra accelerometer white noise "
                                                    "per sample during the vibration",
                                       Limits(0.0, 1e3)),
        "vibration_accel_amplitude_mps2": (0.0, "m/s2", "amplitude of the sinusoidal "
                                                        "vibration on each accelerometer axis",
                                           Limits(0.0, 1e3)),
        "vibration_frequency_hz": (0.0, "Hz", "frequency of the sinusoidal vibration",
                                   Limits(0.0, 1e4)),
        "vibration_mag_factor": (1.0, "", "magnetometer noise multiplied by this during the "
                                          "vibration", Limits(0.0, 1e6)),
    }

    def __init__(self, params: Dict[str, Any], seed: int):
        check_known(params, self.PARAMETERS, "MagnetometerModel")

        def value(name, nonnegative=False):
            return read_declared(params, name, self.PARAMETERS)

        H = value("mag_field_T", nonnegative=True)
        incl = value("mag_inclination")
        if not abs(incl) <= math.pi / 2:
            raise ParameterError(f"parameter 'mag_inclination' = {incl} rad must be within "
                                 "+-pi/2")
        #: earth field in NED [T]
        self.field_ned = np.array([H * math.cos(incl), 0.0, H * math.sin(incl)])
        self.noise = value("mag_noise_T", nonnegative=True)
        self.hard_iron = np.array([value(f"mag_hard_iron_{a}") for a in "xyz"])
        self.soft_iron = _soft_iron(params.get("mag_soft_iron", ""))
        #: the field and soft iron as bytes: models with one key share their body field
        self.field_key = self.field_ned.tobytes() + self.soft_iron.tobytes()
        self.vibration_start = value("vibration_start_s")
        self.vibration_noise = value("vibration_accel_noise_mps2", nonnegative=True)
        self.vibration_amplitude = value("vibration_accel_amplitude_mps2", nonnegative=True)
        self.vibration_frequency = value("vibration_frequency_hz", nonnegative=True)
        self.vibration_mag_factor = value("vibration_mag_factor", nonnegative=True)
        #: the vibration disturbance does something once it starts
        self.vibration_on = (self.vibration_noise > 0.0 or self.vibration_amplitude > 0.0
                             or self.vibration_mag_factor != 1.0)
        self.rng = np.random.default_rng([int(seed), 3003])
        # the normals of NORMALS_BLOCK samples, drawn at once (the generator gives the
        # numbers it gives one sample at a time); row _n_used - 1 is the current sample's
        # (measure, then accel_disturbance)
        self._normals = np.zeros((self.NORMALS_BLOCK, 6))
        self._n_used = self.NORMALS_BLOCK

    def _next_normals(self) -> np.ndarray:
        """The 6 normals of a new sample (3 magnetometer noise, 3 vibration noise)."""
        n = self._n_used
        if n == len(self._normals):
            self._normals = self.rng.standard_normal((self.NORMALS_BLOCK, 6))
            n = 0
        self._n_used = n + 1
        return self._normals[n]

    def vibrating(self, t: float) -> bool:
        """The vibration disturbance acts at time ``t``."""
        return self.vibration_on and t >= self.vibration_start

    def _noise_factor(self, t: float) -> float:
        """The factor of the magnetometer noise at time ``t``."""
        return self.vibration_mag_factor if self.vibrating(t) else 1.0

    def measure(self, t: float, C_bn: np.ndarray) -> np.ndarray:
        """Magnetometer reading [T] at time ``t`` for the attitude ``C_bn``; draws the sample's
        random numbers (call once per sample, then :meth:`accel_disturbance`)."""
        z = self._next_normals()
        body = (self.soft_iron @ (C_bn.T @ self.field_ned)).tolist()
        scale = self.noise * self._noise_factor(t)
        return np.array([_reading(body[i], self.hard_iron[i], scale, z[i]) for i in range(3)])

    def accel_disturbance(self, t: float) -> np.ndarray:
        """Extra specific force [m/s^2] of the vibration at time ``t`` (zero before it)."""
        if not self.vibrating(t):
            return np.zeros(3)
        return np.array(_disturbance(self.vibration_amplitude, self.vibration_frequency,
                                     t - self.vibration_start, self.vibration_noise,
                                     *self._normals[self._n_used - 1, 3:].tolist()))


@jitable
def _reading(body, hard_iron, scale, normal):
    """One axis's reading [T]: the field in body axes ``body`` plus the hard iron plus the
    noise sigma ``scale`` times the sample's normal."""
    return body + hard_iron + scale * normal


@jitable
def _disturbance(amplitude, frequency, elapsed, noise, z0, z1, z2):
    """The vibration's extra specific force [m/s^2] on the three axes, ``elapsed`` seconds
    after its start, with the sample's vibration normals ``z0 .. z2``: the sinusoid of
    ``amplitude`` and ``frequency`` at each axis's phase plus ``noise`` times the normal."""
    phase = 2.0 * math.pi * frequency * elapsed
    return (amplitude * math.sin(phase + _AXIS_PHASES[0]) + noise * z0,
            amplitude * math.sin(phase + _AXIS_PHASES[1]) + noise * z1,
            amplitude * math.sin(phase + _AXIS_PHASES[2]) + noise * z2)
