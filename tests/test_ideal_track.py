"""The shared track of ideal samples (navcore.ins.ideal_track): generators that read it give the
numbers they would compute, bit for bit.

These are self-consistency tests (the generator with the track against the generator without
it): the generator's own numbers are checked against references in test_trajectory.py,
test_strapdown.py and test_pyins_oracle.py.
"""
import math
import threading

import pytest

from conftest import assert_same
from navcore.ins import ideal_track
from navcore.core import state
from navcore.ins.motion_profiles import load_profile
from navcore.ins.trajectory import TrajectoryGenerator


def key_of(profile, dt):
    return ideal_track.track_key(load_profile(profile), dt)


@pytest.fixture(autouse=True)
def fresh_tracks():
    ideal_track.clear()
    yield
    ideal_track.clear()


def fly(gen, n):
    """n samples: (truth dict, dtheta, dvel, rate norm, accel norm) each."""
    out = []
    for _ in range(n):
        s, dtheta, dvel = gen.step()
        out.append((s, dtheta.tolist(), dvel.tolist(), gen.last_rate_norm,
                    gen.last_accel_norm))
    return out


def untracked(monkeypatch, profile, dt, n, prepare=None):
    """The samples computed with no track at all."""
    with monkeypatch.context() as m:
        m.setattr(ideal_track, "find", lambda key: None)
        m.setattr(ideal_track, "register", lambda key, row: None)
        gen = TrajectoryGenerator(profile, dt)
        if prepare is not None:
            prepare(gen)
        return fly(gen, n)


def refuse_to_compute(monkeypatch):
    def compute(self, k):
        raise AssertionError(f"sample {k} computed instead of read from the track")
    monkeypatch.setattr(TrajectoryGenerator, "_compute", compute)


@pytest.mark.parametrize("profile, dt, n", [
    ("uav_maneuver", 0.1, 36_500),     # every segment type of the profile, past its end
    ("turntable_240s", 0.01, 24_000),  # rotations at rest
])
def test_read_samples_equal_computed_ones_self_consistency(monkeypatch, profile, dt, n):
    reference = untracked(monkeypatch, profile, dt, n)
    first = fly(TrajectoryGenerator(profile, dt), n)
    assert ideal_track.find(key_of(profile, dt)) is None    # flown once: nothing recorded
    second = fly(TrajectoryGenerator(profile, dt), n)      # records the track
    assert ideal_track.find(key_of(profile, dt)).n == n + 1
    gen = TrajectoryGenerator(profile, dt)
    with monkeypatch.context() as m:
        refuse_to_compute(m)
        third = fly(gen, n)                                 # reads every sample
    for run in (first, second, third):
        assert_same(run, reference, "samples")
    # the reading generator's state is the computing one's, every field
    with monkeypatch.context() as m:
        m.setattr(ideal_track, "find", lambda key: None)
        computing = TrajectoryGenerator(profile, dt)
        fly(computing, n)
    assert_same(state.capture(gen), state.capture(computing), "state")


def test_state_restored_from_a_reading_generator_continues_exactly(monkeypatch):
    for _ in range(2):
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 3000)
    gen = TrajectoryGenerator("aircraft_500s", 0.01)
    fly(gen, 1500)                                   # read from the track
    tree = state.capture(gen)
    ideal_track.clear()                              # as in another process
    restored = TrajectoryGenerator("aircraft_500s", 0.01)
    state.restore(restored, tree)
    reference = untracked(monkeypatch, "aircraft_500s", 0.01, 3000)
    assert_same(fly(restored, 1500), reference[1500:], "samples")


def test_a_generator_off_the_track_computes(monkeypatch):
    """A state that is not the recorded one (here its latitude one ulp off) is stepped by
    computing, exactly as without the track."""
    for _ in range(2):
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 2000)

    def nudge(g):
        fly(g, 700)
        g.lat = math.nextafter(g.lat, 1.0)
        g._ins.lat = g.lat

    reference = untracked(monkeypatch, "aircraft_500s", 0.01, 600, prepare=nudge)
    gen = TrajectoryGenerator("aircraft_500s", 0.01)
    nudge(gen)
    assert_same(fly(gen, 600), reference, "samples")


def test_a_generator_off_the_track_records_nothing(monkeypatch):
    """An off-track generator at the end of the track does not extend it: the next
    generator still gets the computed samples."""
    for _ in range(2):
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 700)   # the track ends at 700
    gen = TrajectoryGenerator("aircraft_500s", 0.01)
    fly(gen, 700)
    gen.h += 1.0
    gen._ins.h = gen.h
    fly(gen, 100)
    reference = untracked(monkeypatch, "aircraft_500s", 0.01, 800)
    assert_same(fly(TrajectoryGenerator("aircraft_500s", 0.01), 800), reference, "samples")


def test_recording_stops_at_the_sample_limit(monkeypatch):
    monkeypatch.setattr(ideal_track, "MAX_SAMPLES", 500)
    reference = untracked(monkeypatch, "aircraft_500s", 0.01, 1200)
    runs = [fly(TrajectoryGenerator("aircraft_500s", 0.01), 1200) for _ in range(3)]
    assert ideal_track.find(key_of("aircraft_500s", 0.01)).n == 501  # the start and 500 samples
    for run in runs:
        assert_same(run, reference, "samples")


def test_tracks_are_per_profile_and_step(monkeypatch):
    for dt in (0.01, 0.02, 0.01, 0.02):
        fly(TrajectoryGenerator("aircraft_500s", dt), 300)
    keys = [key_of("aircraft_500s", dt) for dt in (0.01, 0.02)]
    assert keys[0] != keys[1]
    assert all(ideal_track.find(k).n == 301 for k in keys)
    reference = untracked(monkeypatch, "aircraft_500s", 0.02, 300)
    assert_same(fly(TrajectoryGenerator("aircraft_500s", 0.02), 300), reference, "samples")


def test_threads_sharing_a_track_get_the_computed_samples(monkeypatch):
    reference = untracked(monkeypatch, "aircraft_500s", 0.01, 4000)
    fly(TrajectoryGenerator("aircraft_500s", 0.01), 10)     # the next one starts the track
    results = [None] * 4

    def worker(i):
        results[i] = fly(TrajectoryGenerator("aircraft_500s", 0.01), 4000)

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert_same(r, reference, "samples")


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="needs fork")
def test_a_forked_child_records_while_a_parent_thread_held_the_lock():
    import multiprocessing

    for _ in range(2):
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 20)
    def child():
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 40)   # records samples 21..40
        assert ideal_track.find(key_of("aircraft_500s", 0.01)).n == 41

    with ideal_track._LOCK:                                    # held at the fork
        proc = multiprocessing.get_context("fork").Process(target=child)
        proc.start()
    proc.join(30)
    if proc.is_alive():    # deadlocked on the parent's lock
        proc.kill()
        proc.join()
    assert proc.exitcode == 0


def test_benchmarks_measure_single_runs(monkeypatch):
    """navfmu bench's runs start no track (each costs what a single run costs), and the
    switch is put back afterwards."""
    import os

    from orchestrator.cli.bench import single_run_costs

    monkeypatch.delenv(ideal_track.SWITCH, raising=False)
    with single_run_costs():
        for _ in range(3):
            fly(TrajectoryGenerator("aircraft_500s", 0.01), 50)
    assert ideal_track.find(key_of("aircraft_500s", 0.01)) is None
    assert ideal_track.SWITCH not in os.environ
    for _ in range(2):
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 50)
    assert ideal_track.find(key_of("aircraft_500s", 0.01)).n == 51
    # a track that exists before is neither read nor extended inside
    track = ideal_track.find(key_of("aircraft_500s", 0.01))
    with single_run_costs(), monkeypatch.context() as m:
        m.setattr(TrajectoryGenerator, "_read", lambda self, k, row: pytest.fail("read"))
        fly(TrajectoryGenerator("aircraft_500s", 0.01), 100)
    assert track.n == 51
