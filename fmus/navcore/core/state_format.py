"""The serialized FMU state: a versioned, checked byte format made of plain data only.

Layout (format version 1)::

    navfmu-fmu-state\\n                                        MAGIC
    {"build":"<hex>","model":"Kf","payload_sha256":"<hex>","payload_size":N,"version":1}\\n
    <payload: N bytes of UTF-8 JSON>

The header is one line of canonical JSON (sorted keys, no spaces): the model name and the
build identity (:func:`build_hash`, the hash of the FMU's Python sources, the same the build
records) say which FMU wrote the state, ``version`` which format, and the payload's size and
SHA-256 catch a truncated or altered blob.  (A checksum is not a signature: anyone can write
a valid blob.  Safety comes from the payload being decoded as data only and then checked
field by field against a component built from its parameters, :mod:`navcore.core.state`.)

The payload is a state tree (:mod:`navcore.core.state`) in JSON, where every JSON object is a
tagged node with exactly one key:

* ``null``, ``true``/``false``, integers, strings: themselves; finite floats: JSON numbers
  (Python's shortest repr, which reads back to the same bits, ``-0.0`` included);
* ``{"float": "7ff8000000000000"}``: a non-finite float by its 64 IEEE bits (NaN payloads
  and the sign kept);
* ``{"array": ["<f8", [3, 3], "<base64>"]}``: a numpy array, dtype (``<f8``, ``<i8``,
  ``|b1``), shape, and its raw little-endian C-order bytes;
* ``{"tuple": [...]}``, ``{"dict": {...}}``, ``{"deque": [maxlen or null, [...]]}``; a JSON
  array is a list.

:func:`decode` refuses, with :class:`StateFormatError` saying what is wrong, a blob larger
than :data:`MAX_STATE_BYTES` (before looking inside), another magic (the pickle-based
states of earlier versions among them), another format version, another model or build, a
size or checksum mismatch, JSON that is not in this vocabulary, nesting deeper than
:data:`MAX_DEPTH`, and arrays whose dtype, shape and data disagree.
"""
from __future__ import annotations

import base64
import binascii
import collections
import hashlib
import json
import math
import struct
from pathlib import Path
from typing import Any, Tuple

import numpy as np

from ..errors import StateFormatError

from .state import ARRAY_DTYPES

MAGIC = b"navfmu-fmu-state\n"
FORMAT_VERSION = 1
#: largest blob decoded: the states of our FMUs are below 50 kB, so a blob near this bound
#: is not one of them
MAX_STATE_BYTES = 8 * 1024 * 1024
MAX_HEADER_BYTES = 1024
#: deepest nesting of the payload (real states: under 10)
MAX_DEPTH = 48
#: integers beyond this magnitude are refused (bit-generator states hold 128-bit integers)
MAX_INT_BITS = 256
_HEADER_KEYS = ("build", "model", "payload_sha256", "payload_size", "version")
_ARRAY_DTYPES = {d.str: d for d in ARRAY_DTYPES}


Identity = Tuple[str, str]  # (model name, build hash)

#: the build-identity file in a built FMU's resources (written by the build, which gives the
#: FMU's packages names private to the build): model, version, build hash, private names
BUILD_FILE = "navfmu_build.json"


def build_hash(script: Path, shell: str = "fmushell", library: str = "navcore") -> str:
    """SHA-256 of an FMU's Python sources: its script and every ``.py`` of the shell and of
    the library beside it (the layout of ``fmus/`` and of an FMU's resources alike)."""
    script = Path(script)
    h = hashlib.sha256()
    files = [script]
    for package in (shell, library):
        files += sorted((script.parent / package).rglob("*.py"))
    for f in files:
        h.update(f.relative_to(script.parent).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def packed_content_hash(files) -> str:
    """SHA-256 of a built FMU's packed Python packages: ``files`` are (path relative to the
    resources folder, bytes) of every ``.py`` file in the packages.  The build records it
    (:data:`BUILD_FILE`); the FMU and the master compute it again to see whether the code was
    changed after the build."""
    h = hashlib.sha256()
    for name, data in sorted(files):
        h.update(name.encode() + b"\0" + hashlib.sha256(data).digest())
    return h.hexdigest()


# -- encoding -------------------------------------------------------------------------------
def encode(tree: Any, identity: Identity) -> bytes:
    """The blob of a state tree written by the FMU ``identity`` = (model, build)."""
    payload = json.dumps(_encode_node(tree), separators=(",", ":"),
                         allow_nan=False).encode("utf-8")
    model, build = identity
    header = _canonical({"build": build, "model": model, "version": FORMAT_VERSION,
                         "payload_sha256": hashlib.sha256(payload).hexdigest(),
                         "payload_size": len(payload)})
    return MAGIC + header + b"\n" + payload


def _canonical(header: dict) -> bytes:
    return json.dumps(header, sort_keys=True, separators=(",", ":")).encode("ascii")


def _encode_node(value: Any) -> Any:
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        return {"float": struct.pack(">d", value).hex()}
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value).tobytes()
        return {"array": [value.dtype.str, list(value.shape), base64.b64encode(data).decode()]}
    if isinstance(value, collections.deque):
        return {"deque": [value.maxlen, [_encode_node(v) for v in value]]}
    if isinstance(value, list):
        return [_encode_node(v) for v in value]
    if isinstance(value, tuple):
        return {"tuple": [_encode_node(v) for v in value]}
    if isinstance(value, dict):
        return {"dict": {k: _encode_node(v) for k, v in value.items()}}
    raise TypeError(f"a {type(value).__name__} is not a state tree value")


# -- decoding -------------------------------------------------------------------------------
def decode(blob: bytes, identity: Identity) -> Any:
    """The state tree in ``blob``, if it is a version-1 state written by FMU ``identity``."""
    if not isinstance(blob, (bytes, bytearray)):
        raise StateFormatError(f"a serialized state must be bytes, got {type(blob).__name__}")
    if len(blob) > MAX_STATE_BYTES:
        raise StateFormatError(f"the blob has {len(blob)} bytes, more than the "
                               f"{MAX_STATE_BYTES} any state of ours can have")
    if not blob.startswith(MAGIC):
        if blob[:1] == b"{":
            raise StateFormatError("the blob is in the pickle-based state format of earlier "
                                   "navfmu versions, which is no longer read (it could run code)")
        raise StateFormatError("the blob is not a navfmu FMU state (wrong magic bytes)"
                               if blob else "the blob is empty")
    header, payload = _split(bytes(blob))
    model, build = identity
    if header["model"] != model:
        raise StateFormatError(f"the state was written by FMU '{header['model']}', not by "
                               f"'{model}'")
    if header["build"] != build:
        raise StateFormatError(f"the state was written by another build of '{model}' "
                               f"(sources {header['build'][:12]}..., this FMU "
                               f"{build[:12]}...)")
    if len(payload) != header["payload_size"]:
        raise StateFormatError(f"the payload has {len(payload)} bytes, the header says "
                               f"{header['payload_size']} (truncated or extended blob)")
    if hashlib.sha256(payload).hexdigest() != header["payload_sha256"]:
        raise StateFormatError("the payload's SHA-256 does not match the header (altered blob)")
    try:
        node = json.loads(payload.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise StateFormatError(f"the payload is not valid JSON: {exc}") from None
    return _decode_node(node, 0, "state")


def _split(blob: bytes) -> Tuple[dict, bytes]:
    end = blob.find(b"\n", len(MAGIC), len(MAGIC) + MAX_HEADER_BYTES + 1)
    if end < 0:
        raise StateFormatError("the blob has no header line (truncated blob?)")
    raw = blob[len(MAGIC):end]
    try:
        header = json.loads(raw.decode("ascii"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError) as exc:
        raise StateFormatError(f"the header is not valid JSON: {exc}") from None
    if not isinstance(header, dict) or sorted(header) != list(_HEADER_KEYS):
        raise StateFormatError(f"the header must have exactly the keys {', '.join(_HEADER_KEYS)}")
    version = header["version"]
    if type(version) is not int or version != FORMAT_VERSION:
        raise StateFormatError(f"the state has format version {version!r}; this FMU reads "
                               f"version {FORMAT_VERSION} only")
    if not (all(isinstance(header[k], str) for k in ("build", "model", "payload_sha256"))
            and type(header["payload_size"]) is int):
        raise StateFormatError("the header has fields of the wrong type")
    if _canonical(header) != raw:
        raise StateFormatError("the header is not in canonical form (altered blob)")
    return header, blob[end + 1:]


def _no_constant(name: str):
    raise ValueError(f"{name} is not allowed (non-finite floats are tagged nodes)")


def _decode_node(node: Any, depth: int, where: str) -> Any:
    if depth > MAX_DEPTH:
        raise StateFormatError(f"{where}: nested deeper than {MAX_DEPTH} levels")
    if node is None or isinstance(node, (bool, str, float)):
        return node
    if isinstance(node, int):
        if node.bit_length() > MAX_INT_BITS:
            raise StateFormatError(f"{where}: integer larger than 2^{MAX_INT_BITS}")
        return node
    if isinstance(node, list):
        return [_decode_node(v, depth + 1, f"{where}[{i}]") for i, v in enumerate(node)]
    if not (isinstance(node, dict) and len(node) == 1):
        raise StateFormatError(f"{where}: a JSON object must be a node with one tag")
    (tag, body), = node.items()
    decoder = _DECODERS.get(tag)
    if decoder is None:
        raise StateFormatError(f"{where}: unknown node tag {tag!r}")
    return decoder(body, depth + 1, where)


def _decode_float(body: Any, depth: int, where: str) -> float:
    try:
        if not (isinstance(body, str) and len(body) == 16):
            raise ValueError(body)
        return struct.unpack(">d", bytes.fromhex(body))[0]
    except ValueError:
        raise StateFormatError(f"{where}: a float node holds 16 hex digits") from None


def _decode_array(body: Any, depth: int, where: str) -> np.ndarray:
    if not (isinstance(body, list) and len(body) == 3 and isinstance(body[2], str)):
        raise StateFormatError(f"{where}: an array node is [dtype, shape, base64 data]")
    dtype_name, shape, data = body
    dtype = _ARRAY_DTYPES.get(dtype_name) if isinstance(dtype_name, str) else None
    if dtype is None:
        raise StateFormatError(f"{where}: array dtype {dtype_name!r} is not allowed (allowed: "
                               f"{', '.join(_ARRAY_DTYPES)})")
    if not (isinstance(shape, list) and len(shape) <= 8
            and all(type(n) is int and 0 <= n <= MAX_STATE_BYTES for n in shape)):
        raise StateFormatError(f"{where}: array shape {shape!r} is not a list of sizes")
    try:
        raw = base64.b64decode(data, validate=True)
    except (binascii.Error, ValueError):
        raise StateFormatError(f"{where}: array data is not base64") from None
    count = math.prod(shape)
    if len(raw) != count * dtype.itemsize:
        raise StateFormatError(f"{where}: {len(raw)} bytes of data for {count} elements of "
                               f"{dtype.str}")
    array = np.frombuffer(raw, dtype=dtype).reshape(shape)
    if dtype.kind == "b" and raw.strip(b"\x00\x01"):
        raise StateFormatError(f"{where}: boolean array holds bytes other than 0 and 1")
    return array


def _decode_list_body(body: Any, depth: int, where: str, tag: str) -> list:
    if not isinstance(body, list):
        raise StateFormatError(f"{where}: a {tag} node holds a JSON array")
    return [_decode_node(v, depth + 1, f"{where}[{i}]") for i, v in enumerate(body)]


def _decode_tuple(body: Any, depth: int, where: str) -> tuple:
    return tuple(_decode_list_body(body, depth, where, "tuple"))


def _decode_dict(body: Any, depth: int, where: str) -> dict:
    if not isinstance(body, dict):
        raise StateFormatError(f"{where}: a dict node holds a JSON object")
    return {k: _decode_node(v, depth + 1, f"{where}.{k}") for k, v in body.items()}


def _decode_deque(body: Any, depth: int, where: str) -> collections.deque:
    if not (isinstance(body, list) and len(body) == 2
            and (body[0] is None or (type(body[0]) is int and 0 <= body[0] <= MAX_STATE_BYTES))):
        raise StateFormatError(f"{where}: a deque node is [maxlen or null, [items]]")
    items = _decode_list_body(body[1], depth, where, "deque")
    if body[0] is not None and len(items) > body[0]:
        raise StateFormatError(f"{where}: deque holds more than its maxlen {body[0]} items")
    return collections.deque(items, maxlen=body[0])


_DECODERS = {"float": _decode_float, "array": _decode_array, "tuple": _decode_tuple,
             "dict": _decode_dict, "deque": _decode_deque}
