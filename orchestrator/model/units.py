"""Units of the values a model binds and connects: a value given in one unit converted to the
unit of the FMU variable it sets, and the checks that the two ends of a connection, and a
connector and its FMU variable, speak one unit (the master converts no connection).

Units are read by pint, in a registry of navfmu's own that knows the units of navigation
and no others: the SI units of the FMU interfaces (``m``, ``s``, ``rad``, ``T``, ``Hz`` with
the prefixes ``n u m c k``), ``deg``, ``min``, ``h``, the standard gravity ``g`` (so ``ug``
is micro-g, not microgram), ``ppm``, ``ft``, ``nmi`` and ``kn``.  The text is the one FMI
and Modelica write: ``m/s2`` is m/s², ``sqrt(h)`` is h^0.5, ``1`` is a pure number.  Any other
unit is unknown and refused by name.
"""
from __future__ import annotations

import functools
import math
import re

from ..errors import NavfmuError

_DEFINITIONS = """
nano- = 1e-9 = n-
micro- = 1e-6 = u-
milli- = 1e-3 = m-
centi- = 1e-2 = c-
kilo- = 1e3 = k-
metre = [length] = m
second = [time] = s
radian = [] = rad
tesla = [magnetic_field] = T
degree = {pi} * radian / 180 = deg
minute = 60 * second = min
hour = 60 * minute = h
hertz = 1 / second = Hz
standard_gravity = 9.80665 * metre / second ** 2 = g
parts_per_million = 1e-6 = ppm
foot = 0.3048 * metre = ft
nautical_mile = 1852 * metre = nmi
knot = nautical_mile / hour = kn
"""


#: units that declare no physical quantity: none, or a generic (dimensionless) signal
GENERIC = ("", "1")


class UnitError(NavfmuError):
    """A unit that is unknown, or that cannot be converted to the one it must meet."""


@functools.lru_cache(maxsize=1)
def _registry():
    import pint

    registry = pint.UnitRegistry(None)
    for line in _DEFINITIONS.format(pi=repr(math.pi)).strip().splitlines():
        registry.define(line)
    return registry


def _pint_text(unit: str) -> str:
    """FMI/Modelica unit text as pint reads it: ``m/s2`` -> ``m/s**2``, ``sqrt(x)`` ->
    ``(x)**0.5``, ``1`` -> a pure number."""
    text = re.sub(r"sqrt\(([^()]*)\)", r"(\1)**0.5", unit.strip())
    text = re.sub(r"(?<=[A-Za-z])(-?\d+)", r"**\1", text)
    return text


@functools.lru_cache(maxsize=256)
def _quantity(unit: str):
    registry = _registry()
    if unit.strip() in ("1", ""):
        return registry.Quantity(1.0)
    try:
        return registry.Quantity(1.0, registry.parse_units(_pint_text(unit)))
    except Exception:       # pint's parse errors have several types; all mean "unknown"
        return None


def _known(unit: str, where: str):
    q = _quantity(unit)
    if q is None:
        raise UnitError(f"{where}: unknown unit '{unit}'")
    return q


def convert(value: float, unit: str, target: str, where: str) -> float:
    """``value`` given in ``unit`` expressed in ``target`` (the FMU variable's unit);
    :class:`UnitError` naming ``where`` if either is unknown or they measure different
    things, or if the variable declares no unit to convert to."""
    if unit == target:
        return value
    if not target:
        raise UnitError(f"{where}: given in '{unit}', but the FMU variable declares no unit "
                        "to convert it to")
    source, goal = _known(unit, where), _known(target, where)
    try:
        return float(value) * float((source / goal).to("").magnitude)
    except Exception:
        raise UnitError(f"{where}: '{unit}' cannot be converted to the variable's unit "
                        f"'{target}'") from None


def check_same(unit: str, other: str, where: str) -> None:
    """``unit`` and ``other`` are one unit (the same text, or two spellings of one unit):
    the master passes a connected value unchanged, so 'deg' against 'rad' or 'm/s' against
    'm' is refused, naming ``where``.  An empty unit (none declared) and the dimensionless
    '1' (a generic signal: a gain's input, a flag) meet any unit."""
    if unit in GENERIC or other in GENERIC or unit == other:
        return
    a, b = _known(unit, where), _known(other, where)
    try:
        factor = float((a / b).to("").magnitude)
    except Exception:
        factor = None
    if factor is None or not math.isclose(factor, 1.0, rel_tol=1e-12):
        raise UnitError(f"{where}: unit '{unit}' against '{other}' (a connection passes the "
                        "value unchanged: give both ends one unit)")


__all__ = ["UnitError", "GENERIC", "convert", "check_same"]
