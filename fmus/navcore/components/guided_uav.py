"""GuidedUav: a fixed-wing UAV flying a waypoint route on a navigation solution.

The vehicle (:mod:`navcore.vehicles.point_mass_uav`, Dryden turbulence of
:mod:`navcore.vehicles.turbulence`) follows the L1 guidance of
:mod:`navcore.vehicles.route_guidance` (Park, Deyst & How 2004).  Guidance reads the inputs
``nav_time``, ``nav_lat/lon/h``, ``nav_vn/ve/vd``, ``nav_yaw`` (the outputs of every INS/GNSS
filter), the solution extrapolated by its velocity from ``nav_time`` to the sample's start;
with ``guide_on_truth`` it uses the vehicle's own truth instead (the
baseline of a filter comparison).  The height loop holds the active leg's height on the same
solution; the airspeed loop uses air data (the true airspeed).

Timing: the vehicle samples every ``sample_period`` on its own grid, like TrajectoryImu; a
sample over ``[t_k, t_k + dt]`` flies the commands computed at ``t_k`` from the newest
navigation solution tagged at or before ``t_k`` (``nav_time``), extrapolated by its velocity
to ``t_k``.  A solution received with a later tag (a master that steps the filter first
hands over its output at the step's end) waits until the samples reach its tag
(:mod:`navcore.vehicles.tagged_solutions`; it is state), so the time tags decide which
solution a sample flies on, not the order of the calls nor the communication step size.
The outputs at t (truth, rates, mission signals) never depend on the inputs at t: no
algebraic loop closes through the vehicle (declared in the model description: every output
has no input dependency), and a master may step it first (Gauss-Seidel, where it takes the
filter's output of the previous step), with everyone at once (Jacobi) or after the filter.

Outputs: the truth of TrajectoryImu's names (ImuSensor and GnssReceiver connect name to
name), ``body_rate_*`` and ``specific_force_*`` at each sample (ImuSensor's ``rates`` input
form), and the mission signals of the true position: ``leg`` (active leg, 0 = first),
``cross_track`` [m] (the true position's distance from the route: from the nearest
point of any leg, right of it positive), ``along_track`` [m] along the active leg,
``waypoints_reached`` and ``waypoint_miss``: the true horizontal distance [m] to the
latest waypoint at the moment guidance switched past it, less the switching distance
guidance meant (the fly-by lead or the acceptance radius; so 0 for a vehicle that knows
where it is, positive when it switched too far out, negative too close).

Refusals: a non-finite navigation input; a solution tagged more than ``max_nav_age`` after
the end of the step that delivers it; one more than ``max_nav_age`` older (or, at the start,
newer) than the sample it is flown on; a solution more than :data:`MAX_ROUTE_DISTANCE` from every
waypoint (an unconnected or diverged filter).
"""
from __future__ import annotations

import math

from ..core import signals
from ..core.component import Component, InputError, Limits, boolean, integer, real, string
from ..core.timing import samples_reached, time_tolerance
from ..vehicles.point_mass_uav import PointMassUav
from ..vehicles.route_guidance import L1Guidance, LocalPlane, Route, parse_route
from ..vehicles.tagged_solutions import TaggedSolutions
from ..vehicles.turbulence import DrydenTurbulence
from .imu_measurement import SEED_LIMITS
from .imu_sensor import RATE_NAMES, RATES

#: farthest a navigation solution may be from every waypoint [m]
MAX_ROUTE_DISTANCE = 1e5
NAV_INPUTS = (real("nav_time", "s", "time the navigation solution is valid for",
                   limits=signals.TIME),
              *signals.state_ports("nav", "estimated", ranged=False),
              real("nav_yaw", "rad", "estimated yaw"))
NAV_NAMES = tuple(p.name for p in NAV_INPUTS)
MISSION = (
    integer("leg", "active leg of the route (0 = from waypoint 0 to waypoint 1)"),
    integer("waypoints_reached", "waypoints guidance has switched past"),
    real("cross_track", "m", "distance of the true position from the route (the nearest point "
         "of any leg), right of that leg positive"),
    real("along_track", "m", "along-track distance of the true position from the active leg's "
         "start"),
    real("waypoint_miss", "m", "true horizontal distance to the latest waypoint reached when "
         "guidance switched past it, less the switching distance guidance meant"),
)
_DEG = math.pi / 180.0
_TIME = Limits(0.0, 1e3, low_open=True)

_PARAMETERS = (
    string("route", "waypoints 'north,east,h; ...' [m] from the origin, heights above the "
           "ellipsoid", "0,0,150; 3000,0,150; 3000,3000,150; 0,3000,150; 0,600,150"),
    real("origin_lat", "rad", "latitude of the route's origin", 0.6998770300497261,
         signals.LATITUDE),
    real("origin_lon", "rad", "longitude of the route's origin", 2.069960492865275,
         signals.LONGITUDE),
    real("ground_height", "m", "terrain height above the ellipsoid (turbulence scales)", 0.0,
         signals.HEIGHT),
    real("airspeed", "m/s", "commanded airspeed (also the start airspeed)", 25.0,
         Limits(5.0, 100.0)),
    boolean("guide_on_truth", "guide on the vehicle's own truth instead of the nav_* inputs "
            "(the baseline)", False),
    real("l1_distance", "m", "L1 look-ahead distance of the guidance", 120.0, Limits(1.0, 1e4)),
    real("acceptance_radius", "m", "a waypoint is reached within this distance (or the lead "
         "of a fly-by turn, if longer; or when passed)", 30.0, Limits(0.0, 1e4)),
    real("bank_limit", "rad", "largest bank", 35.0 * _DEG, Limits(0.0, 80.0 * _DEG)),
    real("load_factor_limit", "", "largest load factor 1/cos(bank) of a level turn", 2.0,
         Limits(1.0, 10.0)),
    real("climb_rate_limit", "m/s", "largest climb or sink rate", 3.0, Limits(0.0, 50.0)),
    real("accel_limit", "m/s2", "largest airspeed change rate", 2.0,
         Limits(0.0, 50.0, low_open=True)),
    real("bank_bandwidth", "rad/s", "natural frequency of the bank loop", 3.0,
         Limits(0.0, 100.0, low_open=True)),
    real("climb_bandwidth", "rad/s", "natural frequency of the flight-path loop", 2.0,
         Limits(0.0, 100.0, low_open=True)),
    real("loop_damping", "", "damping ratio of the bank and flight-path loops", 0.8,
         Limits(0.0, 10.0, low_open=True)),
    real("tau_airspeed", "s", "time constant of the airspeed loop", 3.0, _TIME),
    real("altitude_gain", "Hz", "climb rate commanded per metre of height error", 0.2,
         Limits(0.0, 10.0)),
    *(real(f"wind_{a}", "m/s", f"steady wind (air-mass velocity), {axis}", 0.0,
           signals.VELOCITY) for a, axis in zip(signals.AXES_NED, ("north", "east", "down"))),
    real("turbulence_w20", "m/s", "Dryden turbulence intensity: wind speed at 20 ft "
         "(MIL-F-8785C: light 7.7, moderate 15.4, severe 23.2 m/s; 0 = none)", 0.0,
         Limits(0.0, 50.0)),
    real("gust_response_time", "s", "time constant of the airframe's response to gusts", 0.5,
         _TIME),
    integer("seed", "seed of the turbulence", 3, SEED_LIMITS),
    real("sample_period", "s", "sampling interval of the truth (the IMU period of ImuSensor)",
         0.01, Limits(0.0, 1.0, low_open=True)),
    real("max_nav_age", "s", "a navigation solution older (or newer) than this is refused",
         1.0, Limits(0.0, 3600.0, low_open=True)),
)


class GuidedUav(Component):
    """A guided fixed-wing UAV (module docstring)."""

    description = ("Fixed-wing UAV at guidance-study level (point mass, coordinated "
                   "bank-to-turn, first-order airspeed/climb/bank loops with limits, steady "
                   "wind, MIL-F-8785C Dryden turbulence) flying a waypoint route with L1 "
                   "guidance (Park, Deyst & How 2004) on the nav_* inputs or on its truth. "
                   "Its outputs at t do not depend on its inputs at t (no direct feedthrough).")
    parameters = _PARAMETERS
    inputs = NAV_INPUTS
    outputs = signals.TRUTH + RATES + MISSION
    default_experiment = (0.0, 600.0, 0.01)
    state_fields = ("uav", "turbulence", "gust_ned", "leg", "n_reached", "miss", "n", "out",
                    "solutions")
    derived_fields = ("dt", "route", "plane", "guidance", "start_time")

    def initialize(self, start_time):
        p = self.params
        self.dt = p["sample_period"]
        self.start_time = float(start_time)
        waypoints = parse_route(p["route"])
        self.route = Route(waypoints)
        self.plane = LocalPlane(p["origin_lat"], p["origin_lon"], waypoints[0][2])
        self.guidance = L1Guidance(self.route, p["l1_distance"], p["acceptance_radius"],
                                   min(p["bank_limit"], math.acos(1.0 / p["load_factor_limit"])))
        a, (un, ue), _ = self.route.leg(0)
        lat, lon = self.plane.to_geodetic(a[0], a[1])
        config = {k: p[k] for k in ("bank_bandwidth", "climb_bandwidth", "loop_damping",
                                    "tau_airspeed", "altitude_gain",
                                    "bank_limit", "load_factor_limit", "climb_rate_limit",
                                    "accel_limit", "gust_response_time")}
        config["wind"] = (p["wind_n"], p["wind_e"], p["wind_d"])
        self.uav = PointMassUav(config, lat, lon, a[2], p["airspeed"], math.atan2(ue, un))
        self.turbulence = DrydenTurbulence(p["turbulence_w20"], p["seed"])
        self.turbulence.start(a[2] - p["ground_height"])
        self.gust_ned = self._gust_ned(self.uav.psi)
        self.uav.start_gust(self.gust_ned)
        self.leg, self.n_reached, self.miss, self.n = 0, 0, 0.0, 0
        self.solutions = TaggedSolutions()
        self.out = self._outputs()
        return dict(self.out)

    def _outputs(self):
        uav = self.uav
        north, east = self.plane.to_plane(uav.lat, uav.lon)
        along, _ = self.route.track_errors(self.leg, north, east)
        vn, ve, vd = uav.v_ned
        out = {"truth_time": self.start_time + self.n * self.dt, "truth_lat": uav.lat,
               "truth_lon": uav.lon, "truth_h": uav.h, "truth_vn": vn, "truth_ve": ve,
               "truth_vd": vd, "truth_roll": uav.phi, "truth_pitch": uav.gamma,
               "truth_yaw": uav.yaw()}
        out.update(zip(RATE_NAMES, uav.rates))
        out["leg"] = self.leg
        out["waypoints_reached"] = self.n_reached
        out["cross_track"] = self.route.deviation(north, east)
        out["along_track"] = along
        out["waypoint_miss"] = self.miss
        return out

    def initial_inputs(self, inputs):
        """The inputs at the end of initialization mode: the solution at the start time when
        the vehicle accepts them (a host that sets none there leaves their start values, 0,
        thousands of km from any route: then the first step's solution stands in until one
        is due, :mod:`navcore.vehicles.tagged_solutions`).  The outputs do not change."""
        if not self.params["guide_on_truth"]:
            try:
                self._receive(self.start_time, inputs)
            except InputError:
                pass
        return None

    def step(self, t, h, inputs):
        on_truth = self.params["guide_on_truth"]
        if not on_truth:
            self._receive(t + h, inputs)
        due = samples_reached(self.start_time, self.dt, t + h) - self.n
        if due <= 0:
            return self.out
        for _ in range(due):
            t_sample = self.start_time + self.n * self.dt
            self._fly(self._truth_view() if on_truth else self._nav_view(t_sample))
        self.out = self._outputs()
        return self.out

    def _truth_view(self):
        uav = self.uav
        north, east = self.plane.to_plane(uav.lat, uav.lon)
        return north, east, uav.h, uav.v_ned[0], uav.v_ned[1], uav.yaw()

    def _receive(self, end, inputs):
        """Check the navigation inputs of the step ending at ``end`` and keep their solution,
        on the route's plane, for the samples its tag is due at (module docstring)."""
        self.check_inputs(inputs, NAV_NAMES)
        tag = inputs["nav_time"]
        limit = self.params["max_nav_age"]
        if tag - end > limit + time_tolerance(self.dt, end):
            raise InputError(
                f"{self.model_name}: input 'nav_time' = {tag!r} s is {tag - end:.6g} s ahead "
                f"of the communication step's end t = {end!r} s (parameter 'max_nav_age' = "
                f"{limit:g} s): is the filter's clock the vehicle's?")
        north, east = self.plane.to_plane(inputs["nav_lat"], inputs["nav_lon"])
        if self._off_route(north, east):
            nearest = min(math.hypot(north - w[0], east - w[1]) for w in self.route.waypoints)
            raise InputError(
                f"{self.model_name}: inputs 'nav_lat'/'nav_lon' put the vehicle {nearest / 1e3:.6g}"
                f" km from the nearest waypoint at t = {end!r} s (more than "
                f"{MAX_ROUTE_DISTANCE / 1e3:g} km): is a filter's navigation solution connected?")
        self.solutions.receive(tag, (north, east, inputs["nav_h"], inputs["nav_vn"],
                                     inputs["nav_ve"], inputs["nav_vd"], inputs["nav_yaw"]))

    def _nav_view(self, t_sample):
        """The newest navigation solution due at ``t_sample``, extrapolated to it on the
        route's plane."""
        tag, (north, east, h, vn, ve, vd, yaw) = self.solutions.due(t_sample, self.dt)
        age = t_sample - tag
        limit = self.params["max_nav_age"]
        # the tolerance (>= 0) is needed only beyond the limit
        if not abs(age) <= limit and not abs(age) <= limit + time_tolerance(self.dt, t_sample):
            raise InputError(
                f"{self.model_name}: input 'nav_time' = {tag!r} s is {abs(age):.6g} s "
                f"{'old' if age > 0 else 'ahead'} at t = {t_sample!r} s (parameter "
                f"'max_nav_age' = {limit:g} s): guidance needs a current navigation solution")
        return north + vn * age, east + ve * age, h - vd * age, vn, ve, yaw

    def _off_route(self, north, east):
        """Whether (north, east) is more than :data:`MAX_ROUTE_DISTANCE` from every waypoint;
        the active leg's end, the likely nearest, is tried first."""
        waypoints = self.route.waypoints
        w = waypoints[min(self.leg + 1, len(waypoints) - 1)]
        if math.hypot(north - w[0], east - w[1]) <= MAX_ROUTE_DISTANCE:
            return False
        return all(math.hypot(north - w[0], east - w[1]) > MAX_ROUTE_DISTANCE
                   for w in waypoints)

    def _fly(self, view):
        north, east, h_seen, vn, ve, heading = view
        guidance, uav, p = self.guidance, self.uav, self.params
        speed = math.hypot(vn, ve)
        while guidance.reached(self.leg, north, east, speed):
            w = self.route.waypoints[self.leg + 1]
            t_north, t_east = self.plane.to_plane(uav.lat, uav.lon)
            meant = guidance.switching_distance(self.leg, speed)
            self.miss = math.hypot(t_north - w[0], t_east - w[1]) - meant
            self.leg += 1
            self.n_reached += 1
        bank = guidance.bank_for(guidance.lateral_acceleration(self.leg, north, east, vn, ve,
                                                               heading))
        climb = uav.climb_command(self.route.leg_height(self.leg), h_seen)
        gust_start = self.gust_ned
        if self.turbulence.on:
            self.turbulence.step(self.dt, uav.V, uav.h - p["ground_height"])
            # rotated by the heading the step ends at (first order), so the gust the next
            # step starts from is this one: continuous, and so are the accelerations
            self.gust_ned = self._gust_ned(uav.psi + self.dt * uav.turn_rate())
        uav.step(self.dt, (bank, p["airspeed"], climb), gust_start, self.gust_ned)
        self.n += 1

    def _gust_ned(self, psi):
        """The Dryden gust rotated from the air-path axes (u forward, v right) to NED."""
        u, v, w = self.turbulence.gust
        cs, ss = math.cos(psi), math.sin(psi)
        return u * cs - v * ss, u * ss + v * cs, w
