"""The genetic algorithm (orchestrator.campaigns.genetic) at its edges and in its bookkeeping:
the accepted settings at their limits, eq. 22 at r = 0.5 and with bounds other than [0, 1],
initial rows clipped to [0, 1], each child one gene away from a parent, every batch counted,
the statistics of a generation against the costs it was given, and the refused costs."""

from __future__ import annotations

import numpy as np
import pytest

from orchestrator.campaigns.genetic import GeneticAlgorithm, nonuniform_mutation
from orchestrator.errors import NavfmuError


def test_smallest_settings_are_accepted_and_one_less_is_refused():
    ga = GeneticAlgorithm(1, population=2, generations=1, crossover_probability=0.0,
                          mutation_probability=1.0)
    res = ga.run(lambda rows: [1.0 + float(r[0]) for r in rows])
    assert len(res.best_so_far) == 1 and res.evaluations == 2
    GeneticAlgorithm(1, crossover_probability=1.0, mutation_probability=0.0)
    for bad in ({"n_genes": 0}, {"population": 1}, {"generations": 0},
                {"crossover_probability": -0.1}, {"crossover_probability": 1.5},
                {"mutation_probability": -0.1}, {"mutation_probability": 1.5}):
        with pytest.raises(NavfmuError):
            GeneticAlgorithm(**{"n_genes": 2, **bad})


def test_eq_22_moves_up_at_r_one_half_and_uses_the_given_bounds():
    """Paper 003 eq. 22: up if r >= 0.5; with bounds [0.2, 0.8], f = 1 takes the gene onto
    the bound it moves towards (0.5 + (0.8 - 0.5) = 0.8, 0.5 - (0.5 - 0.2) = 0.2)."""
    a = np.array([0.5])
    assert nonuniform_mutation(a, 0, 0, 10, r=0.5, r2=1.0)[0] == 1.0
    assert nonuniform_mutation(a, 0, 0, 10, r=0.9, r2=1.0, lo=0.2, hi=0.8)[0] == \
        pytest.approx(0.8)
    assert nonuniform_mutation(a, 0, 0, 10, r=0.1, r2=1.0, lo=0.2, hi=0.8)[0] == \
        pytest.approx(0.2)
    # half way at generation 5 of 10: f = 0.5 * (1 - 0.5)^2 = 0.125 of the distance 0.3
    assert nonuniform_mutation(a, 0, 5, 10, r=0.1, r2=0.5, lo=0.2, hi=0.8)[0] == \
        pytest.approx(0.5 - 0.3 * 0.125)


class Recorder:
    """A cost (the squared distance to a target, plus 0.01) that keeps every batch."""

    def __init__(self, target):
        self.target = np.asarray(target, dtype=float)
        self.batches = []

    def cost(self, rows):
        self.batches.append(np.array(rows))
        return [0.01 + float(np.sum((r - self.target) ** 2)) for r in rows]


def test_initial_rows_are_clipped_into_the_unit_cube():
    rec = Recorder([0.5, 0.5])
    GeneticAlgorithm(2, population=4, generations=1, seed=3).run(
        rec.cost, initial=[[-0.5, 1.5], [2.0, -3.0]])
    assert rec.batches[0][0].tolist() == [0.0, 1.0]
    assert rec.batches[0][1].tolist() == [1.0, 0.0]


def _one_gene_from_a_parent(children, parents):
    """Every child equals some parent in all its genes but at most one."""
    for child in children:
        differing = (np.abs(parents - child) > 0).sum(axis=1)
        assert differing.min() <= 1, child


@pytest.mark.parametrize("crossover, mutation", [(1.0, 0.0), (0.0, 1.0)])
def test_crossover_and_mutation_each_change_one_gene(crossover, mutation):
    """Eq. 21 exchanges at one position, eq. 22 moves one gene: a second generation made by
    only one of them is, child by child, one gene away from the first."""
    rec = Recorder([0.3, 0.6, 0.2, 0.9])
    GeneticAlgorithm(4, population=12, generations=2, crossover_probability=crossover,
                     mutation_probability=mutation, seed=4).run(rec.cost)
    assert len(rec.batches) == 2 and len(rec.batches[1]) > 0
    _one_gene_from_a_parent(rec.batches[1], rec.batches[0])


def test_evaluations_count_every_row_sent_and_the_callback_sees_each_generation():
    rec = Recorder([0.2, 0.7])
    seen = []

    def on_generation(g, result):
        seen.append((g, len(result.best_so_far), result.best_so_far[-1]))

    res = GeneticAlgorithm(2, population=8, generations=4, seed=6).run(rec.cost, on_generation)
    assert res.evaluations == sum(len(b) for b in rec.batches)
    assert [(g, n) for g, n, _ in seen] == [(0, 1), (1, 2), (2, 3), (3, 4)]
    assert [b for _, _, b in seen] == res.best_so_far


def test_first_generation_statistics_are_those_of_its_costs():
    """Generation 1 is the first batch (all rows new): its best and mean cost are the minimum
    and mean of the costs returned for it, and the best genes are the row of the minimum."""
    rec = Recorder([0.9, 0.1])
    res = GeneticAlgorithm(2, population=10, generations=1, seed=8).run(rec.cost)
    costs = np.array(rec.cost(rec.batches[0]))
    assert int(np.argmin(costs)) != 0                  # the best is not simply the first row
    assert res.generation_best == [costs.min()]
    assert res.generation_mean == [pytest.approx(costs.mean(), rel=1e-15)]
    assert res.best_genes.tolist() == rec.batches[0][int(np.argmin(costs))].tolist()


@pytest.mark.parametrize("costs_of", [
    lambda rows: [1.0] * (len(rows) - 1),                       # one cost missing
    lambda rows: [float("inf")] + [1.0] * (len(rows) - 1),      # not finite
    lambda rows: [0.0] + [1.0] * (len(rows) - 1),               # not > 0
    lambda rows: [float("nan")] + [1.0] * (len(rows) - 1),
])
def test_a_batch_of_bad_costs_is_refused(costs_of):
    with pytest.raises(NavfmuError, match="every cost must be finite and > 0"):
        GeneticAlgorithm(2, population=4, generations=1).run(costs_of)
