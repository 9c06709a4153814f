"""The XML layer of the SSP files: the namespaces and their literal prefixes, a parse that
reads the files as data only (defusedxml, no DTD, a size limit), and the typed reads of
attributes and ``ssv`` values, each error naming the file and the element."""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import List, Optional, Tuple

import defusedxml.ElementTree as DefusedET
from defusedxml import DefusedXmlException

from ..errors import SspError

SSD_NS = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC_NS = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV_NS = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP_NS = "http://opensimulationplatform.com/SSP/OSPAnnotations"
OSP_ANNOTATION_TYPE = "com.opensimulationplatform"

#: prefix each namespace must be written with (libcosim matches "ssd:System" literally)
REQUIRED_PREFIX = {SSD_NS: "ssd", SSC_NS: "ssc", SSV_NS: "ssv", OSP_NS: "osp"}

TYPES = ("Real", "Integer", "Boolean", "String")
#: largest .ssd / .ssv file read (ours are a few kilobytes)
MAX_FILE_BYTES = 16 * 1024 * 1024


def tag(ns: str, local: str) -> str:
    return "{%s}%s" % (ns, local)


def pretty(tag: str) -> str:
    """``{uri}Local`` -> ``prefix:Local`` for messages."""
    if tag.startswith("{"):
        uri, local = tag[1:].split("}", 1)
        return f"{REQUIRED_PREFIX.get(uri, uri)}:{local}"
    return tag


def parse(path: Path) -> ET.Element:
    """Parse ``path`` as data (no DTD, no entities, at most :data:`MAX_FILE_BYTES`); check
    that the namespaces use the literal prefixes libcosim expects."""
    if not path.is_file():
        raise SspError(f"{path}: file not found")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise SspError(f"{path}: {size} bytes, more than the {MAX_FILE_BYTES} an SSP file "
                       "may have here")
    declared: List[Tuple[str, str]] = []
    try:
        root = None
        for event, item in DefusedET.iterparse(str(path), events=("start-ns", "start"),
                                               forbid_dtd=True):
            if event == "start-ns":
                declared.append(item)
            elif root is None:
                root = item
        # iterparse keeps building the tree; the root element is complete here
    except ET.ParseError as exc:
        # str(exc) already ends with "line L, column C"
        raise SspError(f"{path}: malformed XML: {exc}") from None
    except DefusedXmlException as exc:
        raise SspError(f"{path}: {exc}: a DTD or entity is not allowed in an SSP file") from None
    for prefix, uri in declared:
        want = REQUIRED_PREFIX.get(uri)
        if want is not None and prefix != want:
            shown = f"prefix '{prefix}'" if prefix else "the default namespace"
            raise SspError(
                f"{path}: namespace {uri} is bound to {shown}; write it with the literal "
                f"prefix '{want}:' (libcosim matches tag names literally)"
            )
    return root


def attr(path: Path, elem: ET.Element, name: str, where: str) -> str:
    value = elem.get(name)
    if value is None or value.strip() == "":
        raise SspError(f"{path}: {where} lacks the required attribute '{name}'")
    return value.strip()


def float_attr(path: Path, elem: ET.Element, name: str, where: str,
                required: bool = True, default: Optional[float] = None) -> Optional[float]:
    if elem.get(name) is None and not required:
        return default
    text = attr(path, elem, name, where)
    try:
        value = float(text)
    except ValueError:
        raise SspError(f"{path}: {where} attribute '{name}'=\"{text}\" is not a number") from None
    if not math.isfinite(value):
        raise SspError(f"{path}: {where} attribute '{name}'=\"{text}\" is not finite")
    return value


def only_children(path: Path, elem: ET.Element, allowed: Tuple[str, ...], where: str) -> None:
    for child in elem:
        if child.tag not in allowed:
            raise SspError(
                f"{path}: {where} contains <{pretty(child.tag)}>, which is not supported "
                f"(allowed: {', '.join('<' + pretty(a) + '>' for a in allowed)})"
            )


def osp_annotation(elem: ET.Element) -> Optional[ET.Element]:
    """The ``ssc:Annotation type="com.opensimulationplatform"`` under ``elem/ssd:Annotations``."""
    annotations = elem.find(tag(SSD_NS, "Annotations"))
    if annotations is None:
        return None
    for a in annotations.findall(tag(SSC_NS, "Annotation")):
        if a.get("type") == OSP_ANNOTATION_TYPE:
            return a
    return None


def typed_value(path: Path, elem: ET.Element, where: str) -> Tuple[str, object]:
    """Read ``<ssv:Real value=..>`` (etc.) below a parameter element."""
    children = [c for c in elem if c.tag in {tag(SSV_NS, t) for t in TYPES}]
    if len(children) != 1:
        raise SspError(f"{path}: {where} needs exactly one of <ssv:Real>, <ssv:Integer>, "
                       f"<ssv:Boolean>, <ssv:String> (found {len(children)})")
    child = children[0]
    typ = child.tag.split("}", 1)[1]
    text = child.get("value")
    if text is None:
        raise SspError(f"{path}: {where} <ssv:{typ}> lacks the required attribute 'value'")
    try:
        if typ == "Real":
            value: object = float(text)
        elif typ == "Integer":
            value = int(text.strip())
        elif typ == "Boolean":
            t = text.strip().lower()
            if t not in ("true", "false", "1", "0"):
                raise ValueError(text)
            value = t in ("true", "1")
        else:
            value = text
    except ValueError:
        raise SspError(
            f"{path}: {where} <ssv:{typ} value=\"{text}\"> is not a valid {typ}"
        ) from None
    return typ, value


__all__ = ["SSD_NS", "SSC_NS", "SSV_NS", "OSP_NS", "OSP_ANNOTATION_TYPE", "MAX_FILE_BYTES",
           "TYPES", "tag", "pretty", "parse", "attr", "float_attr", "only_children",
           "osp_annotation", "typed_value"]
