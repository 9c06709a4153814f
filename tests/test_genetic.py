"""The genetic algorithm of paper 003 (orchestrator.campaigns.genetic): operators against the
paper's
formulas, genes in bounds, elitism, reproducibility, and convergence on an analytic cost."""

from __future__ import annotations

import numpy as np
import pytest

from orchestrator.errors import NavfmuError
from orchestrator.campaigns.genetic import (GeneticAlgorithm, arithmetic_crossover, decode,
                                  nonuniform_mutation, roulette)


def test_crossover_is_eq_21():
    a, b = np.array([0.1, 0.2, 0.3]), np.array([0.9, 0.8, 0.7])
    a2, b2 = arithmetic_crossover(a, b, 1, 0.25)
    assert a2.tolist() == pytest.approx([0.1, 0.2 * 0.75 + 0.8 * 0.25, 0.3])
    assert b2.tolist() == pytest.approx([0.9, 0.8 * 0.75 + 0.2 * 0.25, 0.7])
    assert a.tolist() == [0.1, 0.2, 0.3]                      # parents untouched


def test_mutation_is_eq_22_and_shrinks_to_nothing_at_the_last_generation():
    a = np.array([0.4, 0.6])
    up = nonuniform_mutation(a, 0, generation=2, max_generations=10, r=0.7, r2=0.5)
    assert up[0] == pytest.approx(0.4 + 0.6 * 0.5 * (1 - 0.2) ** 2)
    down = nonuniform_mutation(a, 1, generation=2, max_generations=10, r=0.2, r2=0.5)
    assert down[1] == pytest.approx(0.6 - 0.6 * 0.5 * (1 - 0.2) ** 2)
    assert nonuniform_mutation(a, 0, 10, 10, 0.9, 1.0)[0] == 0.4


def test_operators_keep_genes_in_bounds():
    rng = np.random.default_rng(1)
    for _ in range(5000):
        a, b = rng.random(4), rng.random(4)
        a2, b2 = arithmetic_crossover(a, b, int(rng.integers(4)), rng.random())
        m = nonuniform_mutation(a2, int(rng.integers(4)), int(rng.integers(0, 11)), 10,
                                rng.random(), rng.random())
        for g in (a2, b2, m):
            assert np.all((g >= 0.0) & (g <= 1.0))
    # extreme draws land exactly on the bounds, never beyond
    assert nonuniform_mutation(np.array([0.3]), 0, 0, 10, 0.9, 1.0)[0] == 1.0
    assert nonuniform_mutation(np.array([0.3]), 0, 0, 10, 0.1, 1.0)[0] == 0.0


def test_roulette_follows_the_fitness():
    rng = np.random.default_rng(2)
    picks = roulette(rng, np.array([1.0, 3.0]), 40000)
    assert np.mean(picks == 1) == pytest.approx(0.75, abs=0.01)
    with pytest.raises(NavfmuError):
        roulette(rng, np.array([1.0, 0.0]), 1)


def _sphere(target):
    def cost(rows):
        return [0.01 + float(np.sum((r - target) ** 2)) for r in rows]
    return cost


def test_best_so_far_never_worsens_and_the_ga_converges():
    target = np.array([0.2, 0.7, 0.5])
    res = GeneticAlgorithm(3, population=20, generations=30, seed=5).run(_sphere(target))
    assert all(b2 <= b1 for b1, b2 in zip(res.best_so_far, res.best_so_far[1:]))
    # elitism: the best is kept in every generation, so the generation best is the best so far
    assert res.generation_best == res.best_so_far
    assert res.best_cost < 0.01 + 0.01
    assert np.all((res.best_genes >= 0) & (res.best_genes <= 1))
    assert res.evaluations < 20 * 30                           # the elite is not re-run


def test_same_seed_same_result_whatever_the_evaluation_order():
    target = np.array([0.4, 0.1])
    forward = GeneticAlgorithm(2, population=8, generations=6, seed=11).run(_sphere(target))

    def reversed_cost(rows):               # evaluates back to front, as a pool might
        return list(reversed(_sphere(target)(rows[::-1])))

    again = GeneticAlgorithm(2, population=8, generations=6, seed=11).run(reversed_cost)
    assert again.best_so_far == forward.best_so_far
    assert np.array_equal(again.best_genes, forward.best_genes)
    other = GeneticAlgorithm(2, population=8, generations=6, seed=12).run(_sphere(target))
    assert not np.array_equal(other.best_genes, forward.best_genes)


def test_decode_maps_to_the_ranges():
    np.testing.assert_allclose(decode(np.array([0.0, 0.5, 1.0]), np.array([-1.0, 0.0, 2.0]),
                                      np.array([1.0, 10.0, 4.0])), [-1.0, 5.0, 4.0])


def test_bad_settings():
    with pytest.raises(NavfmuError, match="population"):
        GeneticAlgorithm(2, population=1)
    with pytest.raises(NavfmuError, match="generations"):
        GeneticAlgorithm(2, generations=0)


def test_an_initial_row_is_evaluated_and_kept_when_nothing_beats_it():
    """Elitism with a seeded first population: a cost that only the given initial row reaches
    (a spike no random row hits) is the result, with that row's genes."""
    start = np.array([0.123, 0.877])

    def spike(rows):
        return [1.0 if np.array_equal(r, start) else 2.0 for r in rows]

    res = GeneticAlgorithm(2, population=6, generations=5, seed=2).run(spike, initial=[start])
    assert res.best_cost == 1.0 and np.array_equal(res.best_genes, start)
    assert res.best_so_far == [1.0] * 5
