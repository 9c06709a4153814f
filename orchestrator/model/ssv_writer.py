"""Writing an SSP 1.0 parameter set (``.ssv``), the form a component's parameters are bound in
(the tuner's result, a converted configuration)."""
from __future__ import annotations

from typing import Any, Dict, Optional
from xml.sax.saxutils import quoteattr


def ssv_text(name: str, values: Dict[str, Any], bound: Optional[Dict[str, Any]] = None) -> str:
    """An SSP 1.0 parameter set (``.ssv``): the ``bound`` parameters (``{name: [type, value]}``,
    e.g. as the model binds them now), then ``values`` (Real or Integer), so that one file can
    replace a component's bindings (libcosim reads one binding per component)."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssv:ParameterSet version="1.0" name={quoteattr(name)} '
             'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">',
             "  <ssv:Parameters>"]
    typed = [(k, t, v) for k, (t, v) in (bound or {}).items()]
    typed += [(k, "Integer" if isinstance(v, int) else "Real", v) for k, v in values.items()]
    for key, typ, value in typed:
        if typ == "Boolean":
            text = "true" if value else "false"
        elif typ == "String":
            text = str(value)
        else:
            text = repr(value)
        lines.append(f"    <ssv:Parameter name={quoteattr(key)}><ssv:{typ} "
                     f"value={quoteattr(text)}/></ssv:Parameter>")
    lines += ["  </ssv:Parameters>", "</ssv:ParameterSet>", ""]
    return "\n".join(lines)


__all__ = ["ssv_text"]
