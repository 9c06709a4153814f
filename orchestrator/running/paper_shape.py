"""The shape of a scenario's ``paper.json`` (the paper's numbers), checked when it is read, so
that a malformed file is refused by name before any run rather than failing after it.

The blocks, each optional: ``table`` (rows with a ``label``, the ``filter`` they belong to and
per-axis RMS values north/east/down ``position_ned_m``, ``velocity_ned_mps`` and
roll/pitch/yaw ``attitude_deg``, each three numbers or null), ``improvement_percent``
(``baseline`` and ``filter`` names, then numbers or lists of numbers: per axis N/E/D for the
keys ending in ``_ned``), ``time_per_cycle_ms`` (filter -> ms), ``windows`` (name -> ``t0`` <
``t1`` [s] and a ``label``), ``phases`` (an object), ``claims`` (a list) and ``span_s`` (the
``[start, stop]`` [s] of the paper's experiment: its numbers compare only with a run over that
span); text entries (``paper``, ``source``, ``shape``, ``note``) are free.

Files of the earlier east/north/up keys (``position_enu_m``, ``velocity_enu_mps``,
``position_enu``, ``position_ratio_enu``, ...) are still read: :func:`check_reference` returns
them rearranged into today's N/E/D keys (the RMS of up is the RMS of down).
"""
from __future__ import annotations

import math
from numbers import Real
from typing import Any

from ..errors import NavfmuError

#: the per-axis value lists of a table row and what their three entries are
TABLE_AXES = {"position_ned_m": "north, east, down", "velocity_ned_mps": "north, east, down",
              "attitude_deg": "roll, pitch, yaw",
              # the keys of files written before the one axis order
              "position_enu_m": "east, north, up", "velocity_enu_mps": "east, north, up"}
#: a key of the earlier east/north/up order -> today's north/east/down key
_OLD_TABLE_KEYS = {"position_enu_m": "position_ned_m", "velocity_enu_mps": "velocity_ned_mps"}
#: the endings of improvement_percent's per-axis keys: earlier -> today's
_OLD_ENDINGS = {"_ratio_enu": "_ratio_ned", "_enu": "_ned"}
_TEXT = ("note", "baseline", "filter")


def _number(value) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)


def _fail(path, where: str, expected: str, value: Any):
    shown = repr(value)
    shown = shown if len(shown) <= 40 else shown[:37] + "..."
    raise NavfmuError(f"{path}: {where}: expected {expected}, got {shown}")


def _check_row(path, i: int, row) -> None:
    where = f"table[{i}]"
    if not isinstance(row, dict):
        _fail(path, where, "an object", row)
    if not isinstance(row.get("label"), str):
        _fail(path, f"{where}.label", "a text", row.get("label"))
    if row.get("filter") is not None and not isinstance(row["filter"], str):
        _fail(path, f"{where}.filter", "a filter name or null", row["filter"])
    for key, axes in TABLE_AXES.items():
        value = row.get(key)
        if value is not None and not (isinstance(value, list) and len(value) == 3
                                      and all(v is None or _number(v) for v in value)):
            _fail(path, f"{where}.{key}", f"3 numbers ({axes}) or null", value)


def _check_improvement(path, block) -> None:
    if not isinstance(block, dict):
        _fail(path, "improvement_percent", "an object", block)
    for key in ("baseline", "filter"):
        if not isinstance(block.get(key), str):
            _fail(path, f"improvement_percent.{key}", "a filter name", block.get(key))
    for key, value in block.items():
        if key in _TEXT:
            continue
        if not (_number(value) or (isinstance(value, list) and value
                                   and all(v is None or _number(v) for v in value))):
            _fail(path, f"improvement_percent.{key}", "a number or a list of numbers", value)


def _check_windows(path, windows) -> None:
    if not isinstance(windows, dict):
        _fail(path, "windows", "an object of named windows", windows)
    for name, w in windows.items():
        where = f"windows.{name}"
        if not (isinstance(w, dict) and _number(w.get("t0")) and _number(w.get("t1"))
                and w["t1"] > w["t0"]):
            _fail(path, where, "an object with t0 < t1 [s]", w)


def _north_east_down(values):
    """East, north, up RMS values -> north, east, down (RMS of down = RMS of up)."""
    return values if not isinstance(values, list) else [values[1], values[0], values[2]]


def _renamed(path, where: str, entries: dict, renames) -> dict:
    """``entries`` with each earlier east/north/up key (``renames(key)`` -> today's key or
    None) replaced by today's key and its values rearranged; both given: refused."""
    out = {}
    for key, value in entries.items():
        new = renames(key)
        if new is None:
            out.setdefault(key, value)
            continue
        if new in entries:
            _fail(path, f"{where}{key}", f"only one of '{key}' (east, north, up) and '{new}' "
                  "(north, east, down)", value)
        out[new] = _north_east_down(value)
    return out


def _old_improvement_key(key: str):
    for old, new in _OLD_ENDINGS.items():
        if key.endswith(old):
            return key[: -len(old)] + new
    return None


def _migrated(path, data: dict) -> dict:
    """``data`` in today's N/E/D keys (see the module docstring)."""
    data = dict(data)
    data["table"] = [_renamed(path, f"table[{i}].", row, _OLD_TABLE_KEYS.get)
                     for i, row in enumerate(data.get("table", []))]
    if "improvement_percent" in data:
        data["improvement_percent"] = _renamed(path, "improvement_percent.",
                                               data["improvement_percent"],
                                               _old_improvement_key)
    return data


def _check_span(path, span) -> None:
    if not (isinstance(span, list) and len(span) == 2 and all(_number(v) for v in span)
            and span[1] > span[0]):
        _fail(path, "span_s", "[start, stop] [s] with start < stop", span)


def check_reference(data, path) -> dict:
    """``data`` (a parsed paper.json at ``path``) in today's north/east/down keys if it has
    the shape of the module docstring; else :class:`NavfmuError` naming the file and the
    entry."""
    if not isinstance(data, dict):
        _fail(path, "the file", "a JSON object", data)
    table = data.get("table", [])
    if not isinstance(table, list):
        _fail(path, "table", "a list of rows", table)
    for i, row in enumerate(table):
        _check_row(path, i, row)
    if "improvement_percent" in data:
        _check_improvement(path, data["improvement_percent"])
    times = data.get("time_per_cycle_ms", {})
    if not (isinstance(times, dict) and all(_number(v) and v > 0 for v in times.values())):
        _fail(path, "time_per_cycle_ms", "filter names -> positive numbers of ms", times)
    if "windows" in data:
        _check_windows(path, data["windows"])
    for key, kind in (("phases", dict), ("claims", list)):
        if key in data and not isinstance(data[key], kind):
            _fail(path, key, "an object" if kind is dict else "a list", data[key])
    if "span_s" in data:
        _check_span(path, data["span_s"])
    return _migrated(path, data)


__all__ = ["check_reference", "TABLE_AXES"]
