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
the fixes on the IMU's clock, and keeps that run when its fixes fit the filter better; with
no estimate, or one that fits worse, it searches the offset whose run fits the fixes best
(:mod:`navcore.filters.time_offset_search`).  The smoothed solution is then read back on
the GNSS clock.

Supported: :data:`SMOOTHABLE` (the filters whose forward covariances are the model's own:
``Kf``).  The adaptive and robust filters rescale P, Q or R inside their updates (fading
memory, Sage-Husa, robust weights), so the transitions and noise the smoother rebuilds
would not be theirs; the UKF family carries no transition matrix.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from ..errors import NavcoreError
from ..filters.ins_gnss_kf import KfEngine
from ..filters import imu_time_offset, time_offset_search
from ..filters.time_offset_search import OffsetSearch
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
    backend); then :meth:`synchronize` (which may ask for more runs); then
    :meth:`solution`.  ``search``: the likelihood search of the IMU's time offset
    (:class:`navcore.filters.time_offset_search.OffsetSearch`; None: the course estimate
    only)."""

    def __init__(self, model_name: str, search: Optional[OffsetSearch] = OffsetSearch()):
        if model_name not in SMOOTHABLE:
            raise NavcoreError(f"the smoother supports the filters {', '.join(SMOOTHABLE)}, "
                               f"not {model_name} (its updates rescale P, Q or R, or it has "
                               "no transition matrix): run it without smoothing")
        self.recordings = []
        self.search = search
        self.time_offset = 0.0           # [s] the IMU's stamps less the GNSS time
        self.clock = None                # the course estimate (TimeOffset) once synchronized
        self.fits = {}                   # offset [s] -> the fixes' fit (FixFit.mean) of its run
        self.searched = False            # whether the likelihood search ran
        self.component_class = _recording_class(SMOOTHABLE[model_name], self)

    def _started(self):
        started = [c for c in self.recordings if getattr(c, "recording", None) is not None]
        if not started:
            raise NavcoreError("the filter never started (init_mode: no initial state from the "
                               "data): nothing to smooth")
        return started[-1]

    def synchronize(self, rerun, first=None):
        """After the first run (``first``: what it returned, handed back if it stays the
        best): synchronize the IMU's clock with the GNSS clock, calling ``rerun()`` for each
        further run (the fixes then go to the filter at ``gnss_time + time_offset``), and
        keep the run whose fixes fit its filter best (:class:`FixFit`: the mean negative
        log-likelihood of the innovations).  The offsets run: the course estimate
        (:mod:`navcore.filters.imu_time_offset`) when it applies (at least half an IMU
        interval); when there is none or its run does not fit significantly better than
        the run on the IMU's own clock (a walker's heading leads the course), the likelihood
        search
        (:mod:`navcore.filters.time_offset_search`) within its bounds, if the run moved
        (the course's moving fix epochs: without motion the offset is not observable).  An
        offset is kept only when it passes the likelihood-ratio test against none
        (:func:`navcore.filters.time_offset_search.significant`).  Returns what the kept
        run's ``rerun()`` (or ``first``) returned; :attr:`time_offset` is its offset."""
        start = self._started()
        self.clock = start.clock_inputs.estimate()
        self.fits = {0.0: start.fit.mean()}
        best = [0.0, self.fits[0.0], start, first]

        def fit_at(offset):
            self.time_offset, self.recordings = offset, []
            returned = rerun()
            run = self._started()
            fit = self.fits[offset] = run.fit.mean()
            if fit < best[1]:
                best[:] = [offset, fit, run, returned]
            return fit

        def kept():
            return time_offset_search.significant(self.fits[0.0], best[1], start.fit.n)

        if self.clock.applies(start.clock_inputs.imu_interval()):
            fit_at(float(self.clock.tau))
        if self.search is not None and not kept():
            if self.clock.epochs >= imu_time_offset.MIN_EPOCHS:
                self.searched = True
                time_offset_search.search(fit_at, self.fits, self.search)
        elif self.search is not None and self.search.around_start > 0:
            self.searched = True
            time_offset_search.refine(fit_at, best[0], self.fits, self.search)
        if not kept():
            best = [0.0, self.fits[0.0], start, first]
        self.time_offset, self.recordings = best[0], [best[2]]
        return best[3]

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
