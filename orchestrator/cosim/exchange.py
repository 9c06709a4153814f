"""The master's two exchange algorithms: Gauss-Seidel (the default) and Jacobi (libcosim's).

Both move values the same way: every component's latest outputs live in one signal vector per
FMI type (a slice per component, written by its ``get_outputs``), and a component's inputs
are copied out of those vectors into its input buffers by index arrays (one ``take`` per
type), then sent with one batched set per type.  The algorithms differ only in *when* the
inputs are copied and when a component steps; the rules are rule 3 (Gauss-Seidel) and rule 3J
(Jacobi) of :mod:`orchestrator.cosim.master`'s docstring, and the Jacobi rules are those of
libcosim's ``fixed_step_algorithm`` (``src/cosim/algorithm/fixed_step_algorithm.cpp``).
"""
from __future__ import annotations

import math
import time as _time
from typing import Any, Dict, Iterable, List, Sequence, Tuple

import numpy as np

from .backends import NUMERIC_TYPES, Instance

#: the names accepted for ``Simulation(algorithm=...)`` and ``navfmu run --algorithm``
ALGORITHMS = ("gauss-seidel", "jacobi")


# ----------------------------------------------------------------------------------------
# Ordering
# ----------------------------------------------------------------------------------------
def _reachable(n: int, edges: Iterable[Tuple[int, int]]) -> List[set]:
    succ: List[set] = [set() for _ in range(n)]
    for a, b in edges:
        succ[a].add(b)
    reach = []
    for s in range(n):
        seen, stack = set(), [s]
        while stack:
            for nxt in succ[stack.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    stack.append(nxt)
        reach.append(seen)
    return reach


def step_order(n_components: int, connections: Sequence[Tuple[int, int, Any]]
               ) -> Tuple[List[int], List[Any]]:
    """Order components 0..n-1 (declaration order) by the rules 3 and 4 of
    :mod:`orchestrator.cosim.master`.

    ``connections`` are ``(source, destination, key)``; returns the order and the keys of the
    delayed connections (in the order given).
    """
    delayed = {id(c): c for c in connections if c[0] == c[1]}
    active = [c for c in connections if c[0] != c[1]]
    remaining = list(range(n_components))
    order: List[int] = []
    while remaining:
        rem = set(remaining)
        blocked = {b for a, b, _ in active if a in rem and b in rem}
        ready = [i for i in remaining if i not in blocked]
        if ready:
            order.append(ready[0])
            remaining.remove(ready[0])
            continue
        # no component is ready: break the cycle at its earliest-declared component
        sub = [(a, b) for a, b, _ in active if a in rem and b in rem]
        reach = _reachable(n_components, sub)
        on_cycle = [i for i in remaining if i in reach[i]]
        victim = on_cycle[0]
        same_scc = {j for j in remaining if j in reach[victim] and victim in reach[j]}
        for c in list(active):
            if c[1] == victim and c[0] in same_scc:
                delayed[id(c)] = c
                active.remove(c)
    return order, [c[2] for c in connections if id(c) in delayed]


class Slot:
    """One component as the exchange sees it: its instance, decimation and input sources.

    ``sources[t]`` holds, per input of type ``t`` (in the instance's input order), the index
    of the driving output in the signal vector of type ``t``; ``periods[t]`` the libcosim
    transfer period of that connection (lcm of the source's and this component's
    decimation), used by Jacobi only.
    """

    __slots__ = ("index", "name", "n", "instance", "sources", "periods", "uniform", "buffers")

    def __init__(self, index: int, name: str, n: int, instance: Instance,
                 sources: Dict[str, np.ndarray], periods: Dict[str, np.ndarray]):
        self.index = index
        self.name = name
        self.n = n
        self.instance = instance
        self.sources = {t: a for t, a in sources.items() if len(a)}
        self.periods = periods
        #: per type: the transfer period shared by all its inputs, or 0 if they differ
        self.uniform = {t: int(periods[t][0]) if len(set(periods[t].tolist())) == 1 else 0
                        for t in self.sources}
        self.buffers = dict(zip(NUMERIC_TYPES,
                                (instance.real_in, instance.int_in, instance.bool_in)))

    def copy_inputs(self, vectors, counter=None) -> None:
        """Copy this component's inputs from the signal vectors into its input buffers:
        every input (``counter`` None), or only those whose transfer period divides
        ``counter`` (libcosim's transfer after macro step ``counter - 1``).  The signal
        vectors and the buffers may carry a leading run axis (a batch of runs,
        :mod:`orchestrator.cosim.batch`): values move along the last axis."""
        for t, src in self.sources.items():
            if counter is None:
                vectors[t].take(src, axis=-1, out=self.buffers[t], mode="clip")
                continue
            period = self.uniform[t]
            if period:
                if counter % period == 0:
                    vectors[t].take(src, axis=-1, out=self.buffers[t], mode="clip")
                continue
            due = (counter % self.periods[t]) == 0
            self.buffers[t][..., due] = vectors[t][..., src[due]]


class Timing:
    """Per component: summed ``do_step`` time, summed exchange time, number of steps."""

    def __init__(self, n: int):
        self.do_ns = [0] * n
        self.all_ns = [0] * n
        self.calls = [0] * n


def slots_for(names: Sequence[str], decimation: Dict[str, int], instances: Sequence[Instance],
              position: Dict[Tuple[str, str], Tuple[str, int]],
              source_of: Dict[str, Dict[str, Tuple[str, str]]]) -> List[Slot]:
    """Build the slots of prepared ``instances`` (declaration order)."""
    slots = []
    for i, (name, inst) in enumerate(zip(names, instances)):
        sources, periods = {}, {}
        for t in NUMERIC_TYPES:
            inputs = inst.input_names[t]
            sources[t] = np.array([position[source_of[name][v]][1] for v in inputs],
                                  dtype=np.intp)
            periods[t] = np.array([math.lcm(decimation[source_of[name][v][0]], decimation[name])
                                   for v in inputs], dtype=np.int64)
        slots.append(Slot(i, name, decimation[name], inst, sources, periods))
    return slots


class GaussSeidel:
    """Rule 3: due components step in ``order``, each on its sources' latest outputs."""

    def __init__(self, slots: Sequence[Slot], order: Sequence[int], vectors, start: float,
                 h: float, n_steps: int, timing: Timing):
        self.declared = list(slots)
        self.slots = [slots[i] for i in order]
        self.vectors = vectors
        self.start, self.h, self.n_steps = start, h, n_steps
        self.timing = timing

    def initialize(self, start: float, stop: float) -> None:
        """Rule 5: one exchange in order inside initialization mode, then exit in order."""
        for s in self.declared:
            s.instance.enter_initialization(start, stop)
        for s in self.slots:
            s.copy_inputs(self.vectors)
            s.instance.set_inputs()
            s.instance.get_outputs()
        for s in self.slots:
            s.instance.exit_initialization()
        for s in self.slots:
            s.instance.get_outputs()

    def step(self, k: int) -> None:
        """Macro step ``k``: components due at its end step over their window ending there."""
        kp1 = k + 1
        clock = _time.perf_counter_ns
        timing, vectors, start, h = self.timing, self.vectors, self.start, self.h
        for s in self.slots:
            n = s.n
            if n != 1 and kp1 % n:
                continue
            inst = s.instance
            t0 = clock()
            s.copy_inputs(vectors)
            inst.set_inputs()
            t1 = clock()
            inst.do_step(start + (kp1 - n) * h, n * h)
            t2 = clock()
            inst.get_outputs()
            t3 = clock()
            timing.do_ns[s.index] += t2 - t1
            timing.all_ns[s.index] += t3 - t0
            timing.calls[s.index] += 1


class Jacobi:
    """Rule 3J (libcosim's fixed-step algorithm): every due component steps from the start
    of its window on the inputs transferred so far; outputs are read, and transferred along
    a connection, when the source's step ends (and the transfer period divides the count)."""

    def __init__(self, slots: Sequence[Slot], vectors, start: float, h: float, n_steps: int,
                 timing: Timing):
        self.slots = list(slots)
        self.vectors = vectors
        self.start, self.h, self.n_steps = start, h, n_steps
        self.timing = timing
        self._pending_ns = [0] * len(self.slots)

    def initialize(self, start: float, stop: float) -> None:
        """libcosim's ``initialize``: enter initialization and read the outputs; then as many
        iterations as there are components of (set the transferred inputs, read the
        outputs; transfer every connection); then set, exit initialization, read, transfer."""
        vectors = self.vectors
        for s in self.slots:
            s.instance.enter_initialization(start, stop)
            s.instance.get_outputs()
        for iteration in range(len(self.slots)):
            for s in self.slots:
                if iteration:
                    s.instance.set_inputs()
                s.instance.get_outputs()
            for s in self.slots:
                s.copy_inputs(vectors)
        for s in self.slots:
            s.instance.set_inputs()
            s.instance.exit_initialization()
            s.instance.get_outputs()
        for s in self.slots:
            s.copy_inputs(vectors)

    def step(self, k: int) -> None:
        """Macro step ``k``: start the due windows, read the outputs of the windows that end,
        transfer along the connections whose period divides ``k + 1``."""
        kp1 = k + 1
        clock = _time.perf_counter_ns
        timing, vectors, start, h, n_steps = (self.timing, self.vectors, self.start, self.h,
                                              self.n_steps)
        pending = self._pending_ns
        for s in self.slots:
            n = s.n
            if (n != 1 and k % n) or k + n > n_steps:
                continue
            inst = s.instance
            t0 = clock()
            inst.set_inputs()
            t1 = clock()
            inst.do_step(start + k * h, n * h)
            t2 = clock()
            timing.do_ns[s.index] += t2 - t1
            pending[s.index] = t2 - t0
            timing.calls[s.index] += 1
        for s in self.slots:
            if s.n != 1 and kp1 % s.n:
                continue
            t0 = clock()
            s.instance.get_outputs()
            timing.all_ns[s.index] += pending[s.index] + clock() - t0
        for s in self.slots:
            s.copy_inputs(vectors, kp1)


def exchange_for(algorithm: str, slots: Sequence[Slot], order: Sequence[int], vectors,
                 start: float, h: float, n_steps: int, timing: Timing):
    """The exchange object of ``algorithm`` (one of :data:`ALGORITHMS`)."""
    if algorithm == "jacobi":
        return Jacobi(slots, vectors, start, h, n_steps, timing)
    return GaussSeidel(slots, order, vectors, start, h, n_steps, timing)


__all__ = [
    "ALGORITHMS",
    "step_order",
    "Slot",
    "Timing",
    "slots_for",
    "GaussSeidel",
    "Jacobi",
    "exchange_for",
]
