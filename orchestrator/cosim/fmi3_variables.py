"""The variables of an FMU as the master exchanges them, for FMI 2.0 and FMI 3.0 alike, and
what of FMI 3.0 it refuses before anything runs.

FMI 3.0 types are mapped onto the system structure's connector types (the FMI 2 names every
other part of navfmu speaks):

=================  ==========  ================================================
FMI 3.0            connector   exchanged as
=================  ==========  ================================================
Float64            Real        float64
Int32, Int64       Integer     int32 (an Int64 value outside 32 bits is refused
                               when it is read, never wrapped)
Boolean            Boolean     int32 0/1 (fmi3Boolean is one byte)
String             String      parameters only, as for FMI 2.0
Enumeration        Enumeration parameters only (set as Int64)
=================  ==========  ================================================

Refused, by component, variable and type, when the variable is an input or an output: Float32,
Int8, UInt8, Int16, UInt16, UInt32, UInt64, Binary (no connector type holds them without a
conversion the system structure does not state), and arrays (a variable with ``<Dimension>``:
the system structure connects scalars only; an array is not split into elements).  An FMU
with any Clock is refused (clocked partitions need event mode, which the master does not
use).  Such a variable that is a parameter or a local is kept under its FMI 3.0 type name
(``Float32``, ``Float64[3]``) and refused only when a system structure sets it
(:meth:`orchestrator.cosim.master.Simulation`'s parameter check).

Which masters cannot take an FMI 3.0 component at all (libcosim, and ``navfmu package``,
whose archive is written for it) ask :func:`refuse_fmi3`.
"""
from __future__ import annotations

from pathlib import Path
from typing import Dict, Iterable

from .backends import VarInfo
from ..errors import NavfmuError

#: FMI 3.0 type -> connector type, for the types the master exchanges
FMI3_TYPES = {"Float64": "Real", "Int32": "Integer", "Int64": "Integer", "Boolean": "Boolean",
              "String": "String", "Enumeration": "Enumeration"}
#: the FMI versions the master runs
SUPPORTED_VERSIONS = ("2.0", "3.0")


def _unit(v) -> str:
    return v.unit or (v.declaredType.unit if v.declaredType is not None else None) or ""


def _fmi3_type(v) -> str:
    """The connector type of the FMI 3.0 variable ``v``, or its own FMI 3.0 type name (with
    its shape, for an array) when the master cannot exchange it."""
    if v.dimensions:
        shape = ",".join(str(n) if n is not None else "?" for n in (v.shape or ()))
        return f"{v.type}[{shape}]"
    return FMI3_TYPES.get(v.type, v.type)


def _refusal(comp: str, path: Path, v, typ: str) -> NavfmuError:
    what = (f"an array ({typ}); only scalar variables can be connected or recorded"
            if v.dimensions else
            f"{'an' if typ[0] in 'AEIO' else 'a'} {typ}, which no connector type holds (FMI 3.0 "
            f"Float64, Int32, Int64 and Boolean are exchanged)")
    return NavfmuError(f"component '{comp}' ({path.name}): FMI 3.0 {v.causality} '{v.name}' is "
                       f"{what}")


def check_version(md, comp: str, path: Path) -> None:
    """Refuse an FMU the master cannot run: another FMI version, or no co-simulation."""
    if md.fmiVersion not in SUPPORTED_VERSIONS:
        raise NavfmuError(f"component '{comp}': {path} is an FMI {md.fmiVersion} FMU; only "
                          f"FMI 2.0 and 3.0 co-simulation FMUs are supported")
    if md.coSimulation is None:
        raise NavfmuError(f"component '{comp}': {path} does not support co-simulation (model "
                          f"exchange only); only FMI {md.fmiVersion} co-simulation is supported")


def variables_of(md, comp: str, path: Path) -> Dict[str, VarInfo]:
    """The variables of the FMU ``path`` (model description ``md``) of component ``comp``,
    typed as connectors (module docstring); an FMI 3.0 FMU the master cannot exchange with is
    refused here, before anything runs."""
    check_version(md, comp, path)
    path = Path(path)
    variables = {}
    for v in md.modelVariables:
        typ = v.type
        if md.fmiVersion == "3.0":
            if v.type == "Clock":
                raise NavfmuError(f"component '{comp}' ({path.name}): FMI 3.0 clock '{v.name}': "
                                  f"clocked FMUs need event mode, which the master does not use")
            typ = _fmi3_type(v)
            if v.causality in ("input", "output") and typ not in FMI3_TYPES.values():
                raise _refusal(comp, path, v, typ)
        variables[v.name] = VarInfo(v.name, typ, v.causality, _unit(v), v.valueReference)
    return variables


def fmi_version(path) -> str:
    """The FMI version of the FMU ``path`` (``""`` when its model description is unreadable:
    the caller's own reading then reports why)."""
    from fmpy import read_model_description

    try:
        return read_model_description(str(path), validate=False).fmiVersion
    except Exception:  # fmpy raises plain Exception for unreadable files
        return ""


def refuse_fmi3(components: Iterable, who: str) -> None:
    """Refuse the first FMI 3.0 FMU among ``components`` (system structure components) for
    ``who``, a tool that cannot load FMI 3.0 (libcosim segfaults on one)."""
    for spec in components:
        if spec.source.is_file() and fmi_version(spec.source) == "3.0":
            raise NavfmuError(f"component '{spec.name}': {spec.source.name} is an FMI 3.0 FMU, "
                              f"which {who} cannot load (navfmu run runs it)")


__all__ = ["FMI3_TYPES", "SUPPORTED_VERSIONS", "check_version", "variables_of", "fmi_version",
           "refuse_fmi3"]
