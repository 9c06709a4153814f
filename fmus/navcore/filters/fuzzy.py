"""Mamdani fuzzy inference of the R scale factor of paper 003 (Xiao & Lu, sec. 2-3).

Inputs and output
-----------------
For one sensor block (accelerometer or magnetometer) the adaptive filter gives two inputs:

* ``e``: the relative mismatch of the innovation covariance, ``(tr C_z - tr P_z) / tr P_z``
  over the block (paper 003 eqs. 16-19: ``E_k = C_z - P_z``, made dimensionless by ``tr P_z``
  so that one set of membership functions serves both sensors); ``e >= -1``, 0 when the
  measured innovations match the filter's prediction, > 0 when R is too small;
* ``de``: its change since the previous update, ``e_k - e_(k-1)``.

The output is the factor ``F`` of ``R_k = F_k R_(k-1)`` (paper 003 eq. 15) for the block
(paper 003 eq. 25).

Membership functions (triangular, as in the paper)
--------------------------------------------------
Each input has three sets N (negative), Z (zero), P (positive).  Their vertices are fixed
(prior knowledge, paper 003 sec. 3: "the vertices ... are determined by prior knowledge, the
GA optimises the left and right feet"): ``e``: -0.5, 0, 1; ``de``: -0.5, 0, 0.5.  N and P are
shoulders (membership 1 beyond their vertex).  The feet are the eight tunable parameters (the
paper's code length 8):

    e:  N right foot, Z left foot, Z right foot, P left foot
    de: N right foot, Z left foot, Z right foot, P left foot

The output has five triangular sets LD, D, K, I, LI (large decrease, decrease, keep,
increase, large increase) with vertices ``out_ld < out_d < 1 < out_i < out_li`` (K at 1);
each set's feet are its neighbours' vertices (LD and LI end at their own vertex), so the
output sets form a partition of ``[out_ld, out_li]``.  The sets are triangles in ``ln F``
and the centroid is taken there (``F = exp(centroid)``): a factor and its inverse are
equally far from "keep", so with the default vertices (``out_d = 1/out_i``,
``out_ld = 1/out_li``) a matched filter (only K firing) keeps ``F = 1`` exactly instead of
drifting by the asymmetry of linear triangles.

Rule base (AND = min, aggregation = max, centroid defuzzification on a 201-point grid)::

    e \\ de     N     Z     P
    N          LD    D     K
    Z          D     K     I
    P          K     I     LI

i.e. the measured innovations larger than predicted (e P) increase R, more so when the
mismatch grows (de P); smaller ones decrease it; a mismatch already shrinking is left alone.

Why numpy and not a fuzzy library: the inference runs at every measurement update of every
filter instance (10 per second of simulated time, thousands per GA generation).  This
implementation costs a few tens of microseconds per call; scikit-fuzzy's
``ControlSystemSimulation.compute`` rebuilds its rule graph per call and costs milliseconds,
which would dominate the filter's own cost.
"""
from __future__ import annotations

from typing import Dict, Sequence

import numpy as np

from ..core.kernels import jitable, kernel
from ..errors import ParameterError

#: fixed vertices of the input sets N, Z, P
E_VERTICES = (-0.5, 0.0, 1.0)
DE_VERTICES = (-0.5, 0.0, 0.5)

#: the tunable feet: name -> (default, lower bound, upper bound, description); every value
#: in a range keeps its set valid (a foot may reach its vertex: a vertical edge), so a
#: tuner searching the ranges never builds an invalid inference
FEET = {
    "fuzzy_e_n_right": (0.0, -0.5, 1.0, "e: right foot of N (N = 1 up to -0.5)"),
    "fuzzy_e_z_left": (-0.5, -1.0, 0.0, "e: left foot of Z (vertex 0)"),
    "fuzzy_e_z_right": (1.0, 0.0, 3.0, "e: right foot of Z (vertex 0)"),
    "fuzzy_e_p_left": (0.0, -0.5, 1.0, "e: left foot of P (P = 1 from 1)"),
    "fuzzy_de_n_right": (0.0, -0.5, 0.5, "de: right foot of N (N = 1 up to -0.5)"),
    "fuzzy_de_z_left": (-0.5, -1.5, 0.0, "de: left foot of Z (vertex 0)"),
    "fuzzy_de_z_right": (0.5, 0.0, 1.5, "de: right foot of Z (vertex 0)"),
    "fuzzy_de_p_left": (0.0, -0.5, 0.5, "de: left foot of P (P = 1 from 0.5)"),
}
#: output vertices: name -> (default, lower bound, upper bound, description); the ranges
#: are disjoint and ordered, so any choice keeps out_ld < out_d < 1 < out_i < out_li
OUTPUT_VERTICES = {
    "fuzzy_out_ld": (1.0 / 1.5, 0.3, 0.74, "output LD (large decrease) vertex"),
    "fuzzy_out_d": (1.0 / 1.2, 0.75, 0.99, "output D (decrease) vertex"),
    "fuzzy_out_i": (1.2, 1.01, 1.3, "output I (increase) vertex"),
    "fuzzy_out_li": (1.5, 1.31, 4.0, "output LI (large increase) vertex"),
}

# rule table: RULES[i_e][i_de] = index of the output set (0 LD, 1 D, 2 K, 3 I, 4 LI)
RULES = np.array([[0, 1, 2],
                  [1, 2, 3],
                  [2, 3, 4]])
_GRID_POINTS = 201


@jitable
def _shoulder_left(x, vertex, right):
    """1 up to ``vertex``, linear down to 0 at ``right``."""
    if x <= vertex:
        return 1.0
    if x >= right:
        return 0.0
    return (right - x) / (right - vertex)


@jitable
def _shoulder_right(x, left, vertex):
    """0 up to ``left``, linear up to 1 at ``vertex``, 1 beyond."""
    if x >= vertex:
        return 1.0
    if x <= left:
        return 0.0
    return (x - left) / (vertex - left)


@jitable
def _triangle(x, left, vertex, right):
    """1 at ``vertex``, linear down to 0 at each foot (a foot at the vertex: a vertical edge)."""
    if x == vertex:     # first: a vertical edge keeps the vertex at 1, as the shoulders do
        return 1.0
    if x <= left or x >= right:
        return 0.0
    if x <= vertex:
        return (x - left) / (vertex - left)
    return (right - x) / (right - vertex)


def memberships(x: float, vertices: Sequence[float], feet: Sequence[float]) -> np.ndarray:
    """Degrees of N, Z, P of ``x``; ``feet`` = (N right, Z left, Z right, P left)."""
    n_v, z_v, p_v = vertices
    n_right, z_left, z_right, p_left = feet
    return np.array([_shoulder_left(x, n_v, n_right), _triangle(x, z_left, z_v, z_right),
                     _shoulder_right(x, p_left, p_v)])


class FuzzyRScale:
    """The inference of the module docstring; ``params`` maps the names of ``FEET`` and
    ``OUTPUT_VERTICES`` to values (missing ones take their defaults)."""

    def __init__(self, params: Dict[str, float] | None = None):
        params = dict(params or {})
        value = {
            k: float(params.get(k, spec[0])) for k, spec in {**FEET, **OUTPUT_VERTICES}.items()
        }
        self.e_feet = tuple(value[k] for k in list(FEET)[:4])
        self.de_feet = tuple(value[k] for k in list(FEET)[4:])
        for name, vertices, feet in (("fuzzy_e", E_VERTICES, self.e_feet),
                                     ("fuzzy_de", DE_VERTICES, self.de_feet)):
            n_v, z_v, p_v = vertices
            n_right, z_left, z_right, p_left = feet
            if not (n_right >= n_v and z_left <= z_v <= z_right and p_left <= p_v):
                raise ParameterError(
                    f"fuzzy membership feet {name}_*: need N right foot >= {n_v}, Z left foot "
                    f"<= {z_v} <= Z right foot, P left foot <= {p_v}; got {feet}")
        ld, d, i, li = (value[k] for k in OUTPUT_VERTICES)
        if not 0.0 < ld < d < 1.0 < i < li:
            raise ParameterError("fuzzy output vertices: need 0 < fuzzy_out_ld < fuzzy_out_d < "
                                 f"1 < fuzzy_out_i < fuzzy_out_li, got {ld}, {d}, {i}, {li}")
        self.out_vertices = (ld, d, 1.0, i, li)
        v = tuple(float(np.log(x)) for x in self.out_vertices)
        grid = np.linspace(v[0], v[4], _GRID_POINTS)
        sets = []
        for j in range(5):     # the grid ends at v[0] and v[4]: LD only falls, LI only rises
            mu = np.zeros_like(grid)
            if j > 0:
                rise = (grid >= v[j - 1]) & (grid <= v[j])
                mu[rise] = (grid[rise] - v[j - 1]) / (v[j] - v[j - 1])
            if j < 4:
                fall = (grid >= v[j]) & (grid <= v[j + 1])
                mu[fall] = (v[j + 1] - grid[fall]) / (v[j + 1] - v[j])
            sets.append(mu)
        self.grid = grid          # ln F
        self.output_sets = np.array(sets)

    def __call__(self, e: float, de: float) -> float:
        """The factor F for inputs ``e``, ``de`` (1 when no rule fires)."""
        alone = self.__dict__.get("_alone")
        if alone is None:
            alone = self._alone = self.stacked(1)
        return float(alone(np.array([e]), np.array([de]))[0])

    def stacked(self, copies: int) -> "StackedInference":
        """This inference ``copies`` times, as one :class:`StackedInference`."""
        return StackedInference([self] * copies)


#: row j: the flat indices (e row, de column) of the rules of RULES that fire output set j,
#: padded with index 9 (a row of zero strengths)
_FIRING = np.array([np.pad(np.flatnonzero(RULES.ravel() == j), (0, 3), constant_values=9)[:3]
                    for j in range(5)])


class StackedInference:
    """Several :class:`FuzzyRScale` inferences (one per row, each with its own sets) run at
    once by :meth:`__call__`, each giving the floats it gives alone: the memberships (the
    scalar functions), the rules' min and the aggregation's max of every row are one kernel
    call (min and max are exact in any order), and each centroid's dot product is numpy's
    1-D product of its row: a stacked (1, grid) x (grid, 1) product, which numpy computes
    slice by slice as that dot (a stacked 2-D product of the rows rounds otherwise)."""

    def __init__(self, inferences: Sequence[FuzzyRScale]):
        self.inferences = list(inferences)
        #: (8, K): the e then the de feet of every inference
        self.feet = np.array([f.e_feet + f.de_feet for f in inferences], dtype=float).T.copy()
        self.output_sets = np.stack([f.output_sets for f in inferences])  # (K, 5, grid)
        self.grids = np.stack([f.grid for f in inferences])[:, :, None]   # (K, grid, 1)

    def rows(self, indices: Sequence[int]) -> "StackedInference":
        """The inferences of the rows ``indices``, in that order."""
        return StackedInference([self.inferences[i] for i in indices])

    def __call__(self, e: np.ndarray, de: np.ndarray) -> np.ndarray:
        """The factors F (K,) for the inputs ``e``, ``de`` (K,), row k by inference k."""
        aggregate = np.empty((len(e), self.output_sets.shape[2]))
        _aggregate_rows(np.asarray(e, dtype=float), np.asarray(de, dtype=float), self.feet,
                        self.output_sets, _FIRING, aggregate)
        total = aggregate.sum(axis=1)
        # each slice of the stacked (1, grid) x (grid, 1) product is numpy's 1-D dot
        centroid = np.matmul(aggregate[:, None, :], self.grids)[:, 0, 0]
        fires = ~(total <= 0.0)
        return np.where(fires, np.exp(centroid / np.where(fires, total, 1.0)), 1.0)


@jitable
def _minimum(a, b):
    """numpy's ``minimum`` of two floats (a NaN wins, the first one first)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a <= b else b


@jitable
def _maximum(a, b):
    """numpy's ``maximum`` of two floats (a NaN wins, the first one first)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a >= b else b


@kernel
def _aggregate_rows(e, de, feet, output_sets, firing, aggregate):
    """The aggregated output set (row k of ``aggregate``, on inference k's grid) of every
    inference k for the inputs ``e[k]``, ``de[k]``: the memberships of the input sets
    (``feet``: (8, K), the e then the de feet of :func:`memberships`), the rules' strengths
    (AND = min), each output set's firing (aggregation = max over its rules, ``firing``: the
    rule indices of each output set, 9 for none) and the sets cut at it, joined by max."""
    strength = np.empty(10)
    strength[9] = 0.0
    for k in range(e.shape[0]):
        f = feet[:, k]
        mu_e = (_shoulder_left(e[k], E_VERTICES[0], f[0]),
                _triangle(e[k], f[1], E_VERTICES[1], f[2]),
                _shoulder_right(e[k], f[3], E_VERTICES[2]))
        mu_de = (_shoulder_left(de[k], DE_VERTICES[0], f[4]),
                 _triangle(de[k], f[5], DE_VERTICES[1], f[6]),
                 _shoulder_right(de[k], f[7], DE_VERTICES[2]))
        for i in range(3):
            for j in range(3):
                strength[3 * i + j] = _minimum(mu_e[i], mu_de[j])
        row = aggregate[k]
        for o in range(output_sets.shape[1]):
            fired = _maximum(_maximum(strength[firing[o, 0]], strength[firing[o, 1]]),
                             strength[firing[o, 2]])
            for g in range(row.shape[0]):
                cut = _minimum(output_sets[k, o, g], fired)
                row[g] = cut if o == 0 else _maximum(row[g], cut)
