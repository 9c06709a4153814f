"""Start values: the model description's are the FMU's.

The model description writes every start value exactly (a Real as its shortest round-trip
text, :func:`start_text`; pythonfmu's 16 digits do not round-trip), and an instance takes the
start values of its parameters from the model description of the FMU it was loaded from
(``<resources>/../modelDescription.xml``).  So a copy of an FMU whose model description
carries other start values (``navfmu package`` and ``navfmu export`` write a scenario's
parameters so) runs with them in a host that sets no parameter at all, and a host that sets
them still does.  A start text that does not parse as its variable's type makes
``fmi2ExitInitializationMode`` fail with a message naming the variable.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, Optional

from navcore.core.start_text import parse_start, start_text

#: (path, mtime, size) -> {name: (type, start text)}: each model description read once
_READ: Dict[tuple, Dict[str, tuple]] = {}


def _starts(md_path: Path) -> Dict[str, tuple]:
    stat = md_path.stat()
    key = (str(md_path), stat.st_mtime_ns, stat.st_size)
    if key not in _READ:
        starts = {}
        for sv in ET.parse(md_path).getroot().iter("ScalarVariable"):
            if sv.get("causality") == "parameter" and len(sv) and "start" in sv[0].attrib:
                starts[sv.get("name")] = (sv[0].tag, sv[0].get("start"))
        _READ[key] = starts
    return _READ[key]


def model_description_of(slave) -> Optional[Path]:
    """The model description of the FMU ``slave`` was loaded from (None when it runs outside
    an FMU, as in the builder)."""
    resources = getattr(slave, "resources", None)
    if not resources or Path(resources).name != "resources":
        return None
    md_path = Path(resources).parent / "modelDescription.xml"
    return md_path if md_path.is_file() else None


def apply_start_values(slave, parameters) -> Optional[str]:
    """Set the registered values of ``parameters`` (ports) to the model description's start
    values; returns the message for a start text that does not parse (None if all do)."""
    md_path = model_description_of(slave)
    if md_path is None:
        return None
    try:
        starts = _starts(md_path)
    except (OSError, ET.ParseError) as exc:
        return f"cannot read the start values of {md_path}: {exc}"
    for port in parameters:
        type_name, text = starts.get(port.name, (None, None))
        if text is None:
            continue
        if type_name != port.type:
            return f"parameter '{port.name}' is {port.type} but {md_path} declares {type_name}"
        try:
            slave._values[port.name] = parse_start(port.type, text)
        except ValueError as exc:
            return f"start value of parameter '{port.name}' in {md_path}: {exc}"
    return None
