"""Malformed nodes of a serialized FMU state (navcore.core.state_format) are refused with a
StateFormatError that names where they are, never an uncaught TypeError or ValueError; the
deque maxlen bounds of the format description; the build hash by its definition.
"""
from __future__ import annotations

import collections
import hashlib
import json
import math

import pytest

from navcore.core import state_format
from navcore.errors import StateFormatError
from test_state_format import IDENTITY, b64, handmade_blob

LIMIT = state_format.MAX_STATE_BYTES

MALFORMED_NODES = {
    "float of 16 list items": ({"float": [0] * 16}, "16 hex digits"),
    "float of 2 hex digits": ({"float": "00"}, "16 hex digits"),
    "array data not text": ({"array": ["<f8", [1], 5]}, r"\[dtype, shape, base64 data\]"),
    "array of two items": ({"array": ["<f8", [1]]}, r"\[dtype, shape, base64 data\]"),
    "deque of three items": ({"deque": [None, [], 3]}, r"\[maxlen or null, \[items\]\]"),
    "deque maxlen a float": ({"deque": [1.5, []]}, "maxlen or null"),
    "deque maxlen negative": ({"deque": [-1, []]}, "maxlen or null"),
    "deque maxlen too large": ({"deque": [LIMIT + 1, []]}, "maxlen or null"),
    "deque items not a list": ({"dict": {"q": {"deque": [2, 7]}}},
                               r"^state\.q: a deque node holds a JSON array$"),
    "tuple items not a list": ({"dict": {"t": {"tuple": 7}}},
                               r"^state\.t: a tuple node holds a JSON array$"),
    "deque beyond its maxlen": ({"deque": [1, [1, 2]]}, "more than its maxlen 1"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED_NODES))
def test_malformed_node_is_refused_with_its_place(case):
    node, message = MALFORMED_NODES[case]
    with pytest.raises(StateFormatError, match=message):
        state_format.decode(handmade_blob(node), IDENTITY)


@pytest.mark.parametrize("maxlen, items", [(0, []), (LIMIT, [1.0]), (None, [1.0, 2.0])])
def test_deque_maxlen_from_zero_to_the_blob_bound_is_read(maxlen, items):
    tree = state_format.decode(handmade_blob({"deque": [maxlen, items]}), IDENTITY)
    assert tree == collections.deque(items, maxlen=maxlen) and tree.maxlen == maxlen


def test_an_array_node_with_its_data_reads():
    tree = state_format.decode(handmade_blob({"array": ["<i8", [1], b64(bytes(8))]}), IDENTITY)
    assert tree.tolist() == [0]


def test_build_hash_is_the_sha256_of_the_named_sources(tmp_path):
    """The hash of (relative path, bytes) of the script, then of every .py of the shell and of
    the library in sorted order; nothing else counts."""
    (tmp_path / "Kf.py").write_bytes(b"script")
    for name, text in (("fmushell/b.py", b"shell b"), ("fmushell/a.py", b"shell a"),
                       ("navcore/sub/c.py", b"lib c"), ("navcore/notes.txt", b"ignored"),
                       ("other/d.py", b"ignored")):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(text)
    expected = hashlib.sha256(b"Kf.pyscript" + b"fmushell/a.pyshell a" + b"fmushell/b.pyshell b"
                              + b"navcore/sub/c.pylib c").hexdigest()
    assert state_format.build_hash(tmp_path / "Kf.py") == expected
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "c.py").write_bytes(b"lib c")
    assert state_format.build_hash(tmp_path / "Kf.py", "fmushell", "lib") == hashlib.sha256(
        b"Kf.pyscript" + b"fmushell/a.pyshell a" + b"fmushell/b.pyshell b" + b"lib/c.pylib c"
    ).hexdigest()


def _nested(levels, wrap):
    node = wrap(None)
    for _ in range(levels - 1):
        node = wrap(node)
    return node


# a list is one level, a tuple or dict node two (the node and its body): MAX_DEPTH = 48 admits
# nodes at depths 0..48, so 49 nested lists and 25 nested tuples or dicts
NESTINGS = {"list": (49, lambda n: [] if n is None else [n]),
            "tuple": (25, lambda n: {"tuple": [] if n is None else [n]}),
            "dict": (25, lambda n: {"dict": {} if n is None else {"a": n}})}


@pytest.mark.parametrize("kind", sorted(NESTINGS))
def test_nesting_up_to_max_depth_is_read_and_one_more_level_refused(kind):
    assert state_format.MAX_DEPTH == 48
    levels, wrap = NESTINGS[kind]
    state_format.decode(handmade_blob(_nested(levels, wrap)), IDENTITY)
    with pytest.raises(StateFormatError, match="nested deeper than 48 levels"):
        state_format.decode(handmade_blob(_nested(levels + 1, wrap)), IDENTITY)


def test_integers_up_to_256_bits_are_read():
    assert state_format.decode(handmade_blob(2 ** 256 - 1), IDENTITY) == 2 ** 256 - 1
    with pytest.raises(StateFormatError, match="larger than 2"):
        state_format.decode(handmade_blob(-(2 ** 256)), IDENTITY)


@pytest.mark.parametrize("node, place", [([[1, {"bogus": 1}]], r"state\[0\]\[1\]"),
                                         ({"tuple": [1, {"bogus": 1}]}, r"state\[1\]"),
                                         ({"deque": [None, [{"bogus": 1}]]}, r"state\[0\]")])
def test_an_error_names_the_place_of_the_node(node, place):
    with pytest.raises(StateFormatError, match=rf"^{place}: unknown node tag 'bogus'$"):
        state_format.decode(handmade_blob(node), IDENTITY)


EIGHT_BYTES = b64(bytes(8))
MALFORMED_ARRAYS = {
    "dtype a list": (["<f8"], [1], EIGHT_BYTES, "not allowed"),
    "a bool size": ("<f8", [True], EIGHT_BYTES, "not a list of sizes"),
    "nine dimensions": ("<f8", [1] * 9, EIGHT_BYTES, "not a list of sizes"),
    "a size beyond the blob bound": ("<f8", [LIMIT + 1, 0], "", "not a list of sizes"),
    "a negative size": ("<f8", [-1], EIGHT_BYTES, "not a list of sizes"),
    "a character outside base64": ("<f8", [1], "AAAA*AAAAAAA=", "not base64"),
    "a bool byte 'X'": ("|b1", [1], b64(b"X"), "0 and 1"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED_ARRAYS))
def test_malformed_array_is_refused(case):
    dtype, shape, data, message = MALFORMED_ARRAYS[case]
    with pytest.raises(StateFormatError, match=message):
        state_format.decode(handmade_blob({"array": [dtype, shape, data]}), IDENTITY)


@pytest.mark.parametrize("shape, data", [([1] * 8, EIGHT_BYTES), ([0], ""),
                                         ([LIMIT, 0], ""), ([2, 0, 3], "")])
def test_array_shapes_within_the_bounds_are_read(shape, data):
    array = state_format.decode(handmade_blob({"array": ["<f8", shape, data]}), IDENTITY)
    assert array.shape == tuple(shape)


def test_encode_writes_compact_json_and_a_sorted_header():
    # the header and payload byte for byte, as the format description lays them out
    blob = state_format.encode({"a": [1, 2.5], "t": (None,)}, IDENTITY)
    payload = b'{"dict":{"a":[1,2.5],"t":{"tuple":[null]}}}'
    header = (b'{"build":"' + IDENTITY[1].encode() + b'","model":"Kf","payload_sha256":"'
              + hashlib.sha256(payload).hexdigest().encode() + b'","payload_size":43,'
              b'"version":1}')
    assert blob == b"navfmu-fmu-state\n" + header + b"\n" + payload


def _blob_with_header_of(size):
    """A valid blob whose header line has ``size`` bytes (the model name fills it)."""
    short = handmade_blob({"dict": {}}, ("", IDENTITY[1]))
    model = "M" * (size - (len(short.split(b"\n")[1])))
    return handmade_blob({"dict": {}}, (model, IDENTITY[1])), (model, IDENTITY[1])


def test_a_header_of_max_header_bytes_is_read_and_a_longer_one_refused():
    assert state_format.MAX_HEADER_BYTES == 1024
    blob, identity = _blob_with_header_of(1024)
    assert state_format.decode(blob, identity) == {}
    blob, identity = _blob_with_header_of(1025)
    with pytest.raises(StateFormatError, match="no header line"):
        state_format.decode(blob, identity)


def _raw_blob(header_fields, payload):
    header = {"build": IDENTITY[1], "model": IDENTITY[0], "version": 1,
              "payload_sha256": hashlib.sha256(payload).hexdigest(),
              "payload_size": len(payload), **header_fields}
    text = json.dumps(header, sort_keys=True, separators=(",", ":"))
    return b"navfmu-fmu-state\n" + text.encode() + b"\n" + payload


def test_the_header_ends_at_the_first_newline():
    # JSON allows a newline between tokens: the payload may hold one
    assert state_format.decode(_raw_blob({}, b"[1,\n2]"), IDENTITY) == [1, 2]


def test_a_nan_literal_in_the_header_is_not_json_here():
    blob = _raw_blob({"build": math.nan}, b"[]")
    with pytest.raises(StateFormatError, match="the header is not valid JSON: NaN"):
        state_format.decode(blob, IDENTITY)


def test_a_blob_of_max_state_bytes_is_read():
    # JSON allows whitespace after the value: pad the payload to a blob of exactly the bound
    # (the header's payload_size grows from 1 digit to 7)
    pad = LIMIT - len(_raw_blob({}, b"[]")) - (len(str(LIMIT)) - 1)
    blob = _raw_blob({}, b"[]" + b" " * pad)
    assert len(blob) == LIMIT and state_format.decode(blob, IDENTITY) == []
    with pytest.raises(StateFormatError, match="more than"):
        state_format.decode(blob + b" ", IDENTITY)


@pytest.mark.parametrize("fields, message", [
    ({"extra": 1}, "exactly the keys build, model, payload_sha256, payload_size, version"),
    ({"payload_size": "2"}, "fields of the wrong type"),
    ({"build": 5}, "fields of the wrong type")])
def test_the_header_has_its_keys_with_their_types(fields, message):
    with pytest.raises(StateFormatError, match=message):
        state_format.decode(_raw_blob(fields, b"[]"), IDENTITY)
