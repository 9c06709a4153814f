"""JSON-ready values for the files navfmu writes: NaN as null, keys as text, other objects
as their text (``json.dumps`` would write NaN, which JSON does not have)."""
from __future__ import annotations


def jsonable(value):
    """``value`` with every NaN replaced by None, dict keys by their text, tuples by lists and
    any other non-JSON object by its ``str``."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, float) and value != value:
        return None  # NaN is not JSON
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


__all__ = ["jsonable"]
