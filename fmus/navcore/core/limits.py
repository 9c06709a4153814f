"""The accepted range of a numeric parameter or input (``Limits``), one definition for the
component contract and the sensor error models that check their own parameters."""
from __future__ import annotations

import math
from dataclasses import dataclass

#: the unit text of a dimensionless quantity
DIMENSIONLESS = "1"


@dataclass(frozen=True)
class Limits:
    """Accepted range of a numeric parameter: ``low``..``high`` (inclusive unless
    ``low_open``/``high_open``); infinite bounds mean unbounded (a Real is always finite)."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False

    def contains(self, x: float) -> bool:
        if not math.isfinite(x):
            return False
        above = x > self.low if self.low_open else x >= self.low
        below = x < self.high if self.high_open else x <= self.high
        return above and below

    def text(self, unit: str = "") -> str:
        """The range as a user reads it, e.g. ``[0, 1e+04] m``, ``(0, 1)`` or ``finite``."""
        if self.low == -math.inf and self.high == math.inf:
            return "finite"
        lo = "-inf" if self.low == -math.inf else f"{self.low:.6g}"
        hi = "inf" if self.high == math.inf else f"{self.high:.6g}"
        left = "(" if self.low_open or self.low == -math.inf else "["
        right = ")" if self.high_open or self.high == math.inf else "]"
        return f"{left}{lo}, {hi}{right}" + (f" {unit}" if unit not in ("", DIMENSIONLESS) else "")


#: any finite value
FINITE = Limits()
