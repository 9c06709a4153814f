"""ImuSensor: the IMU and magnetometer of TrajectoryImu, driven by a vehicle's truth inputs.

Any vehicle model (an FMU exported from Modelica or Simulink, a C model, :class:`GuidedUav`)
connects its truth outputs name to name: ``truth_time``, ``truth_lat``/``truth_lon`` [rad,
WGS-84 geodetic], ``truth_h`` [m above the ellipsoid], ``truth_vn/ve/vd`` [m/s, NED, over the
earth], ``truth_roll/pitch/yaw`` [rad, ZYX Euler of body forward-right-down in NED].  The
outputs, parameters and error models are those of TrajectoryImu
(:mod:`navcore.components.imu_measurement`, one implementation for both).

Ideal increments (``input_form`` = ``truth``): between two consecutive truth samples the
increments are the exact inverse of navcore's strapdown (:meth:`Strapdown.inverse_update`,
the increments that :meth:`Strapdown.update` integrates from the first sample's velocity and
attitude to the second's), as TrajectoryImu builds them along its profile.  Position is not
driven by the increments: the mechanization integrates it as the trapezoid of the two
velocities (:func:`navcore.ins.strapdown.integrate_position`); a vehicle integrating position
otherwise (a rectangle rule, RK4) differs from it by its own integration error, which for a
rectangle rule telescopes to at most ``|v_end - v_start| dt / 2`` over a whole flight.

Ideal increments (``input_form`` = ``rates``): for a dynamics model that outputs its rates,
the inputs ``body_rate_x/y/z`` [rad/s, inertial angular rate in body axes, earth rate
included] and ``specific_force_x/y/z`` [m/s2, body axes] at the sample instants become
increments by the trapezoid over the interval, as the sensor-log converters do
(:func:`navcore.sensors.log_converters.trapezoid_increments`): an error of ``dt^3 w''/12`` per
interval (third order in the step), plus the sculling and coning content a trapezoid of
two samples cannot see.  The truth inputs still give the sample times and the attitude of the
magnetometer.

Sampling: the truth at the start time is the input values at the end of initialization mode
(the FMI rule: inputs set in initialization mode hold at the start), or, when they are all
still 0 there (a host that sets none), the first truth received: under a Jacobi master that
is the start sample; a later one starts the sensor there, with a warning (its first IMU
interval ends one period after it, so a filter started at the start time refuses it); then
every new truth sample (``truth_time`` later than the previous one) closes one IMU interval,
whose outputs are tagged ``imu_time`` = ``truth_time``, ``imu_dt`` = ``imu_period``.  A step
that brings the same ``truth_time`` again (a Jacobi master, a sensor stepped faster than the
vehicle) holds the outputs.  So the sensor follows the time tags under any master; it is
stepped at least as often as the vehicle outputs.

Refusals (an :class:`InputError` naming the input and the time; nothing is resampled): a
non-finite or out-of-range input; ``truth_time`` going back; a sample interval that is not
``imu_period`` (within :func:`navcore.core.timing.time_tolerance`); a jump between two samples no
vehicle makes: a velocity change above :data:`MAX_ACCELERATION` times the interval, a rotation
above :data:`MAX_ANGULAR_RATE` times the interval, or a position farther from the trapezoid of
the two velocities than :func:`position_tolerance`.
"""
from __future__ import annotations

import math

from ..core import signals
from ..core.component import Component, InputError, Limits, real, string
from ..core.timing import same_time
from ..ins.rotations import _euler_rows
from ..ins.strapdown import InverseStrapdown, _radii, integrate_position
from ..sensors.log_converters import trapezoid_increments
from .imu_measurement import ERROR_PARAMETERS, ImuMeasurement

#: largest acceleration over the earth a truth sample may imply [m/s^2]: 100 g, the range of
#: the IMU's velocity increments (navcore.signals.DVEL, 1 km/s per 1 s interval)
MAX_ACCELERATION = 1e3
#: largest angular rate a truth sample may imply [rad/s]: 50 rad/s (2900 deg/s), beyond the
#: gyro range of tactical and MEMS IMUs
MAX_ANGULAR_RATE = 50.0
#: fixed part of the position tolerance [m]: rounding of positions written as text or float32
POSITION_TOLERANCE_M = 0.01

#: the truth inputs, in the order the sensor reads them
TRUTH_NAMES = tuple(p.name for p in signals.TRUTH)
#: the rate-form inputs
RATES = (
    *(real(f"body_rate_{a}", "rad/s", f"inertial angular rate about body {a} at truth_time "
           "(input_form 'rates')") for a in signals.AXES_BODY),
    *(real(f"specific_force_{a}", "m/s2", f"specific force along body {a} at truth_time "
           "(input_form 'rates')") for a in signals.AXES_BODY),
)
RATE_NAMES = tuple(p.name for p in RATES)
#: the inputs of input_form 'rates'
TRUTH_AND_RATE_NAMES = TRUTH_NAMES + RATE_NAMES
INPUT_FORMS = ("truth", "rates")
_IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def position_tolerance(dv_norm, dt):
    """Largest distance [m] between a truth position and the trapezoid of the velocities:
    twice what a rectangle rule gives (``|dv| dt / 2``), plus :data:`POSITION_TOLERANCE_M`."""
    return dv_norm * dt + POSITION_TOLERANCE_M


class ImuSensor(ImuMeasurement, Component):
    """TrajectoryImu's IMU and magnetometer on a vehicle's truth (module docstring)."""

    description = ("IMU and magnetometer of TrajectoryImu (same outputs, parameters and error "
                   "models) driven by a vehicle model's truth inputs: the ideal increments "
                   "between two truth samples are the exact inverse of the strapdown "
                   "(input_form 'truth'), or the trapezoid of the vehicle's body rates and "
                   "specific force (input_form 'rates'). Refuses non-finite truth, time going "
                   "back, a sample interval other than imu_period and jumps no vehicle makes.")
    parameters = (
        real("imu_period", "s", "IMU sampling interval: the vehicle's truth_time must advance "
             "by exactly this between samples", 0.01, Limits(0.0, 1.0, low_open=True)),
        string("input_form", "'truth': increments by the exact inverse strapdown between two "
               "truth samples; 'rates': the trapezoid of the body_rate_* and "
               "specific_force_* inputs", "truth"),
        *ERROR_PARAMETERS,
    )
    inputs = signals.TRUTH + RATES
    outputs = signals.IMU + signals.MAG
    #: the start sample (:meth:`initial_inputs`) sets the magnetometer; whether the inputs
    #: are a sample at all reads every one of them
    initial_dependencies = {name: TRUTH_AND_RATE_NAMES for name in signals.MAG_NAMES}
    default_experiment = (0.0, 500.0, 0.01)
    state_fields = ("errors", "magnetometer", "ins", "started", "last_time", "last_rates",
                    "out")
    derived_fields = ("dt", "rates_form", "mag_on", "_no_mag", "start_time")

    def initialize(self, start_time):
        self.dt = self.params["imu_period"]
        form = self.params["input_form"]
        self.require("input_form", form in INPUT_FORMS, f"is not one of {list(INPUT_FORMS)}")
        self.rates_form = form == "rates"
        self.build_error_models()
        self.start_time = float(start_time)
        # the inverse strapdown at the latest truth sample; replaced by the start sample
        self.ins = InverseStrapdown(0.0, 0.0, 0.0, (0.0, 0.0, 0.0), _IDENTITY)
        self.started = False
        self.last_time = self.start_time
        self.last_rates = (0.0,) * 6
        out = {}
        self.start_outputs(out, self.start_time, None)
        self.out = out
        return dict(out)

    def _names(self):
        return TRUTH_AND_RATE_NAMES if self.rates_form else TRUTH_NAMES

    def initial_inputs(self, inputs):
        """The truth at the start time: the inputs at the end of initialization mode.  Inputs
        still at their start values (all 0: a host that sets no inputs in initialization
        mode) are not a sample: the first step's inputs start the sensor instead."""
        if all(inputs[n] == 0.0 for n in self._names()):
            return None
        self.check_inputs(inputs, self._names())
        t = inputs["truth_time"]
        if not same_time(t, self.start_time, self.dt):
            raise InputError(
                f"{self.model_name}: input 'truth_time' = {t!r} s at the end of initialization "
                f"mode is not the start time "
                f"{self.start_time!r} s: the sensor needs the vehicle's truth at the start "
                "time, set as its inputs in initialization mode")
        self._take(inputs)
        self.started = True
        self.start_magnetometer(self.out, self.start_time, _attitude(inputs))
        return dict(self.out)

    def _first_sample(self, inputs):
        """Without a start sample, the first truth received starts the sensor: at the start
        time (a Jacobi master) as if given in initialization mode; later, with a warning,
        the first IMU interval then ending one imu_period after it."""
        self.check_inputs(inputs, self._names())
        t = inputs["truth_time"]
        if not same_time(t, self.start_time, self.dt):
            self.notify(f"{self.model_name}: no truth at the start time {self.start_time!r} s "
                        "(the inputs were not set in initialization mode): the sample at "
                        f"truth_time = {t!r} s starts the sensor; its first IMU interval ends "
                        f"at {t + self.dt!r} s")
            self.last_time = t
        self._take(inputs)
        self.started = True
        self.start_magnetometer(self.out, t, _attitude(inputs))
        return self.out

    def _take(self, inputs):
        v = (inputs["truth_vn"], inputs["truth_ve"], inputs["truth_vd"])
        self.ins = InverseStrapdown(inputs["truth_lat"], inputs["truth_lon"], inputs["truth_h"],
                                    v, _euler_rows(*_attitude(inputs)))
        if self.rates_form:
            self.last_rates = tuple(inputs[n] for n in RATE_NAMES)

    def step(self, t, h, inputs):
        if not self.started:   # no start sample from initialization mode
            return self._first_sample(inputs)
        self.check_inputs(inputs, self._names())
        t_new = inputs["truth_time"]
        t_last = self.last_time
        dt = self.dt
        if same_time(t_new, t_last, dt):
            return self.out                # the same sample again: hold
        if t_new < t_last or not same_time(t_new - t_last, dt, dt):
            self._refuse_interval(t_new, t_last)
        attitude = _attitude(inputs)
        if self.rates_form:
            dtheta, dvel = self._rate_increments(inputs)
            self._take(inputs)
            gx, gy, gz = dtheta.tolist()
            angle = math.sqrt(gx * gx + gy * gy + gz * gz)
        else:
            dtheta, dvel, angle = self._exact_increments(inputs, attitude, t_new)
        self.last_time = t_new
        return self.measure(self.out, t_new, dt, dtheta, dvel, angle / dt, attitude)

    def _refuse_interval(self, t_new, t_last):
        name, dt = self.model_name, self.dt
        if t_new < t_last:
            raise InputError(f"{name}: input 'truth_time' = {t_new!r} s goes back from the "
                             f"previous sample at {t_last!r} s")
        raise InputError(
            f"{name}: input 'truth_time' = {t_new!r} s is {t_new - t_last:.9g} s after the "
            f"previous sample at {t_last!r} s; the sensor takes one truth sample every "
            f"parameter 'imu_period' = {dt!r} s (nothing is resampled): output the "
            "vehicle's truth at that period and step the sensor at least as often")

    def _exact_increments(self, inputs, attitude, t_new):
        """The inverse strapdown from the previous truth sample to this one, after checking
        that no vehicle makes the jump between them; with the rotation angle |dtheta|."""
        ins, dt = self.ins, self.dt
        lat, lon, h = inputs["truth_lat"], inputs["truth_lon"], inputs["truth_h"]
        v1 = [inputs["truth_vn"], inputs["truth_ve"], inputs["truth_vd"]]
        v0 = ins.v
        dn, de, dd = v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]
        dv = math.sqrt(dn * dn + de * de + dd * dd)
        if dv > MAX_ACCELERATION * dt:
            self._jump(f"the velocity changes by {dv:.6g} m/s in {dt:g} s at truth_time = "
                       f"{t_new!r} s (more than {MAX_ACCELERATION:g} m/s2)", "truth_vn")
        plat, plon, ph = integrate_position(ins.lat, ins.lon, ins.h, v0, v1, dt)
        rn, re = _radii(lat)
        north, east = (lat - plat) * (rn + h), (lon - plon) * (re + h) * math.cos(lat)
        miss = math.sqrt(north * north + east * east + (h - ph) * (h - ph))
        if miss > position_tolerance(dv, dt):
            self._jump(f"the position is {miss:.6g} m from where the velocities lead at "
                       f"truth_time = {t_new!r} s (tolerance {position_tolerance(dv, dt):.3g} "
                       "m)", "truth_lat")
        # the same function (and floats) as the trajectory generator's Strapdown._inverse_to
        dtheta, dvel = ins.step_to(lat, lon, h, v1, _euler_rows(*attitude), dt)
        gx, gy, gz = dtheta
        angle = math.sqrt(gx * gx + gy * gy + gz * gz)
        if angle > MAX_ANGULAR_RATE * dt:   # (a refusal ends the run: the state may move)
            self._jump(f"the attitude turns by {angle:.6g} rad in {dt:g} s at truth_time = "
                       f"{t_new!r} s (more than {MAX_ANGULAR_RATE:g} rad/s)", "truth_roll")
        return dtheta, dvel, angle

    def _jump(self, what, name):
        first = " (the previous sample is the start, set in initialization mode)" \
            if self.last_time == self.start_time else ""
        raise InputError(f"{self.model_name}: input '{name}': {what}{first}: no vehicle makes "
                         "that jump between two samples")

    def _rate_increments(self, inputs):
        rates = tuple(inputs[n] for n in RATE_NAMES)
        limit = (MAX_ANGULAR_RATE,) * 3 + (MAX_ACCELERATION,) * 3
        for n, x, bound in zip(RATE_NAMES, rates, limit):
            if abs(x) > bound:
                raise InputError(f"{self.model_name}: input '{n}' = {x!r} at truth_time = "
                                 f"{inputs['truth_time']!r} s is beyond {bound:g} (no vehicle)")
        increments = trapezoid_increments((0.0, self.dt), (self.last_rates, rates))[0]
        return increments[:3].copy(), increments[3:].copy()


def _attitude(inputs):
    return inputs["truth_roll"], inputs["truth_pitch"], inputs["truth_yaw"]
