"""The master's exchange (orchestrator.cosim.exchange) with recording stand-in components and
a counting clock, against the rules of orchestrator.cosim.master's docstring written out by
hand: the step order and the delayed connections of rules 3 and 4, the transfer periods
(lcm of the decimations), the call sequences of Gauss-Seidel (rules 3 and 5) and Jacobi
(rules 3J and 5J, libcosim's fixed-step algorithm) and the timing sums of rule 7."""
from __future__ import annotations

import numpy as np
import pytest

from orchestrator.cosim import exchange
from orchestrator.cosim.exchange import (GaussSeidel, Jacobi, Slot, Timing, exchange_for,
                                         slots_for, step_order)


# ----------------------------------------------------------------------------------------
# rules 3 and 4: order and delayed connections
# ----------------------------------------------------------------------------------------
def test_order_is_topological_with_ties_by_declaration():
    assert step_order(3, []) == ([0, 1, 2], [])
    assert step_order(3, [(2, 1, "c21"), (1, 0, "c10")]) == ([2, 1, 0], [])
    # 2 feeds 0; 1 is free: 1 is declared before 2 but 0 waits for 2
    assert step_order(3, [(2, 0, "c20")]) == ([1, 2, 0], [])


def test_a_self_connection_is_always_delayed():
    assert step_order(2, [(0, 0, "self"), (0, 1, "c01")]) == ([0, 1], ["self"])
    # ... and holds nothing back: a component fed only by itself keeps its place
    assert step_order(2, [(0, 0, "self")]) == ([0, 1], ["self"])


def test_a_two_cycle_is_cut_at_its_earliest_declared_component():
    assert step_order(2, [(0, 1, "c01"), (1, 0, "c10")]) == ([0, 1], ["c10"])
    # a component outside the cycle goes first; the cycle {1, 2} is cut at 1
    assert step_order(3, [(0, 1, "c01"), (1, 2, "c12"), (2, 1, "c21")]) == ([0, 1, 2],
                                                                          ["c21"])


def test_only_inputs_from_the_victim_s_own_cycle_are_delayed():
    """Cycles {0, 1} and {2, 3}, with 2 -> 0 between them.  Nothing is ready: 0 is the
    earliest on a cycle, only 1 -> 0 is delayed (2 -> 0 is not in its strongly connected
    component); 0 still waits for 2, so the next cut is at 2 (3 -> 2); then 2, 0, and of the
    ready 1 and 3 the earlier-declared 1."""
    connections = [(0, 1, "c01"), (1, 0, "c10"), (2, 0, "c20"), (2, 3, "c23"), (3, 2, "c32")]
    assert step_order(4, connections) == ([2, 0, 1, 3], ["c10", "c32"])


def test_a_component_waiting_on_a_cycle_is_not_cut():
    """1 is not on the cycle {0, 2} but waits for it; the cut is at 0 (2 -> 0)."""
    connections = [(0, 2, "c02"), (2, 0, "c20"), (2, 1, "c21")]
    assert step_order(3, connections) == ([0, 2, 1], ["c20"])


# ----------------------------------------------------------------------------------------
# stand-ins
# ----------------------------------------------------------------------------------------
class StandIn:
    """An instance that logs every call; its one Real output is the end time of its last
    step (0 before any), written into the master's signal vector when read."""

    def __init__(self, name, log, vectors, out_index, real_inputs=()):
        self.name, self.log, self.vectors, self.out_index = name, log, vectors, out_index
        self.input_names = {"Real": tuple(real_inputs), "Integer": (), "Boolean": ()}
        self.real_in = np.zeros(len(real_inputs))
        self.int_in = np.zeros(0, dtype=np.int32)
        self.bool_in = np.zeros(0, dtype=np.int32)
        self.value = 0.0

    def enter_initialization(self, start, stop):
        self.log.append(("enter", self.name, start, stop))

    def exit_initialization(self):
        self.log.append(("exit", self.name))

    def set_inputs(self):
        self.log.append(("set", self.name, tuple(self.real_in.tolist())))

    def do_step(self, t, dt):
        self.log.append(("step", self.name, t, dt))
        self.value = t + dt

    def get_outputs(self):
        self.log.append(("get", self.name))
        self.vectors["Real"][self.out_index] = self.value


class CountingClock:
    """perf_counter_ns that advances by 1 ns per call."""

    def __init__(self):
        self.now = 0

    def perf_counter_ns(self):
        self.now += 1
        return self.now


def _vectors(n_real):
    return {"Real": np.zeros(n_real), "Integer": np.zeros(0, dtype=np.int32),
            "Boolean": np.zeros(0, dtype=np.int32)}


def _sink_and_source(log, vectors):
    """'sink' (declared first, every step) reads 'src' (every 2 steps): src runs first."""
    sink = StandIn("sink", log, vectors, 0, real_inputs=["u"])
    src = StandIn("src", log, vectors, 1)
    position = {("sink", "y"): ("Real", 0), ("src", "y"): ("Real", 1)}
    source_of = {"sink": {"u": ("src", "y")}, "src": {}}
    return slots_for(["sink", "src"], {"sink": 1, "src": 2}, [sink, src], position, source_of)


START, H = 10.0, 0.5


def test_slots_carry_sources_and_lcm_transfer_periods():
    log, vectors = [], _vectors(3)
    a = StandIn("a", log, vectors, 0, real_inputs=["from_b", "from_c"])
    b = StandIn("b", log, vectors, 1, real_inputs=["from_a"])
    c = StandIn("c", log, vectors, 2)
    position = {("a", "y"): ("Real", 0), ("b", "y"): ("Real", 1), ("c", "y"): ("Real", 2)}
    source_of = {"a": {"from_b": ("b", "y"), "from_c": ("c", "y")},
                 "b": {"from_a": ("a", "y")}, "c": {}}
    sa, sb, sc = slots_for(["a", "b", "c"], {"a": 2, "b": 3, "c": 1}, [a, b, c], position,
                           source_of)
    assert (sa.index, sa.name, sa.n, sb.n, sc.n) == (0, "a", 2, 3, 1)
    assert sa.sources["Real"].tolist() == [1, 2] and sb.sources["Real"].tolist() == [0]
    assert sa.periods["Real"].tolist() == [6, 2] and sb.periods["Real"].tolist() == [6]
    assert sa.uniform == {"Real": 0} and sb.uniform == {"Real": 6}
    assert sc.sources == {} and sc.uniform == {}          # types without inputs are dropped


def test_inputs_are_copied_when_their_transfer_period_divides_the_counter():
    log, vectors = [], _vectors(3)
    vectors["Real"][:] = [7.0, 8.0, 9.0]
    inst = StandIn("a", log, vectors, 0, real_inputs=["p", "q"])
    mixed = Slot(0, "a", 1, inst, {"Real": np.array([2, 1], dtype=np.intp)},
                 {"Real": np.array([3, 2])})
    mixed.copy_inputs(vectors, 2)
    assert inst.real_in.tolist() == [0.0, 8.0]             # only q's period 2 divides 2
    mixed.copy_inputs(vectors, 3)
    assert inst.real_in.tolist() == [9.0, 8.0]
    inst.real_in[:] = 0.0
    uniform = Slot(0, "a", 1, inst, {"Real": np.array([2, 1], dtype=np.intp)},
                   {"Real": np.array([2, 2])})
    uniform.copy_inputs(vectors, 3)
    assert inst.real_in.tolist() == [0.0, 0.0]
    uniform.copy_inputs(vectors, 4)
    assert inst.real_in.tolist() == [9.0, 8.0]
    inst.real_in[:] = 0.0
    uniform.copy_inputs(vectors)                           # no counter: every input
    assert inst.real_in.tolist() == [9.0, 8.0]


def test_integer_and_boolean_inputs_go_to_their_own_buffers():
    vectors = {"Real": np.array([1.5]), "Integer": np.array([4, 5], dtype=np.int32),
               "Boolean": np.array([1], dtype=np.int32)}
    inst = StandIn("a", [], vectors, 0, real_inputs=["r"])
    inst.int_in = np.zeros(2, dtype=np.int32)
    inst.bool_in = np.zeros(1, dtype=np.int32)
    slot = Slot(0, "a", 1, inst, {"Real": np.array([0], dtype=np.intp),
                                  "Integer": np.array([1, 0], dtype=np.intp),
                                  "Boolean": np.array([0], dtype=np.intp)},
                {"Real": np.array([1]), "Integer": np.array([1, 1]), "Boolean": np.array([1])})
    slot.copy_inputs(vectors, 1)
    assert (inst.real_in.tolist(), inst.int_in.tolist(), inst.bool_in.tolist()) == (
        [1.5], [5, 4], [1])


# ----------------------------------------------------------------------------------------
# Gauss-Seidel (rules 3 and 5) and Jacobi (rules 3J and 5J)
# ----------------------------------------------------------------------------------------
def _run(algorithm, n_steps, monkeypatch):
    monkeypatch.setattr(exchange, "_time", CountingClock())
    log, vectors = [], _vectors(2)
    slots = _sink_and_source(log, vectors)
    order, _ = step_order(2, [(1, 0, "src.y -> sink.u")])
    timing = Timing(2)
    ex = exchange_for(algorithm, slots, order, vectors, START, H, n_steps, timing)
    ex.initialize(START, START + n_steps * H)
    init = list(log)
    del log[:]
    for k in range(n_steps):
        ex.step(k)
    return ex, init, log, timing


def test_gauss_seidel_initializes_in_order_and_steps_due_components_on_latest_outputs(
        monkeypatch):
    ex, init, steps, timing = _run("gauss-seidel", 4, monkeypatch)
    assert isinstance(ex, GaussSeidel)
    assert init == [("enter", "sink", 10.0, 12.0), ("enter", "src", 10.0, 12.0),
                    ("set", "src", ()), ("get", "src"), ("set", "sink", (0.0,)),
                    ("get", "sink"), ("exit", "src"), ("exit", "sink"),
                    ("get", "src"), ("get", "sink")]
    # src (every 2 steps) is due at the end of macro steps 1 and 3, over [t_{k+1} - 2h,
    # t_{k+1}]; sink, after it, sees its output at t_{k+1}
    assert steps == [
        ("set", "sink", (0.0,)), ("step", "sink", 10.0, 0.5), ("get", "sink"),
        ("set", "src", ()), ("step", "src", 10.0, 1.0), ("get", "src"),
        ("set", "sink", (11.0,)), ("step", "sink", 10.5, 0.5), ("get", "sink"),
        ("set", "sink", (11.0,)), ("step", "sink", 11.0, 0.5), ("get", "sink"),
        ("set", "src", ()), ("step", "src", 11.0, 1.0), ("get", "src"),
        ("set", "sink", (12.0,)), ("step", "sink", 11.5, 0.5), ("get", "sink")]
    # a counting clock: 1 ns around do_step, 3 ns for copy/set/step/get, per call
    assert (timing.calls, timing.do_ns, timing.all_ns) == ([4, 2], [4, 2], [12, 6])


JACOBI_INIT = [("enter", "sink", 10.0, 12.0), ("get", "sink"),
               ("enter", "src", 10.0, 12.0), ("get", "src"),
               ("get", "sink"), ("get", "src"),                          # iteration 1
               ("set", "sink", (0.0,)), ("get", "sink"), ("set", "src", ()), ("get", "src"),
               ("set", "sink", (0.0,)), ("exit", "sink"), ("get", "sink"),
               ("set", "src", ()), ("exit", "src"), ("get", "src")]


def test_jacobi_steps_from_window_starts_and_transfers_at_the_lcm_period(monkeypatch):
    ex, init, steps, timing = _run("jacobi", 4, monkeypatch)
    assert isinstance(ex, Jacobi)
    assert init == JACOBI_INIT
    # src's window [10, 11] starts at k = 0 and is read at its end (c = 2); the transfer
    # period is lcm(1, 2) = 2, so sink sees 11.0 from k = 2 and 12.0 after c = 4
    assert steps == [
        ("set", "sink", (0.0,)), ("step", "sink", 10.0, 0.5),
        ("set", "src", ()), ("step", "src", 10.0, 1.0), ("get", "sink"),
        ("set", "sink", (0.0,)), ("step", "sink", 10.5, 0.5), ("get", "sink"), ("get", "src"),
        ("set", "sink", (11.0,)), ("step", "sink", 11.0, 0.5),
        ("set", "src", ()), ("step", "src", 11.0, 1.0), ("get", "sink"),
        ("set", "sink", (11.0,)), ("step", "sink", 11.5, 0.5), ("get", "sink"), ("get", "src")]
    assert ex.slots[0].instance.real_in.tolist() == [12.0]
    # 1 ns around do_step; set + step (2 ns) plus the read at the window's end (1 ns)
    assert (timing.calls, timing.do_ns, timing.all_ns) == ([4, 2], [4, 2], [12, 6])


def test_jacobi_does_not_start_a_window_ending_after_the_stop(monkeypatch):
    _, _, steps, timing = _run("jacobi", 3, monkeypatch)
    assert [e for e in steps if e[0] == "step" and e[1] == "src"] == [
        ("step", "src", 10.0, 1.0)]
    assert timing.calls == [3, 1]


def test_jacobi_transfers_only_when_the_lcm_of_both_decimations_divides_the_counter():
    """src every 2 steps feeds dest every 3: the connection transfers at c = 6 only
    (lcm(2, 3)), so dest's window from k = 3 still runs on the initial value, although src's
    output of its first window (11.0) was read at c = 2; at c = 6 dest receives 13.0."""
    log, vectors = [], _vectors(2)
    dest = StandIn("dest", log, vectors, 0, real_inputs=["u"])
    src = StandIn("src", log, vectors, 1)
    slots = slots_for(["dest", "src"], {"dest": 3, "src": 2}, [dest, src],
                      {("dest", "y"): ("Real", 0), ("src", "y"): ("Real", 1)},
                      {"dest": {"u": ("src", "y")}, "src": {}})
    ex = Jacobi(slots, vectors, START, H, 6, Timing(2))
    ex.initialize(START, START + 6 * H)
    del log[:]
    for k in range(6):
        ex.step(k)
    assert [e for e in log if e[1] == "dest" and e[0] in ("set", "step")] == [
        ("set", "dest", (0.0,)), ("step", "dest", 10.0, 1.5),
        ("set", "dest", (0.0,)), ("step", "dest", 11.5, 1.5)]
    assert dest.real_in.tolist() == [13.0]
