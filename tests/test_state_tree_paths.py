"""State trees of small declared objects (navcore.core.state), by hand: what a tree holds (copies,
Python scalars for numpy ones), and that every refusal starts with the path of the value it
refuses (``Outer.inner.values[1].a``) and names the kinds it expected and got."""

from __future__ import annotations

import collections
import re

import numpy as np
import pytest

from navcore.core.state import capture, capture_value, restore
from navcore.errors import StateError


class Inner:
    state_fields = ("values", "table", "pair", "recent", "spare")

    def __init__(self):
        self.values = [1.0, 2.0]
        self.table = {"a": 1.0, "b": [True, 2]}
        self.pair = (1, 2.0)
        self.recent = collections.deque([1.0, 2.0], maxlen=3)
        self.spare = None


class Outer:
    state_fields = ("inner", "x")

    def __init__(self):
        self.inner = Inner()
        self.x = np.zeros(2)


def _refusal(field, value):
    """The message of restoring a fresh Outer from its tree with ``inner.<field>`` replaced."""
    tree = capture(Outer())
    tree["inner"][field] = value
    with pytest.raises(StateError) as refused:
        restore(Outer(), tree)
    return str(refused.value)


def test_numpy_scalars_become_python_scalars():
    for value, kind, plain in ((np.float64(1.5), float, 1.5), (np.int64(3), int, 3),
                               (np.bool_(True), bool, True), (np.float32(0.5), float, 0.5)):
        got = capture_value(value, "v")
        assert type(got) is kind and got == plain
    got = capture_value((np.float64(1.5), 2.0), "v")
    assert [type(v) for v in got] == [float, float]


def test_the_tree_holds_copies_of_arrays():
    outer = Outer()
    outer.inner.pair = (np.ones(2), 1.0)
    tree = capture(outer)
    outer.x[0] = 7.0
    outer.inner.pair[0][0] = 7.0
    np.testing.assert_array_equal(tree["x"], [0.0, 0.0])
    np.testing.assert_array_equal(tree["inner"]["pair"][0], [1.0, 1.0])
    tree = capture(Outer())
    fresh = Outer()
    restore(fresh, tree)
    tree["x"][1] = 5.0
    np.testing.assert_array_equal(fresh.x, [0.0, 0.0])


def test_capture_refusals_start_with_the_path():
    outer = Outer()
    outer.x = np.zeros(2, dtype=np.float32)
    with pytest.raises(StateError, match=r"^Outer\.x: arrays of dtype float32 cannot be state"):
        capture(outer)
    outer = Outer()
    outer.inner.table = {"a": {1, 2}}
    with pytest.raises(StateError, match=r"^Outer\.inner\.table\.a: a set cannot be state"):
        capture(outer)


@pytest.mark.parametrize("field, value, message", [
    ("values", (1.0, 2.0), r"^Outer\.inner\.values: expected list, got a value of kind tuple"),
    ("values", {1.0}, r"^Outer\.inner\.values: expected list, got a value of kind set"),
    ("values", [1.0, "text"], r"^Outer\.inner\.values\[1\]: expected float, got a value of "
                              r"kind str"),
    ("values", [1.0, 2.0, {"k": "text"}], r"^Outer\.inner\.values\[2\]\.k: expected numeric "
                                          r"data, got a value of kind str"),
    ("table", {"a": 1.0, "b": [True, "x"]}, r"^Outer\.inner\.table\.b\[1\]: expected int, got "
                                            r"a value of kind str"),
    ("table", {"a": 1.0, "b": [False, "x", 1]}, r"^Outer\.inner\.table\.b\[1\]: expected "
                                                r"numeric data"),
    ("pair", (1, 2.0, 3.0), r"^Outer\.inner\.pair: expected 2 items, got 3"),
    ("pair", (1.0, 2.0), r"^Outer\.inner\.pair\[0\]: expected int, got a value of kind float"),
    ("recent", collections.deque([1.0], maxlen=2), r"^Outer\.inner\.recent: expected a deque "
                                                   r"of maxlen 3"),
    ("recent", collections.deque([1.0, "x"], maxlen=3), r"^Outer\.inner\.recent\[1\]: "),
    ("spare", [1.0, ["x"]], r"^Outer\.inner\.spare\[1\]\[0\]: expected numeric data, got a "
                            r"value of kind str"),
    ("spare", collections.deque([{"k": "x"}]), r"^Outer\.inner\.spare\[0\]\.k: expected numeric"),
    ("spare", {"k": np.float32(1.0)}, None),
])
def test_restore_refusals_start_with_the_path_and_name_the_kinds(field, value, message):
    if message is None:              # a numpy float is numeric data where no value is expected
        tree = capture(Outer())
        tree["inner"][field] = value
        restore(Outer(), tree)
        return
    refusal = _refusal(field, value)
    assert re.match(message, refusal), refusal


def test_numeric_data_where_no_value_is_expected():
    """A field that is None in the fresh object takes numbers, bools, arrays and containers of
    them, and refuses text at any depth."""
    tree = capture(Outer())
    tree["inner"]["spare"] = [True, 1, 2.5, np.zeros(1), (None,), {"k": [False]}]
    fresh = Outer()
    restore(fresh, tree)
    assert fresh.inner.spare[0] is True and fresh.inner.spare[5] == {"k": [False]}
    assert _refusal("spare", ("x",)).startswith("Outer.inner.spare[0]: expected numeric data")


def test_restore_names_a_tree_that_is_not_the_fields():
    tree = capture(Outer())
    tree["inner"] = [1.0]
    with pytest.raises(StateError, match=r"^Outer\.inner: expected the fields of a Inner, got a "
                                         r"value of kind list"):
        restore(Outer(), tree)
    with pytest.raises(StateError, match=r"^Outer: expected the fields of a Outer"):
        restore(Outer(), [])


def test_numpy_scalars_in_a_tuple_become_python_scalars():
    got = capture_value((np.float64(1.5), np.int64(2)), "v")
    assert [type(v) for v in got] == [float, int] and got == (1.5, 2)


def test_a_big_endian_array_is_held_little_endian():
    """The allowed dtypes are stored little-endian: a '>f8' array becomes a '<f8' copy with the
    same values (a '>f4' one is refused)."""
    big = np.array([1.5, -2.0], dtype=">f8")
    got = capture_value(big, "v")
    assert got.dtype == np.dtype("<f8")
    np.testing.assert_array_equal(got, [1.5, -2.0])
    big[0] = 9.0
    assert got[0] == 1.5
    with pytest.raises(StateError, match=r"^v: arrays of dtype >f4 cannot be state"):
        capture_value(np.zeros(1, dtype=">f4"), "v")


def test_refused_items_of_lists_and_deques_are_named_by_index():
    with pytest.raises(StateError, match=r"^v\[1\]: a set cannot be state"):
        capture_value([1.0, {2.0}], "v")
    with pytest.raises(StateError, match=r"^v\[1\]: a set cannot be state"):
        capture_value(collections.deque([1.0, {2.0}]), "v")


class Holder:
    state_fields = ("items",)

    def __init__(self):
        self.items = [Outer(), Outer()]


def test_a_list_of_objects_is_restored_item_by_item():
    holder = Holder()
    holder.items[1].x[:] = [3.0, 4.0]
    tree = capture(holder)
    fresh = Holder()
    restore(fresh, tree)
    np.testing.assert_array_equal(fresh.items[1].x, [3.0, 4.0])
    tree["items"][1]["x"] = np.zeros(3)
    with pytest.raises(StateError, match=r"^Holder\.items\[1\]\.x: expected a float64 array"):
        restore(Holder(), tree)
    tree["items"] = tuple(capture(holder)["items"])
    with pytest.raises(StateError, match=r"^Holder\.items: expected a list of 2 objects"):
        restore(Holder(), tree)
