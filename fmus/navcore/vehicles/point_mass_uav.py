"""A fixed-wing UAV at the level of a guidance study: point mass, coordinated bank-to-turn.

State: airspeed ``V`` [m/s], air-relative heading ``psi`` and flight-path angle ``gamma``
[rad], bank ``phi`` [rad], the rates of bank and flight-path angle, position (geodetic) and
the gust the airframe feels.  Dynamics with the commands held over a step (guidance-level
model as in Beard & McLain, *Small Unmanned Aircraft* (2012) ch. 9, coordinated turn; the
bank and flight-path loops second order, so the body rates stay continuous when a command
steps, as at a waypoint switch or a navigation update)::

    psi''  : psi' = g tan(phi) / V                          (coordinated turn)
    phi''  = w_b^2 (phi_c - phi) - 2 zeta w_b phi',     |phi_c| <= min(bank_limit, acos(1/n_max))
    gamma''= w_g^2 (gamma_c - gamma) - 2 zeta w_g gamma',
             gamma_c = asin(clip(k_h (h_c - h_seen), +-climb_rate_limit) / V)   (V at the
             step's start)
    V'     = clip((V_c - V) / tau_airspeed, +-accel_limit)

integrated by one classical Runge-Kutta step per sample.  Ground velocity (NED) =
``V [cos(gamma) cos(psi), cos(gamma) sin(psi), -sin(gamma)]`` + steady wind + felt gust, the
felt gust a first-order lag (``gust_response_time``) of the Dryden gust
(:mod:`navcore.vehicles.turbulence`, rotated from the air-path axes by ``psi``, linear between its
samples): the airframe's translational response to the air mass, which a point mass
otherwise lacks.  Position is the
trapezoid of the ground velocities (:func:`navcore.ins.strapdown.integrate_position`), so the
strapdown's exact inverse (ImuSensor) reproduces the truth.  Attitude: roll ``phi``, pitch
``gamma``, yaw ``psi`` (no angle of attack or sideslip: the body x axis is the air-relative
velocity, so the nose crabs into a cross wind).

Body rates and specific force at a sample (for an IMU taking rates): the Euler rates from the
dynamics give ``omega_nb^b``; the inertial body rate adds ``C_nb (omega_ie^n + omega_en^n)``;
the specific force is ``C_nb (dv/dt + (2 omega_ie^n + omega_en^n) x v - g^n)`` (Groves 2013
eq. 5.54), each from the derivatives at the end of the step just flown.
"""
from __future__ import annotations

import math

from ..ins.constants import G0
from ..ins.earth import OMEGA_IE
from ..ins.rotations import _euler_rows
from ..ins.strapdown import _gravity, _radii, integrate_position


def _clip(x, limit):
    return max(-limit, min(limit, x))


class PointMassUav:
    """The dynamics of the module docstring; limits and loop constants from ``config`` (a
    dict: bank_bandwidth, climb_bandwidth, loop_damping, tau_airspeed, altitude_gain,
    bank_limit, load_factor_limit, climb_rate_limit, accel_limit, gust_response_time, wind
    (n, e, d))."""

    state_fields = ("lat", "lon", "h", "V", "psi", "gamma", "phi", "gamma_rate", "phi_rate",
                    "felt_gust", "v_ned", "rates")
    derived_fields = ("config", "bank_max", "_loops")

    def __init__(self, config, lat, lon, h, V, psi):
        self.config = dict(config)
        c = self.config
        self.bank_max = min(c["bank_limit"], math.acos(1.0 / c["load_factor_limit"]))
        self._loops = (c["loop_damping"], c["bank_bandwidth"], c["climb_bandwidth"],
                       c["tau_airspeed"], c["accel_limit"])
        self.lat, self.lon, self.h = float(lat), float(lon), float(h)
        self.V, self.psi, self.gamma, self.phi = float(V), float(psi), 0.0, 0.0
        self.gamma_rate = self.phi_rate = 0.0
        self.felt_gust = (0.0, 0.0, 0.0)
        self.v_ned = self._ground_velocity()
        #: (body rate x, y, z, specific force x, y, z) at the latest sample
        self.rates = self._rates((0.0,) * 6, (0.0, 0.0, 0.0))

    def _ground_velocity(self):
        V, psi, gamma = self.V, self.psi, self.gamma
        wn, we, wd = self.config["wind"]
        gn, ge, gd = self.felt_gust
        cg = math.cos(gamma)
        return (V * cg * math.cos(psi) + wn + gn, V * cg * math.sin(psi) + we + ge,
                -V * math.sin(gamma) + wd + gd)

    def attitude(self):
        """(roll, pitch, yaw) [rad], yaw in (-pi, pi]."""
        return self.phi, self.gamma, math.atan2(math.sin(self.psi), math.cos(self.psi))

    def start_gust(self, gust_ned):
        """The rates at the start in the gust ``gust_ned`` (the felt gust starts at 0)."""
        tau = self.config["gust_response_time"]
        self.rates = self._rates((0.0,) * 6, tuple(g / tau for g in gust_ned))

    def turn_rate(self):
        """psi' [rad/s] now."""
        return G0 * math.tan(self.phi) / self.V

    def _derivatives(self, x, targets):
        """d/dt of (V, psi, gamma, phi, gamma', phi') towards ``targets`` = (bank, airspeed,
        flight-path angle), the bank already limited."""
        V, psi, gamma, phi, gamma_rate, phi_rate = x
        bank_c, airspeed_c, gamma_c = targets
        zeta, wb, wg, tau_v, accel_limit = self._loops
        dV = (airspeed_c - V) / tau_v
        return (max(-accel_limit, min(accel_limit, dV)),
                G0 * math.tan(phi) / V,
                gamma_rate,
                phi_rate,
                wg * wg * (gamma_c - gamma) - 2.0 * zeta * wg * gamma_rate,
                wb * wb * (bank_c - phi) - 2.0 * zeta * wb * phi_rate)

    def _targets(self, commands):
        """(bank, airspeed, flight-path angle) the loops follow over a step of ``commands``
        (bank, airspeed, climb rate): the bank limited, the climb rate as an angle at the
        airspeed the step starts with."""
        bank_c, airspeed_c, climb_c = commands
        return (_clip(bank_c, self.bank_max), airspeed_c,
                math.asin(_clip(climb_c / self.V, 1.0)))

    def climb_command(self, h_command, h_seen):
        """The climb rate [m/s] the height loop asks for, on the height guidance sees."""
        c = self.config
        return _clip(c["altitude_gain"] * (h_command - h_seen), c["climb_rate_limit"])

    def _state(self):
        return (self.V, self.psi, self.gamma, self.phi, self.gamma_rate, self.phi_rate)

    def step(self, dt, commands, gust_start, gust_end):
        """Fly ``dt`` [s] with ``commands`` = (bank, airspeed, climb rate) held and the Dryden
        gust (NED) going linearly from ``gust_start`` to ``gust_end``; returns the new ground
        velocity."""
        x = self._state()
        f = self._derivatives
        targets = self._targets(commands)
        half = 0.5 * dt
        k1 = f(x, targets)
        k2 = f([a + half * b for a, b in zip(x, k1)], targets)
        k3 = f([a + half * b for a, b in zip(x, k2)], targets)
        k4 = f([a + dt * b for a, b in zip(x, k3)], targets)
        sixth = dt / 6.0
        (self.V, self.psi, self.gamma, self.phi, self.gamma_rate, self.phi_rate) = [
            a + sixth * (p + 2.0 * q + 2.0 * r + s) for a, p, q, r, s in zip(x, k1, k2, k3, k4)]
        # f' = (g(t) - f) / tau with g linear over the step, solved exactly
        tau = self.config["gust_response_time"]
        decay = math.exp(-dt / tau)
        felt = []
        for now, g0, g1 in zip(self.felt_gust, gust_start, gust_end):
            slope = (g1 - g0) / dt
            felt.append(g1 - tau * slope + (now - g0 + tau * slope) * decay)
        self.felt_gust = tuple(felt)
        v_prev = self.v_ned
        self.v_ned = self._ground_velocity()
        self.lat, self.lon, self.h = integrate_position(self.lat, self.lon, self.h, v_prev,
                                                        self.v_ned, dt)
        gust_rate = tuple((g - now) / tau for now, g in zip(self.felt_gust, gust_end))
        self.rates = self._rates(f(self._state(), targets), gust_rate)
        return self.v_ned

    def _rates(self, derivatives, gust_rate):
        """(inertial body rate [rad/s] x, y, z, specific force [m/s^2] x, y, z) now."""
        dV, dpsi, dgamma, dphi = derivatives[:4]
        phi, theta, _ = self.attitude()
        psi, V, gamma = self.psi, self.V, self.gamma
        sp, cp, st, ct = math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta)
        # omega_nb^b from the ZYX Euler rates
        p = dphi - dpsi * st
        q = dgamma * cp + dpsi * ct * sp
        r = -dgamma * sp + dpsi * ct * cp
        # acceleration over the earth: d/dt of the air-relative velocity + the felt gust's
        cg, sg, cs, ss = math.cos(gamma), math.sin(gamma), math.cos(psi), math.sin(psi)
        a = (dV * cg * cs - V * sg * dgamma * cs - V * cg * ss * dpsi + gust_rate[0],
             dV * cg * ss - V * sg * dgamma * ss + V * cg * cs * dpsi + gust_rate[1],
             -dV * sg - V * cg * dgamma + gust_rate[2])
        lat, h = self.lat, self.h
        vn, ve, vd = self.v_ned
        rn, re = _radii(lat)
        sl, cl = math.sin(lat), math.cos(lat)
        # omega_in^n = omega_ie^n + omega_en^n, and 2 omega_ie^n + omega_en^n (Groves 5.41, 5.44)
        en, ee, ed = ve / (re + h), -vn / (rn + h), -ve * sl / (cl * (re + h))
        wn, wd = OMEGA_IE * cl, -OMEGA_IE * sl
        in_n, in_e, in_d = wn + en, ee, wd + ed
        cn, ce, cd = 2.0 * wn + en, ee, 2.0 * wd + ed
        fn = a[0] + (ce * vd - cd * ve)
        fe = a[1] + (cd * vn - cn * vd)
        fd = a[2] + (cn * ve - ce * vn) - _gravity(lat, h)
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = _euler_rows(phi, theta, psi)
        # C_bn^T resolves NED vectors in body axes
        return (p + c00 * in_n + c10 * in_e + c20 * in_d,
                q + c01 * in_n + c11 * in_e + c21 * in_d,
                r + c02 * in_n + c12 * in_e + c22 * in_d,
                c00 * fn + c10 * fe + c20 * fd,
                c01 * fn + c11 * fe + c21 * fd,
                c02 * fn + c12 * fe + c22 * fd)
