"""navcore.filters.array_checks, the input checks of the laws: what each accepts (as float
arrays of the documented shape, a scalar as the documented shape) and what it refuses, with
the argument's name first in the message."""
from __future__ import annotations

import numpy as np
import pytest

from navcore.errors import InputError
from navcore.filters.array_checks import matrix, square, symmetrize, vector


def test_a_vector_is_float_and_a_scalar_is_one_element():
    a = vector("v", [1, 2, 3])
    assert a.dtype == np.float64 and a.tolist() == [1.0, 2.0, 3.0]
    one = vector("v", 3)
    assert one.dtype == np.float64 and one.shape == (1,) and one[0] == 3.0


@pytest.mark.parametrize("bad, words", [([[1.0, 2.0]], "expected a vector of shape (m,), got "
                                         "shape (1, 2)"),
                                        ([1.0, np.nan], "contains NaN or inf"),
                                        ([np.inf], "contains NaN or inf")])
def test_a_vector_of_another_shape_or_not_finite_is_refused(bad, words):
    with pytest.raises(InputError) as e:
        vector("innovation", bad)
    assert str(e.value).startswith("innovation: ") and words in str(e.value)


def test_a_matrix_is_float_with_the_rows_and_columns_asked_for():
    a = matrix("K", [[1, 2], [3, 4], [5, 6]], rows=3, cols=2)
    assert a.dtype == np.float64 and a.shape == (3, 2) and a[2, 1] == 6.0
    assert matrix("K", np.ones((4, 2)), cols=2).shape == (4, 2)        # rows: any
    assert matrix("K", np.ones((2, 5)), rows=2).shape == (2, 5)        # columns: any
    assert matrix("K", np.ones((2, 5))).shape == (2, 5)


def test_a_scalar_is_a_matrix_only_where_both_sizes_are_one():
    a = matrix("R", 2, rows=1, cols=1)
    assert a.dtype == np.float64 and a.shape == (1, 1) and a[0, 0] == 2.0
    for rows, cols, want in ((None, None, "(n, n)"), (1, None, "(1, n)"), (None, 1, "(n, 1)"),
                             (2, 1, "(2, 1)"), (1, 2, "(1, 2)")):
        with pytest.raises(InputError, match=r"^R: expected shape " + want.replace("(", r"\(")
                           .replace(")", r"\)") + r", got \(\)$"):
            matrix("R", 2.0, rows=rows, cols=cols)
    with pytest.raises(InputError, match=r"^R: expected shape \(1, 1\), got \(1,\)$"):
        matrix("R", [2.0], rows=1, cols=1)                # a vector is not a scalar


@pytest.mark.parametrize("shape, rows, cols", [((3, 2), 2, 2), ((3, 2), 3, 3), ((3,), None, None),
                                               ((1, 2, 2), None, None)])
def test_a_matrix_of_another_shape_is_refused(shape, rows, cols):
    with pytest.raises(InputError, match=r"^K: expected shape \("):
        matrix("K", np.ones(shape), rows=rows, cols=cols)


def test_a_matrix_with_nan_or_inf_is_refused():
    for value in (np.nan, np.inf, -np.inf):
        x = np.ones((2, 2))
        x[1, 0] = value
        with pytest.raises(InputError, match=r"^P: contains NaN or inf$"):
            matrix("P", x, rows=2, cols=2)


def test_a_square_matrix_is_float_and_a_scalar_is_one_by_one():
    a = square("G", [[2, 1], [1, 3]])
    assert a.dtype == np.float64 and a.tolist() == [[2.0, 1.0], [1.0, 3.0]]
    one = square("G", 4)
    assert one.dtype == np.float64 and one.shape == (1, 1) and one[0, 0] == 4.0
    assert square("G", 4, 1).shape == (1, 1)
    assert square("G", np.eye(3), 3).shape == (3, 3)


@pytest.mark.parametrize("x, m, words", [(np.ones((2, 3)), None, "expected a square matrix, "
                                          "got shape (2, 3)"),
                                         (np.ones(3), None, "expected a square matrix, got "
                                          "shape (3,)"),
                                         (np.eye(3), 2, "expected shape (2, 2), got (3, 3)"),
                                         (5.0, 2, "expected shape (2, 2), got (1, 1)"),
                                         (np.diag([1.0, np.nan]), 2, "contains NaN or inf")])
def test_a_square_matrix_of_another_shape_or_not_finite_is_refused(x, m, words):
    with pytest.raises(InputError) as e:
        square("G", x, m)
    assert str(e.value).startswith("G: ") and words in str(e.value)


def test_symmetrize_is_the_mean_with_the_transpose():
    a = np.array([[1.0, 2.0], [4.0, 3.0]])
    assert symmetrize(a).tolist() == [[1.0, 3.0], [3.0, 3.0]]
