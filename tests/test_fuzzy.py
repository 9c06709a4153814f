"""The Mamdani inference of paper 003 (navcore.filters.fuzzy) on hand-computed inputs, and the
covariance-matching adaptation (navcore.filters.ahrs.FuzzyAdaptiveR) on white noise of known size.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.filters.ahrs import FuzzyAdaptiveR
from navcore.core.component import ParameterError
from navcore.filters.fuzzy import FuzzyRScale, memberships

LN12, LN15 = math.log(1.2), math.log(1.5)


def test_memberships_of_the_default_sets_by_hand():
    # e = 0.5: N 0 (N falls to 0 at 0), Z (1 - 0.5) / 1 = 0.5, P (0.5 - 0) / 1 = 0.5
    np.testing.assert_allclose(memberships(0.5, (-0.5, 0.0, 1.0), (0.0, -0.5, 1.0, 0.0)),
                               [0.0, 0.5, 0.5])
    # e = -0.25: N (0 + 0.25) / 0.5 = 0.5, Z (-0.25 + 0.5) / 0.5 = 0.5, P 0
    np.testing.assert_allclose(memberships(-0.25, (-0.5, 0.0, 1.0), (0.0, -0.5, 1.0, 0.0)),
                               [0.5, 0.5, 0.0])
    # shoulders beyond the outer vertices
    np.testing.assert_allclose(memberships(5.0, (-0.5, 0.0, 1.0), (0.0, -0.5, 1.0, 0.0)),
                               [0.0, 0.0, 1.0])


def test_matched_filter_keeps_r():
    assert FuzzyRScale()(0.0, 0.0) == pytest.approx(1.0, abs=1e-12)


def _centroid(mu, u):
    return float(np.sum(mu * u) / np.sum(mu))


def test_output_for_e_half_de_zero_by_hand():
    """e = 0.5, de = 0: rules (Z, Z) -> K and (P, Z) -> I fire with 0.5 each (memberships
    above).  In u = ln F, K = triangle(-ln1.2, 0, ln1.2) and I = triangle(0, ln1.2, ln1.5),
    both clipped at 0.5; their union's centroid, integrated here on a fine grid."""
    u = np.linspace(-LN15, LN15, 2_000_001)

    def tri(x, a, b, c):
        return np.clip(np.minimum((x - a) / (b - a), (c - x) / (c - b)), 0.0, 1.0)

    union = np.maximum(np.minimum(tri(u, -LN12, 0.0, LN12), 0.5),
                       np.minimum(tri(u, 0.0, LN12, LN15), 0.5))
    expected = math.exp(_centroid(union, u))
    assert FuzzyRScale()(0.5, 0.0) == pytest.approx(expected, rel=2e-3)
    assert 1.09 < expected < 1.13


def test_output_for_large_growing_mismatch_is_large_increase():
    """e >= 1 and de >= 0.5: only (P, P) -> LI fires, fully; the centroid of the LI
    triangle (ln1.2, ln1.5, ln1.5) is (ln1.2 + 2 ln1.5) / 3."""
    expected = math.exp((LN12 + 2 * LN15) / 3)
    assert FuzzyRScale()(3.0, 1.0) == pytest.approx(expected, rel=2e-3)
    # and the mirror image
    assert FuzzyRScale()(-1.0, -1.0) == pytest.approx(1.0 / expected, rel=2e-3)


def test_bad_feet_are_parameter_errors():
    with pytest.raises(ParameterError, match="fuzzy_e"):
        FuzzyRScale({"fuzzy_e_z_left": 0.5})
    FuzzyRScale({"fuzzy_e_z_left": 0.0, "fuzzy_e_n_right": -0.5})   # vertical edges are fine
    with pytest.raises(ParameterError, match="fuzzy_out"):
        FuzzyRScale({"fuzzy_out_i": 0.9})


def test_adaptation_finds_the_true_noise_level():
    """Innovations of white noise 10x larger than R assumes (Pzz = 0): the accelerometer
    scale climbs to about 100 (variance), the magnetometer one stays near 1."""
    rng = np.random.default_rng(0)
    R0 = np.diag([1e-4] * 3 + [1e-4] * 3)
    adapt = FuzzyAdaptiveR(FuzzyRScale(), window=20, r_scale_min=0.1, r_scale_max=1e4)
    scale = np.ones(2)
    history = []
    for _ in range(3000):
        v = np.concatenate((0.1 * rng.standard_normal(3), 0.01 * rng.standard_normal(3)))
        scale = adapt.step(v, np.zeros((6, 6)), R0, scale)
        history.append(scale.copy())
    late = np.exp(np.mean(np.log(np.array(history[1000:])), axis=0))
    assert 50 < late[0] < 200
    assert 0.5 < late[1] < 2.0


def test_any_values_within_the_declared_ranges_are_valid():
    """A tuner may pick any corner of the ranges: every one builds a valid inference."""
    from navcore.filters.fuzzy import FEET, OUTPUT_VERTICES

    specs = {**FEET, **OUTPUT_VERTICES}
    rng = np.random.default_rng(4)
    for _ in range(300):
        values = {k: (lo if rng.random() < 0.3 else hi if rng.random() < 0.5
                      else rng.uniform(lo, hi)) for k, (_, lo, hi, _) in specs.items()}
        f = FuzzyRScale(values)
        assert 0.3 <= f(rng.normal(), rng.normal()) <= 4.0


# every cell of the rule table: inputs at the sets' vertices fire exactly one rule, fully, so the
# output is the centroid of one output set in ln F, by hand (LD and LI end at their own
# vertex: right triangles, centroid 1/3 of the way from the vertex to the other end)
_LN = {"LD": (2 * -LN15 - LN12) / 3, "D": (-LN15 - LN12 + 0.0) / 3, "K": 0.0,
       "I": (0.0 + LN12 + LN15) / 3, "LI": (LN12 + 2 * LN15) / 3}
_TABLE = {("N", "N"): "LD", ("N", "Z"): "D", ("N", "P"): "K",
          ("Z", "N"): "D", ("Z", "Z"): "K", ("Z", "P"): "I",
          ("P", "N"): "K", ("P", "Z"): "I", ("P", "P"): "LI"}
_E_AT = {"N": -0.5, "Z": 0.0, "P": 1.0}
_DE_AT = {"N": -0.5, "Z": 0.0, "P": 0.5}


@pytest.mark.parametrize("cell", sorted(_TABLE), ids=lambda c: f"e_{c[0]}-de_{c[1]}")
def test_every_rule_cell_by_hand(cell):
    e_set, de_set = cell
    got = FuzzyRScale()(_E_AT[e_set], _DE_AT[de_set])
    assert math.log(got) == pytest.approx(_LN[_TABLE[cell]], abs=2e-3)


def _mamdani_by_hand(e, de, t_norm):
    """The paper's inference written out independently on a fine grid, with the given t-norm
    (AND), max aggregation and the centroid in ln F."""
    u = np.linspace(-LN15, LN15, 600_001)

    def tri(x, a, b, c):
        rise = np.ones_like(x) if a == b else (x - a) / (b - a)
        fall = np.ones_like(x) if b == c else (c - x) / (c - b)
        return np.clip(np.minimum(rise, fall), 0.0, 1.0)

    out = {"LD": tri(u, -LN15, -LN15, -LN12), "D": tri(u, -LN15, -LN12, 0.0),
           "K": tri(u, -LN12, 0.0, LN12), "I": tri(u, 0.0, LN12, LN15),
           "LI": tri(u, LN12, LN15, LN15)}
    mu_e = dict(zip("NZP", memberships(e, (-0.5, 0.0, 1.0), (0.0, -0.5, 1.0, 0.0))))
    mu_de = dict(zip("NZP", memberships(de, (-0.5, 0.0, 0.5), (0.0, -0.5, 0.5, 0.0))))
    aggregate = np.zeros_like(u)
    for (a, b), name in _TABLE.items():
        aggregate = np.maximum(aggregate, np.minimum(out[name], t_norm(mu_e[a], mu_de[b])))
    return math.exp(_centroid(aggregate, u))


def test_the_and_of_the_rules_is_the_minimum():
    """e = -0.1 (N 0.2, Z 0.8), de = 0.45 (Z 0.1, P 0.9): four rules fire with different
    strengths, where min and product differ by 3 %; ours is the paper's min."""
    by_min = _mamdani_by_hand(-0.1, 0.45, min)
    by_product = _mamdani_by_hand(-0.1, 0.45, lambda a, b: a * b)
    assert abs(by_min - by_product) > 0.02 * by_min   # the case tells the two t-norms apart
    assert FuzzyRScale()(-0.1, 0.45) == pytest.approx(by_min, rel=1e-3)


def test_de_is_the_growth_of_the_mismatch():
    """A mismatch that grows between two updates gives de > 0 (and the larger factor of the
    (P, P) cell); one that shrinks gives de < 0."""
    R0 = np.eye(6) * 1e-4
    adapt = FuzzyAdaptiveR(FuzzyRScale(), window=2, r_scale_min=1e-3, r_scale_max=1e4)
    scale = np.ones(2)
    for v in (0.01, 0.02, 0.04):                        # innovations growing, Pzz = 0
        scale = adapt.step(np.full(6, v), np.zeros((6, 6)), R0, scale)
    assert adapt.de[0] > 0 and adapt.e[0] > 0
    grown = adapt.de[0]
    for v in (0.02, 0.01):
        adapt.step(np.full(6, v), np.zeros((6, 6)), R0, np.ones(2))
    assert adapt.de[0] < 0 < grown


def _centroid_by_loops(inference, e, de):
    """The inference of the module docstring written out with Python loops: rule table,
    min/max, centroid over the grid (the reference the stacked inference must reproduce)."""
    mu_e = memberships(e, (-0.5, 0.0, 1.0), inference.e_feet).tolist()
    mu_de = memberships(de, (-0.5, 0.0, 0.5), inference.de_feet).tolist()
    rules = [[0, 1, 2], [1, 2, 3], [2, 3, 4]]
    fired = [0.0] * 5
    for i in range(3):
        for j in range(3):
            fired[rules[i][j]] = max(fired[rules[i][j]], min(mu_e[i], mu_de[j]))
    sets = inference.output_sets.tolist()
    aggregate = [max(min(sets[k][g], fired[k]) for k in range(5))
                 for g in range(len(inference.grid))]
    total = math.fsum(aggregate)
    if total <= 0.0:
        return 1.0
    return math.exp(math.fsum(a * x for a, x in zip(aggregate, inference.grid.tolist())) / total)


def test_stacked_inferences_with_their_own_sets_against_loops():
    """Rows of different feet and output vertices (the GA's per-run parameters) in one
    StackedInference: each row's factor is its own inference's, within rounding of the
    loop-and-fsum reference (the centroid's sums round in another order there)."""
    from navcore.filters.fuzzy import FEET, OUTPUT_VERTICES, StackedInference
    rng = np.random.default_rng(11)
    inferences = [FuzzyRScale()] + [
        FuzzyRScale({k: rng.uniform(lo, hi) for k, (_, lo, hi, _) in
                     {**FEET, **OUTPUT_VERTICES}.items()}) for _ in range(5)]
    rows = [inferences[k % 6] for k in range(60)]
    e, de = rng.uniform(-1.0, 3.0, 60), rng.uniform(-1.0, 1.0, 60)
    e[:3], de[:3] = (0.0, 0.5, -0.5), (0.0, 0.0, -0.5)     # vertices: matched, I, LD
    stacked = StackedInference(rows)(e, de)
    expected = [_centroid_by_loops(f, a, b) for f, a, b in zip(rows, e.tolist(), de.tolist())]
    np.testing.assert_allclose(stacked, expected, rtol=1e-13)
    assert stacked[0] == 1.0
    assert len(set(np.round(stacked, 6).tolist())) > 30           # the rows differ
    # each row is the single inference, bit for bit
    assert stacked.tolist() == [f(a, b) for f, a, b in zip(rows, e.tolist(), de.tolist())]


@pytest.mark.parametrize("compiled", [True, False], ids=["kernel", "source"])
def test_the_compiled_aggregation_is_numpy_s_minimum_and_maximum(compiled):
    """The aggregated output sets of StackedInference's kernel against the same inference
    in numpy (memberships per element, np.minimum of the rules' degrees, np.maximum over
    each output set's rules and over the cut sets), bit for bit: inputs at the vertices and
    feet, beyond the shoulders, random ones and NaN (which numpy's min and max propagate)."""
    from navcore.filters import fuzzy
    rng = np.random.default_rng(12)
    inferences = [FuzzyRScale()] + [
        FuzzyRScale({k: rng.uniform(lo, hi) for k, (_, lo, hi, _) in
                     {**fuzzy.FEET, **fuzzy.OUTPUT_VERTICES}.items()}) for _ in range(3)]
    rows = [inferences[k % 4] for k in range(80)]
    e, de = rng.uniform(-1.5, 3.5, 80), rng.uniform(-1.5, 1.5, 80)
    e[:8] = (-0.5, 0.0, 1.0, *rows[3].e_feet, np.nan)
    de[8:16] = (-0.5, 0.0, 0.5, *rows[11].de_feet, np.nan)
    stacked = fuzzy.StackedInference(rows)
    got = np.empty((80, len(rows[0].grid)))
    kernel = (fuzzy._aggregate_rows if compiled
              else getattr(fuzzy._aggregate_rows, "py_func", fuzzy._aggregate_rows))
    kernel(e, de, stacked.feet, stacked.output_sets, fuzzy._FIRING, got)
    for k, f in enumerate(rows):
        mu_e = memberships(e[k], fuzzy.E_VERTICES, f.e_feet)
        mu_de = memberships(de[k], fuzzy.DE_VERTICES, f.de_feet)
        strength = np.append(np.minimum(mu_e[:, None], mu_de[None]).ravel(), 0.0)
        fired = strength[fuzzy._FIRING].max(axis=1)
        expected = np.max(np.minimum(f.output_sets, fired[:, None]), axis=0)
        assert np.array_equal(got[k], expected, equal_nan=True), k
    assert np.isnan(got[7]).all() and np.isnan(got[15]).all()


def test_stacked_centroid_products_are_each_row_s_dot():
    """The centroids' stacked (1, grid) x (grid, 1) products of StackedInference against
    numpy's 1-D dot of each row (what one inference computed before they were stacked),
    bit for bit, on the grid's length and on random memberships."""
    from navcore.filters.fuzzy import _GRID_POINTS
    rng = np.random.default_rng(4)
    aggregate = rng.random((400, _GRID_POINTS))
    grids = np.log(rng.uniform(0.2, 5.0, (400, _GRID_POINTS)))
    stacked = np.matmul(aggregate[:, None, :], grids[:, :, None])[:, 0, 0]
    expected = [float(np.dot(a, g)) for a, g in zip(aggregate, grids)]
    assert stacked.view(np.uint64).tolist() == np.array(expected).view(np.uint64).tolist()
