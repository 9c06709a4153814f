"""OMSimulator's annotation on the archive's System: the co-simulation master it runs.

OMSimulator's SSD importer (``Model::importFromSnapshot``) takes the kind of a System from a
vendor annotation on it, ``ssc:Annotation type="org.openmodelica"`` holding
``oms:Annotations/oms:SimulationInformation`` with a ``oms:FixedStepMaster`` (a weakly coupled
system: co-simulation FMUs) or a solver (strongly coupled: model exchange).  A System without
one gets no kind, and the import stops (``[NewSystem] internal error``, then ``Unable to add
System``).  So every archive's System carries::

    <ssd:Annotations>
      <ssc:Annotation type="org.openmodelica">
        <oms:Annotations>
          <oms:SimulationInformation>
            <oms:FixedStepMaster description="oms-ma" stepSize="<base step>"/>

as its last child (where SSP 1.0 puts a System's annotations), with ``xmlns:oms`` declared on
the root.  OMSimulator reads only the first ``ssc:Annotation`` of a System, so ours goes first
in an ``ssd:Annotations`` the System already has.  Other readers skip an annotation type they
do not know: libcosim and :func:`orchestrator.model.ssp.load_model` read the archive with the
same numbers.  The step is the model's base step (OMSimulator's ``--stepSize`` overrides it).

The text is edited in place (comments and layout kept), not re-serialized.
"""
from __future__ import annotations

import re

OMS_ANNOTATION_TYPE = "org.openmodelica"
OMS_NS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
#: OMSimulator's name of its fixed-step co-simulation master
OMS_FIXED_STEP_MASTER = "oms-ma"

_ROOT = re.compile(r"<ssd:SystemStructureDescription\b[^>]*?(?=/?>)", re.S)
#: the System's own ``ssd:Annotations`` (its last child) and its closing tag
_SYSTEM_END = re.compile(
    r"(?P<annotations></ssd:Annotations>\s*?)?(?P<indent>(?:^[ \t]*)?)</ssd:System>", re.M)


def _annotation(step: float, indent: str) -> str:
    lines = (f'<ssc:Annotation type="{OMS_ANNOTATION_TYPE}">',
             "  <oms:Annotations>",
             "    <oms:SimulationInformation>",
             f'      <oms:FixedStepMaster description="{OMS_FIXED_STEP_MASTER}" '
             f'stepSize="{step!r}"/>',
             "    </oms:SimulationInformation>",
             "  </oms:Annotations>",
             "</ssc:Annotation>")
    return "".join(f"{indent}{line}\n" for line in lines)


def _declare_namespace(text: str) -> str:
    root = _ROOT.search(text)
    if root is None or re.search(r"\bxmlns:oms\s*=", root.group(0)):
        return text
    return f'{text[:root.end()]}\n    xmlns:oms="{OMS_NS}"{text[root.end():]}'


def with_oms_system_annotation(text: str, base_step: float) -> str:
    """``text`` (an .ssd with one System) with OMSimulator's fixed-step master annotation on
    its System (module docstring); unchanged if that System already has an annotation of
    type ``org.openmodelica``."""
    text = _declare_namespace(text)
    end = list(_SYSTEM_END.finditer(text))[-1]  # the outermost System closes last
    indent = end.group("indent") + "  "
    if end.group("annotations"):
        opening = text.rfind("<ssd:Annotations", 0, end.start())
        block = text[opening:end.start()]
        if f'type="{OMS_ANNOTATION_TYPE}"' in block:
            return text
        head = text.index(">", opening) + 1
        return (f"{text[:head]}\n{_annotation(base_step, indent + '  ')}"
                f"{text[head:].lstrip(chr(10))}")
    block = (f"{indent}<ssd:Annotations>\n{_annotation(base_step, indent + '  ')}"
             f"{indent}</ssd:Annotations>\n")
    return f"{text[:end.start()]}{block}{text[end.start():]}"


__all__ = ["with_oms_system_annotation", "OMS_ANNOTATION_TYPE", "OMS_NS"]
