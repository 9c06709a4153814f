"""The components wrapped by the FMUs: TrajectoryImu, GnssReceiver and the INS/GNSS filters.

Each class is a :class:`~navcore.component.Component`: it declares its variables (signal names
and units from :mod:`navcore.signals`) and advances with ``step(t, h, inputs)``.  ``REGISTRY``
maps the FMU model names to these classes, so the master can run the same objects directly.
"""
from __future__ import annotations

import math

import numpy as np

from . import signals
from . import state as _state
from .component import (Component, InputError, Limits,
                        ParameterError, boolean, integer, real, string)
from .gnss_errors import POS_SIGMA_LIMITS, VEL_SIGMA_LIMITS, GnssErrorModel
from .imu_errors import (ACCEL_BIAS_LIMITS, ACCEL_VRW_LIMITS, DPH, DPSH, GYRO_ARW_LIMITS,
                         GYRO_BIAS_LIMITS, INTENSITY_REFERENCE_RATE, UG, ImuErrorModel)
from .ins_gnss_kf import MEASUREMENTS, ErrorStateKf, KfConfig
from .latency import SolutionHistory
from .magnetometer import MagnetometerModel
from .rotations import _euler_rows, dcm_to_euler
from .strapdown import Strapdown
from .timing import same_time, samples_reached, time_tolerance
from .trajectory import TrajectoryGenerator, load_profile

#: accepted seeds (numpy's generators take non-negative integers; FMI Integers are 32 bit)
SEED_LIMITS = Limits(0, 2**31 - 1)
#: default latency bound of the filters (parameter ``max_fix_age``) [s]: a 1 Hz receiver
#: under a Jacobi master (libcosim) reaches the filter one receiver period (1 s) after the
#: fix was taken; the extra half period covers a receiver's own output latency up to 0.5 s
#: on top (or a 2 Hz receiver with a 1 s delay)
DEFAULT_MAX_FIX_AGE = 1.5

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


# ---------------------------------------------------------------------------------------
class TrajectoryImu(Component):
    """6-DOF truth from a motion profile and the IMU increments measured along it.

    Samples every ``imu_period`` on its own grid (:mod:`navcore.timing`): a communication
    step covering k epochs computes all k samples and outputs the last (k steps of one
    period give the same numbers bit for bit); a step reaching no epoch holds the outputs.
    """

    model_name = "TrajectoryImu"
    description = ("Truth trajectory from a motion profile on WGS-84 and the strapdown IMU "
                   "increments along it, with bias, noise, Gauss-Markov, scale-factor, "
                   "misalignment and manoeuvre-dependent noise errors; a three-axis "
                   "magnetometer and a vibration disturbance.")
    parameters = (
        string("profile", "built-in motion profile name (static, turntable_240s, "
               "aircraft_500s, manoeuvre_1h, uav_maneuver) or path of a JSON profile file",
               "aircraft_500s"),
        real("imu_period", "s", "IMU sampling interval (samples on this grid; any communication "
             "step)", 0.01,
             Limits(0.0, 1.0, low_open=True)),
        boolean("extend_profile", "allow a run beyond the profile's end (the truth then flies "
                "on at the final velocity and attitude)", False),
        integer("seed", "seed of every random error of the IMU and the magnetometer", 1,
                SEED_LIMITS),
        *ports_from_table(ImuErrorModel.PARAMETERS),
        *ports_from_table(MagnetometerModel.PARAMETERS),
    )
    inputs = ()
    outputs = signals.TRUTH + signals.IMU + signals.MAG
    default_experiment = (0.0, 500.0, 0.01)
    state_fields = ("generator", "errors", "magnetometer", "n", "out")
    derived_fields = ("dt", "mag_on", "_no_mag", "start_time")

    def initialize(self, start_time):
        self.dt = self.params["imu_period"]
        profile = load_profile(self.params["profile"])
        self.generator = TrajectoryGenerator(profile, self.dt)
        error_params = {k: self.params[k] for k in ImuErrorModel.PARAMETERS}
        self.errors = ImuErrorModel(error_params, self.params["seed"])
        self.magnetometer = MagnetometerModel(
            {k: self.params[k] for k in MagnetometerModel.PARAMETERS}, self.params["seed"])
        mag = self.magnetometer
        # the magnetometer/vibration model runs (and draws) only when it is switched on, so a
        # scenario without it keeps its numbers and its speed
        self.mag_on = bool(mag.field_ned.any() or mag.vibrating(math.inf))
        self.start_time = float(start_time)
        self.n = 0
        truth = self.generator.state()
        out = self._truth(truth)
        out.update({p.name: 0.0 for p in signals.IMU + signals.MAG})
        out["imu_time"] = out["mag_time"] = self.start_time
        self._no_mag = {p.name: out[p.name] for p in signals.MAG}
        if self.mag_on:
            self._write_mag(out, self.start_time, truth)
        self.out = out
        return dict(out)

    def check_stop_time(self, stop_time):
        """Refuse a run past the profile's end unless ``extend_profile``."""
        end = self.start_time + self.generator.duration
        if not self.params["extend_profile"] and stop_time > end + time_tolerance(self.dt, end):
            raise ParameterError(
                f"{self.model_name}: the run ends at {stop_time:g} s, after the end of "
                f"profile '{self.params['profile']}' at {end:g} s; stop by {end:g} s or set "
                "parameter 'extend_profile' = true to fly on at the final velocity")

    def _write_mag(self, out, t, truth):
        C_bn = np.array(_euler_rows(truth["roll"], truth["pitch"], truth["yaw"]))
        m = self.magnetometer.measure(t, C_bn)
        out["mag_time"] = t
        out["mag_x"], out["mag_y"], out["mag_z"] = (float(v) for v in m)

    def _truth(self, s):
        return {"truth_time": self.start_time + s["time"], "truth_lat": s["lat"],
                "truth_lon": s["lon"], "truth_h": s["h"], "truth_vn": s["vn"],
                "truth_ve": s["ve"], "truth_vd": s["vd"], "truth_roll": s["roll"],
                "truth_pitch": s["pitch"], "truth_yaw": s["yaw"]}

    def step(self, t, h, inputs):
        for _ in range(samples_reached(self.start_time, self.dt, t + h) - self.n):
            self.out = self._sample()
        return self.out

    def _sample(self):
        truth, dtheta, dvel = self.generator.step()
        self.n += 1
        t_end = self.start_time + self.n * self.dt
        intensity = self.generator.last_rate_norm / INTENSITY_REFERENCE_RATE
        dtheta, dvel = self.errors.apply(t_end, self.dt, dtheta, dvel, intensity)
        out = self._truth(truth)
        if self.mag_on:
            self._write_mag(out, t_end, truth)
            if self.magnetometer.vibrating(t_end):
                dvel = dvel + self.magnetometer.accel_disturbance(t_end) * self.dt
        else:
            out.update(self._no_mag)
        out["imu_time"] = t_end
        out["imu_dt"] = self.dt
        for i, a in enumerate(signals.AXES_BODY):
            dth, dv = float(dtheta[i]), float(dvel[i])   # plain floats: the outputs are state
            out[f"imu_dtheta_{a}"] = dth
            out[f"imu_dvel_{a}"] = dv
            out[f"imu_gyro_{a}"] = dth / self.dt
            out[f"imu_accel_{a}"] = dv / self.dt
        return out


# ---------------------------------------------------------------------------------------
class GnssReceiver(Component):
    """Position/velocity fixes from the truth at the receiver's own rate, with its errors.

    Driven by the truth's time tag: a fix is taken when ``truth_time`` reaches the next epoch
    of its grid (one per step; epochs a coarse step jumps over are skipped), so any
    communication step works.  ``output_delay`` > 0 publishes each fix at the first
    communication point at least that long after ``gnss_time`` (which keeps the time the
    fix was taken): the latency of a real receiver's solution.
    """

    model_name = "GnssReceiver"
    description = ("GNSS receiver: position and velocity fixes from the truth at its own rate "
                   "with per-axis noise, noise steps, outlier patches, periodic m-times "
                   "outliers and outages; 'gnss_epoch' counts fixes.")
    parameters = (
        integer("seed", "seed of every random error of the receiver", 2, SEED_LIMITS),
        real("output_delay", "s", "latency of the receiver's output: a fix is published this "
             "long after it was taken, with its gnss_time unchanged (0 = at once)", 0.0,
             Limits(0.0, 3600.0)),
        *ports_from_table(GnssErrorModel.PARAMETERS),
    )
    inputs = signals.TRUTH[:7]
    outputs = signals.GNSS + signals.GNSS_INJECTED
    default_experiment = (0.0, 500.0, 1.0)
    state_fields = ("model", "next_fix", "n_fix", "out", "queue")
    derived_fields = ("interval", "delay", "start_time")

    def initialize(self, start_time):
        self.delay = self.params["output_delay"]
        self.queue = []   # fixes taken, not yet published (output_delay > 0)
        self.model = GnssErrorModel({k: self.params[k] for k in GnssErrorModel.PARAMETERS},
                                    self.params["seed"])
        self.interval = self.params["fix_interval"]
        self.next_fix = float(start_time) + self.interval
        self.n_fix = 0
        self.start_time = float(start_time)
        self.out = {p.name: p.default() for p in self.outputs}
        self.out["gnss_time"] = float(start_time)
        return dict(self.out)

    def step(self, t, h, inputs):
        self.check_inputs(inputs, ("truth_time", "truth_lat", "truth_lon", "truth_h",
                                          "truth_vn", "truth_ve", "truth_vd"))
        t_truth = inputs["truth_time"]
        if t_truth + time_tolerance(self.interval, t_truth) >= self.next_fix:
            fix = self._fix(t_truth, inputs)
            if self.delay == 0.0:
                self.out = fix
            else:
                self.queue.append(fix)
        if self.queue:
            now = t + h
            tol = time_tolerance(self.interval, now)
            while self.queue and self.queue[0]["gnss_time"] + self.delay <= now + tol:
                self.out = self.queue.pop(0)
        return self.out

    def _fix(self, t_truth, inputs):
        # one fix per due epoch; epochs missed by a coarse step are skipped, not queued
        k = samples_reached(self.start_time, self.interval, t_truth)
        self.next_fix = self.start_time + (k + 1) * self.interval
        fix = self.model.measure(t_truth, inputs["truth_lat"], inputs["truth_lon"],
                                 inputs["truth_h"],
                                 np.array([inputs["truth_vn"], inputs["truth_ve"],
                                           inputs["truth_vd"]]))
        self.n_fix += 1
        return {"gnss_time": t_truth, "gnss_lat": fix["lat"], "gnss_lon": fix["lon"],
                "gnss_h": fix["h"], "gnss_vn": fix["vn"], "gnss_ve": fix["ve"],
                "gnss_vd": fix["vd"], "gnss_valid": bool(fix["valid"]),
                "gnss_epoch": self.n_fix, "gnss_outlier": bool(fix["outlier"])}


# ---------------------------------------------------------------------------------------
#: accepted ranges of the filters' parameters: the initial state within the ranges of the
#: signals (navcore.signals); an assumed GNSS sigma positive and at most the receiver model's
_ANGLE = signals.EULER_ANGLE
_R_POS = Limits(0.0, POS_SIGMA_LIMITS.high, low_open=True)
_R_VEL = Limits(0.0, VEL_SIGMA_LIMITS.high, low_open=True)
_TAU = Limits(0.0, 1e9)
_FILTER_PARAMETERS = (
    *signals.state_ports("init", "initial"),
    real("init_roll", "rad", "initial roll", 0.0, _ANGLE),
    real("init_pitch", "rad", "initial pitch", 0.0, _ANGLE),
    real("init_yaw", "rad", "initial yaw", 0.0, _ANGLE),
    real("p0_pos", "m", "initial 1-sigma position error, each axis", 5.0, Limits(0.0, 1e5)),
    real("p0_vel", "m/s", "initial 1-sigma velocity error, each axis", 0.3, Limits(0.0, 1e3)),
    real("p0_att_level", "rad", "initial 1-sigma roll/pitch (north/east tilt) error",
         math.radians(1.0), Limits(0.0, math.pi)),
    real("p0_att_yaw", "rad", "initial 1-sigma heading error", math.radians(1.0),
         Limits(0.0, math.pi)),
    real("p0_gyro_bias_dph", "deg/h", "initial 1-sigma gyro bias", 0.1, GYRO_BIAS_LIMITS),
    real("p0_accel_bias_ug", "ug", "initial 1-sigma accelerometer bias", 100.0,
         ACCEL_BIAS_LIMITS),
    real("q_gyro_arw_dpsh", "deg/sqrt(h)", "gyro angle random walk assumed by the filter", 0.001,
         GYRO_ARW_LIMITS),
    real("q_accel_vrw_ugpsHz", "ug/sqrt(Hz)", "accel velocity random walk assumed by the filter",
         5.0, ACCEL_VRW_LIMITS),
    real("q_gyro_bias_instability_dph", "deg/h", "Gauss-Markov gyro bias sigma assumed", 0.0,
         GYRO_BIAS_LIMITS),
    real("q_gyro_bias_tau_s", "s", "Gauss-Markov gyro bias correlation time (0 = constant)", 0.0,
         _TAU),
    real("q_accel_bias_instability_ug", "ug", "Gauss-Markov accel bias sigma assumed", 0.0,
         ACCEL_BIAS_LIMITS),
    real("q_accel_bias_tau_s", "s", "Gauss-Markov accel bias correlation time (0 = constant)",
         0.0, _TAU),
    real("r_pos_n", "m", "GNSS position 1-sigma assumed, north", 5.0, _R_POS),
    real("r_pos_e", "m", "GNSS position 1-sigma assumed, east", 5.0, _R_POS),
    real("r_pos_d", "m", "GNSS position 1-sigma assumed, down", 5.0, _R_POS),
    real("r_vel_n", "m/s", "GNSS velocity 1-sigma assumed, north", 0.3, _R_VEL),
    real("r_vel_e", "m/s", "GNSS velocity 1-sigma assumed, east", 0.3, _R_VEL),
    real("r_vel_d", "m/s", "GNSS velocity 1-sigma assumed, down", 0.3, _R_VEL),
    string("measurement", "GNSS measurement used: 'position' or 'position_velocity'",
           "position_velocity"),
    real("max_fix_age", "s", "latency bound: a fix whose gnss_time is more than this from the "
         "filter's nav_time is not applied (counted in n_stale_fixes); a later one is applied "
         "at its gnss_time by re-propagation", DEFAULT_MAX_FIX_AGE, Limits(0.0, 3600.0)),
)

_IMU_INPUT_NAMES = tuple(p.name for p in signals.IMU[:8])
_GNSS_VALUE_NAMES = ("gnss_time", "gnss_lat", "gnss_lon", "gnss_h", "gnss_vn", "gnss_ve",
                     "gnss_vd")


class InsGnssFilter(Component):
    """Common shell of every INS/GNSS filter: same parameters, inputs and outputs.

    Subclasses name their engine (``engine_class``), may add parameters (``extra_parameters``)
    and diagnostic outputs (``extra_outputs``), and build the engine in :meth:`make_engine`.

    Time of validity, for every engine: a fix is applied at the IMU epoch nearest its
    ``gnss_time`` -- at once, after waiting (a fix from the future) or by rollback and exact
    re-propagation from a checkpoint (a late fix; :mod:`navcore.latency`, Groves 2013 sec.
    3.3) -- within the latency bound ``max_fix_age`` (:data:`DEFAULT_MAX_FIX_AGE`); beyond
    it, it is counted in ``n_stale_fixes``.  The filter follows the IMU's time tags, not the
    communication step: each new interval must start where the last one integrated ended.
    """

    engine_class = ErrorStateKf
    extra_parameters = ()
    extra_outputs = ()
    #: the filter applies fixes, so it keeps the history that late ones need
    applies_fixes = True
    inputs = signals.FILTER_INPUTS
    default_experiment = (0.0, 500.0, 0.01)
    state_fields = ("engine", "nav_time", "last_epoch", "out", "imu_dt", "history", "pending",
                    "n_stale", "late_fixes")
    derived_fields = ("max_fix_age",)

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.parameters = _FILTER_PARAMETERS + tuple(cls.extra_parameters)
        cls.outputs = signals.FILTER_OUTPUTS + tuple(cls.extra_outputs)

    # -- configuration -----------------------------------------------------------------
    def make_config(self):
        p = self.params
        self.require("measurement", p["measurement"] in MEASUREMENTS,
                     f"is not one of {sorted(MEASUREMENTS)}")
        p0 = np.concatenate([
            np.full(3, p["p0_pos"]), np.full(3, p["p0_vel"]),
            [p["p0_att_level"], p["p0_att_level"], p["p0_att_yaw"]],
            np.full(3, p["p0_gyro_bias_dph"] * DPH), np.full(3, p["p0_accel_bias_ug"] * UG)])
        r = [p["r_pos_n"], p["r_pos_e"], p["r_pos_d"], p["r_vel_n"], p["r_vel_e"], p["r_vel_d"]]
        return KfConfig(
            p0=p0, gyro_arw=p["q_gyro_arw_dpsh"] * DPSH, accel_vrw=p["q_accel_vrw_ugpsHz"] * UG,
            gyro_bias_sigma=p["q_gyro_bias_instability_dph"] * DPH,
            gyro_bias_tau=p["q_gyro_bias_tau_s"],
            accel_bias_sigma=p["q_accel_bias_instability_ug"] * UG,
            accel_bias_tau=p["q_accel_bias_tau_s"],
            r_sigma=np.array(r[:MEASUREMENTS[p["measurement"]]]),
            measurement=p["measurement"])

    def engine_options(self):
        """Validated keyword arguments of the engine beyond (config, nav); subclasses extend."""
        return {}

    def make_engine(self, config, nav):
        return self.engine_class(config, nav, **self.engine_options())

    def fresh_engine(self):
        """The engine as it starts, built from the parameters (validated first)."""
        p = self.params
        config = self.make_config()
        nav = Strapdown.from_euler(p["init_lat"], p["init_lon"], p["init_h"],
                                   np.array([p["init_vn"], p["init_ve"], p["init_vd"]]),
                                   p["init_roll"], p["init_pitch"], p["init_yaw"])
        return self.make_engine(config, nav)

    # -- life cycle --------------------------------------------------------------------
    def initialize(self, start_time):
        p = self.params
        self.engine = self.fresh_engine()
        self.nav_time = float(start_time)
        self.imu_dt = 0.0            # length of the last IMU interval integrated
        self.last_epoch = 0
        self.max_fix_age = p["max_fix_age"]
        self.history = SolutionHistory(self.nav_time, self.engine)
        self.pending = []            # fixes from the future: (gnss_time, lat, lon, h, v)
        self.n_stale = 0
        self.late_fixes = False      # a fix was applied in the past: dense checkpoints
        self.out = {q.name: q.default() for q in self.outputs}
        self._write_solution()
        self.write_diagnostics(None)  # extra outputs start from the engine's initial state
        return dict(self.out)

    def step(self, t, h, inputs):
        """Integrate the new IMU interval (if any), then apply the fixes due (module
        :mod:`navcore.latency`: at the IMU epoch nearest their gnss_time)."""
        self.check_inputs(inputs, _IMU_INPUT_NAMES)
        imu_dt = inputs["imu_dt"]
        imu_time = inputs["imu_time"]
        out = self.out
        out["updated"] = False
        integrated = False
        # a new IMU interval ends after the one already integrated: mechanize it
        if imu_time > self.nav_time + 0.5 * imu_dt and imu_dt > 0:
            begin = imu_time - imu_dt
            if not same_time(begin, self.nav_time, imu_dt):
                skipped = round((begin - self.nav_time) / imu_dt)
                raise InputError(
                    f"{self.model_name}: input 'imu_time' = {imu_time!r} s with 'imu_dt' = "
                    f"{imu_dt!r} s starts at {begin!r} s, but the last IMU interval integrated "
                    f"ended at nav_time = {self.nav_time!r} s ({skipped} IMU intervals "
                    "skipped or overlapping); step the filter at least as often as the IMU "
                    "delivers samples")
            self.imu_dt = imu_dt
            dtheta = np.array([inputs["imu_dtheta_x"], inputs["imu_dtheta_y"],
                               inputs["imu_dtheta_z"]])
            dvel = np.array([inputs["imu_dvel_x"], inputs["imu_dvel_y"], inputs["imu_dvel_z"]])
            self._integrate((imu_time, dtheta, dvel, imu_dt))
            integrated = True
            while self.pending and self.pending[0][0] <= self.nav_time + self._half_interval():
                self._apply(self.pending.pop(0))
        epoch = inputs["gnss_epoch"]
        if epoch != self.last_epoch:
            self.last_epoch = epoch
            if inputs["gnss_valid"]:
                self._receive_fix(inputs)
        if integrated or out["updated"]:   # otherwise the engine, so the solution, is unchanged
            self._write_solution()
        return out

    def _integrate(self, increment):
        imu_time, dtheta, dvel, imu_dt = increment
        self.engine.propagate(dtheta, dvel, imu_dt)
        self.nav_time = imu_time
        if self.applies_fixes:
            self.history.record(increment, self.engine, self.max_fix_age + imu_dt,
                                self.late_fixes)

    def _half_interval(self):
        """A fix within this of an IMU epoch is applied at that epoch."""
        return 0.5 * self.imu_dt + time_tolerance(self.imu_dt, self.nav_time)

    def _receive_fix(self, inputs):
        """A new valid fix: apply it now, later (from the future) or in the past (rollback),
        or count it as stale when it is outside the latency bound."""
        self.check_inputs(inputs, _GNSS_VALUE_NAMES)
        fix = (inputs["gnss_time"], inputs["gnss_lat"], inputs["gnss_lon"], inputs["gnss_h"],
               np.array([inputs["gnss_vn"], inputs["gnss_ve"], inputs["gnss_vd"]]))
        age = self.nav_time - fix[0]
        self.out["fix_age"] = age
        half = self._half_interval()
        bound = self.max_fix_age + time_tolerance(self.imu_dt, self.nav_time)
        too_far = abs(age) > bound
        # (within the bound the history reaches back far enough unless a fix was applied)
        before_applied = not too_far and fix[0] < self.history.oldest_time() - half
        if too_far or before_applied:
            self._stale(fix[0], age, before_applied)
        elif fix[0] > self.nav_time + half:
            self.pending.append(fix)
        elif fix[0] >= self.nav_time - half:
            self._apply(fix)
        else:
            self._apply_in_the_past(fix, half)

    def _stale(self, gnss_time, age, before_applied):
        self.n_stale += 1
        self.out["n_stale_fixes"] = self.n_stale
        if self.n_stale == 1:
            why = ("is older than the epoch of a fix already applied" if before_applied else
                   f"is {abs(age):.6g} s {'old' if age > 0 else 'ahead'}, beyond parameter "
                   f"'max_fix_age' = {self.max_fix_age} s")
            self.notify(f"{self.model_name}: at nav_time = {self.nav_time:.6g} s the fix taken at "
                        f"gnss_time = {gnss_time:.6g} s {why}: not applied (counted in "
                        "n_stale_fixes; later stale fixes are only counted)")

    def _apply_in_the_past(self, fix, half):
        """Roll back to the checkpoint before the fix's epoch, re-propagate to it, apply the
        fix, re-propagate to the present (module :mod:`navcore.latency`)."""
        self.late_fixes = True
        self.nav_time, tree, replay = self.history.rollback(fix[0] + half)
        self.engine = self.fresh_engine()
        _state.restore(self.engine, tree, f"{self.model_name} checkpoint")
        applied = self.nav_time >= fix[0] - half
        if applied:
            self._apply(fix)
        for increment in replay:
            self._integrate(increment)
            if not applied and self.nav_time >= fix[0] - half:
                self._apply(fix)
                applied = True

    def _apply(self, fix):
        """Measurement update with ``fix`` at the current IMU epoch (its gnss_time within
        half an interval); the history restarts here."""
        gnss_time, lat, lon, h, v = fix
        engine = self.engine
        z = engine.measurement(lat, lon, h, v, self.nav_time - gnss_time)
        result = engine.update(z)
        self.history.restart(self.nav_time, engine)
        out = self.out
        out["updated"] = True
        out["nis"] = result.nis
        out["nis_dof"] = len(z)
        out["q_scale"] = result.q_scale
        out["r_scale"] = result.r_scale
        out["fading_factor"] = result.fading_factor
        out["outlier"] = result.outlier
        self.write_diagnostics(result)

    def write_diagnostics(self, result):
        """Subclasses write their extra outputs here: after every update (``result``) and
        once at initialization (``result`` None)."""

    def _write_solution(self):
        engine = self.engine
        nav = engine.nav
        out = self.out
        out["nav_time"] = self.nav_time
        out["nav_lat"], out["nav_lon"], out["nav_h"] = nav.lat, nav.lon, nav.h
        out["nav_vn"], out["nav_ve"], out["nav_vd"] = (float(x) for x in nav.v_ned)
        out["nav_roll"], out["nav_pitch"], out["nav_yaw"] = (float(x) for x in
                                                             dcm_to_euler(nav.C_bn))
        for i, a in enumerate(signals.AXES_BODY):
            out[f"nav_bg_{a}"] = float(engine.gyro_bias[i])
            out[f"nav_ba_{a}"] = float(engine.accel_bias[i])
        std = np.sqrt(np.maximum(engine.covariance_diagonal(), 0.0))
        for i, name in enumerate(_STD_NAMES):
            out[name] = float(std[i])
        if not math.isfinite(sum(out.values())):  # one pass over every output
            bad = next(k for k, v in out.items() if not math.isfinite(v))
            raise InputError(f"{self.model_name}: output '{bad}' became non-finite at t = "
                             f"{self.nav_time} s (the filter diverged)")


_STD_NAMES = tuple(p.name for p in signals.FILTER_OUTPUTS if p.name.startswith("std_"))


class Kf(InsGnssFilter):
    """Baseline 15-state loosely coupled error-state Kalman filter (closed loop)."""

    model_name = "Kf"
    description = ("INS/GNSS loosely coupled 15-state error-state Kalman filter with closed-loop "
                   "feedback (baseline, fixed Q and R).")


REGISTRY = {cls.model_name: cls for cls in (TrajectoryImu, GnssReceiver, Kf)}


# ---------------------------------------------------------------------------------------
# Adaptive / robust filters of papers 001 and 004 (engines in navcore.adaptive_filters).
from .adaptive_filters import (  # noqa: E402  (kept with the classes that use them)
    DEFAULT_FORGETTING_FACTOR, DEFAULT_OUTLIER_ALPHA, DEFAULT_RESERVE_GAMMA,
    REPLACEMENT_VARIANCES, IakfKf,
    Igg3RobustKf as _Igg3Engine, InsOnlyKf, NewtonRobustKf as _NewtonEngine, SageHusaFadingKf)
from .adaptive_laws import CHI2_THRESHOLD_PAPER_004, DEFAULT_R_FLOOR_FRACTION  # noqa: E402

_R_EST_OUTPUTS = (
    *(real(f"r_est_p{a}", "m", f"Sage-Husa estimate of the GNSS position 1-sigma, {a.upper()} "
           "(sqrt of the R diagonal after the latest update)") for a in signals.AXES_NED),
    *(real(f"r_est_v{a}", "m/s", f"Sage-Husa estimate of the GNSS velocity 1-sigma, {a.upper()} "
           "(0 when velocity is not measured)") for a in signals.AXES_NED),
)
_R_EST_NAMES = tuple(p.name for p in _R_EST_OUTPUTS)


class SageHusaFading(InsGnssFilter):
    """Simplified Sage-Husa R estimation + fading memory (paper 001 eqs. 9-12)."""

    model_name = "SageHusaFading"
    description = ("INS/GNSS 15-state error-state KF with the simplified Sage-Husa measurement-"
                   "noise estimator (paper 001 eq. 9) and the fading-memory filter (eqs. 10-12).")
    engine_class = SageHusaFadingKf
    extra_parameters = (
        real("forgetting_factor", "", "Sage-Husa forgetting factor b, 0 < b <= 1 (paper 001: "
             "0.95-0.99; memory about 1/(1-b) updates)", DEFAULT_FORGETTING_FACTOR,
             Limits(0.0, 1.0, low_open=True)),
        real("reserve_gamma", "", "reserve coefficient gamma of the divergence test (paper 001 "
             "eq. 11; 1 = strictest)", DEFAULT_RESERVE_GAMMA, Limits(0.0, 1e12, low_open=True)),
        real("r_floor_fraction", "", "floor of the estimated R as a fraction of the initial R "
             "diagonal (variances)", DEFAULT_R_FLOOR_FRACTION, Limits(0.0, 1e6, low_open=True)),
        real("max_fading_factor", "", "cap on the fading factor lambda (0 = no cap, as in the "
             "paper; else >= 1)", 0.0, Limits(0.0, 1e6)),
    )
    extra_outputs = _R_EST_OUTPUTS

    def engine_options(self):
        p = self.params
        cap = p["max_fading_factor"]
        self.require("max_fading_factor", not 0.0 < cap < 1.0, "must be 0 (no cap) or >= 1")
        return dict(forgetting_factor=p["forgetting_factor"], reserve_gamma=p["reserve_gamma"],
                    r_floor_fraction=p["r_floor_fraction"], max_fading_factor=cap or None)

    def write_diagnostics(self, result):
        sigma = self.engine.r_sigma_estimate()
        for i, value in enumerate(sigma):
            self.out[_R_EST_NAMES[i]] = float(value)


class Iakf(SageHusaFading):
    """Paper 001's improved adaptive KF: Sage-Husa + fading + outlier compression (eqs. 9-14)."""

    model_name = "Iakf"
    description = ("Improved adaptive Kalman filter of paper 001: simplified Sage-Husa R "
                   "estimation, fading memory and chi-square outlier compression of the "
                   "innovation (eqs. 9-14), on the 15-state INS/GNSS error-state KF.")
    engine_class = IakfKf
    extra_parameters = SageHusaFading.extra_parameters + (
        real("outlier_alpha", "", "significance alpha of the chi2(m) outlier gate of eq. 14 "
             "(paper 001: 0.05 or 0.02)", DEFAULT_OUTLIER_ALPHA,
             Limits(0.0, 1.0, low_open=True, high_open=True)),
    )
    extra_outputs = SageHusaFading.extra_outputs + (
        real("compression", "", "outlier compression factor Y of the latest update (eq. 14; "
             "1 = no outlier)", 1.0),
    )

    def engine_options(self):
        options = super().engine_options()
        options["outlier_alpha"] = self.params["outlier_alpha"]
        return options

    def write_diagnostics(self, result):
        super().write_diagnostics(result)
        self.out["compression"] = self.engine.compression


class NewtonRobustKf(InsGnssFilter):
    """Paper 004: per-observation chi-square test + Newton extrapolation of failed ones."""

    model_name = "NewtonRobustKf"
    description = ("Robust INS/GNSS KF of paper 004: per-observation chi-square test "
                   "(threshold 6.635) and replacement of failed observations by the Newton "
                   "forward extrapolation of the previous observations.")
    engine_class = _NewtonEngine
    extra_parameters = (
        real("chi2_threshold", "", "gate of the per-observation chi-square statistic "
             "v_i^2/S_ii (paper 004: 6.635 = chi2(1) at alpha 0.01)", CHI2_THRESHOLD_PAPER_004,
             Limits(0.0, 1e6, low_open=True)),
        integer("newton_order", "order of the Newton extrapolation polynomial (paper 004: 4)", 4,
                Limits(0, 10)),
        string("replacement_variance", "R of a replaced observation: 'propagated' (R times the "
               "noise gain of the extrapolation) or 'nominal' (R unchanged)", "propagated"),
    )
    extra_outputs = (
        real("chi2_max", "", "largest per-observation chi-square statistic of the latest "
             "update"),
        integer("n_rejected", "observation components replaced at the latest update"),
    )

    def engine_options(self):
        p = self.params
        self.require("replacement_variance", p["replacement_variance"] in REPLACEMENT_VARIANCES,
                     f"is not one of {list(REPLACEMENT_VARIANCES)}")
        return dict(chi2_threshold=p["chi2_threshold"], newton_order=p["newton_order"],
                    replacement_variance=p["replacement_variance"])

    def write_diagnostics(self, result):
        self.out["chi2_max"] = self.engine.chi2_max
        self.out["n_rejected"] = self.engine.n_rejected


class Igg3RobustKf(InsGnssFilter):
    """IGG-III equivalent-weight robust KF (the equivalent-weight method of paper 004 1.2)."""

    model_name = "Igg3RobustKf"
    description = ("Robust INS/GNSS KF with IGG-III equivalent weights on the standardized "
                   "innovations (R_ii / w_i; w = 1 below k0, 0 above k1).")
    engine_class = _Igg3Engine
    extra_parameters = (
        real("igg_k0", "", "IGG-III constant k0: standardized innovations up to k0 keep full "
             "weight", 1.5, Limits(0.0, 100.0, low_open=True)),
        real("igg_k1", "", "IGG-III constant k1: standardized innovations above k1 are "
             "rejected", 3.0, Limits(0.0, 100.0, low_open=True)),
    )
    extra_outputs = (
        real("min_weight", "", "smallest IGG-III weight of the latest update (1 = none "
             "down-weighted)", 1.0),
        integer("n_rejected", "observation components rejected (weight 0) at the latest update"),
    )

    def engine_options(self):
        p = self.params
        self.require("igg_k1", p["igg_k1"] > p["igg_k0"], f"must be > igg_k0 = {p['igg_k0']}")
        return dict(igg_k0=p["igg_k0"], igg_k1=p["igg_k1"])

    def write_diagnostics(self, result):
        self.out["min_weight"] = float(self.engine.weights.min())
        self.out["n_rejected"] = self.engine.n_rejected


class InsOnly(InsGnssFilter):
    """Free inertial navigation: the Kf's mechanization with no measurement update.

    GNSS inputs are accepted (same contract as every filter, so it swaps in) and ignored:
    ``updated`` stays False, the diagnostics keep their start values, and the std_* outputs
    show the covariance propagated from P0 with the process noise alone.
    """

    model_name = "InsOnly"
    description = ("Free strapdown inertial navigation (no GNSS update), same inputs and "
                   "outputs as the INS/GNSS filters; the covariance only propagates.")
    engine_class = InsOnlyKf
    applies_fixes = False

    def _receive_fix(self, inputs):
        """No measurement update: the GNSS fix is ignored."""


REGISTRY.update({cls.model_name: cls for cls in (SageHusaFading, Iakf, NewtonRobustKf,
                                                 Igg3RobustKf, InsOnly)})


# ---------------------------------------------------------------------------------------
# Unscented filters of paper 000 (engines in navcore.ukf_filters).
from .ukf_filters import (  # noqa: E402  (kept with the classes that use them)
    DEFAULT_PREDICT_INTERVAL, CtfaUkfEngine, ImmUkfEngine, UkfEngine)

#: accepted Q scales of the IMM models (relative to the configured Q)
_Q_SCALE = Limits(0.0, 1e12, low_open=True)
#: most IMM models a component offers (outputs model_prob_1..3)
_IMM_MAX_MODELS = 3


class Ukf(InsGnssFilter):
    """Paper 000's UKF: 15-state error-state UKF, nonlinear large-misalignment error model."""

    model_name = "Ukf"
    description = ("INS/GNSS 15-state error-state unscented Kalman filter (paper 000 eqs. 11-23) "
                   "with a nonlinear rotation-vector large-misalignment error model, fixed Q and "
                   "R, closed-loop feedback.")
    engine_class = UkfEngine
    extra_parameters = (
        real("ukf_predict_interval", "s", "interval of the UKF time update (interval means of "
             "the nominal navigation; 0 = every IMU step); always also before an update",
             DEFAULT_PREDICT_INTERVAL, Limits(0.0, 3600.0)),
        real("ukf_alpha", "", "scaled unscented transform alpha (eq. 11, 0 < alpha <= 1)", 1.0,
             Limits(0.0, 1.0, low_open=True)),
        real("ukf_beta", "", "scaled unscented transform beta (eq. 13; 2 = Gaussian)", 2.0,
             Limits(-1e3, 1e3)),
        real("ukf_kappa", "", "scaled unscented transform kappa (eq. 11; n + kappa > 0 for the "
             "15-state filter)", 0.0, Limits(-15.0, 1e3, low_open=True)),
    )

    def engine_options(self):
        p = self.params
        return dict(predict_interval=p["ukf_predict_interval"], alpha=p["ukf_alpha"],
                    beta=p["ukf_beta"], kappa=p["ukf_kappa"])


class CtfaUkf(Ukf):
    """Paper 000's CTFA-UKF: UKF + chi-square fuzzy adaptive process noise (eqs. 24-25)."""

    model_name = "CtfaUkf"
    description = ("Fuzzy adaptive UKF with chi-square test (CTFA-UKF, paper 000): the UKF whose "
                   "process noise Q moves between Qmin and Qmax as a piecewise-linear function "
                   "of the innovation chi-square statistic (eqs. 24-25).")
    engine_class = CtfaUkfEngine
    extra_parameters = Ukf.extra_parameters + (
        real("q_max_scale", "", "Qmax = q_max_scale * Qmin, Qmin = the configured Q (paper 000: "
             "an integer multiple; 100 = the noise variance of a 10 deg/s manoeuvre in "
             "models/uav_maneuver)", 100.0, Limits(1.0, 1e12)),
        real("ctfa_t1", "", "lower chi-square threshold of eq. 25 (0 = 6.25 for a 3-dimensional "
             "measurement, else the 90 % chi-square quantile)", 0.0, Limits(0.0, 1e4)),
        real("ctfa_t2", "", "upper chi-square threshold of eq. 25 (0 = 11.35 for a 3-dimensional "
             "measurement, else the 99 % chi-square quantile)", 0.0, Limits(0.0, 1e4)),
        real("ctfa_pass_decay", "", "ours, not the paper's: factor on Q - Qmin at every update "
             "whose chi-square passes (below ctfa_t1); 1 = eq. 25 as printed (Q_k-1 kept), "
             "0 = back to Qmin at once, in between an exponential return to Qmin", 1.0,
             Limits(0.0, 1.0)),
    )
    extra_outputs = (
        real("chi2", "", "chi-square statistic of the latest update (eq. 24)"),
    )

    def engine_options(self):
        p = self.params
        return dict(super().engine_options(), q_max_scale=p["q_max_scale"], t1=p["ctfa_t1"],
                    t2=p["ctfa_t2"], pass_decay=p["ctfa_pass_decay"])

    def make_engine(self, config, nav):
        engine = super().make_engine(config, nav)
        if not engine.schedule.T2 > engine.schedule.T1:
            raise ParameterError(f"{self.model_name}: parameters 'ctfa_t1' = "
                                 f"{engine.schedule.T1} and 'ctfa_t2' = {engine.schedule.T2} "
                                 "must satisfy t1 < t2")
        return engine

    def write_diagnostics(self, result):
        self.out["chi2"] = self.engine.chi2


class ImmUkf(Ukf):
    """IMM-UKF (paper 000's comparison): 2 or 3 UKFs with different Q scales."""

    model_name = "ImmUkf"
    description = ("Interacting multiple model UKF (paper 000's IMM-UKF, its ref. [14]): 2 or 3 "
                   "UKFs with different process-noise scales, Markov model switching, mixing "
                   "once per GNSS interval, closed-loop feedback of the combined estimate.")
    engine_class = ImmUkfEngine
    extra_parameters = Ukf.extra_parameters + (
        integer("imm_models", "number of models (2 or 3)", 2, Limits(2, 3)),
        real("imm_q_scale_1", "", "Q scale of model 1 relative to the configured Q", 1.0,
             _Q_SCALE),
        real("imm_q_scale_2", "", "Q scale of model 2 (default: CtfaUkf's Qmax)", 100.0,
             _Q_SCALE),
        real("imm_q_scale_3", "", "Q scale of model 3 (used when imm_models = 3; default "
             "between models 1 and 2)", 10.0, _Q_SCALE),
        real("imm_p_stay", "", "Markov probability of staying in a model per GNSS interval "
             "(diagonal of the transition matrix; the rest spread evenly)", 0.95,
             Limits(0.0, 1.0, low_open=True, high_open=True)),
    )
    extra_outputs = tuple(
        real(f"model_prob_{j}", "", f"IMM probability of model {j} after the latest update "
             "(0 for an unused model)") for j in range(1, _IMM_MAX_MODELS + 1))

    def engine_options(self):
        p = self.params
        names = [f"imm_q_scale_{j}" for j in range(1, p["imm_models"] + 1)]
        return dict(super().engine_options(), q_scales=[p[n] for n in names],
                    p_stay=p["imm_p_stay"])

    def write_diagnostics(self, result):
        self.out["q_scale"] = self.engine.q_scale
        mu = self.engine.model_probabilities
        for j in range(_IMM_MAX_MODELS):
            self.out[f"model_prob_{j + 1}"] = float(mu[j]) if j < len(mu) else 0.0


REGISTRY.update({cls.model_name: cls for cls in (Ukf, CtfaUkf, ImmUkf)})


# ---------------------------------------------------------------------------------------
# Replay of recorded sensor logs (navcore.replay).
from .replay import ImuGnssReplay  # noqa: E402  (registered with the other components)

REGISTRY[ImuGnssReplay.model_name] = ImuGnssReplay


# ---------------------------------------------------------------------------------------
# Attitude (AHRS) filters of paper 003 (components in navcore.ahrs_components).
from .ahrs_components import REGISTRY as _AHRS_REGISTRY  # noqa: E402

REGISTRY.update(_AHRS_REGISTRY)
