"""A real-coded genetic algorithm: the optimiser of paper 003 (Xiao & Lu, sec. 3), generic.

Operators, as the paper states them:

* **coding**: every gene is a real number in ``[0, 1]``; gene ``j`` maps linearly to the
  range ``[lo_j, hi_j]`` of its parameter (:func:`decode`);
* **initial population**: uniform random genes;
* **selection**: roulette wheel, the probability of an individual proportional to its
  fitness.  The GA minimises a cost ``J > 0`` (paper 003 eq. 20: an attitude RMS), and its
  fitness is ``1 / J`` ("the higher the fitness, the likelier the choice");
* **crossover** (eq. 21, arithmetic): parents ``a_k``, ``a_l`` exchange at one random
  position ``j`` with a random ``b`` in ``[0, 1]``::

      a_kj' = a_kj (1 - b) + a_lj b,      a_lj' = a_lj (1 - b) + a_kj b

  (the paper's printed first line, ``a_ij (1 - b)``, is a typo for ``a_kj``);
* **mutation** (eq. 22, non-uniform, Michalewicz 1996): one random gene ``a_ij`` of the
  child moves towards a bound, with ``f(g) = r_2 (1 - g / G_max)^2``::

      a_ij' = a_ij + (a_max - a_ij) f(g)    if r >= 0.5
      a_ij' = a_ij - (a_ij - a_min) f(g)    if r <  0.5

  with ``r``, ``r_2`` uniform in ``[0, 1]``, so the steps shrink as generation ``g``
  approaches ``G_max`` and the gene never leaves ``[a_min, a_max] = [0, 1]``;
* **elitism** (not in the paper; asked for so the best never gets worse): the best
  individual so far enters each new generation unchanged;
* **seeding** (not in the paper): :meth:`GeneticAlgorithm.run` may put given individuals
  (the current parameter values) into the first population in place of random ones, so the
  result is never worse than the starting point on the cost the GA sees.

Everything random comes from one ``numpy.random.default_rng(seed)``, drawn in a fixed order
independent of how the costs were computed, and costs are looked up by gene vector (an
individual evaluated once is never run again): the same seed gives the same generations,
whatever executor evaluates them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Dict, List, Sequence, Tuple

import numpy as np

from ..errors import NavfmuError
from .defaults import DEFAULT_SEED

#: evaluate a batch of gene vectors (rows in [0, 1]) -> their costs J (> 0, lower is better)
Evaluate = Callable[[np.ndarray], Sequence[float]]


def decode(genes: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Parameter values of genes in [0, 1] (linear map to ``[lo, hi]``)."""
    return lo + np.asarray(genes, dtype=float) * (hi - lo)


def roulette(rng: np.random.Generator, fitness: np.ndarray, k: int) -> np.ndarray:
    """``k`` indices drawn with probability proportional to ``fitness`` (all > 0)."""
    fitness = np.asarray(fitness, dtype=float)
    if not (fitness > 0).all() or not np.isfinite(fitness).all():
        raise NavfmuError("genetic algorithm: roulette selection needs finite fitness > 0")
    return rng.choice(fitness.size, size=k, p=fitness / fitness.sum())


def arithmetic_crossover(a: np.ndarray, b: np.ndarray, j: int, beta: float
                         ) -> Tuple[np.ndarray, np.ndarray]:
    """Eq. 21 at position ``j`` with weight ``beta``; returns new copies."""
    a2, b2 = a.copy(), b.copy()
    a2[j] = a[j] * (1.0 - beta) + b[j] * beta
    b2[j] = b[j] * (1.0 - beta) + a[j] * beta
    return a2, b2


def nonuniform_mutation(a: np.ndarray, j: int, generation: int, max_generations: int,
                        r: float, r2: float, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    """Eq. 22 on gene ``j``; returns a new copy (the gene stays within ``[lo, hi]``)."""
    f = r2 * (1.0 - generation / max_generations) ** 2
    out = a.copy()
    if r >= 0.5:
        out[j] = a[j] + (hi - a[j]) * f
    else:
        out[j] = a[j] - (a[j] - lo) * f
    return out


@dataclass
class GaResult:
    """Outcome of :meth:`GeneticAlgorithm.run`: per generation the best cost so far, the best
    and mean cost of that generation; the best genes and their cost."""

    best_genes: np.ndarray
    best_cost: float
    best_so_far: List[float] = field(default_factory=list)
    generation_best: List[float] = field(default_factory=list)
    generation_mean: List[float] = field(default_factory=list)
    evaluations: int = 0


@dataclass
class GeneticAlgorithm:
    """The GA of the module docstring over ``n_genes`` genes."""

    n_genes: int
    population: int = 10
    generations: int = 5
    crossover_probability: float = 0.8
    mutation_probability: float = 0.2
    seed: int = DEFAULT_SEED

    def __post_init__(self):
        if self.n_genes < 1:
            raise NavfmuError("genetic algorithm: need at least one parameter to tune")
        if self.population < 2:
            raise NavfmuError(f"--population: need at least 2 individuals, got {self.population}")
        if self.generations < 1:
            raise NavfmuError(f"--generations: need at least 1, got {self.generations}")
        for name in ("crossover_probability", "mutation_probability"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise NavfmuError(f"genetic algorithm: {name} must be in [0, 1]")

    def _offspring(self, rng, pop, cost, generation):
        """Next population: the elite, then roulette-selected pairs crossed and mutated."""
        fitness = 1.0 / np.asarray(cost)
        children = [pop[int(np.argmin(cost))].copy()]
        while len(children) < self.population:
            i, k = roulette(rng, fitness, 2)
            a, b = pop[i], pop[k]
            if rng.random() < self.crossover_probability:
                a, b = arithmetic_crossover(a, b, int(rng.integers(self.n_genes)), rng.random())
            for child in (a, b):
                if rng.random() < self.mutation_probability:
                    child = nonuniform_mutation(child, int(rng.integers(self.n_genes)),
                                                generation, self.generations, rng.random(),
                                                rng.random())
                children.append(child.copy())
        return np.array(children[:self.population])

    def run(self, evaluate: Evaluate, on_generation: Callable[[int, GaResult], None] = None,
            initial: Sequence[Sequence[float]] = ()) -> GaResult:
        """Evolve ``generations`` generations (the first is random, its first rows replaced
        by ``initial``, genes clipped to [0, 1]); ``evaluate`` gets each generation's
        not-yet-evaluated gene vectors as one batch."""
        rng = np.random.default_rng(self.seed)
        known: Dict[bytes, float] = {}
        result = GaResult(np.zeros(self.n_genes), float("inf"))
        pop = rng.random((self.population, self.n_genes))
        for i, row in enumerate(list(initial)[:self.population]):
            pop[i] = np.clip(np.asarray(row, dtype=float), 0.0, 1.0)
        for g in range(self.generations):
            if g > 0:
                pop = self._offspring(rng, pop, cost, g)
            new = [row for row in pop if row.tobytes() not in known]
            unique = {row.tobytes(): row for row in new}
            if unique:
                rows = np.array(list(unique.values()))
                costs = [float(c) for c in evaluate(rows)]
                if len(costs) != len(rows) or not all(c > 0 and np.isfinite(c) for c in costs):
                    raise NavfmuError("genetic algorithm: every cost must be finite and > 0")
                known.update(zip(unique, costs))
                result.evaluations += len(rows)
            cost = np.array([known[row.tobytes()] for row in pop])
            best = int(np.argmin(cost))
            if cost[best] < result.best_cost:
                result.best_cost, result.best_genes = float(cost[best]), pop[best].copy()
            result.generation_best.append(float(cost[best]))
            result.generation_mean.append(float(cost.mean()))
            result.best_so_far.append(result.best_cost)
            if on_generation is not None:
                on_generation(g, result)
        return result
