"""What the master knows of each component before anything is instantiated: its variables
(name, type, causality, unit, value reference), its model name and how to make an instance
(an FMU in the master's process or in a host process of its own, :mod:`.isolation`), read
from the FMU's model description or from the direct backend's registered class."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Dict, Mapping

from .backends import Instance, VarInfo
from .direct_instance import DirectInstance
from ..errors import NavfmuError
from .fmi3_instance import open_fmu
from .fmi3_variables import variables_of
from .hosted_instance import HostedFmuInstance
from .isolation import Isolation
from ..model.fmu_path import searched_places
from ..model.ssp import ComponentSpec


@dataclass
class Described:
    """A component of the model as described before it runs; ``make()`` instantiates it."""

    spec: ComponentSpec
    variables: Dict[str, VarInfo]
    source: str            # FMU path or Python class, for messages
    model_name: str
    make: Callable[[], Instance]
    #: whether it runs in a host process of its own (:mod:`.isolation`)
    hosted: bool = False


def _model_name_of_fmu(path: Path) -> str:
    from fmpy import read_model_description

    try:
        return read_model_description(str(path), validate=False).modelName
    except Exception as exc:  # fmpy raises plain Exception for unreadable files
        raise NavfmuError(f"cannot read the model description of {path}: {exc}") from None


def describe_fmu(spec: ComponentSpec, isolation: Isolation = Isolation()) -> Described:
    """The FMU of ``spec``, made in the master's process or in a host process of its own
    as ``isolation`` says."""
    from fmpy import read_model_description

    path = spec.source
    if not path.is_file():
        where = f"source=\"{spec.source_text}\" " if spec.source_text else ""
        raise NavfmuError(f"component '{spec.name}': FMU file not found: {path} ({where}searched "
                          f"{searched_places()})")
    try:
        md = read_model_description(str(path), validate=False)
    except Exception as exc:  # fmpy raises plain Exception for unreadable files
        raise NavfmuError(f"component '{spec.name}': cannot read the model description of "
                          f"{path}: {exc}") from None
    variables = variables_of(md, spec.name, path)
    if isolation.hosts(path, md.modelName):
        return Described(spec, variables, str(path), md.modelName,
                          lambda: HostedFmuInstance(path, spec.name, isolation.call_timeout),
                          hosted=True)
    return Described(spec, variables, str(path), md.modelName,
                      lambda: open_fmu(path, spec.name))


def describe_direct(spec: ComponentSpec, registry: Mapping[str, type]) -> Described:
    model_name = spec.source.stem
    if model_name not in registry and spec.source.is_file():
        model_name = _model_name_of_fmu(spec.source)
    probe = DirectInstance.from_registry(model_name, spec.name, registry)
    return Described(spec, probe.variables, probe.source, model_name,
                      lambda: DirectInstance.from_registry(model_name, spec.name, registry))


__all__ = ["Described", "describe_fmu", "describe_direct"]
