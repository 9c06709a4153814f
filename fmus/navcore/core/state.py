"""Declared state: what defines an object's state, taken and restored as plain data.

A class takes part by declaring, as class attributes, which of its instance attributes are
state and which are rebuilt from the parameters::

    class Strapdown:
        state_fields = ("lat", "lon", "h", "v_ned", "C_bn", "_v_prev", ...)

    class KfEngine:
        state_fields = ("nav", "P", "gyro_bias", ...)      # nav: a declared object itself
        derived_fields = ("config", "q_density", "R0", "m", "H")

A subclass declares only the attributes it adds; the declarations of every class of the MRO
add up (:func:`declared_fields`).  :func:`capture` turns an object into a *state tree* (a dict
field -> value) and refuses, with :class:`StateError` naming them, instance attributes that
are in neither list, so an attribute added without a declaration fails the first time a
state is taken (and the test that walks every registered component).

Values a state field may hold (:func:`capture_value`): None, bool, int, float, str, numpy
arrays of float64/int64/bool, lists, tuples, dicts with str keys and deques of these, a
``numpy.random.Generator`` (its ``bit_generator.state``, a plain dict) and objects that
declare their own fields (captured recursively; a list of such objects too).  Numpy scalars
become Python scalars.  The tree holds copies: later changes of the object do not reach it.

:func:`restore` writes a tree into an object *freshly built from the same parameters*: for
every declared field the fresh value says what is expected.  A declared object is restored
in place (so its derived attributes stay those of the fresh build), a Generator gets its
bit-generator state, anything else is replaced by a copy of the tree's value after a kind
check (same kind, same dtype and shape for arrays, same keys for dicts; where the fresh
object has no value to compare with -- a field that is None, the items of a list or deque of
another length -- only numeric data is accepted: None, numbers, arrays and containers of
them, no text).  The tree never names a class: nothing in it is
called, imported or instantiated, so a tree from an untrusted source is only data.
"""
from __future__ import annotations

import collections
import functools
from typing import Any, Dict, Tuple

import numpy as np

from ..errors import StateError

#: dtypes a state array may have (stored little-endian)
ARRAY_DTYPES = (np.dtype("<f8"), np.dtype("<i8"), np.dtype("|b1"))
#: the allowed dtypes in this machine's byte order (copied as they are)
_NATIVE_DTYPES = tuple(d for d in ARRAY_DTYPES if d.isnative)


@functools.lru_cache(maxsize=None)   # declarations are class attributes: one walk per class
def declared_fields(cls) -> Tuple[Tuple[str, ...], Tuple[str, ...]]:
    """(state fields, derived fields) of ``cls``: the declarations of its MRO, in order."""
    state, derived = [], []
    for klass in reversed(cls.__mro__):
        own = vars(klass)
        state += [f for f in own.get("state_fields", ()) if f not in state]
        derived += [f for f in own.get("derived_fields", ()) if f not in derived]
    return tuple(state), tuple(derived)


def is_declared(obj: Any) -> bool:
    """True for an object whose class declares its state (``state_fields``)."""
    return hasattr(type(obj), "state_fields") and not isinstance(obj, type)


@functools.lru_cache(maxsize=None)
def _known_fields(cls) -> frozenset:
    state, derived = declared_fields(cls)
    return frozenset(state) | frozenset(derived)


def undeclared_attributes(obj: Any) -> Tuple[str, ...]:
    """Instance attributes of ``obj`` that are neither state nor derived fields."""
    known = _known_fields(type(obj))
    attributes = vars(obj)
    if known.issuperset(attributes):     # the usual case, by one set operation
        return ()
    return tuple(sorted(a for a in attributes if a not in known))


#: what :func:`capture` reads for a declared field an object does not have
_NOT_SET = object()


def capture(obj: Any, where: str = "") -> Dict[str, Any]:
    """The state tree of a declared object (see the module docstring)."""
    where = where or type(obj).__name__
    missing = undeclared_attributes(obj)
    if missing:
        raise StateError(
            f"{where}: attribute(s) {', '.join(missing)} of {type(obj).__name__} are neither in "
            "state_fields nor in derived_fields; declare them (navcore.core.state)")
    state, _ = declared_fields(type(obj))
    tree = {}
    for name in state:
        # one lookup: a field may be a property that computes its value
        value = getattr(obj, name, _NOT_SET)
        kind = type(value)
        # capture_value's first two cases, without naming the field (a latency history
        # captures its engine after every fix)
        if kind in _PLAIN_TYPES:
            tree[name] = value
        elif kind is np.ndarray and value.dtype in _NATIVE_DTYPES:
            tree[name] = np.array(value, copy=True)
        elif value is _NOT_SET:
            raise StateError(f"{where}.{name}: declared state field is not set")
        else:
            tree[name] = capture_value(value, f"{where}.{name}")
    return tree



#: types a tree holds as they are (immutable): the common case, checked first
_PLAIN_TYPES = frozenset((type(None), bool, str, int, float))


def capture_value(value: Any, where: str) -> Any:
    """A copy of ``value`` made of the kinds a state tree holds (module docstring)."""
    kind = type(value)
    if kind in _PLAIN_TYPES:
        return value
    if kind is np.ndarray and value.dtype in _NATIVE_DTYPES:
        return np.array(value, copy=True)
    if kind is tuple and all(type(v) is float for v in value):   # e.g. a 3-vector of floats
        return value
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, float)):
        return value if type(value) in (int, float) else _python_scalar(value)
    if isinstance(value, np.generic):
        return _python_scalar(value)
    if isinstance(value, np.ndarray):
        dtype = value.dtype.newbyteorder("<") if value.dtype.byteorder == ">" else value.dtype
        if dtype not in ARRAY_DTYPES:
            raise StateError(f"{where}: arrays of dtype {value.dtype} cannot be state "
                             f"(allowed: {', '.join(d.str for d in ARRAY_DTYPES)})")
        return np.array(value, dtype=dtype, copy=True)
    if isinstance(value, np.random.Generator):
        return capture_value(value.bit_generator.state, f"{where}.bit_generator")
    if is_declared(value):
        return capture(value, where)
    if isinstance(value, collections.deque):
        return collections.deque((capture_value(v, f"{where}[{i}]") for i, v in enumerate(value)),
                                 maxlen=value.maxlen)
    if isinstance(value, (list, tuple)):
        items = [v if type(v) in _PLAIN_TYPES else capture_value(v, f"{where}[{i}]")
                 for i, v in enumerate(value)]
        return items if isinstance(value, list) else tuple(items)
    if isinstance(value, dict):
        for key in value:
            if not isinstance(key, str):
                raise StateError(f"{where}: dict keys must be str, got {key!r}")
        return {k: capture_value(v, f"{where}.{k}") for k, v in value.items()}
    raise StateError(f"{where}: a {type(value).__name__} cannot be state; declare its class's "
                     "fields (state_fields/derived_fields) or store plain data")


def _python_scalar(value: Any) -> Any:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    raise StateError(f"numpy scalar of type {type(value).__name__} cannot be state")


def restore(obj: Any, tree: Any, where: str = "") -> None:
    """Write the state tree ``tree`` into ``obj``, freshly built from the same parameters."""
    where = where or type(obj).__name__
    state, _ = declared_fields(type(obj))
    if not isinstance(tree, dict):
        raise StateError(f"{where}: expected the fields of a {type(obj).__name__}, got "
                         f"{_kind_name(tree)}")
    missing = [f for f in state if f not in tree]
    extra = [f for f in tree if f not in state]
    if missing or extra:
        raise StateError(f"{where}: the state's fields do not match {type(obj).__name__} "
                         f"(missing: {', '.join(missing) or '-'}; unknown: "
                         f"{', '.join(map(str, extra)) or '-'})")
    for name in state:
        current = getattr(obj, name)
        setattr(obj, name, restore_value(current, tree[name], f"{where}.{name}"))


def restore_value(current: Any, node: Any, where: str) -> Any:
    """The value a field holding ``current`` (in the fresh object) takes from ``node``."""
    if is_declared(current):
        restore(current, node, where)
        return current
    if isinstance(current, np.random.Generator):
        if not isinstance(node, dict):
            raise StateError(f"{where}: expected a bit-generator state, got {_kind_name(node)}")
        try:
            current.bit_generator.state = copy_value(node)
        except (TypeError, ValueError, KeyError, OverflowError) as exc:
            raise StateError(f"{where}: not a valid {type(current.bit_generator).__name__} "
                             f"state ({exc})") from None
        return current
    if isinstance(current, list) and any(is_declared(v) for v in current):
        if not isinstance(node, list) or len(node) != len(current):
            raise StateError(f"{where}: expected a list of {len(current)} objects")
        for i, (item, sub) in enumerate(zip(current, node)):
            restore_value(item, sub, f"{where}[{i}]")
        return current
    check_kind(current, node, where)
    return copy_value(node)


def check_kind(current: Any, value: Any, where: str) -> None:
    """Raise :class:`StateError` unless ``value`` may replace ``current`` (module docstring)."""
    if current is None:
        _check_numeric_data(value, where)
        return
    if isinstance(current, np.ndarray):
        if not (isinstance(value, np.ndarray) and value.dtype == current.dtype
                and value.shape == current.shape):
            raise StateError(f"{where}: expected a {current.dtype} array of shape "
                             f"{current.shape}, got {_kind_name(value)}")
        return
    kind = _kind(current)
    if _kind(value) != kind:
        raise StateError(f"{where}: expected {kind}, got {_kind_name(value)}")
    if kind == "dict":
        if set(value) != set(current):
            raise StateError(f"{where}: the keys differ from those of this component")
        for key in current:
            check_kind(current[key], value[key], f"{where}.{key}")
    elif kind == "tuple" and len(value) == len(current):
        for i, (c, v) in enumerate(zip(current, value)):
            check_kind(c, v, f"{where}[{i}]")
    elif kind == "tuple":
        raise StateError(f"{where}: expected {len(current)} items, got {len(value)}")
    elif kind == "deque" and value.maxlen != current.maxlen:
        raise StateError(f"{where}: expected a deque of maxlen {current.maxlen}")
    if kind in ("list", "deque"):
        if len(value) == len(current):
            for i, (c, v) in enumerate(zip(current, value)):
                check_kind(c, v, f"{where}[{i}]")
        else:
            for i, v in enumerate(value):
                _check_numeric_data(v, f"{where}[{i}]")


def _check_numeric_data(value: Any, where: str) -> None:
    """Accept None, numbers, arrays and lists/tuples/deques/dicts of these (no text)."""
    kind = _kind(value)
    if kind in ("list", "tuple", "deque"):
        for i, v in enumerate(value):
            _check_numeric_data(v, f"{where}[{i}]")
    elif kind == "dict":
        for k, v in value.items():
            _check_numeric_data(v, f"{where}.{k}")
    elif kind not in ("None", "bool", "int", "float", "array"):
        raise StateError(f"{where}: expected numeric data, got {_kind_name(value)}")


def _kind(value: Any) -> str:
    if value is None:
        return "None"
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, np.integer)):
        return "int"
    if isinstance(value, (float, np.floating)):
        return "float"
    for kind, types in (("str", str), ("array", np.ndarray), ("deque", collections.deque),
                        ("list", list), ("tuple", tuple), ("dict", dict)):
        if isinstance(value, types):
            return kind
    return type(value).__name__


def _kind_name(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return f"a {value.dtype} array of shape {value.shape}"
    return f"a value of kind {_kind(value)}"


def copy_value(node: Any) -> Any:
    """A deep copy of a state tree value (arrays copied and writeable)."""
    if isinstance(node, np.ndarray):
        return np.array(node, copy=True)
    if isinstance(node, collections.deque):
        return collections.deque((copy_value(v) for v in node), maxlen=node.maxlen)
    if isinstance(node, list):
        return [copy_value(v) for v in node]
    if isinstance(node, tuple):
        return tuple(copy_value(v) for v in node)
    if isinstance(node, dict):
        return {k: copy_value(v) for k, v in node.items()}
    return node
