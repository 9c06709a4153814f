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
from ..ins.rotations import _euler_rows_of
from ..ins.strapdown import _gravity, _radii, integrate_position


def _clip(x, limit):
    """``max(-limit, min(limit, x))``, written out (the builtins' calls cost more)."""
    x = x if x < limit else limit
    return x if x > -limit else -limit


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
        zeta, wb, wg = c["loop_damping"], c["bank_bandwidth"], c["climb_bandwidth"]
        #: the loops' coefficients w^2 and 2 zeta w (the products _derivatives would form
        #: first), the airspeed time constant and the acceleration limit
        self._loops = (wg * wg, 2.0 * zeta * wg, wb * wb, 2.0 * zeta * wb, c["tau_airspeed"],
                       c["accel_limit"])
        self.lat, self.lon, self.h = float(lat), float(lon), float(h)
        self.V, self.psi, self.gamma, self.phi = float(V), float(psi), 0.0, 0.0
        self.gamma_rate = self.phi_rate = 0.0
        self.felt_gust = (0.0, 0.0, 0.0)
        trig = self._trig()
        self.v_ned = self._ground_velocity(trig)
        #: (body rate x, y, z, specific force x, y, z) at the latest sample
        self.rates = self._rates((0.0,) * 6, (0.0, 0.0, 0.0), trig)

    def _trig(self):
        """(sin, cos) of roll ``phi``, of pitch ``gamma`` and of heading ``psi``, flat."""
        phi, gamma, psi = self.phi, self.gamma, self.psi
        return (math.sin(phi), math.cos(phi), math.sin(gamma), math.cos(gamma),
                math.sin(psi), math.cos(psi))

    def _ground_velocity(self, trig):
        V = self.V
        _, _, sg, cg, ss, cs = trig
        wn, we, wd = self.config["wind"]
        gn, ge, gd = self.felt_gust
        return (V * cg * cs + wn + gn, V * cg * ss + we + ge, -V * sg + wd + gd)

    def attitude(self):
        """(roll, pitch, yaw) [rad], yaw in (-pi, pi]."""
        return self.phi, self.gamma, self.yaw()

    def yaw(self):
        """The heading ``psi`` wrapped to (-pi, pi]."""
        return math.atan2(math.sin(self.psi), math.cos(self.psi))

    def start_gust(self, gust_ned):
        """The rates at the start in the gust ``gust_ned`` (the felt gust starts at 0)."""
        tau = self.config["gust_response_time"]
        self.rates = self._rates((0.0,) * 6, tuple(g / tau for g in gust_ned), self._trig())

    def turn_rate(self):
        """psi' [rad/s] now."""
        return G0 * math.tan(self.phi) / self.V

    def _derivatives(self, x, targets):
        """d/dt of (V, psi, gamma, phi, gamma', phi') towards ``targets`` = (bank, airspeed,
        flight-path angle), the bank already limited."""
        V, psi, gamma, phi, gamma_rate, phi_rate = x
        bank_c, airspeed_c, gamma_c = targets
        wg2, damp_g, wb2, damp_b, tau_v, accel_limit = self._loops
        dV = (airspeed_c - V) / tau_v
        # _clip written out: this runs five times a sample
        dV = dV if dV < accel_limit else accel_limit
        return (dV if dV > -accel_limit else -accel_limit,
                G0 * math.tan(phi) / V,
                gamma_rate,
                phi_rate,
                wg2 * (gamma_c - gamma) - damp_g * gamma_rate,
                wb2 * (bank_c - phi) - damp_b * phi_rate)

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
        k2 = f(_moved(x, half, k1), targets)
        k3 = f(_moved(x, half, k2), targets)
        k4 = f(_moved(x, dt, k3), targets)
        sixth = dt / 6.0
        (self.V, self.psi, self.gamma, self.phi, self.gamma_rate,
         self.phi_rate) = _rk4_sum(x, sixth, k1, k2, k3, k4)
        # f' = (g(t) - f) / tau with g linear over the step, solved exactly
        tau = self.config["gust_response_time"]
        decay = math.exp(-dt / tau)
        (f0, f1, f2), (a0, a1, a2), (b0, b1, b2) = self.felt_gust, gust_start, gust_end
        s0, s1, s2 = (b0 - a0) / dt, (b1 - a1) / dt, (b2 - a2) / dt
        f0 = b0 - tau * s0 + (f0 - a0 + tau * s0) * decay
        f1 = b1 - tau * s1 + (f1 - a1 + tau * s1) * decay
        f2 = b2 - tau * s2 + (f2 - a2 + tau * s2) * decay
        self.felt_gust = (f0, f1, f2)
        v_prev = self.v_ned
        trig = self._trig()
        self.v_ned = self._ground_velocity(trig)
        self.lat, self.lon, self.h = integrate_position(self.lat, self.lon, self.h, v_prev,
                                                        self.v_ned, dt)
        gust_rate = ((b0 - f0) / tau, (b1 - f1) / tau, (b2 - f2) / tau)
        self.rates = self._rates(f(self._state(), targets), gust_rate, trig)
        return self.v_ned

    def _rates(self, derivatives, gust_rate, trig):
        """(inertial body rate [rad/s] x, y, z, specific force [m/s^2] x, y, z) now;
        ``trig``: :meth:`_trig` of now."""
        dV, dpsi, dgamma, dphi = derivatives[:4]
        V = self.V
        # roll phi, pitch theta = gamma (attitude()), heading psi
        sp, cp, st, ct, ss, cs = trig
        # omega_nb^b from the ZYX Euler rates
        p = dphi - dpsi * st
        q = dgamma * cp + dpsi * ct * sp
        r = -dgamma * sp + dpsi * ct * cp
        # acceleration over the earth: d/dt of the air-relative velocity + the felt gust's
        cg, sg = ct, st
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
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = _euler_rows_of(sp, cp, st, ct,
                                                                           ss, cs)
        # C_bn^T resolves NED vectors in body axes
        return (p + c00 * in_n + c10 * in_e + c20 * in_d,
                q + c01 * in_n + c11 * in_e + c21 * in_d,
                r + c02 * in_n + c12 * in_e + c22 * in_d,
                c00 * fn + c10 * fe + c20 * fd,
                c01 * fn + c11 * fe + c21 * fd,
                c02 * fn + c12 * fe + c22 * fd)


def _moved(x, h, k):
    """``x + h k`` of two 6-tuples (the Runge-Kutta stages)."""
    x0, x1, x2, x3, x4, x5 = x
    k0, k1, k2, k3, k4, k5 = k
    return (x0 + h * k0, x1 + h * k1, x2 + h * k2, x3 + h * k3, x4 + h * k4, x5 + h * k5)


def _rk4_sum(x, sixth, k1, k2, k3, k4):
    """``x + sixth (k1 + 2 k2 + 2 k3 + k4)`` of 6-tuples, in the classical order (written
    out: a loop over the six components costs three times as much)."""
    x0, x1, x2, x3, x4, x5 = x
    a0, a1, a2, a3, a4, a5 = k1
    b0, b1, b2, b3, b4, b5 = k2
    c0, c1, c2, c3, c4, c5 = k3
    d0, d1, d2, d3, d4, d5 = k4
    return (x0 + sixth * (a0 + 2.0 * b0 + 2.0 * c0 + d0),
            x1 + sixth * (a1 + 2.0 * b1 + 2.0 * c1 + d1),
            x2 + sixth * (a2 + 2.0 * b2 + 2.0 * c2 + d2),
            x3 + sixth * (a3 + 2.0 * b3 + 2.0 * c3 + d3),
            x4 + sixth * (a4 + 2.0 * b4 + 2.0 * c4 + d4),
            x5 + sixth * (a5 + 2.0 * b5 + 2.0 * c5 + d5))
