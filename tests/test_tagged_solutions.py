"""Time tags decide which navigation solution GuidedUav's guidance flies on, never call order:
the choice itself (navcore.vehicles.tagged_solutions), the same guided flight under every
delivery and communication step a master may use, a solution tagged after a sample kept back
until its tag, and that pending solution saved and restored with the vehicle."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.components.registry import GuidedUav
from navcore.core import state_format
from navcore.vehicles.tagged_solutions import TaggedSolutions

DT = 0.01                 # the vehicle's sample period (its default)
NAV_EVERY = 10            # the navigation source publishes every 10 samples (0.1 s)
SAMPLES = 4000            # 40 s: the first leg, with the jump at 20 s
PARAMS = {"turbulence_w20": 7.7, "wind_e": 5.0, "seed": 3}
LAT0, LON0 = 0.6998770300497261, 2.069960492865275     # GuidedUav's default route origin
EARTH = 6.378e6           # metres to radians here: any error will do, it is an error
NAMES = sorted(p.name for p in GuidedUav.outputs)


# -- the choice by time tag ------------------------------------------------------------------
def test_the_newest_solution_tagged_at_or_before_the_time_is_due():
    s = TaggedSolutions()
    assert s.due(0.0, DT) is None
    s.receive(0.2, (2.0,))
    s.receive(0.1, (1.0,))               # out of order: kept in tag order
    s.receive(0.3, (3.0,))
    assert s.due(0.0, DT) == (0.1, (1.0,))     # nothing due yet: the earliest stands in
    assert s.pending[0] == (0.1, (1.0,)) and s.current is None
    # within the time tolerance (1e-11 s on a 0.01 s grid) a tag is due, beyond it not
    assert s.due(0.2 - 2e-11, DT) == (0.1, (1.0,))
    assert s.due(0.2 - 5e-12, DT) == (0.2, (2.0,)) and s.pending == [(0.3, (3.0,))]
    s.receive(0.3, (3.5,))               # the same tag again: the later delivery holds
    s.receive(0.05, (9.0,))              # older than the one in use: never the newest due
    assert s.due(0.29, DT) == (0.2, (2.0,))
    assert s.due(0.5, DT) == (0.3, (3.5,)) and s.pending == []
    s.receive(0.3, (4.0,))               # the one in use delivered again
    assert s.due(0.5, DT) == (0.3, (4.0,))


# -- one guided flight, whatever the master ----------------------------------------------------
def _nav_row(out, east_error):
    """A navigation source's solution at the vehicle's output ``out``: its truth, tagged with
    its time, ``east_error`` metres east and 0.05 m/s fast eastwards."""
    lat = out["truth_lat"]
    return {"nav_time": out["truth_time"], "nav_lat": lat,
            "nav_lon": out["truth_lon"] + east_error / (EARTH * math.cos(lat)),
            "nav_h": out["truth_h"], "nav_vn": out["truth_vn"],
            "nav_ve": out["truth_ve"] + 0.05, "nav_vd": out["truth_vd"],
            "nav_yaw": out["truth_yaw"]}


def _error(t):
    """The source's east error at t: drifting 0.2 m/s, jumping 12 m at 20 s (a filter's
    correction at a fix), so a solution used early or late shows in the flight."""
    return 0.2 * t + (12.0 if t >= 20.0 else 0.0)


def _closed_loop(every):
    """GuidedUav guided on a source that publishes every 0.1 s the vehicle's own truth at
    that instant with :func:`_error`, stepped ``every`` samples at a time (a divisor of
    10), each step seeing the source's output at its start (Jacobi): (the solutions
    published, the outputs at every 0.1 s by sample number)."""
    uav = GuidedUav(**PARAMS)
    published = [_nav_row(uav.start(0.0), _error(0.0))]
    uav.initial_inputs(published[0])      # as a master sets them in initialization mode
    h, rows = every * DT, {}
    for j in range(SAMPLES // every):
        out = uav.advance(j * h, h, published[-1])
        end = (j + 1) * every
        if end % NAV_EVERY == 0:
            rows[end] = [out[n] for n in NAMES]
            published.append(_nav_row(out, _error(out["truth_time"])))
    return published, rows


def _replay(published, every, late):
    """GuidedUav guided on the recorded ``published`` solutions, stepped ``every`` samples at
    a time; ``late``: each step sees the source's output at the step's start (Jacobi), else
    at its end (a recording, or a master stepping the source first): the outputs at every
    multiple of both the step and 0.1 s."""
    uav = GuidedUav(**PARAMS)
    uav.start(0.0)
    uav.initial_inputs(published[0])
    h, rows = every * DT, {}
    for j in range(SAMPLES // every):
        seen = (j if late else j + 1) * every // NAV_EVERY     # the source's latest epoch
        out = uav.advance(j * h, h, published[seen])
        end = (j + 1) * every
        if end % NAV_EVERY == 0:
            rows[end] = [out[n] for n in NAMES]
    return rows


@pytest.fixture(scope="module")
def loop():
    return _closed_loop(1)


def _same(reference, rows):
    """Whether ``rows`` equal ``reference`` bit for bit where both have a row (at least
    every 0.3 s of the 40 s)."""
    keys = sorted(set(reference) & set(rows))
    assert len(keys) >= SAMPLES // (3 * NAV_EVERY)
    return np.array_equal(np.array([reference[k] for k in keys]),
                          np.array([rows[k] for k in keys]))


@pytest.mark.parametrize("every", [2, 5, 10])
def test_the_closed_loop_flies_the_same_at_every_step_size(loop, every):
    """Steps of 1 to 10 samples up to the source's period: the source's solutions reach the
    vehicle at the same tags, so the flights agree bit for bit."""
    assert _same(loop[1], _closed_loop(every)[1])


@pytest.mark.parametrize("every, late", [(1, False), (3, False), (5, True), (5, False),
                                         (10, True), (10, False)])
def test_a_recorded_solution_flies_the_loop_at_every_step_and_exchange(loop, every, late):
    """The loop's solutions replayed (as verify replays a recording) with every step size up
    to the source's period, seen at each step's start or at its end: each sample flies on
    the newest solution tagged at or before it, extrapolated by the same age, so the replay
    is the closed loop's flight bit for bit, whichever step delivers the solution (the
    tolerance is 0: nothing but the time tags enters the choice).  Before the tags decided,
    a solution seen at the step's end was flown from the step's start on, early.  (Steps of
    3 samples seeing the source at their start are left out: a solution published inside
    such a step reaches the vehicle at the next one, after the samples that needed it.)"""
    published, reference = loop
    assert _same(reference, _replay(published, every, late))
    assert reference[SAMPLES][NAMES.index("waypoints_reached")] == 0
    assert abs(reference[SAMPLES][NAMES.index("cross_track")]) < 20.0    # it flew the leg


# -- a solution tagged after the sample waits ------------------------------------------------
def _solution(t, east=0.0):
    """A solution tagged ``t`` flying north along the first leg, ``east`` metres off it."""
    return {"nav_time": t, "nav_lat": LAT0 + 25.0 * t / EARTH,
            "nav_lon": LON0 + east / (EARTH * math.cos(LAT0)), "nav_h": 150.0,
            "nav_vn": 25.0, "nav_ve": 0.0, "nav_vd": 0.0, "nav_yaw": 0.0}


A, B = _solution(0.0), _solution(0.05, east=40.0)


def _run(deliveries, uav=None, first=0):
    """The outputs after each step of DT from ``first`` on, delivering ``deliveries[j]``."""
    if uav is None:
        uav = GuidedUav(**PARAMS)
        uav.start(0.0)
    return [dict(uav.advance((first + j) * DT, DT, d)) for j, d in enumerate(deliveries)]


def test_a_solution_tagged_after_the_sample_is_used_from_its_tag_on():
    """B (tagged 0.05 s) delivered from the second step on, ahead of its time, against B
    delivered from its time on and against A alone: the samples before 0.05 s fly on A,
    the one at 0.05 s on B."""
    ahead = _run([A] + [B] * 9)
    on_time = _run([A] * 5 + [B] * 5)
    a_only = _run([A] * 10)
    assert ahead == on_time
    assert ahead[:5] == a_only[:5]                  # outputs up to 0.05 s: flown on A
    assert ahead[5] != a_only[5]                    # the sample at 0.05 s flies on B


def test_a_pending_solution_is_saved_and_restored_with_the_vehicle():
    """The state after the second step holds B pending; a vehicle restored from it (through
    the FMU state's bytes) and fed A alone afterwards still turns to B at 0.05 s, as the
    original does; one that never received B does not."""
    uav = GuidedUav(**PARAMS)
    uav.start(0.0)
    _run([A, B], uav)
    blob = state_format.encode(uav.get_state(), ("GuidedUav", "test"))
    restored = GuidedUav.from_state(state_format.decode(blob, ("GuidedUav", "test")))
    assert [tag for tag, _ in restored.solutions.pending] == [0.05]
    original = _run([A] * 8, uav, first=2)
    again = _run([A] * 8, restored, first=2)
    assert again == original == _run([A] + [B] * 9)[2:]
    assert again != _run([A] * 10)[2:]
