"""The archive's SSP text as strict SSP readers take it.

OMSimulator's importer (and any reader that validates the standard's types strictly) stops at
two things our model folders hold:

* ``<ssv:String>`` parameter values (it reads only Real, Integer and Boolean): dropped from
  the archive's parameter sets, inline and in ``.ssv`` files.  Nothing is lost: every packaged
  FMU copy carries the scenario's parameter values, Strings included, as its start values
  (:mod:`orchestrator.packaging.fmu_copies`), and a host that binds no String starts from them;
* annotations on a Component (``osp:StepSizeHint``): it refuses any element of a Component but
  connectors, geometry and parameter bindings.  These are dropped only on request
  (``navfmu package --no-step-hints``): libcosim and our master read the hints, and without
  them every component steps at the base step, which changes the numbers of a Jacobi run.

The text is edited in place (comments and layout kept), not re-serialized.
"""
from __future__ import annotations

import re

#: an attribute list: quoted values may hold '>'
_ATTRS = r'(?:"[^"]*"|\'[^\']*\'|[^>"\'])*'
_STRING_PARAMETER = re.compile(
    rf"[ \t]*<ssv:Parameter\b{_ATTRS}>\s*<ssv:String\b{_ATTRS}"
    rf"(?:/>|>\s*</ssv:String>)\s*</ssv:Parameter>[ \t]*\n?")
_COMPONENT = re.compile(r"<ssd:Component\b.*?</ssd:Component>", re.S)
_ANNOTATIONS = re.compile(r"[ \t]*<ssd:Annotations\b.*?</ssd:Annotations>[ \t]*\n?", re.S)


def without_string_values(text: str) -> str:
    """``text`` (an .ssd or .ssv) without its ``<ssv:Parameter>`` elements of type String."""
    return _STRING_PARAMETER.sub("", text)


def without_component_annotations(text: str) -> str:
    """``text`` (an .ssd) without the ``<ssd:Annotations>`` of its Components (the step
    hints); the DefaultExperiment's annotation (the base step) stays: readers skip it."""
    return _COMPONENT.sub(lambda m: _ANNOTATIONS.sub("", m.group(0)), text)


__all__ = ["without_string_values", "without_component_annotations"]
