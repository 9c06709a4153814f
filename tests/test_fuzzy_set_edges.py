"""The edges of paper 003's fuzzy sets (navcore.filters.fuzzy) by hand: the shoulders beyond
their vertices, the sets at their vertices with vertical edges, slopes of non-default feet, the
bounds of the output vertices, and the factor of a weakly fired rule and of no rule at all."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.core.component import ParameterError
from navcore.filters.fuzzy import FuzzyRScale, memberships

E_V, DE_V = (-0.5, 0.0, 1.0), (-0.5, 0.0, 0.5)
E_FEET, DE_FEET = (0.0, -0.5, 1.0, 0.0), (0.0, -0.5, 0.5, 0.0)


def test_each_set_is_one_at_and_beyond_its_vertex():
    np.testing.assert_array_equal(memberships(-1.0, E_V, E_FEET), [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(memberships(-0.5, E_V, E_FEET), [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(memberships(0.0, E_V, E_FEET), [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(memberships(1.0, E_V, E_FEET), [0.0, 0.0, 1.0])


def test_a_vertical_edge_keeps_its_vertex_at_one():
    """Feet at their vertices (allowed, FEET's ranges reach them): every set is still 1 at its
    vertex and 0 just beyond the vertical edge."""
    vertical = (-0.5, 0.0, 0.0, 1.0)          # N right, Z left, Z right, P left
    np.testing.assert_array_equal(memberships(-0.5, E_V, vertical), [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(memberships(0.0, E_V, vertical), [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(memberships(1.0, E_V, vertical), [0.0, 0.0, 1.0])
    np.testing.assert_array_equal(memberships(-0.25, E_V, vertical), [0.0, 0.0, 0.0])
    # and the whole inference with vertical Z edges: e = de = 0 is (Z, Z) -> K, F = 1
    f = FuzzyRScale({"fuzzy_e_z_left": 0.0, "fuzzy_e_z_right": 0.0,
                     "fuzzy_de_z_left": 0.0, "fuzzy_de_z_right": 0.0})
    assert f(0.0, 0.0) == 1.0


def test_slopes_of_the_de_sets_and_of_moved_feet():
    # de = 0.25: Z (0.5 - 0.25) / 0.5 = 0.5, P (0.25 - 0) / (0.5 - 0) = 0.5
    np.testing.assert_allclose(memberships(0.25, DE_V, DE_FEET), [0.0, 0.5, 0.5])
    # de = 0.4: Z 0.1 / 0.5 = 0.2, P 0.4 / 0.5 = 0.8
    np.testing.assert_allclose(memberships(0.4, DE_V, DE_FEET), [0.0, 0.2, 0.8])
    # e with P's left foot moved to 0.5: e = 0.75 gives P (0.75 - 0.5) / (1 - 0.5) = 0.5
    np.testing.assert_allclose(memberships(0.75, E_V, (0.0, -0.5, 1.0, 0.5)),
                               [0.0, 0.25, 0.5])


@pytest.mark.parametrize("vertex, value", [("fuzzy_out_ld", 0.0), ("fuzzy_out_ld", 1.0 / 1.2),
                                           ("fuzzy_out_d", 1.0), ("fuzzy_out_i", 1.0),
                                           ("fuzzy_out_i", 1.5)])
def test_output_vertices_must_be_strictly_ordered(vertex, value):
    """0 < LD < D < 1 < I < LI strictly: equal neighbours (D = 1/1.2 = 0.83.., LI = 1.5) or
    LD = 0 (ln 0) are refused."""
    with pytest.raises(ParameterError, match="fuzzy output vertices"):
        FuzzyRScale({vertex: value})


@pytest.mark.parametrize("foot, prefix", [("fuzzy_e_z_left", "fuzzy_e"),
                                          ("fuzzy_de_z_left", "fuzzy_de")])
def test_bad_feet_name_their_input(foot, prefix):
    with pytest.raises(ParameterError, match=rf"^fuzzy membership feet {prefix}_\*:"):
        FuzzyRScale({foot: 0.5})


# feet leaving a gap between e's Z (ending at 0.5) and P (starting at 0.9)
_GAPPED = {"fuzzy_e_z_right": 0.5, "fuzzy_e_p_left": 0.9}


def test_no_rule_fired_keeps_r():
    """e = 0.7 lies in the gap: no e set, so no rule, fires; the documented factor is 1."""
    assert FuzzyRScale(_GAPPED)(0.7, 0.0) == 1.0


def test_a_weakly_fired_rule_still_sets_the_factor():
    """e = 0.9005: only P, at (0.9005 - 0.9) / 0.1 = 0.005; de = 0: only Z.  The one rule
    (P, Z) -> I fires at 0.005: the output is the centroid, in ln F, of the I triangle
    (0, ln 1.2, ln 1.5) clipped at 0.005, nearly its base's midpoint, worked out on a fine grid.
    """
    ln12, ln15 = math.log(1.2), math.log(1.5)
    u = np.linspace(0.0, ln15, 1_000_001)
    clipped = np.minimum(np.minimum(u / ln12, (ln15 - u) / (ln15 - ln12)), 0.005)
    expected = math.exp(float(np.sum(clipped * u) / np.sum(clipped)))
    assert 1.22 < expected < 1.23
    assert FuzzyRScale(_GAPPED)(0.9005, 0.0) == pytest.approx(expected, rel=2e-3)


@pytest.mark.parametrize("vertices", [{}, {"fuzzy_out_ld": 0.3, "fuzzy_out_d": 0.9,
                                           "fuzzy_out_i": 1.01, "fuzzy_out_li": 4.0}])
def test_the_output_sets_are_a_partition_of_the_output_range(vertices):
    """Each output set's feet are its neighbours' vertices, so at every point of the grid
    (which runs from ln out_ld to ln out_li) the memberships add up to 1, at the two ends too,
    where LD and LI are 1 alone."""
    f = FuzzyRScale(vertices)
    assert f.grid[0] == math.log(f.out_vertices[0])
    assert f.grid[-1] == math.log(f.out_vertices[-1])
    np.testing.assert_allclose(f.output_sets.sum(axis=0), 1.0, rtol=0.0, atol=1e-12)
    assert f.output_sets[0, 0] == 1.0 and f.output_sets[4, -1] == 1.0
