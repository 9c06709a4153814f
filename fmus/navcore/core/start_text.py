"""The exact text of an FMI start value and its parse: one definition for the FMU shell, which
writes and reads its own model description, and for the packager, which writes a scenario's
values into FMU copies.  A Real is written as its shortest round-trip text (``repr``), so the
value read back is the value written, bit for bit.
"""
from __future__ import annotations

import math


def start_text(type_name: str, value) -> str:
    """The exact text of a start value of FMI type ``type_name``."""
    if type_name == "Real":
        return repr(float(value))
    if type_name == "Boolean":
        return "true" if value else "false"
    return str(int(value)) if type_name == "Integer" else str(value)


def parse_start(type_name: str, text: str):
    """The value of a start text (raises ValueError)."""
    if type_name == "Real":
        value = float(text)
        if not math.isfinite(value):
            raise ValueError(f"{text!r} is not a finite number")
        return value
    if type_name == "Integer":
        return int(text)
    if type_name == "Boolean":
        if text not in ("true", "false", "1", "0"):
            raise ValueError(f"{text!r} is not true or false")
        return text in ("true", "1")
    return text
