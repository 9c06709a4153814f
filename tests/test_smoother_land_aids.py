"""The smoother over a Kf run with the land aids (navcore.components.smoothing): ZUPT, ZARU
and the NHC are Kalman updates of the same error state (KfEngine.aid_update), so the
recording must hold each of them as it holds a fix's update.

On the simulated car of tests/land_vehicles.py: the smoothed solution with the NHC far below
the forward filter with the NHC in the outage while driving; and, stopped inside that
outage, the smoothed solution's last epoch equal to the forward filter's (nominal state and
biases bit for bit, sigmas to rounding), which fails when the aids' updates are hidden from
the recording (checked here too, so the check is seen to bite).
"""
from __future__ import annotations

import numpy as np
import pytest

from direct_replay import FilterRun, run_filter
from land_vehicles import CAR, CAR_OUTAGES, DETECTOR, FILTER_START, outage_errors, vehicle_sensors
from navcore.components import smoothing
from navcore.filters.ins_gnss_kf import KfEngine

ALL_AIDS = {"zupt": True, "zaru": True, "nhc": True}
SOLUTION_OUTPUTS = dict(zip(("lat", "lon", "h"), ("nav_lat", "nav_lon", "nav_h")))


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    return vehicle_sensors(CAR, CAR_OUTAGES, tmp_path_factory.mktemp("car"))[0]


def _smoothed_run(sensors, stop_row=None, **aids):
    """(forward run, smoothed solution) of the recording Kf over ``sensors``."""
    session = smoothing.SmoothingSession("Kf")
    forward = run_filter(sensors, session.component_class,
                         overrides={**FILTER_START, **DETECTOR, **aids}, stop_row=stop_row)
    return forward, session.solution()


def _on_rows(forward, solution):
    """The smoothed solution as a run over the forward run's rows (its epochs)."""
    t = forward.sensors.time[forward.rows]
    k = np.searchsorted(solution["time"], t - 1e-9)
    assert np.allclose(solution["time"][k], t, rtol=0, atol=1e-9)
    return FilterRun(forward.sensors, "Kf-smoothed", forward.rows,
                     {out: solution[key][k] for key, out in SOLUTION_OUTPUTS.items()})


def test_smoothed_with_the_nhc_is_far_below_the_forward_filter_with_it(car):
    """The 30 s outage while the car drives: measured forward 2.01 m RMS / 4.51 m max,
    smoothed 0.33 / 0.40 m (0.37 / 0.57 m when the recording missed the NHC's updates)."""
    forward, solution = _smoothed_run(car, nhc=True)
    fwd = outage_errors(forward, CAR_OUTAGES)[1]
    smoothed = outage_errors(_on_rows(forward, solution), CAR_OUTAGES)[1]
    assert fwd[0] > 1.0
    assert smoothed[0] < 0.25 * fwd[0] and smoothed[2] < 0.15 * fwd[2], (smoothed, fwd)


def _last_epoch_mismatch(forward, solution):
    """The smoothed solution's last epoch against the forward engine's state there:
    (largest difference of the nominal state and biases, largest relative difference of
    the sigmas)."""
    engine = forward.component.engine
    assert solution["time"][-1] == forward.component.nav_time
    smoothed = [solution[k][-1] for k in ("lat", "lon", "h", "vn", "ve", "vd", "roll",
                                          "pitch", "yaw")]
    state = np.concatenate([np.subtract(smoothed, engine.nav.solution()),
                            solution["gyro_bias"][-1] - engine.gyro_bias,
                            solution["accel_bias"][-1] - engine.accel_bias])
    sigma = np.sqrt(engine.covariance_diagonal())
    return np.max(np.abs(state)), np.max(np.abs(solution["std"][-1] / sigma - 1.0))


def _hide_aid_updates(monkeypatch):
    """The recording engine's aid updates applied without its recorder seeing them."""
    engine_class = smoothing.SmoothingSession("Kf").component_class.engine_class

    def unrecorded(self, H, z, R):
        recorder, self.recorder = self.recorder, None
        try:
            KfEngine.aid_update(self, H, z, R)
        finally:
            self.recorder = recorder

    monkeypatch.setattr(engine_class, "aid_update", unrecorded)


def test_the_recording_holds_every_aid_update(car, monkeypatch):
    """Stopped inside the outage while driving, 0.04 s after an aid epoch (the stretch from
    it rebuilt by the smoother): the smoothed last epoch is the forward filter's, and one
    update is recorded per aid epoch; with the aids' updates hidden from the recording the
    same check fails by far."""
    stop = int(round(160.04 / car.h))
    forward, solution = _smoothed_run(car, stop_row=stop, **ALL_AIDS)
    state, sigma = _last_epoch_mismatch(forward, solution)
    assert state == 0.0 and sigma < 1e-9, (state, sigma)
    aids = forward.component.engine.aids
    recorded = forward.component.recording.updates.n - 1          # less the start
    assert aids.n_nhc > 500 and aids.n_zupt > 200
    assert aids.n_nhc + aids.n_zupt <= recorded <= forward.component.engine.n_updates

    _hide_aid_updates(monkeypatch)
    forward, solution = _smoothed_run(car, stop_row=stop, **ALL_AIDS)
    state, sigma = _last_epoch_mismatch(forward, solution)
    assert state > 1e-5 and sigma > 0.5, (state, sigma)
