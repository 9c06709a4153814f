"""The shape of a scenario's ``paper.json`` (the paper's numbers), checked when it is read, so
that a malformed file is refused by name before any run rather than failing after it.

The blocks, each optional: ``table`` (rows with a ``label``, the ``filter`` they belong to and
per-axis RMS values east/north/up ``position_enu_m``, ``velocity_enu_mps`` and roll/pitch/yaw
``attitude_deg``, each three numbers or null), ``improvement_percent`` (``baseline`` and
``filter`` names, then numbers or lists of numbers), ``time_per_cycle_ms`` (filter -> ms),
``windows`` (name -> ``t0`` < ``t1`` [s] and a ``label``), ``phases`` (an object) and
``claims`` (a list); text entries (``paper``, ``source``, ``shape``, ``note``) are free.
"""
from __future__ import annotations

import math
from numbers import Real
from typing import Any

from ..errors import NavfmuError

#: the per-axis value lists of a table row and what their three entries are
TABLE_AXES = {"position_enu_m": "east, north, up", "velocity_enu_mps": "east, north, up",
              "attitude_deg": "roll, pitch, yaw"}
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


def check_reference(data, path) -> dict:
    """``data`` (a parsed paper.json at ``path``) if it has the shape of the module
    docstring; else :class:`NavfmuError` naming the file and the entry."""
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
    return data


__all__ = ["check_reference", "TABLE_AXES"]
