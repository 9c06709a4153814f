"""A waypoint route and the L1 lateral guidance that flies it.

Route: waypoints as north/east offsets [m] from an origin (geodetic latitude/longitude [rad])
and a height [m] above the WGS-84 ellipsoid, written ``"n,e,h; n,e,h; ..."``.  Positions are
projected onto the local level plane of the origin (``north = dlat (R_N + h0)``, ``east =
dlon (R_E + h0) cos(lat0)``, radii and ``h0`` of the origin and the first waypoint): over a
route of 20 km the plane departs from the ellipsoid's geometry by (d / R)^2, under 1e-5
relative; guidance and the mission signals (cross-track error) use the same projection.

Legs go from waypoint i to waypoint i + 1.  A leg is flown until the vehicle, as guidance
sees it, is within the switching distance of its end or past the end's perpendicular; then
the next leg is active (after the last waypoint the last leg is flown on, extended).  The
switching distance is the larger of the acceptance radius and the lead of a fly-by turn,
``R tan(|dchi| / 2)`` with the turn radius ``R = V^2 / (g tan(bank_max))`` at the ground
speed V and ``dchi`` the change of course at the waypoint, so the turn joins the next leg
tangentially instead of overshooting it by about R.

Lateral guidance: Park, Deyst & How, "A new nonlinear guidance logic for trajectory
tracking", AIAA GNC 2004 (the "L1" law): the lateral acceleration command is

    a_cmd = 2 V^2 / L1 sin(eta)                                    (paper eq. 1)

with ``V`` the ground speed, ``eta`` the angle from the ground velocity to the line of sight
to the reference point, the point on the leg at distance ``L1`` ahead of the vehicle.  On a
straight leg the law is, linearised, a PD loop with damping 0.707 and natural frequency
``sqrt(2) V / L1`` (the paper's linearisation); a coordinated bank ``atan(a_cmd / g)``
realises it.  Where
the leg is farther than L1 (no point at that distance) the reference point is the nearest
point of the leg, and ``|eta|`` is capped at 90 degrees (a full turn command towards it), the
extension the paper leaves open.
"""
from __future__ import annotations

import math

from ..errors import ParameterError
from ..ins.constants import G0
from ..ins.strapdown import _radii

#: least distance between two consecutive waypoints [m]
MIN_LEG_LENGTH = 1.0
_HALF_PI = 0.5 * math.pi


def parse_route(text, name="route"):
    """Waypoints ``[(north, east, h), ...]`` [m] of the route text (module docstring);
    :class:`ParameterError` naming parameter ``name`` on anything else."""
    points = []
    for i, item in enumerate(str(text).split(";"), start=1):
        if not item.strip():
            continue
        fields = item.split(",")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            values = []
        if len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise ParameterError(f"parameter '{name}': waypoint {i} is {item.strip()!r}, not "
                                 "three finite numbers 'north,east,h' [m]")
        if not -1e5 <= values[2] <= 1e6:
            raise ParameterError(f"parameter '{name}': waypoint {i} height {values[2]:g} m is "
                                 "outside [-1e5, 1e6] m")
        if max(abs(values[0]), abs(values[1])) > 1e6:
            raise ParameterError(f"parameter '{name}': waypoint {i} is more than 1000 km from "
                                 "the origin")
        if points and math.hypot(values[0] - points[-1][0],
                                 values[1] - points[-1][1]) < MIN_LEG_LENGTH:
            raise ParameterError(f"parameter '{name}': waypoint {i} is within "
                                 f"{MIN_LEG_LENGTH:g} m of waypoint {i - 1} (no leg)")
        points.append(tuple(values))
    if len(points) < 2:
        raise ParameterError(f"parameter '{name}' needs at least two waypoints "
                             "'n,e,h; n,e,h', got {len(points)}")
    return points


class LocalPlane:
    """The level plane of the route's origin: geodetic <-> (north, east) [m]."""

    def __init__(self, lat0, lon0, h0):
        self.lat0, self.lon0, self.h0 = float(lat0), float(lon0), float(h0)
        rn, re = _radii(self.lat0)
        self.k_north = rn + self.h0
        self.k_east = (re + self.h0) * math.cos(self.lat0)

    def to_plane(self, lat, lon):
        return (lat - self.lat0) * self.k_north, (lon - self.lon0) * self.k_east

    def to_geodetic(self, north, east):
        return self.lat0 + north / self.k_north, self.lon0 + east / self.k_east


class Route:
    """Legs of a waypoint list on a :class:`LocalPlane`: geometry of a point against a leg."""

    def __init__(self, waypoints):
        self.waypoints = [tuple(w) for w in waypoints]
        self.n_legs = len(self.waypoints) - 1
        #: (start, unit direction (n, e), length) of each leg: asked for several times a
        #: sample, so computed once
        self.legs = [self._geometry(i) for i in range(self.n_legs)]

    def _geometry(self, i):
        a, b = self.waypoints[i], self.waypoints[i + 1]
        dn, de = b[0] - a[0], b[1] - a[1]
        length = math.hypot(dn, de)
        return a, (dn / length, de / length), length

    def leg(self, i):
        """(start, unit direction (n, e), length) of leg ``i`` (the last leg beyond)."""
        return self.legs[i if i < self.n_legs else -1]

    def track_errors(self, i, north, east):
        """(along-track [m] from the leg's start, cross-track [m], right of the leg
        positive) of a point against leg ``i``."""
        return _track_errors(self.leg(i), north, east)

    def deviation(self, north, east):
        """Signed distance [m] of a point from the route: to the nearest point of any leg
        (the last one extended beyond its end), right of that leg positive."""
        best = math.inf
        last = self.n_legs - 1
        for i, leg in enumerate(self.legs):
            along, cross = _track_errors(leg, north, east)
            if along < 0.0 or (along > leg[2] and i < last):
                end = leg[0] if along < 0.0 else self.waypoints[i + 1]
                d = math.hypot(north - end[0], east - end[1])
                cross = math.copysign(d, cross)
            if abs(cross) < abs(best):
                best = cross
        return best

    def leg_height(self, i):
        """The commanded height on leg ``i``: its end waypoint's."""
        return self.waypoints[min(i, self.n_legs - 1) + 1][2]


def _track_errors(leg, north, east):
    """(along-track, cross-track) [m] of a point against ``leg`` (:meth:`Route.leg`)."""
    a, (un, ue), _ = leg
    rn, re = north - a[0], east - a[1]
    return rn * un + re * ue, un * re - ue * rn


class L1Guidance:
    """Park, Deyst & How (2004) L1 guidance with waypoint switching (module docstring)."""

    def __init__(self, route, l1_distance, acceptance_radius, bank_max):
        self.route = route
        self.l1 = float(l1_distance)
        self.acceptance = float(acceptance_radius)
        self.turn_factor = 1.0 / (G0 * math.tan(bank_max)) if bank_max > 0.0 else 0.0
        #: tan(|dchi| / 2) of the turn at the end of each leg (0 after the last)
        self.half_turns = []
        for i in range(route.n_legs):
            if i + 1 < route.n_legs:
                (_, (un, ue), _), (_, (vn, ve), _) = route.leg(i), route.leg(i + 1)
                turn = abs(math.atan2(un * ve - ue * vn, un * vn + ue * ve))
                self.half_turns.append(math.tan(min(0.5 * turn, 0.45 * math.pi)))
            else:
                self.half_turns.append(0.0)

    def switching_distance(self, i, speed):
        """Distance [m] from the end of leg ``i`` at which it is done (module docstring)."""
        lead = speed * speed * self.turn_factor * self.half_turns[i]
        return max(self.acceptance, lead)

    def reached(self, i, north, east, speed):
        """Whether the leg ``i`` is done for a vehicle seen at (north, east) flying at the
        ground speed ``speed``."""
        if i >= self.route.n_legs:
            return False
        _, _, length = self.route.leg(i)
        b = self.route.waypoints[i + 1]
        along, _ = self.route.track_errors(i, north, east)
        return (along >= length or math.hypot(north - b[0], east - b[1])
                <= self.switching_distance(i, speed))

    def lateral_acceleration(self, i, north, east, vn, ve, heading):
        """a_cmd [m/s^2] (right positive) on leg ``i`` for the vehicle at (north, east) with
        ground velocity (vn, ve); ``heading`` [rad] stands in for the velocity's direction
        when the vehicle is nearly at rest."""
        a, (un, ue), _ = self.route.leg(i)
        along, cross = self.route.track_errors(i, north, east)
        ahead = math.sqrt(max(self.l1 * self.l1 - cross * cross, 0.0))
        pn = a[0] + (along + ahead) * un - north
        pe = a[1] + (along + ahead) * ue - east
        speed = math.hypot(vn, ve)
        course = math.atan2(ve, vn) if speed > 1.0 else heading
        eta = math.atan2(pe, pn) - course
        eta = math.atan2(math.sin(eta), math.cos(eta))
        # max(-pi/2, min(pi/2, eta)), written out
        eta = eta if eta < _HALF_PI else _HALF_PI
        eta = eta if eta > -_HALF_PI else -_HALF_PI
        return 2.0 * speed * speed / self.l1 * math.sin(eta)

    @staticmethod
    def bank_for(acceleration):
        """The coordinated-turn bank [rad] of a lateral acceleration [m/s^2]."""
        return math.atan(acceleration / G0)
