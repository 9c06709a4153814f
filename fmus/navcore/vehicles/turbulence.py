"""Continuous turbulence: the Dryden form of MIL-F-8785C, seeded, in discrete time.

Form (MIL-F-8785C sec. 3.7.2, the Dryden spectra; also MIL-HDBK-1797 app. A, which
restates them with ``L_u = 2 L_v = 2 L_w``; we use 8785C's lengths): gust velocities along
the air-relative flight direction (u), to its right (v) and down (w) with the spectra

    Phi_u(W) = sigma_u^2 (2 L_u / pi) / (1 + (L_u W)^2)
    Phi_v(W) = sigma_v^2 (L_v / pi) (1 + 3 (L_v W)^2) / (1 + (L_v W)^2)^2       (w alike)

of the spatial frequency W [rad/m], flown through at the airspeed V (Taylor's frozen
turbulence), i.e. the shaping filters ``H_u(s) = 1 / (1 + T_u s)`` and
``H_v(s) = (1 + sqrt(3) T_v s) / (1 + T_v s)^2`` with ``T = L / V``, scaled to the variance
sigma^2.  Their autocorrelations (the test's independent reference) are
``R_u(tau) = sigma_u^2 exp(-tau/T_u)`` and
``R_v(tau) = sigma_v^2 exp(-tau/T_v) (1 - tau/(2 T_v))``.

Low-altitude scales and intensities (MIL-F-8785C 3.7.2.3, h in ft, 10 ft <= h <= 1000 ft):
``L_w = h``, ``L_u = L_v = h / (0.177 + 0.000823 h)^1.2``, ``sigma_w = 0.1 W20``,
``sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4``, with ``W20`` the wind speed at
20 ft (light turbulence 15 kt, moderate 30 kt, severe 45 kt).  Below 10 ft the 10 ft values
apply; above 1000 ft the 1000 ft values (8785C interpolates to its medium/high-altitude
model between 1000 and 2000 ft; a guidance-study UAV flies below that).

Discretization: exact for the step ``dt`` with the scales held over the step.  Each filter
state is normalized so that its stationary covariance does not depend on T (a u state of
variance 1; the two states of v and of w, the outputs of the two cascaded lags of
``H_v``, with covariance [[1/2, 1/4], [1/4, 1/4]]), so a change of airspeed or height between
steps keeps the process stationary; with ``a = dt / T``: ``x_u' = e^-a x_u + sqrt(1 - e^-2a)
n``, and for v: ``x' = e^-a [[1, 0], [a, 1]] x + w``, ``cov(w) = int_0^a e^-2s [[1, s], [s,
s^2]] ds``; the gust is ``sigma (sqrt(3) x_1 + (1 - sqrt(3)) x_2)`` (unit variance).
"""
from __future__ import annotations

import math

import numpy as np

FT = 0.3048
_SQRT3 = math.sqrt(3.0)
#: height band of the low-altitude model [m]
LOW_ALTITUDE_MIN = 10.0 * FT
LOW_ALTITUDE_MAX = 1000.0 * FT
#: normals drawn per step: u, then the two driving noises of v and of w
NORMALS_PER_STEP = 5
#: steps whose normals are drawn in one call of the generator (the same sequence as one call
#: per step: a generator call costs more than the numbers it draws)
BLOCK_STEPS = 64


def low_altitude(h, w20):
    """MIL-F-8785C low-altitude scales (L_u, L_v, L_w) [m] and intensities (sigma_u, sigma_v,
    sigma_w) [m/s] at height ``h`` [m] above ground for the wind speed ``w20`` [m/s] at 20 ft."""
    h_ft = min(max(h, LOW_ALTITUDE_MIN), LOW_ALTITUDE_MAX) / FT
    base = 0.177 + 0.000823 * h_ft
    L_uv = h_ft / base ** 1.2 * FT
    sigma_w = 0.1 * w20
    sigma_uv = sigma_w / base ** 0.4
    return (L_uv, L_uv, h_ft * FT), (sigma_uv, sigma_uv, sigma_w)


def _second_order_noise(a):
    """Lower Cholesky factor (c11, c21, c22) of the normalized v/w driving-noise covariance
    over ``a = dt / T`` (module docstring)."""
    e = math.exp(-2.0 * a)
    q11 = 0.5 * (1.0 - e)
    q12 = 0.25 - e * (0.5 * a + 0.25)
    q22 = 0.25 - e * (0.5 * a * a + 0.5 * a + 0.25)
    c11 = math.sqrt(q11)
    c21 = q12 / c11
    return c11, c21, math.sqrt(max(q22 - c21 * c21, 0.0))


class DrydenTurbulence:
    """Seeded Dryden gusts (u, v, w) [m/s] in the air-path axes (module docstring).

    ``w20`` [m/s] is the intensity (0: no turbulence, nothing drawn); ``seed`` seeds the
    generator.  :meth:`step` advances by ``dt`` at airspeed ``V`` and height above ground
    ``h``; :attr:`gust` is the current (u, v, w)."""

    state_fields = ("rng", "x_u", "x_v", "x_w", "gust", "_normals", "_next")
    derived_fields = ("w20", "on")

    def __init__(self, w20, seed):
        self.w20 = float(w20)
        self.on = self.w20 > 0.0
        self.rng = np.random.default_rng(seed)
        if self.on:   # stationary start
            z = self.rng.standard_normal(NORMALS_PER_STEP).tolist()
            self.x_u = z[0]
            self.x_v = (math.sqrt(0.5) * z[1], math.sqrt(0.125) * (z[1] + z[2]))
            self.x_w = (math.sqrt(0.5) * z[3], math.sqrt(0.125) * (z[3] + z[4]))
        else:
            self.x_u, self.x_v, self.x_w = 0.0, (0.0, 0.0), (0.0, 0.0)
        self.gust = (0.0, 0.0, 0.0)
        #: the normals of the current block, and the index of the next step's first one
        self._normals = []
        self._next = 0

    def _output(self, sigmas):
        s_u, s_v, s_w = sigmas
        return (s_u * self.x_u,
                s_v * (_SQRT3 * self.x_v[0] + (1.0 - _SQRT3) * self.x_v[1]),
                s_w * (_SQRT3 * self.x_w[0] + (1.0 - _SQRT3) * self.x_w[1]))

    def start(self, h):
        """The gust at the start (the stationary draw of ``__init__``) at height ``h``."""
        if self.on:
            self.gust = self._output(low_altitude(h, self.w20)[1])
        return self.gust

    def step(self, dt, V, h):
        """Advance by ``dt`` [s] at airspeed ``V`` [m/s] and height ``h`` [m]; the new gust."""
        if not self.on:
            return self.gust
        (L_u, L_v, L_w), sigmas = low_altitude(h, self.w20)
        z, i = self._normals, self._next
        if i == len(z):
            z = self._normals = self.rng.standard_normal(NORMALS_PER_STEP
                                                         * BLOCK_STEPS).tolist()
            i = 0
        self._next = i + NORMALS_PER_STEP
        a = dt * V / L_u
        e = math.exp(-a)
        self.x_u = e * self.x_u + math.sqrt(1.0 - e * e) * z[i]
        self.x_v = self._second_order(self.x_v, dt * V / L_v, z[i + 1], z[i + 2])
        self.x_w = self._second_order(self.x_w, dt * V / L_w, z[i + 3], z[i + 4])
        self.gust = self._output(sigmas)
        return self.gust

    @staticmethod
    def _second_order(x, a, n1, n2):
        e = math.exp(-a)
        c11, c21, c22 = _second_order_noise(a)
        return (e * x[0] + c11 * n1, e * (a * x[0] + x[1]) + c21 * n1 + c22 * n2)
