"""The shell every INS/GNSS filter component shares: its parameters, inputs, outputs and timing.

:class:`InsGnssFilter` declares the parameters common to every filter
(:mod:`navcore.components.filter_parameters`), the filter inputs
and outputs of :mod:`navcore.core.signals`, and the stepping rule (IMU time tags, fixes applied at
their time of validity through :mod:`navcore.filters.latency`).  The filter families
(:mod:`navcore.components.kf_components`, :mod:`navcore.components.ukf_components`) subclass it with
their engine and their extra parameters and diagnostics.
"""
from __future__ import annotations

import math

import numpy as np

from ..core import signals
from ..core import state as _state
from ..core.component import Component, InputError
from ..errors import DivergenceError, StepSizeError
from ..ins.constants import DPH, DPSH, UG
from ..filters.initial_state import (FROM_FIX, INIT_CHECK_SIGMAS, INIT_MODES, Initializer,
                                     disagreement, level_sigma)
from ..filters.static_alignment import RestDetector
from ..filters.initial_biases import (StaticBiasEstimator, bias_sigmas, check_static_mode,
                                      given_biases)
from ..filters.ins_gnss_kf import MEASUREMENTS, KfConfig, KfEngine
from .filter_parameters import FILTER_PARAMETERS
from ..filters.land_aids import LandAids
from ..filters.latency import SolutionHistory
from .filter_batch import InsGnssFilterBatch
from ..filters.correlated_gnss import CorrelatedFixes
from ..filters.nis_monitor import NIS_WARNING_PARAMETERS, NisMonitor
from ..filters.recovery import RECOVERY_PARAMETERS
from ..ins.lever_arm import antenna_fix, lever_arm_of
from ..ins import earth
from ..ins.rotations import euler_to_dcm
from ..ins.strapdown import Strapdown
from ..core.timing import same_time, time_tolerance

#: a first fix farther than this from the filter's position, and farther than
#: FIRST_FIX_SIGMAS initial position sigmas, is no measurement error: the GNSS source flies
#: another trajectory than the filter's init_* describe (a host that left a String such as a
#: trajectory's ``profile`` at its default, or init_* not set); the filter warns once
FIRST_FIX_DISTANCE_M = 1000.0
FIRST_FIX_SIGMAS = 100.0

_IMU_INPUT_NAMES = tuple(p.name for p in signals.IMU[:8])
_GNSS_VALUE_NAMES = ("gnss_time", "gnss_lat", "gnss_lon", "gnss_h", "gnss_vn", "gnss_ve",
                     "gnss_vd")

_STD_NAMES = tuple(p.name for p in signals.FILTER_OUTPUTS if p.name.startswith("std_"))
_STD_INPUT_NAMES = tuple(p.name for p in signals.GNSS_STD)


class InsGnssFilter(Component):
    """Common shell of every INS/GNSS filter: same parameters, inputs and outputs.

    Subclasses name their engine (``engine_class``), may add parameters (``extra_parameters``)
    and diagnostic outputs (``extra_outputs``), and build the engine in :meth:`make_engine`.

    Time of validity, for every engine: a fix is applied at the IMU epoch nearest its
    ``gnss_time`` -- at once, after waiting (a fix from the future) or by rollback and exact
    re-propagation from a checkpoint (a late fix; :mod:`navcore.filters.latency`, Groves 2013 sec.
    3.3) -- within the latency bound ``max_fix_age``
    (:data:`navcore.components.filter_parameters.DEFAULT_MAX_FIX_AGE`); beyond it, it is
    counted in ``n_stale_fixes``.  The filter follows the IMU's time tags, not the communication
    step: each new interval must start where the last one integrated ended.
    """

    engine_class = KfEngine
    #: many runs in one call (navcore.core.batch): the Kf family's IMU intervals
    batch_class = InsGnssFilterBatch
    extra_parameters = ()
    extra_outputs = ()
    #: engine attributes written, under the same names, to outputs after every update
    engine_diagnostics = ()
    #: the filter applies fixes, so it keeps the history that late ones need
    applies_fixes = True
    inputs = signals.FILTER_INPUTS
    default_experiment = (0.0, 500.0, 0.01)
    state_fields = ("engine", "nav_time", "last_epoch", "out", "imu_dt", "history", "pending",
                    "n_stale", "late_fixes", "nis_monitor", "initializer", "static_bias",
                    "correlated", "rest")
    derived_fields = ("max_fix_age",)

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.parameters = (FILTER_PARAMETERS + RECOVERY_PARAMETERS + NIS_WARNING_PARAMETERS
                          + tuple(cls.extra_parameters))
        cls.outputs = signals.FILTER_OUTPUTS + tuple(cls.extra_outputs)

    # -- configuration -----------------------------------------------------------------
    def make_config(self):
        p = self.params
        self.require("measurement", p["measurement"] in MEASUREMENTS,
                     f"is not one of {sorted(MEASUREMENTS)}")
        p0 = np.concatenate([
            np.full(3, p["p0_pos"]), np.full(3, p["p0_vel"]),
            [p["p0_att_level"], p["p0_att_level"], p["p0_att_yaw"]],
            bias_sigmas(p, p["p0_gyro_bias_dph"] * DPH, p["p0_accel_bias_ug"] * UG)])
        r = [p["r_pos_n"], p["r_pos_e"], p["r_pos_d"], p["r_vel_n"], p["r_vel_e"], p["r_vel_d"]]
        gyro_bias0, accel_bias0 = given_biases(p)
        k = p["imu_noise_factor"]       # navcore.filters.process_noise_factor
        return KfConfig(
            p0=p0, gyro_arw=k * p["q_gyro_arw_dpsh"] * DPSH,
            accel_vrw=k * p["q_accel_vrw_ugpsHz"] * UG,
            gyro_bias_sigma=k * p["q_gyro_bias_instability_dph"] * DPH,
            gyro_bias_tau=p["q_gyro_bias_tau_s"],
            accel_bias_sigma=k * p["q_accel_bias_instability_ug"] * UG,
            accel_bias_tau=p["q_accel_bias_tau_s"],
            r_sigma=np.array(r[:MEASUREMENTS[p["measurement"]]]),
            measurement=p["measurement"], lever_arm=lever_arm_of(p),
            gyro_bias0=gyro_bias0, accel_bias0=accel_bias0)

    def engine_options(self):
        """Validated keyword arguments of the engine beyond (config, nav); subclasses extend."""
        return {}

    def make_engine(self, config, nav):
        """The engine, with the land aids (:mod:`navcore.filters.land_aids`) when any is on."""
        engine = self.engine_class(config, nav, **self.engine_options())
        if LandAids.wanted(self.params):
            engine.aids = LandAids(self.params)
        return engine

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
        self.nis_monitor = NisMonitor(p["nis_warning_s"], p["imu_noise_factor"])
        self.correlated = CorrelatedFixes(p["gnss_corr_time"])
        self.out = {q.name: q.default() for q in self.outputs}
        self.require("init_mode", p["init_mode"] in INIT_MODES, f"is not one of {INIT_MODES}")
        self.initializer = Initializer(p["init_mode"], p["init_speed_min"], p["align_time"],
                                       p["measurement"] == "position_velocity")
        why = check_static_mode(p["init_mode"], p["init_static_time"])
        self.require("init_static_time", why is None, why or "")
        self.static_bias = StaticBiasEstimator(p["init_static_time"])
        self.rest = (RestDetector(p["static_window"], p["static_accel_std"],
                                  p["static_rate_std"]) if p["init_mode"] == "static" else None)
        self.out["aligned"] = self.initializer.done
        self._write_solution()
        self.write_diagnostics(None)  # extra outputs start from the engine's initial state
        return dict(self.out)

    def step(self, t, h, inputs):
        """Integrate the new IMU interval (if any), then apply the fixes due (module
        :mod:`navcore.filters.latency`: at the IMU epoch nearest their gnss_time)."""
        self.check_inputs(inputs, _IMU_INPUT_NAMES)
        out = self.out
        out["updated"] = False
        if not self.initializer.done:
            return self._step_before_start(inputs)
        integrated = False
        increment = self._new_interval(inputs)
        if increment is not None:
            self._integrate(increment)
            integrated = True
            while self.pending and self.pending[0][0] <= self.nav_time + self._half_interval():
                self._apply(self.pending.pop(0))
        self._take_epoch(inputs)
        if integrated or out["updated"]:   # otherwise the engine, so the solution, is unchanged
            self._write_solution()
        return out

    def _take_epoch(self, inputs):
        """A new GNSS epoch (``gnss_epoch`` changed): its fix, when valid, is received."""
        fix = self._epoch_fix(inputs)
        if fix is not None:
            self._apply(fix)

    def _epoch_fix(self, inputs):
        """:meth:`_take_epoch` but the update: the fix to apply at the current IMU epoch,
        or None (no new epoch, an invalid fix, or one :meth:`_fix_to_apply` dealt with)."""
        epoch = inputs["gnss_epoch"]
        if epoch != self.last_epoch:
            self.last_epoch = epoch
            if inputs["gnss_valid"]:
                if not self.initializer.checked:
                    self._check_given_state(inputs)
                return self._fix_to_apply(inputs)
        return None

    def _new_interval(self, inputs):
        """The increment (imu_time, dtheta, dvel, imu_dt) of a new IMU interval, one that
        ends after the one already integrated and starts where it ended; None without one."""
        imu_dt = inputs["imu_dt"]
        imu_time = inputs["imu_time"]
        if imu_time > self.nav_time + 0.5 * imu_dt and imu_dt > 0:
            begin = imu_time - imu_dt
            if not same_time(begin, self.nav_time, imu_dt):
                skipped = round((begin - self.nav_time) / imu_dt)
                raise StepSizeError(
                    f"{self.model_name}: input 'imu_time' = {imu_time!r} s with 'imu_dt' = "
                    f"{imu_dt!r} s starts at {begin!r} s, but the last IMU interval integrated "
                    f"ended at nav_time = {self.nav_time!r} s ({skipped} IMU intervals "
                    "skipped or overlapping); step the filter at least as often as the IMU "
                    "delivers samples")
            self.imu_dt = imu_dt
            dtheta = np.array([inputs["imu_dtheta_x"], inputs["imu_dtheta_y"],
                               inputs["imu_dtheta_z"]])
            dvel = np.array([inputs["imu_dvel_x"], inputs["imu_dvel_y"], inputs["imu_dvel_z"]])
            return imu_time, dtheta, dvel, imu_dt
        return None

    # -- the start from the data (navcore.initial_state) -----------------------------------
    def _step_before_start(self, inputs):
        """Before the initial state is known: the IMU intervals and fixes go to the
        initializer; nav_time follows the IMU; nothing is integrated or updated."""
        init = self.initializer
        increment = self._new_interval(inputs)
        if increment is not None:
            imu_time, dtheta, dvel, imu_dt = increment
            nav = self.engine.nav
            init.add_interval(dtheta, dvel, imu_dt, nav.lat, nav.h)
            self.static_bias.add_interval(dtheta, dvel, imu_dt)
            if init.mode == "static":
                self.rest.add_interval(dtheta, dvel, imu_dt)
            self.nav_time = self.out["nav_time"] = imu_time
        state = None
        epoch = inputs["gnss_epoch"]
        if epoch != self.last_epoch:
            self.last_epoch = epoch
            if inputs["gnss_valid"]:
                self.check_inputs(inputs, _GNSS_VALUE_NAMES)
                fix = _fix_of(inputs)
                if init.mode in FROM_FIX:
                    state = init.state_from_fix(fix, self.nav_time)
                    warning = None if state is not None else init.waiting_warning(fix[0])
                    if warning:
                        self.notify(f"{self.model_name}: {warning}")
                else:
                    init.note_fix(fix)
        if init.alignment_ready():
            p = self.params
            state = init.state_from_alignment((p["init_lat"], p["init_lon"], p["init_h"]))
        if state is not None:
            self._start_from(state)
        return self.out

    def _start_from(self, state):
        """Build the engine at ``state`` (lat, lon, h, v_ned, roll, pitch, yaw) now."""
        lat, lon, h, v, roll, pitch, yaw = state
        p = self.params
        config = self.make_config()
        r = np.array([p[f"r_{q}_{a}"] for q in ("pos", "vel") for a in "ned"])
        std = self.initializer.start_std
        if p["r_from_receiver"] and std is not None and np.all(std > 0):
            r[:3] = std                 # the receiver's own sigmas of the fix started from
        config.p0 = self.initializer.start_sigmas(
            config.p0, r if self.initializer.use_fix_velocity else r[:3],
            max(math.hypot(v[0], v[1]), p["init_speed_min"]))
        if p["init_static_time"] > 0.0:
            bias, sigma, warning = self.static_bias.estimate(lat)
            if warning:
                self.notify(f"{self.model_name}: {warning}")
            else:
                config.gyro_bias0, config.p0[9:12] = bias, sigma
        if p["init_mode"] == "static":
            state = self._static_alignment(state, config)
            lat, lon, h, v, roll, pitch, yaw = state
        elif p["init_mode"] == "align":
            # levelled at rest as 'static' is: its level is known to the accelerometer bias
            # over g, not to the configured p0_att_level (a 10 deg prior made the UKF's
            # points predict a -g E[1 - cos phi] = -0.3 m/s^2 vertical error that is not there)
            config.p0[6:8] = level_sigma(config.p0[12:14], earth.gravity(lat, h))
        if config.lever_arm is not None:   # the fix is the antenna's: back to the IMU
            lat, lon, h, _ = antenna_fix(lat, lon, h, v, euler_to_dcm(roll, pitch, yaw),
                                         -config.lever_arm, np.zeros(3))
        nav = Strapdown.from_euler(lat, lon, h, np.asarray(v, dtype=float), roll, pitch, yaw)
        self.engine = self.make_engine(config, nav)
        self.history = SolutionHistory(self.nav_time, self.engine)
        self.initializer.done = True
        self.out["aligned"] = True
        self._write_solution()
        self.write_diagnostics(None)

    def _static_alignment(self, state, config):
        """``init_mode = 'static'``: ``state`` levelled on the rest period, ``config`` with
        the gyro biases and the level's sigmas of the rest (or as it was, with a warning,
        when the IMU was not static; :mod:`navcore.filters.static_alignment`)."""
        lat, lon, h, v, roll, pitch, yaw = state
        roll_r, pitch_r, level_sigma, bias, bias_sigma, warning = self.rest.estimate(
            lat, config.p0[12:14], earth.gravity(lat, h))
        if warning:
            self.notify(f"{self.model_name}: {warning}")
            return state
        config.gyro_bias0, config.p0[9:12] = bias, bias_sigma
        config.p0[6:8] = level_sigma
        return lat, lon, h, v, roll_r, pitch_r, yaw

    def _check_given_state(self, inputs):
        """At the first valid fix of a given initial state: warn when the state is more than
        INIT_CHECK_SIGMAS sigmas off the fix (navcore.initial_state)."""
        self.initializer.checked = True
        self.check_inputs(inputs, _GNSS_VALUE_NAMES)
        fix = _fix_of(inputs)
        engine = self.engine
        z = engine.measurement(*fix[1:5], self.nav_time - fix[0])
        p = self.params
        sigmas, axis, metres = disagreement(z, engine.covariance_diagonal()[:3],
                                            [p["r_pos_n"], p["r_pos_e"], p["r_pos_d"]])
        gross = float(np.linalg.norm(z[:3])) > max(FIRST_FIX_DISTANCE_M,
                                                   FIRST_FIX_SIGMAS * p["p0_pos"])
        if sigmas > INIT_CHECK_SIGMAS and not gross:    # gross: _check_first_fix says it
            self.initializer.warned = True
            self.notify(f"{self.model_name}: the given initial state is {metres:.4g} m off the "
                        f"first fix (gnss_time = {fix[0]:.6g} s) along {'NED'[axis]}, "
                        f"{sigmas:.3g} sigmas of sqrt(P + R) (more than {INIT_CHECK_SIGMAS:g}): "
                        "check init_lat/init_lon (rad) and init_h, or set init_mode = 'gnss'")

    def _integrate(self, increment):
        imu_time, dtheta, dvel, imu_dt = increment
        engine = self.engine
        engine.propagate(dtheta, dvel, imu_dt)
        if engine.aids is not None:
            engine.aids.after_interval(engine, dtheta, dvel, imu_dt, imu_time)
        self.nav_time = imu_time
        if self.applies_fixes:
            self.history.record(increment, self.engine, self.max_fix_age + imu_dt,
                                self.late_fixes)

    def _half_interval(self):
        """A fix within this of an IMU epoch is applied at that epoch."""
        return 0.5 * self.imu_dt + time_tolerance(self.imu_dt, self.nav_time)

    def _fix_to_apply(self, inputs):
        """A new valid fix: returned to be applied now; or held for later (from the future),
        applied in the past (rollback) or counted as stale when it is outside the latency
        bound, and None returned."""
        self.check_inputs(inputs, _GNSS_VALUE_NAMES)
        fix = _fix_of(inputs)
        age = self.nav_time - fix[0]
        self.out["fix_age"] = age
        half = self._half_interval()
        too_far = self._beyond_latency_bound(age)
        # (within the bound the history reaches back far enough unless a fix was applied)
        before_applied = not too_far and fix[0] < self.history.oldest_time() - half
        if too_far or before_applied:
            self._stale(fix[0], age, before_applied)
        elif fix[0] > self.nav_time + half:
            self.pending.append(fix)
        elif fix[0] >= self.nav_time - half:
            return fix
        else:
            self._apply_in_the_past(fix, half)
        return None

    def _beyond_latency_bound(self, age):
        return abs(age) > self.max_fix_age + time_tolerance(self.imu_dt, self.nav_time)

    def applies_at_once(self, gnss_time):
        """Whether :meth:`_fix_to_apply` applies a fix taken at ``gnss_time`` at the current
        IMU epoch, the history then restarting there (not stale, not held for later, no
        rollback: a fix within half an interval is never before the oldest checkpoint,
        which is at or before ``nav_time``)."""
        half = self._half_interval()
        return (not self._beyond_latency_bound(self.nav_time - gnss_time)
                and self.nav_time - half <= gnss_time <= self.nav_time + half)

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
        fix, re-propagate to the present (module :mod:`navcore.filters.latency`)."""
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
        z = self._measure(fix)
        self._applied(z, self.engine.update(z))
        if self.engine.aids is not None:
            self.engine.aids.note_fix(fix[0], fix[4])

    def _measure(self, fix):
        """The measurement ``z`` of ``fix`` (:meth:`_apply` before the engine's update)."""
        gnss_time, lat, lon, h, v, std = fix
        engine = self.engine
        self._position_r(engine, std, gnss_time)
        z = engine.measurement(lat, lon, h, v, self.nav_time - gnss_time)
        if self.out["nis_dof"] == 0:   # the first fix applied
            self._check_first_fix(gnss_time, float(np.linalg.norm(z[:3])))
        return z

    def _applied(self, z, result):
        """:meth:`_apply` after the engine's update with ``z``, which gave ``result``: the
        history restarts, the outputs and the NIS monitor take the result."""
        self.history.restart(self.nav_time, self.engine)
        out = self.out
        out["updated"] = True
        out["nis"] = result.nis
        out["nis_dof"] = len(z)
        out["q_scale"] = result.q_scale
        out["r_scale"] = result.r_scale
        out["fading_factor"] = result.fading_factor
        out["outlier"] = result.outlier
        self.write_diagnostics(result)
        warning = self.nis_monitor.observe(self.nav_time, result.nis, len(z))
        if warning:
            self.notify(f"{self.model_name}: {warning}")

    def _check_first_fix(self, gnss_time, distance):
        bound = max(FIRST_FIX_DISTANCE_M, FIRST_FIX_SIGMAS * self.params["p0_pos"])
        if distance > bound:
            self.notify(f"{self.model_name}: the first fix (gnss_time = {gnss_time:.6g} s) is "
                        f"{distance / 1000.0:.4g} km from the filter's position (parameters "
                        "init_lat, init_lon, init_h): the GNSS source flies another trajectory "
                        "than the filter is set up for (a String parameter left at its default, "
                        "such as the trajectory's 'profile', by a host that does not apply it?); "
                        "the solution is off until the filter converges to the fixes")

    def _position_r(self, engine, std, gnss_time):
        """The position part of the engine's nominal R for this fix: the receiver's sigmas
        (``r_from_receiver``; else ``r_pos_*``), each variance scaled for the errors'
        correlation with the last fix's (``gnss_corr_time``,
        :mod:`navcore.filters.correlated_gnss`); the velocity part stays r_vel_*.  With
        neither set, R stays the configured one."""
        p = self.params
        factor = self.correlated.factor(gnss_time)
        if p["r_from_receiver"]:
            variances = self._receiver_sigmas(std, gnss_time) ** 2
        elif factor != 1.0:
            variances = np.array([p["r_pos_n"], p["r_pos_e"], p["r_pos_d"]]) ** 2
        else:
            return
        R = engine.R0.copy()
        R[[0, 1, 2], [0, 1, 2]] = variances * factor
        engine.R0 = R

    def _receiver_sigmas(self, std, gnss_time):
        """The receiver's sigmas of this fix (``r_from_receiver``), refused when not positive."""
        bad = np.flatnonzero(~(std > 0))
        if bad.size:
            name = _STD_INPUT_NAMES[int(bad[0])]
            raise InputError(f"{self.model_name}: input '{name}' = {float(std[bad[0]])!r} m "
                             f"for the fix at gnss_time = {gnss_time!r} s with parameter "
                             "'r_from_receiver' "
                             "= true: the receiver gives no sigma (a log without std_n/e/d "
                             "columns, or the input is not connected)")
        return std

    def write_diagnostics(self, result):
        """The extra outputs, after every update (``result``) and once at initialization
        (``result`` None): each name in ``engine_diagnostics`` copied from the engine's
        attribute of that name; subclasses add what needs computing."""
        for name in self.engine_diagnostics:
            self.out[name] = getattr(self.engine, name)

    def _write_solution(self):
        engine = self.engine
        nav = engine.nav
        out = self.out
        out["nav_time"] = self.nav_time
        update = out.update
        update(zip(signals.NAV_SOLUTION_NAMES, nav.solution()))
        update(zip(signals.NAV_BG_NAMES, engine.gyro_bias.tolist()))
        update(zip(signals.NAV_BA_NAMES, engine.accel_bias.tolist()))
        update(zip(_STD_NAMES, np.sqrt(np.maximum(engine.covariance_diagonal(), 0.0)).tolist()))
        if not math.isfinite(sum(out.values())):  # one pass over every output
            bad = next(k for k, v in out.items() if not math.isfinite(v))
            raise DivergenceError(f"{self.model_name}: output '{bad}' became non-finite at "
                                  f"t = {self.nav_time} s (the filter diverged)")


def _fix_of(inputs):
    """The fix of the GNSS inputs: (gnss_time, lat, lon, h, v_ned, receiver sigmas NED)."""
    return (inputs["gnss_time"], inputs["gnss_lat"], inputs["gnss_lon"], inputs["gnss_h"],
            np.array([inputs["gnss_vn"], inputs["gnss_ve"], inputs["gnss_vd"]]),
            np.array([inputs.get(name, 0.0) for name in _STD_INPUT_NAMES]))
