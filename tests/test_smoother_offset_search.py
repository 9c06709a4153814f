"""The likelihood search of the IMU's time offset (navcore.filters.time_offset_search,
SmoothingSession.synchronize): on a simulated car that drives straight (speeding up and
braking, no turn, so the course-rate estimate has none), the offset whose run fits the
fixes best is the lag put into the IMU's stamps, and the car on time gives about 0.
"""
from __future__ import annotations

import dataclasses

import pytest

from direct_replay import run_filter
from navcore.components import smoothing
from navcore.filters import time_offset_search
from navcore.filters.time_offset_search import OffsetSearch
from test_smoother_time_offset import FILTER, LAG_ROWS, on_time_and_late

#: a straight drive: speeds changed by 1-2 m/s^2, no turn
STRAIGHT_CAR = (("stop", 5.0), ("speed", 5.0, 10.0), ("speed", 3.0, 4.0), ("speed", 3.0, 9.0),
                ("speed", 5.0, 0.0), ("stop", 2.0))
#: the test's budget: at most 4 grid runs and 4 refinements
SEARCH = OffsetSearch(bound=0.5, step=0.25, tolerance=0.02, refinements=4)


@pytest.fixture(scope="module")
def straight_car(tmp_path_factory):
    """(on time, IMU stamped 0.2 s late): the straight car's sensor records, no outage."""
    return on_time_and_late(STRAIGHT_CAR, (), tmp_path_factory.mktemp("straight_car"))


def _synchronized(sensors):
    session = smoothing.SmoothingSession("Kf", search=SEARCH)
    run_filter(sensors, session.component_class, overrides=FILTER)
    session.synchronize(lambda: run_filter(sensors, session.component_class, overrides=FILTER))
    return session


def test_the_search_finds_the_lag_without_turns(straight_car):
    """Measured: stamped 0.2 s late, 0.201 s (mean negative log-likelihood per fix 17.8
    on the IMU's clock, -15.7 at 0.201 s; 8 runs besides the first); on time, 0.000 s
    (-15.7; 7 runs)."""
    on_time, late = straight_car
    session = _synchronized(late)
    assert "no turns" in session.clock.reason
    assert session.searched and len(session.fits) <= 1 + 4 + 4
    assert session.time_offset == pytest.approx(LAG_ROWS * late.h, abs=0.03), session.fits
    assert session.fits[session.time_offset] < session.fits[0.0] - 1.0, session.fits
    session = _synchronized(on_time)
    assert abs(session.time_offset) <= 0.03, session.fits


def test_the_search_reuses_what_ran_and_keeps_its_budget():
    """A cost with two dips (the deeper at 0.137 s, a shallow one at -0.35 s, where a
    refinement started from -0.5 would stop): the grid finds the deeper one and Brent
    refines it to the tolerance; the known offsets are not run again.  Refined from an
    estimate (0.12 s, +/-0.05 s): Brent only, inside that interval."""
    ran = []

    def cost(tau):
        ran.append(tau)
        return min((tau - 0.137) ** 2, 0.02 + 2.0 * (tau + 0.35) ** 2)

    best, costs = time_offset_search.search(cost, {0.0: cost(0.0), 0.61: 1.0}, SEARCH)
    assert best == pytest.approx(0.137, abs=SEARCH.tolerance)
    assert len(ran) <= 1 + 4 + SEARCH.refinements and len(set(ran)) == len(ran)
    assert ran.count(0.0) == 1 and 0.61 in costs and 0.61 not in ran
    ran.clear()
    near = dataclasses.replace(SEARCH, around_start=0.05)
    best, costs = time_offset_search.refine(cost, 0.12, {0.12: cost(0.12)}, near)
    assert best == pytest.approx(0.137, abs=SEARCH.tolerance)
    assert len(ran) <= 1 + SEARCH.refinements and all(abs(t - 0.12) <= 0.05 for t in ran)


def test_an_offset_is_taken_only_beyond_chance():
    """The likelihood-ratio test: 2 N dJ against chi2(1) at 1 % (6.63)."""
    assert time_offset_search.significant(-7.0, -7.1, 100)        # 20
    assert not time_offset_search.significant(-7.0, -7.03, 100)   # 6
    assert not time_offset_search.significant(-7.0, -6.0, 100)
