"""The attitude filter components of paper 003: UkfAhrs and FuzzyUkfAhrs (one AHRS contract).

Both declare ``signals.AHRS_INPUTS`` (IMU increments with ``imu_time``/``imu_dt``, the
magnetometer with ``mag_time``) and at least ``signals.AHRS_OUTPUTS``, so either replaces
the other in a system model.  A filter never reads truth.

Timing: a new IMU interval (``imu_time`` beyond the one already integrated) adds its gyro
increment to the pending time update; once ``update_interval`` has passed since the previous
update, the filter runs the UKF time update and the measurement update with that sample's
specific force (``imu_dvel / imu_dt``) and the magnetometer sample, provided ``mag_time`` is
within ``max_mag_age`` of ``imu_time`` (else the update waits for a fresh sample).  So the
numbers depend on the time tags, not on whether the master hands the inputs over in the same
or the next step.  Without ``init_attitude = 'parameters'`` the first sample initialises the
attitude by TRIAD (:func:`navcore.filters.ahrs.triad_attitude`).
"""
from __future__ import annotations

import math

import numpy as np

from ..core import signals
from .ahrs_batch import AhrsFilterBatch
from ..filters.ahrs import FuzzyAdaptiveR, UkfAhrsEngine, triad_attitude
from ..core.component import Component, Limits, integer, real, string
from ..ins.constants import DPH, DPSH, G0
from ..errors import DivergenceError, ParameterError, StepSizeError
from ..filters.fuzzy import FEET, OUTPUT_VERTICES, FuzzyRScale
from ..ins.rotations import euler_to_dcm
from ..core.timing import same_time

_INIT_MODES = ("measurement", "parameters")
_INPUT_NAMES = tuple(p.name for p in signals.AHRS_INPUTS)

_AHRS_PARAMETERS = (
    string("init_attitude", "'measurement' (TRIAD from the first accelerometer and "
           "magnetometer sample) or 'parameters' (init_roll/pitch/yaw)", "measurement"),
    real("init_roll", "rad", "initial roll (init_attitude = 'parameters')", 0.0),
    real("init_pitch", "rad", "initial pitch (init_attitude = 'parameters')", 0.0),
    real("init_yaw", "rad", "initial yaw (init_attitude = 'parameters')", 0.0),
    real("gravity_mps2", "m/s2", "local gravity magnitude g of the measurement model", G0,
         Limits(0.0, 100.0, low_open=True)),
    real("mag_field_T", "T", "earth field intensity H of the measurement model", 5.0e-5,
         Limits(0.0, 1e-3, low_open=True)),
    real("mag_inclination", "rad", "earth field inclination I of the measurement model",
         math.radians(60.0), Limits(-math.pi / 2, math.pi / 2, True, True)),
    real("p0_att", "rad", "initial 1-sigma attitude error, each axis", math.radians(5.0),
         Limits(0.0, math.pi, low_open=True)),
    real("p0_gyro_bias_dph", "deg/h", "initial 1-sigma gyro bias", 100.0, Limits(0.0, 1e6)),
    real("q_gyro_arw_dpsh", "deg/sqrt(h)", "gyro angle random walk assumed by the filter", 0.3,
         Limits(0.0, 1e4)),
    real("q_gyro_bias_rw_dphpsh", "deg/h/sqrt(h)", "gyro bias random walk assumed", 1.0,
         Limits(0.0, 1e6)),
    real("r_accel_mps2", "m/s2", "accelerometer 1-sigma per axis assumed (nominal R)", 0.02,
         Limits(0.0, 1e3, low_open=True)),
    real("r_mag_T", "T", "magnetometer 1-sigma per axis assumed (nominal R)", 2.0e-7,
         Limits(0.0, 1e-3, low_open=True)),
    real("update_interval", "s", "interval of the measurement updates (0 = every IMU sample)",
         0.1, Limits(0.0, 100.0)),
    real("max_mag_age", "s", "a magnetometer sample further than this from imu_time is not "
         "used", 0.05, Limits(0.0, 100.0)),
    real("ukf_alpha", "", "scaled unscented transform alpha (0 < alpha <= 1)", 1.0,
         Limits(0.0, 1.0, low_open=True)),
    real("ukf_beta", "", "scaled unscented transform beta (2 = Gaussian)", 2.0),
    real("ukf_kappa", "", "scaled unscented transform kappa (6 + kappa > 0)", 0.0,
         Limits(-6.0, 1e6, low_open=True)),
)


def _vectors(inputs, imu_dt):
    """The specific force [m/s^2] (the velocity increment over ``imu_dt``) and the
    magnetometer reading [T] of a step's inputs."""
    return (np.array([inputs[n] for n in signals.IMU_DVEL_NAMES]) / imu_dt,
            np.array([inputs[n] for n in signals.MAG_NAMES]))


class AhrsFilter(Component):
    """Common shell of the AHRS filters (see the module docstring)."""

    state_fields = ("engine", "nav_time", "last_update", "out")
    extra_parameters = ()
    extra_outputs = ()
    inputs = signals.AHRS_INPUTS
    #: paper 003's turntable run (ahrs_turntable: 240 s, IMU at 50 Hz)
    default_experiment = (0.0, 240.0, 0.02)
    batch_class = AhrsFilterBatch

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.parameters = _AHRS_PARAMETERS + tuple(cls.extra_parameters)
        cls.outputs = signals.AHRS_OUTPUTS + tuple(cls.extra_outputs)

    def make_adaptive(self):
        """The R adaptation of the filter (None: fixed R)."""
        return None

    def make_engine(self):
        p = self.params
        self.require("init_attitude", p["init_attitude"] in _INIT_MODES,
                     f"is not one of {list(_INIT_MODES)}")
        return UkfAhrsEngine(
            p["gravity_mps2"], p["mag_field_T"], p["mag_inclination"],
            p["q_gyro_arw_dpsh"] * DPSH, p["q_gyro_bias_rw_dphpsh"] * DPH / 60.0,
            p["r_accel_mps2"], p["r_mag_T"], p["p0_att"], p["p0_gyro_bias_dph"] * DPH,
            p["ukf_alpha"], p["ukf_beta"], p["ukf_kappa"], adaptive=self.make_adaptive())

    # -- life cycle --------------------------------------------------------------------
    def initialize(self, start_time):
        p = self.params
        self.engine = self.make_engine()
        self.nav_time = float(start_time)
        self.last_update = -math.inf
        self.out = {q.name: q.default() for q in self.outputs}
        if p["init_attitude"] == "parameters":
            self.engine.start(euler_to_dcm(p["init_roll"], p["init_pitch"], p["init_yaw"]))
            self._write_solution(sigmas=True)
        self.out["nav_time"] = self.nav_time
        return dict(self.out)

    def step(self, t, h, inputs):
        self.check_inputs(inputs, _INPUT_NAMES)
        imu_dt, imu_time = inputs["imu_dt"], inputs["imu_time"]
        out = self.out
        out["updated"] = False
        if not (imu_time > self.nav_time + 0.5 * imu_dt and imu_dt > 0):
            return out
        begin = imu_time - imu_dt
        if self.engine.started and not same_time(begin, self.nav_time, imu_dt):
            raise StepSizeError(
                f"{self.model_name}: input 'imu_time' = {imu_time!r} s with 'imu_dt' = "
                f"{imu_dt!r} s starts at {begin!r} s, but the last IMU interval integrated "
                f"ended at nav_time = {self.nav_time!r} s; step the filter at least as often "
                "as the IMU delivers samples")
        mag_fresh = abs(inputs["mag_time"] - imu_time) <= self.params["max_mag_age"] + 1e-9
        engine = self.engine
        self.nav_time = imu_time
        if not engine.started:
            if not mag_fresh:
                return out
            engine.start(triad_attitude(*_vectors(inputs, imu_dt),
                                        self.params["mag_inclination"]))
            self.last_update = imu_time
            self._write_solution(sigmas=True)
            return out
        engine.accumulate([inputs[n] for n in signals.IMU_DTHETA_NAMES], imu_dt)
        due = imu_time - self.last_update >= self.params["update_interval"] - 1e-9
        if due and mag_fresh:
            engine.update(*_vectors(inputs, imu_dt))
            self.last_update = imu_time
            out["updated"] = True
            out["nis"] = engine.last_nis
            out["nis_dof"] = 6
            self.write_diagnostics()
        self._write_solution(sigmas=out["updated"])
        return out

    def write_diagnostics(self):
        """Subclasses write their extra outputs here after every update."""

    def _write_solution(self, sigmas):
        engine, out = self.engine, self.out
        out["nav_time"] = self.nav_time
        out["aligned"] = True
        out["nav_roll"], out["nav_pitch"], out["nav_yaw"] = (float(a) for a in engine.euler())
        if sigmas:
            for name, s in zip(("std_roll", "std_pitch", "std_yaw"), engine.euler_sigma()):
                out[name] = float(s)
        out.update(zip(signals.NAV_BG_NAMES, engine.gyro_bias.tolist()))
        out["r_scale_accel"], out["r_scale_mag"] = (float(s) for s in engine.r_scale)
        if not all(math.isfinite(out[k]) for k in ("nav_roll", "nav_pitch", "nav_yaw")):
            raise DivergenceError(f"{self.model_name}: the attitude became non-finite at "
                                  f"t = {self.nav_time} s (filter diverged)")


class UkfAhrs(AhrsFilter):
    """Paper 003's conventional UKF: MRP attitude + gyro bias, fixed R."""

    description = ("Attitude UKF (paper 003): modified Rodrigues parameters and gyro bias as "
                   "the state, gravity and earth-field vectors from the accelerometer and the "
                   "magnetometer as measurements, fixed R.")


class FuzzyUkfAhrs(AhrsFilter):
    """Paper 003's fuzzy adaptive UKF: R_k = F_k R_(k-1), F from a Mamdani inference."""

    description = ("Fuzzy adaptive attitude UKF (paper 003): the UkfAhrs whose accelerometer "
                   "and magnetometer R blocks are scaled at every update by a Mamdani fuzzy "
                   "inference on the innovation covariance mismatch (paper 003 eqs. 15-19, 25); "
                   "the membership feet are parameters (GA-tunable).")
    extra_parameters = (
        integer("fuzzy_window", "window N of the measured innovation covariance (paper 003 "
                "eq. 17)", 20, Limits(2, 100000)),
        real("r_scale_min", "", "smallest R scale factor (times the nominal R)", 0.5,
             Limits(0.0, 1.0, low_open=True)),
        real("r_scale_max", "", "largest R scale factor (times the nominal R)", 1.0e5,
             Limits(1.0, 1e12)),
        *(real(name, "", desc, default, Limits(lo, hi))
          for name, (default, lo, hi, desc) in {**FEET, **OUTPUT_VERTICES}.items()),
    )
    extra_outputs = (
        real("fuzzy_e_accel", "", "fuzzy input e of the accelerometer block: "
             "(tr C_z - tr P_z) / tr P_z"),
        real("fuzzy_de_accel", "", "fuzzy input de of the accelerometer block (change of e)"),
        real("fuzzy_e_mag", "", "fuzzy input e of the magnetometer block"),
        real("fuzzy_de_mag", "", "fuzzy input de of the magnetometer block"),
    )

    def make_adaptive(self):
        p = self.params
        try:
            inference = FuzzyRScale({k: p[k] for k in (*FEET, *OUTPUT_VERTICES)})
        except ParameterError as exc:
            raise ParameterError(f"{self.model_name}: parameters {exc}") from None
        return FuzzyAdaptiveR(inference, p["fuzzy_window"], p["r_scale_min"],
                              p["r_scale_max"])

    def write_diagnostics(self):
        adaptive = self.engine.adaptive
        out = self.out
        out["fuzzy_e_accel"], out["fuzzy_e_mag"] = (float(v) for v in adaptive.e)
        out["fuzzy_de_accel"], out["fuzzy_de_mag"] = (float(v) for v in adaptive.de)

