"""Test vehicle written without navfmu: a kinematic aircraft in plain pythonfmu (no numpy, no
navfmu code) meeting the vehicle contract of docs/guide/vehicle_in_the_loop.md.

Its motion is closed-form in time: airspeed 40 +- 3 m/s (period 30 s), a weave of turn rate
0.15 sin(2 pi t / 40) rad/s, flight-path angle 0.08 sin(2 pi t / 50) rad, coordinated bank
roll = atan(V psi' / 9.81), pitch = flight-path angle.  Velocity (NED), attitude, the body
rates (inertial, earth and transport rate included) and the specific force (WGS-84 normal
gravity, Coriolis) follow from it exactly; the geodetic position is integrated from the
velocity on a fixed 2 ms grid of its own (midpoint rule), so any communication step that
is a multiple of it gives the same trajectory.  Outputs are valid from initialization mode
on (written in ``enter_initialization_mode`` and ``exit_initialization_mode``); its state
(position, time) is saved and restored with the FMU state.

``BUG`` switches on one realistic defect (the tests build one FMU per value; the class is
renamed with it, so every FMU carries its own module): see ``BUGS``.
"""
import json
import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Real

BUG = ""
BUGS = {
    "": "none",
    "ne_swap": "the velocity output as east, north, down",
    "rate_sign": "the body rates with their sign flipped",
    "no_gravity": "the specific force without gravity",
    "nan_until_step": "outputs NaN until the first doStep",
    "euler_step": "position integrated by one Euler step per communication step",
    "restore_forgets": "a restored FMU state keeps the position it replaces",
    "project_module": "claims a route in its project's module; a second instance finds it "
                      "claimed",
}
if BUG == "project_module":
    import kinematic_aircraft_routes   # the author's own module, shipped in resources/

A, E2, OMEGA = 6378137.0, 6.69437999014e-3, 7.292115e-5
GAMMA_E, K_SOM, F_FLAT, M_GRAV = 9.7803253359, 0.00193185265241, 1 / 298.257223563, 0.00344978600308
LAT0, LON0, H0 = 0.6998770300497261, 2.069960492865275, 150.0
V0, DV, W_V = 40.0, 3.0, 2 * math.pi / 30
R_TURN, W_TURN = 0.15, 2 * math.pi / 40
GAMMA, W_GAMMA = 0.08, 2 * math.pi / 50
G_BANK = 9.81
GRID = 0.002
OUTPUTS = ("truth_time", "truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve", "truth_vd",
           "truth_roll", "truth_pitch", "truth_yaw", "body_rate_x", "body_rate_y", "body_rate_z",
           "specific_force_x", "specific_force_y", "specific_force_z")
UNITS = {"truth_time": "s", "truth_lat": "rad", "truth_lon": "rad", "truth_h": "m",
         "truth_roll": "rad", "truth_pitch": "rad", "truth_yaw": "rad"}


def unit_of(name):
    if name in UNITS:
        return UNITS[name]
    return "rad/s" if name.startswith("body") else ("m/s2" if name.startswith("specific")
                                                     else "m/s")


def radii(lat):
    w = 1.0 - E2 * math.sin(lat) ** 2
    return A * (1.0 - E2) / w ** 1.5, A / math.sqrt(w)


def gravity(lat, h):
    s2 = math.sin(lat) ** 2
    g0 = GAMMA_E * (1.0 + K_SOM * s2) / math.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F_FLAT + M_GRAV - 2.0 * F_FLAT * s2) * h
                 + 3.0 * h ** 2 / A ** 2)


def motion(t):
    """Speed, flight-path angle, heading and their first (and the heading's second) rates."""
    v, v_dot = V0 + DV * math.sin(W_V * t), DV * W_V * math.cos(W_V * t)
    psi = R_TURN / W_TURN * (1.0 - math.cos(W_TURN * t))
    psi_dot, psi_ddot = R_TURN * math.sin(W_TURN * t), R_TURN * W_TURN * math.cos(W_TURN * t)
    gam, gam_dot = GAMMA * math.sin(W_GAMMA * t), GAMMA * W_GAMMA * math.cos(W_GAMMA * t)
    return v, v_dot, gam, gam_dot, psi, psi_dot, psi_ddot


def velocity(t):
    v, _, gam, _, psi, _, _ = motion(t)
    return (v * math.cos(gam) * math.cos(psi), v * math.cos(gam) * math.sin(psi),
            -v * math.sin(gam))


def position_rate(lat, h, vel):
    rn, re = radii(lat)
    return vel[0] / (rn + h), vel[1] / ((re + h) * math.cos(lat)), -vel[2]


def body_to_ned(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch),
                              math.sin(pitch), math.cos(yaw), math.sin(yaw))
    return ((cp * cy, -cr * sy + sr * sp * cy, sr * sy + cr * sp * cy),
            (cp * sy, cr * cy + sr * sp * sy, -sr * cy + cr * sp * sy),
            (-sp, sr * cp, cr * cp))


def to_body(c, x):
    return tuple(sum(c[i][j] * x[i] for i in range(3)) for j in range(3))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def truth(t, lat, h):
    """Velocity, attitude, body rates and specific force at t (position lat, h)."""
    v, v_dot, gam, gam_dot, psi, psi_dot, psi_ddot = motion(t)
    x = v * psi_dot / G_BANK
    roll, roll_dot = math.atan(x), (v_dot * psi_dot + v * psi_ddot) / G_BANK / (1 + x * x)
    pitch, pitch_dot = gam, gam_dot
    vel = velocity(t)
    cg, sg, cpsi, spsi = math.cos(gam), math.sin(gam), math.cos(psi), math.sin(psi)
    acc = (v_dot * cg * cpsi + v * (-sg * gam_dot * cpsi - cg * spsi * psi_dot),
           v_dot * cg * spsi + v * (-sg * gam_dot * spsi + cg * cpsi * psi_dot),
           -v_dot * sg - v * cg * gam_dot)
    sr, cr, sp, cp = math.sin(roll), math.cos(roll), math.sin(pitch), math.cos(pitch)
    rate_nb = (roll_dot - psi_dot * sp, pitch_dot * cr + psi_dot * cp * sr,
               -pitch_dot * sr + psi_dot * cp * cr)
    rn, re = radii(lat)
    w_ie = (OMEGA * math.cos(lat), 0.0, -OMEGA * math.sin(lat))
    w_en = (vel[1] / (re + h), -vel[0] / (rn + h), -vel[1] * math.tan(lat) / (re + h))
    c = body_to_ned(roll, pitch, psi)
    rate_ib = tuple(a + b for a, b in zip(rate_nb, to_body(c, [a + b for a, b in zip(w_ie, w_en)])))
    coriolis = cross([2 * a + b for a, b in zip(w_ie, w_en)], vel)
    g = 0.0 if BUG == "no_gravity" else gravity(lat, h)
    force = to_body(c, (acc[0] + coriolis[0], acc[1] + coriolis[1], acc[2] + coriolis[2] - g))
    if BUG == "rate_sign":
        rate_ib = tuple(-w for w in rate_ib)
    yaw = math.atan2(math.sin(psi), math.cos(psi))
    return vel, (roll, pitch, yaw), rate_ib, force


class KinematicAircraft(Fmi2Slave):
    author = "verify test"
    description = "kinematic aircraft (closed-form weave), plain pythonfmu"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name in OUTPUTS:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.output))
        self._t, self._pos = 0.0, [LAT0, LON0, H0]
        if BUG == "project_module":
            kinematic_aircraft_routes.claim("weave")

    def to_xml(self, model_options=dict()):
        root = super().to_xml(model_options)
        structure = root.find("ModelStructure")
        unknowns = structure.makeelement("InitialUnknowns", {})
        for i, v in enumerate(self.vars.values()):
            if v.causality == Fmi2Causality.output:
                unknowns.append(unknowns.makeelement("Unknown", {"index": str(i + 1)}))
        structure.append(unknowns)
        units = root.makeelement("UnitDefinitions", {})     # pythonfmu 0.7 writes no units
        for unit in sorted({unit_of(n) for n in OUTPUTS}):
            units.append(units.makeelement("Unit", {"name": unit}))
        root.insert(list(root).index(root.find("LogCategories")), units)
        for variable in root.find("ModelVariables"):
            variable.find("Real").set("unit", unit_of(variable.get("name")))
        return root

    def _get_fmu_state(self):
        state = super()._get_fmu_state()
        state["_t"] = self._t
        if BUG != "restore_forgets":
            state["_pos"] = list(self._pos)
        return state

    def _set_fmu_state(self, state):
        super()._set_fmu_state({k: v for k, v in state.items() if not k.startswith("_")})
        self._t = state["_t"]
        if "_pos" in state:
            self._pos = list(state["_pos"])

    @staticmethod
    def _fmu_state_to_bytes(state):
        return json.dumps(state).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(data):
        return json.loads(data.decode("utf-8"))

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._t = start_time or 0.0

    def enter_initialization_mode(self):
        self._write()

    def exit_initialization_mode(self):
        self._write()
        if BUG == "nan_until_step":
            for name in OUTPUTS:
                setattr(self, name, float("nan"))

    def _advance(self, t_end):
        """Integrate the position to ``t_end`` on the fixed grid (midpoint rule)."""
        lat, lon, h = self._pos
        i, t = round(self._t / GRID), self._t
        while t < t_end - 1e-12:
            dt = min((i + 1) * GRID - t, t_end - t)
            k1 = position_rate(lat, h, velocity(t))
            lm, hm = lat + 0.5 * dt * k1[0], h + 0.5 * dt * k1[2]
            k2 = position_rate(lm, hm, velocity(t + 0.5 * dt))
            lat, lon, h = lat + dt * k2[0], lon + dt * k2[1], h + dt * k2[2]
            i += 1
            t = min(i * GRID, t_end)
        self._pos, self._t = [lat, lon, h], t_end

    def _euler(self, t_end):
        lat, lon, h = self._pos
        k = position_rate(lat, h, velocity(self._t))
        dt = t_end - self._t
        self._pos, self._t = [lat + dt * k[0], lon + dt * k[1], h + dt * k[2]], t_end

    def do_step(self, current_time, step_size):
        t_end = current_time + step_size
        if abs(t_end - round(t_end / GRID) * GRID) < 1e-9:    # on the grid: exactly there
            t_end = round(t_end / GRID) * GRID
        (self._euler if BUG == "euler_step" else self._advance)(t_end)
        self._write()
        return True

    def _write(self):
        lat, lon, h = self._pos
        vel, att, rate, force = truth(self._t, lat, h)
        if BUG == "ne_swap":
            vel = (vel[1], vel[0], vel[2])
        values = (self._t, lat, lon, h) + vel + att + rate + force
        for name, value in zip(OUTPUTS, values):
            setattr(self, name, value)
