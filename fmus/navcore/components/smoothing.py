"""The smoother's facade: a filter component that records its forward pass, and the smoothed
solution of that recording (:mod:`navcore.filters.rts_smoother`).

The real-time filter components stay causal: a run to be smoothed swaps in the recording
class of :class:`SmoothingSession` (same parameters, inputs, outputs and numbers as the
filter; it only keeps what the backward pass needs) under the direct backend, and asks the
session for the smoothed solution afterwards.  The master knows nothing of the recording:
it runs a component class from a registry, as always.

A replayed log's IMU may be stamped late against the GNSS clock (a logger's latency): the
session then synchronizes (:meth:`SmoothingSession.synchronize`, after the first run): it
estimates the offset from the IMU and the fixes that run saw
(:mod:`navcore.filters.imu_time_offset`) and, when it matters, asks for the run again with
the fixes on the IMU's clock, and keeps that run when its fixes fit the filter better; the
smoothed solution is then read back on the GNSS clock.

Supported: :data:`SMOOTHABLE` (the filters whose forward covariances are the model's own:
``Kf``).  The adaptive and robust filters rescale P, Q or R inside their updates (fading
memory, Sage-Husa, robust weights), so the transitions and noise the smoother rebuilds
would not be theirs; the UKF family carries no transition matrix.
"""
from __future__ import annotations

import numpy as np

from ..errors import NavcoreError
from ..filters.ins_gnss_kf import KfEngine
from ..filters import imu_time_offset
from ..filters.rts_smoother import KfRecording, smooth
from .smoothing_clock import ClockInputs, FixFit
from .kf_components import Kf

#: filter model name -> its component class, the filters the smoother supports
SMOOTHABLE = {"Kf": Kf}


class _RecordingKfEngine(KfEngine):
    """KfEngine that reports to ``recorder`` (the recording component, None before it
    records) each IMU interval it integrates and each correction it feeds back: a fix's
    update and a land aid's pseudo-measurement (:meth:`KfEngine.aid_update`, which ZUPT,
    ZARU and the NHC call between two intervals) alike, as they happen.  A recording that
    saw only the fixes would smooth as if the aids had never corrected the state, while the
    nominal states it stores carry their corrections."""

    derived_fields = ("recorder",)

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.recorder = None

    def propagate(self, dtheta, dvel, dt):
        # the specific force in NED the transition is built with (attitude at the start)
        f_ned = self.nav.rows[0, 6:15].reshape(3, 3) @ (dvel / dt - self.accel_bias)
        super().propagate(dtheta, dvel, dt)
        if self.recorder is not None:
            self.recorder.recorded_interval(dt, f_ned)

    def apply(self, dx, P):
        super().apply(dx, P)
        if self.recorder is not None:
            self.recorder.recorded_update(np.array(dx, dtype=float))


def _recording_class(base, session):
    """``base`` (a Kf-family component class) recording into ``session.recordings``."""

    class Recording(base):
        engine_class = _RecordingKfEngine

        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            session.recordings.append(self)

        def step(self, t, h, inputs):
            if session.time_offset:          # the fixes on the IMU's clock
                inputs = {**inputs, "gnss_time": inputs["gnss_time"] + session.time_offset}
            else:
                self.clock_inputs.take(inputs)
            return super().step(t, h, inputs)

        def _begin_recording(self):
            cfg = self.engine.config
            self.recording = KfRecording(self.engine.q_density, cfg.gyro_bias_tau,
                                         cfg.accel_bias_tau)
            self.recording.start(self.nav_time, self.engine)
            self.engine.recorder = self

        def make_engine(self, config, nav):
            engine = super().make_engine(config, nav)
            if getattr(self, "recording", None) is not None:   # a rollback's fresh engine
                engine.recorder = self
            return engine

        def initialize(self, start_time):
            self.recording = None
            self.clock_inputs = ClockInputs()        # what synchronize() compares
            self.fit = FixFit()                      # what keeps_synchronization() compares
            out = super().initialize(start_time)
            if self.initializer.done:
                self._begin_recording()
            return out

        def _start_from(self, state):
            self.recording = None            # the engine built here records from its start
            super()._start_from(state)
            self._begin_recording()

        def _integrate(self, increment):
            self.recording.truncate_after(self.nav_time)     # a rollback's replay
            self.interval_end = increment[0]
            super()._integrate(increment)

        def recorded_interval(self, dt, f_ned):
            """The engine integrated the interval ending at ``interval_end``."""
            self.recording.add_epoch(self.interval_end, dt, self.engine.nav.rows[0], f_ned)

        def recorded_update(self, dx):
            """The engine fed back ``dx`` (a fix or a land aid) at the latest epoch."""
            self.recording.add_update(dx, self.engine)

        def _apply(self, fix):
            self.recording.truncate_after(self.nav_time)     # a fix applied in the past
            super()._apply(fix)

        def _applied(self, z, result):
            super()._applied(z, result)
            self.fit.add(result)

    Recording.__name__ = Recording.__qualname__ = base.__name__
    Recording.model_name = base.model_name
    return Recording


class SmoothingSession:
    """One smoothed run of filter ``model_name``: run :attr:`component_class` (direct
    backend); then, to synchronize the IMU's clock, :meth:`synchronize` and, when it says
    so, the run again and :meth:`keeps_synchronization`; then :meth:`solution`."""

    def __init__(self, model_name: str):
        if model_name not in SMOOTHABLE:
            raise NavcoreError(f"the smoother supports the filters {', '.join(SMOOTHABLE)}, "
                               f"not {model_name} (its updates rescale P, Q or R, or it has "
                               "no transition matrix): run it without smoothing")
        self.recordings = []
        self.time_offset = 0.0           # [s] the IMU's stamps less the GNSS time
        self.clock = None                # the estimate (TimeOffset) once synchronized
        self.fits = None                 # (first run's, second run's) FixFit.mean
        self._first = None               # the first run's component during the second
        self.component_class = _recording_class(SMOOTHABLE[model_name], self)

    def _started(self):
        started = [c for c in self.recordings if getattr(c, "recording", None) is not None]
        if not started:
            raise NavcoreError("the filter never started (init_mode: no initial state from the "
                               "data): nothing to smooth")
        return started[-1]

    def synchronize(self) -> bool:
        """After the first run: estimate the IMU's time offset from the inputs its filter
        received (:mod:`navcore.filters.imu_time_offset`).  True when the offset applies
        (at least half an IMU interval): run again (the fixes then go to the filter on the
        IMU's clock), then :meth:`keeps_synchronization`."""
        first = self._started()
        self.clock = first.clock_inputs.estimate()
        if not self.clock.applies(first.clock_inputs.imu_interval()):
            return False
        self._first, self.time_offset, self.recordings = first, self.clock.tau, []
        return True

    def keeps_synchronization(self) -> bool:
        """After the second run: whether its fixes fit its filter better than the first
        run's fit theirs (:class:`navcore.components.smoothing_clock.FixFit`: the mean
        negative log-likelihood of the innovations, the likelihood ratio of "late by the
        estimate" against "on time").  If not, the session goes back to the first run (its
        recording, no offset) and says False: the estimate read a lag that is not the
        clock's (a walker's heading leads the course)."""
        second = self._started()
        self.fits = (self._first.fit.mean(), second.fit.mean())
        if self.fits[1] < self.fits[0]:
            return True
        self.time_offset, self.recordings = 0.0, [self._first]
        return False

    def solution(self):
        """The smoothed solution of the run (:func:`navcore.filters.rts_smoother.smooth`; on
        the GNSS clock after a synchronized run), with ``recording_bytes``: the memory the
        recording held."""
        rec = self._started().recording
        out = smooth(rec)
        if self.time_offset:
            out = imu_time_offset.on_gnss_clock(out, self.time_offset)
        out["recording_bytes"] = rec.nbytes
        return out


__all__ = ["SMOOTHABLE", "SmoothingSession"]
