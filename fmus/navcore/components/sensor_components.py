"""The sensor components: TrajectoryImu (truth and IMU along a motion profile) and GnssReceiver.

Each class is a :class:`~navcore.core.component.Component`: it declares its variables (signal names
and units from :mod:`navcore.core.signals`) and advances with ``step(t, h, inputs)``.  The error
models they wrap declare their own parameter tables;
:func:`navcore.components.imu_measurement.ports_from_table` turns such a table into ports.
TrajectoryImu's IMU and magnetometer outputs are
:class:`navcore.components.imu_measurement.ImuMeasurement`'s, shared with
:class:`navcore.components.imu_sensor.ImuSensor`.
"""
from __future__ import annotations

import numpy as np

from ..core import signals
from ..core.component import Component, Limits, ParameterError, boolean, integer, real, string
from ..sensors.gnss_errors import GnssErrorModel
from ..ins.lever_arm import LEVER_ARM_PARAMETERS, antenna_fix, lever_arm_of
from ..ins.rotations import dcm_to_rotvec, euler_to_dcm
from .imu_measurement import ERROR_PARAMETERS, SEED_LIMITS, ImuMeasurement, ports_from_table
from ..core.timing import samples_reached, time_tolerance
from ..ins.trajectory import TrajectoryGenerator
from .gnss_receiver_batch import GnssReceiverBatch
from .trajectory_imu_batch import TrajectoryImuBatch

# ---------------------------------------------------------------------------------------
class TrajectoryImu(ImuMeasurement, Component):
    """6-DOF truth from a motion profile and the IMU increments measured along it.

    Samples every ``imu_period`` on its own grid (:mod:`navcore.core.timing`): a communication
    step covering k epochs computes all k samples and outputs the last (k steps of one
    period give the same numbers bit for bit); a step reaching no epoch holds the outputs.
    """

    description = ("Truth trajectory from a motion profile on WGS-84 and the strapdown IMU "
                   "increments along it, with bias, noise, Gauss-Markov, scale-factor, "
                   "misalignment and manoeuvre-dependent noise errors; a three-axis "
                   "magnetometer and a vibration disturbance.")
    file_parameters = ("profile",)
    parameters = (
        string("profile", "built-in motion profile name (static, turntable_240s, "
               "aircraft_500s, manoeuvre_1h, uav_maneuver) or path of a JSON profile file",
               "aircraft_500s"),
        real("imu_period", "s", "IMU sampling interval (samples on this grid; any communication "
             "step)", 0.01,
             Limits(0.0, 1.0, low_open=True)),
        boolean("extend_profile", "allow a run beyond the profile's end (the truth then flies "
                "on at the final velocity and attitude)", False),
        *ERROR_PARAMETERS,
    )
    inputs = ()
    outputs = signals.TRUTH + signals.IMU + signals.MAG
    default_experiment = (0.0, 500.0, 0.01)
    #: many runs of one profile in one call (navcore.core.batch)
    batch_class = TrajectoryImuBatch
    state_fields = ("generator", "errors", "magnetometer", "n", "out")
    derived_fields = ("dt", "mag_on", "_no_mag", "start_time")

    def initialize(self, start_time):
        self.dt = self.params["imu_period"]
        self.generator = TrajectoryGenerator(self.params["profile"], self.dt)
        self.build_error_models()
        self.start_time = float(start_time)
        self.n = 0
        truth = self.generator.state()
        out = self._truth(truth)
        self.start_outputs(out, self.start_time, _attitude(truth))
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
        return self.measure(self._truth(truth), t_end, self.dt, dtheta, dvel,
                            self.generator.last_rate_norm, _attitude(truth))


def _attitude(truth):
    """(roll, pitch, yaw) of a truth dict of the trajectory generator."""
    return truth["roll"], truth["pitch"], truth["yaw"]


# ---------------------------------------------------------------------------------------
class GnssReceiver(Component):
    """Position/velocity fixes from the truth at the receiver's own rate, with its errors.

    Driven by the truth's time tag: a fix is taken when ``truth_time`` reaches the next epoch
    of its grid (one per step; epochs a coarse step jumps over are skipped), so any
    communication step works.  ``output_delay`` > 0 publishes each fix at the first
    communication point at least that long after ``gnss_time`` (which keeps the time the
    fix was taken): the latency of a real receiver's solution.

    ``lever_arm_x/y/z`` (body frame, from the truth's reference point to the antenna) moves
    the fixes to the antenna (:mod:`navcore.ins.lever_arm`): that needs the truth attitude
    inputs ``truth_roll/pitch/yaw`` connected; the antenna velocity's rotation term uses the
    body's turn rate from the attitude change between two steps of the receiver (exact for
    a constant rate, first order otherwise).
    """

    description = ("GNSS receiver: position and velocity fixes from the truth at its own rate "
                   "with per-axis noise, noise steps, outlier patches, periodic m-times "
                   "outliers and outages; 'gnss_epoch' counts fixes.")
    parameters = (
        integer("seed", "seed of every random error of the receiver", 2, SEED_LIMITS),
        real("output_delay", "s", "latency of the receiver's output: a fix is published this "
             "long after it was taken, with its gnss_time unchanged (0 = at once)", 0.0,
             Limits(0.0, 3600.0)),
        *ports_from_table(GnssErrorModel.PARAMETERS),
        *LEVER_ARM_PARAMETERS,
    )
    inputs = signals.TRUTH
    outputs = signals.GNSS + signals.GNSS_INJECTED
    default_experiment = (0.0, 500.0, 1.0)
    #: many receivers in one call (navcore.core.batch)
    batch_class = GnssReceiverBatch
    state_fields = ("model", "next_fix", "n_fix", "out", "queue", "attitude_prev")
    derived_fields = ("interval", "delay", "start_time", "lever")

    def initialize(self, start_time):
        self.delay = self.params["output_delay"]
        self.queue = []   # fixes taken, not yet published (output_delay > 0)
        self.model = GnssErrorModel({k: self.params[k] for k in GnssErrorModel.PARAMETERS},
                                    self.params["seed"])
        self.interval = self.params["fix_interval"]
        self.lever = lever_arm_of(self.params)
        self.attitude_prev = None     # (truth_time, C_bn rows) of the last step, lever arm only
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
        attitude = None if self.lever is None else self._attitude(t_truth, inputs)
        if t_truth + time_tolerance(self.interval, t_truth) >= self.next_fix:
            fix = self._fix(t_truth, inputs, attitude)
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

    def _attitude(self, t_truth, inputs):
        """(C_bn, rate of the body against NED [rad/s]) from the truth attitude now and at the
        previous step (zero rate at the first step)."""
        self.check_inputs(inputs, ("truth_roll", "truth_pitch", "truth_yaw"))
        C_bn = euler_to_dcm(inputs["truth_roll"], inputs["truth_pitch"], inputs["truth_yaw"])
        rate = np.zeros(3)
        if self.attitude_prev is not None and t_truth > self.attitude_prev[0]:
            t0, rows = self.attitude_prev
            rate = dcm_to_rotvec(C_bn @ np.array(rows).T) / (t_truth - t0)
        self.attitude_prev = (t_truth, C_bn.tolist())
        return C_bn, rate

    def _fix(self, t_truth, inputs, attitude=None):
        # one fix per due epoch; epochs missed by a coarse step are skipped, not queued
        k = samples_reached(self.start_time, self.interval, t_truth)
        self.next_fix = self.start_time + (k + 1) * self.interval
        position = (inputs["truth_lat"], inputs["truth_lon"], inputs["truth_h"],
                    np.array([inputs["truth_vn"], inputs["truth_ve"], inputs["truth_vd"]]))
        if attitude is not None:
            position = antenna_fix(*position, attitude[0], self.lever, attitude[1])
        fix = self.model.measure(t_truth, *position)
        self.n_fix += 1
        return {"gnss_time": t_truth, "gnss_lat": fix["lat"], "gnss_lon": fix["lon"],
                "gnss_h": fix["h"], "gnss_vn": fix["vn"], "gnss_ve": fix["ve"],
                "gnss_vd": fix["vd"], "gnss_valid": bool(fix["valid"]),
                "gnss_epoch": self.n_fix, "gnss_outlier": bool(fix["outlier"])}

