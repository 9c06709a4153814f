"""The parameter tables of docs/signals.md as committed text: the documented contract that
tests hold the code to (read here from the document, not from the declarations that
generate it)."""
from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Dict, NamedTuple

SIGNALS_MD = Path(__file__).resolve().parents[1] / "docs" / "signals.md"
_RANGE = re.compile(r"^(?P<left>[\[(])(?P<low>[^,]+), (?P<high>[^\])]+)(?P<right>[\])])$")


class DocumentedParameter(NamedTuple):
    type: str
    unit: str
    default: str
    range: str          # as printed: "[0, 10000]", "(0, 1]", "finite", "-"


def _component_of(header: str) -> str:
    """``TrajectoryImu parameters`` -> TrajectoryImu; ``SageHusaFading: additional
    parameters`` -> SageHusaFading; ``INS/GNSS filter parameters (Kf; every ...)`` -> Kf."""
    named = re.search(r"\((\w+); every", header)
    return named.group(1) if named else header.split()[0].rstrip(":")


def documented_parameters() -> Dict[str, Dict[str, DocumentedParameter]]:
    """component -> parameter -> its row in the ``... parameters`` sections of signals.md."""
    tables: Dict[str, Dict[str, DocumentedParameter]] = {}
    for section in SIGNALS_MD.read_text().split("\n## ")[1:]:
        header, _, body = section.partition("\n")
        if "parameters" not in header.split("(")[0]:
            continue
        rows = tables.setdefault(_component_of(header), {})
        for line in body.splitlines():
            if line.startswith("| `"):
                cells = [c.strip() for c in line.strip("|").split("|")]
                rows[cells[0].strip("`")] = DocumentedParameter(*cells[1:5])
    return tables


class DocumentedRange(NamedTuple):
    low: float
    high: float
    low_closed: bool
    high_closed: bool


def parse_range(text: str) -> DocumentedRange:
    """``[0, 1e+06]`` -> DocumentedRange(0.0, 1e6, True, True); ``inf`` bounds are open."""
    m = _RANGE.match(text)
    assert m, f"not a range: {text!r}"
    return DocumentedRange(float(m.group("low")), float(m.group("high")),
                           m.group("left") == "[", m.group("right") == "]")


def printed_exactly(text_value: float) -> bool:
    """Whether a bound as printed (6 significant digits) is the bound itself: zero, or at
    most 4 significant digits (1.5708 is pi/2 rounded, 0.74 and 1e+06 are themselves)."""
    if text_value == 0.0 or not math.isfinite(text_value):
        return True
    return float(f"{text_value:.4g}") == text_value


__all__ = ["documented_parameters", "parse_range", "printed_exactly", "DocumentedParameter",
           "DocumentedRange", "SIGNALS_MD"]
